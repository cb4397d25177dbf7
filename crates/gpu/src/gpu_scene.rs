//! A scene on the GPU: world-space vertex and index buffers (instances flattened, since
//! lightlab's scenes are static), one draw per instance, materials with mip-mapped textures,
//! and per-instance edge adjacency for shadow volumes.

use crate::shadow_volume::VolumeMesh;
use crate::uniforms::GpuMaterial;
use bytemuck::{Pod, Zeroable};
use glam::{Mat3, Vec3, Vec4};
use lightlab_scene::{AlphaMode, Scene, Texture};
use wgpu::util::DeviceExt;

/// One vertex (WGSL `VertexIn`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub tangent: [f32; 4],
    pub uv0: [f32; 2],
    pub uv1: [f32; 2],
    /// COLOR_0 as 16-bit unorm (glTF's range, [0, 1]); white without.
    pub color: [u16; 4],
}

pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2, 4 => Float32x2,
    5 => Unorm16x4
];

pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    }
}

/// Where an instance's light-map lives in the light-map texture array: array coordinates =
/// `offset + uv1 · scale` on layer `page` (the upload adds `page` to x, which the shader splits
/// off again).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvRect {
    pub page: u32,
    pub offset: [f32; 2],
    pub scale: [f32; 2],
}

/// One instance: a range of the index buffer with one material.
#[derive(Clone, Debug)]
pub struct Draw {
    /// Where the instance's vertices start in the vertex buffer.
    pub first_vertex: u32,
    /// Its light-map rectangle, if it has one.
    pub rect: Option<UvRect>,
    /// The instance's transform when its vertices were written.
    pub transform: glam::Mat4,
    pub first_index: u32,
    pub index_count: u32,
    pub material: usize,
    pub bounds: (Vec3, Vec3),
    /// Adjacency for shadow volumes; None for materials that cannot cast them (alpha masks).
    pub volume: Option<VolumeMesh>,
}

pub struct GpuMaterialBinding {
    pub bind_group: wgpu::BindGroup,
    pub double_sided: bool,
    pub alpha_masked: bool,
}

pub struct GpuScene {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub draws: Vec<Draw>,
    pub materials: Vec<GpuMaterialBinding>,
    pub bounds: (Vec3, Vec3),
    pub triangles: usize,
}

/// The material bind group layout (WGSL group 1).
pub fn material_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let tex = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("material"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                // The vertex stage reads the wind sway weight.
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            tex(1),
            tex(2),
            tex(3),
            tex(4),
            tex(6),
            wgpu::BindGroupLayoutEntry {
                binding: 5,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    })
}

/// Box-filtered mip chain of a linear RGBA texture, as f16.
fn mip_chain(t: &Texture) -> Vec<(u32, u32, Vec<half::f16>)> {
    box_chain(t, t.to_linear(), |c| c.to_array())
}

/// The mip chain of a tangent-space normal map for every `raster::NormalFilter`: RGB the box
/// mean of the finest level's unit normals (xyz·½ + ½, unnormalised, so box-mipped normals are
/// today's), alpha the spread of those normals under the texel as Toksvig's σ² = (1 − r)/r, r
/// the length of their mean. The finest level's normals are renormalised first (an 8-bit map's
/// are not unit, and would read as spread), so its σ² is 0 and magnified maps are not widened.
/// The means are kept in f32 between levels; only the stored texels are f16.
fn normal_mip_chain(t: &Texture) -> Vec<(u32, u32, Vec<half::f16>)> {
    let unit = t
        .to_linear()
        .iter()
        .map(|c| (c.truncate() * 2.0 - Vec3::ONE).normalize_or(Vec3::Z))
        .collect();
    box_chain(t, unit, |m| {
        let r = m.length().max(1e-3);
        let spread = ((1.0 - r) / r).clamp(0.0, 16.0);
        (*m * 0.5 + Vec3::splat(0.5)).extend(spread).to_array()
    })
}

/// Every level of `finest` (`t`'s size) box-filtered down to 1 × 1 in f32, each stored as the
/// f16 RGBA of `texel`.
fn box_chain<T>(
    t: &Texture,
    finest: Vec<T>,
    texel: impl Fn(&T) -> [f32; 4],
) -> Vec<(u32, u32, Vec<half::f16>)>
where
    T: Copy + Default + std::ops::Add<Output = T> + std::ops::Div<f32, Output = T>,
{
    let mut levels = vec![];
    let (mut w, mut h) = (t.width.max(1), t.height.max(1));
    let mut cur = finest;
    loop {
        let data = cur
            .iter()
            .flat_map(|c| texel(c).map(half::f16::from_f32))
            .collect();
        levels.push((w, h, data));
        if w == 1 && h == 1 {
            break;
        }
        (cur, w, h) = box_down(&cur, w, h);
    }
    levels
}

/// One 2 × 2 box-filtered level down (edges clamped for odd sizes).
fn box_down<T>(cur: &[T], w: u32, h: u32) -> (Vec<T>, u32, u32)
where
    T: Copy + Default + std::ops::Add<Output = T> + std::ops::Div<f32, Output = T>,
{
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let mut next = vec![T::default(); (nw * nh) as usize];
    for y in 0..nh {
        for x in 0..nw {
            let mut s = T::default();
            for dy in 0..2 {
                for dx in 0..2 {
                    let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                    s = s + cur[(sy * w + sx) as usize];
                }
            }
            next[(y * nw + x) as usize] = s / 4.0;
        }
    }
    (next, nw, nh)
}

fn upload_texture(device: &wgpu::Device, queue: &wgpu::Queue, t: &Texture) -> wgpu::TextureView {
    upload_levels(device, queue, t, mip_chain(t))
}

/// A mip chain (RGBA f16 levels) as a sampled texture.
fn upload_levels(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    t: &Texture,
    levels: Vec<(u32, u32, Vec<half::f16>)>,
) -> wgpu::TextureView {
    let tex = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(&t.name),
        size: wgpu::Extent3d {
            width: t.width.max(1),
            height: t.height.max(1),
            depth_or_array_layers: 1,
        },
        mip_level_count: levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (level, (w, h, data)) in levels.iter().enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &tex,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(data),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 8),
                rows_per_image: Some(*h),
            },
            wgpu::Extent3d {
                width: *w,
                height: *h,
                depth_or_array_layers: 1,
            },
        );
    }
    tex.create_view(&Default::default())
}

impl GpuScene {
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, scene: &Scene) -> GpuScene {
        Self::with_lightmap_uvs(device, queue, scene, None)
    }

    /// Upload with UV1 mapped into a light-map array: `rects[instance]`.
    pub fn with_lightmap_uvs(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        rects: Option<&[Option<UvRect>]>,
    ) -> GpuScene {
        let mut g = Geometry::new(scene, rects);
        if g.vertices.is_empty() {
            g.lo = Vec3::ZERO;
            g.hi = Vec3::ZERO;
            // wgpu does not allow empty buffers to be bound as vertex buffers.
            g.vertices.push(Vertex::zeroed());
            g.indices.extend([0, 0, 0]);
        }
        let vb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene vertices"),
            contents: bytemuck::cast_slice(&g.vertices),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        let ib = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene indices"),
            contents: bytemuck::cast_slice(&g.indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        GpuScene {
            vertices: vb,
            indices: ib,
            triangles: g.draws.iter().map(|d| d.index_count as usize / 3).sum(),
            draws: g.draws,
            materials: upload_materials(device, queue, scene),
            bounds: (g.lo, g.hi),
        }
    }
}

/// The scene flattened to world space: one vertex and index range per instance.
struct Geometry {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
    draws: Vec<Draw>,
    lo: Vec3,
    hi: Vec3,
}

impl Geometry {
    /// Every instance's vertices in world space (light-map UVs placed in their page rectangle
    /// when `rects` has one), counter-clockwise triangles, and its draw.
    fn new(scene: &Scene, rects: Option<&[Option<UvRect>]>) -> Geometry {
        let mut vertices: Vec<Vertex> = vec![];
        let mut indices: Vec<u32> = vec![];
        let mut draws = vec![];
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for ii in 0..scene.instances.len() {
            let rect = rects.and_then(|r| r.get(ii).copied().flatten());
            let base = vertices.len() as u32;
            let (verts, world, flip) = instance_vertices(scene, ii, rect);
            vertices.extend(verts);
            let (dlo, dhi) = world_bounds(&world);
            let mesh = &scene.meshes[scene.instances[ii].mesh];
            let first_index = indices.len() as u32;
            // A mirroring transform flips the winding: restore counter-clockwise.
            for t in mesh.indices.chunks_exact(3) {
                if flip {
                    indices.extend([base + t[0], base + t[2], base + t[1]]);
                } else {
                    indices.extend([base + t[0], base + t[1], base + t[2]]);
                }
            }
            lo = lo.min(dlo);
            hi = hi.max(dhi);
            let local: Vec<u32> = indices[first_index as usize..]
                .iter()
                .map(|i| i - base)
                .collect();
            draws.push(Draw {
                first_vertex: base,
                rect,
                transform: scene.instances[ii].transform,
                first_index,
                index_count: mesh.indices.len() as u32,
                material: mesh.material,
                bounds: (dlo, dhi),
                volume: casts_volume(scene, ii).then(|| VolumeMesh::new(&world, &local)),
            });
        }
        Geometry {
            vertices,
            indices,
            draws,
            lo,
            hi,
        }
    }
}

/// Whether instance `ii` casts shadow volumes (alpha-masked materials cannot).
fn casts_volume(scene: &Scene, ii: usize) -> bool {
    let mesh = &scene.meshes[scene.instances[ii].mesh];
    scene.materials[mesh.material].alpha_mode == AlphaMode::Opaque
}

fn world_bounds(world: &[Vec3]) -> (Vec3, Vec3) {
    world.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), w| (lo.min(*w), hi.max(*w)),
    )
}

/// Instance `ii`'s vertices in world space (light-map UVs placed in `rect` when given), its
/// world positions, and whether its transform mirrors (which flips the winding).
fn instance_vertices(
    scene: &Scene,
    ii: usize,
    rect: Option<UvRect>,
) -> (Vec<Vertex>, Vec<Vec3>, bool) {
    let inst = &scene.instances[ii];
    let mesh = &scene.meshes[inst.mesh];
    let nm = inst.normal_matrix();
    let m3 = Mat3::from_mat4(inst.transform);
    let flip = if m3.determinant() < 0.0 { -1.0 } else { 1.0 };
    let mut vertices = Vec::with_capacity(mesh.positions.len());
    let mut world = Vec::with_capacity(mesh.positions.len());
    for (i, p) in mesh.positions.iter().enumerate() {
        let w = inst.transform.transform_point3(*p);
        world.push(w);
        let n = mesh
            .normals
            .get(i)
            .map(|n| (nm * *n).normalize_or_zero())
            .unwrap_or(Vec3::Y);
        let t = mesh
            .tangents
            .get(i)
            .map_or(Vec4::new(1.0, 0.0, 0.0, 1.0), |t| {
                (m3 * t.truncate()).normalize_or_zero().extend(t.w * flip)
            });
        let uv1 = mesh
            .uv1
            .as_ref()
            .and_then(|u| u.get(i))
            .map_or([0.0; 2], |u| u.to_array());
        vertices.push(Vertex {
            position: w.to_array(),
            normal: n.to_array(),
            tangent: t.to_array(),
            uv0: mesh.uv0.get(i).map_or([0.0; 2], |u| u.to_array()),
            uv1: match rect {
                Some(r) => [
                    r.page as f32 + r.offset[0] + uv1[0] * r.scale[0],
                    r.offset[1] + uv1[1] * r.scale[1],
                ],
                None => uv1,
            },
            color: mesh.colors.get(i).map_or([u16::MAX; 4], |c| {
                c.to_array()
                    .map(|x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16)
            }),
        });
    }
    (vertices, world, flip < 0.0)
}

impl GpuScene {
    /// Instance `i` moved to its transform in `scene` (same meshes as when uploaded): its
    /// vertices are rewritten, and its bounds, shadow volume and the scene's bounds follow.
    /// A move that turns a transform into a mirroring one (or back) keeps the old winding.
    pub fn move_instance(&mut self, queue: &wgpu::Queue, scene: &Scene, i: usize) {
        let Some(d) = self.draws.get(i) else {
            return;
        };
        let (verts, world, _) = instance_vertices(scene, i, d.rect);
        let first = d.first_vertex;
        queue.write_buffer(
            &self.vertices,
            first as u64 * std::mem::size_of::<Vertex>() as u64,
            bytemuck::cast_slice(&verts),
        );
        let d = &mut self.draws[i];
        d.bounds = world_bounds(&world);
        let to = scene.instances[i].transform;
        if let Some(v) = &mut d.volume {
            v.transform(to * d.transform.inverse());
        }
        d.transform = to;
        self.bounds = self.draws.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), d| (lo.min(d.bounds.0), hi.max(d.bounds.1)),
        );
    }
}

/// Every material's uniforms and textures as a bind group (one default material when the
/// scene has none), with a white texture where a map is missing.
fn upload_materials(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &Scene,
) -> Vec<GpuMaterialBinding> {
    let layout = material_layout(device);
    let white = upload_texture(
        device,
        queue,
        &Texture {
            name: "white".into(),
            width: 1,
            height: 1,
            texels: lightlab_scene::Texels::Rgba32F(vec![Vec4::ONE]),
            srgb: false,
        },
    );
    // A texture read as a normal map gets its own chain (with the spread in alpha); one read
    // otherwise too is uploaded twice.
    let as_normal = |i: usize| {
        scene
            .materials
            .iter()
            .any(|m| m.normal_texture.is_some_and(|r| r.texture == i))
    };
    let as_other = |i: usize| {
        scene.materials.iter().any(|m| {
            [
                m.base_color_texture,
                m.metallic_roughness_texture,
                m.emissive_texture,
                m.transmission_texture,
            ]
            .iter()
            .any(|r| r.is_some_and(|r| r.texture == i))
        })
    };
    let (textures, normals): (Vec<_>, Vec<_>) = scene
        .textures
        .iter()
        .enumerate()
        .map(|(i, t)| {
            (
                as_other(i).then(|| upload_texture(device, queue, t)),
                as_normal(i).then(|| upload_levels(device, queue, t, normal_mip_chain(t))),
            )
        })
        .unzip();
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("material"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        address_mode_w: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        anisotropy_clamp: 8,
        ..Default::default()
    });
    let fallback = [lightlab_scene::Material::default()];
    let list: &[lightlab_scene::Material] = if scene.materials.is_empty() {
        &fallback
    } else {
        &scene.materials
    };
    let textures = MaterialTextures {
        layout: &layout,
        white: &white,
        textures: &textures,
        normals: &normals,
        sampler: &sampler,
    };
    let (table_layers, _) = crate::brdf_tables::layers(list);
    list.iter()
        .zip(table_layers)
        .map(|(m, layer)| material_binding(device, &textures, m, layer))
        .collect()
}

/// What every material's bind group shares.
struct MaterialTextures<'a> {
    layout: &'a wgpu::BindGroupLayout,
    white: &'a wgpu::TextureView,
    /// Each texture as colour (or data), where a material reads it so.
    textures: &'a [Option<wgpu::TextureView>],
    /// Each texture as a normal map, where a material reads it so.
    normals: &'a [Option<wgpu::TextureView>],
    sampler: &'a wgpu::Sampler,
}

/// A material's GPU uniforms: factors, which maps it has and their UV sets, its model.
fn gpu_material(m: &lightlab_scene::Material, table_layer: Option<u32>) -> GpuMaterial {
    let refs = [
        m.base_color_texture,
        m.metallic_roughness_texture,
        m.normal_texture,
        m.emissive_texture,
    ];
    let mut flags = 0u32;
    let mut uv_sets = 0u32;
    let mut uv_transform = [[0.0f32; 4]; 12];
    let mut put = |i: usize, r: &lightlab_scene::TextureRef| {
        uv_sets |= (r.uv_set & 1) << i;
        let [a, b] = r.transform.0;
        uv_transform[2 * i] = [a[0], a[1], a[2], 0.0];
        uv_transform[2 * i + 1] = [b[0], b[1], b[2], 0.0];
    };
    if let Some(r) = &m.transmission_texture {
        // Bit 5 (bit 4 is double-sided).
        flags |= 32;
        put(5, r);
    }
    for (i, r) in refs.iter().enumerate() {
        if let Some(r) = r {
            flags |= 1 << i;
            put(i, r);
        }
    }
    if m.double_sided {
        flags |= 16;
    }
    GpuMaterial {
        base_color: m.base_color.to_array(),
        emissive: (m.emissive * m.emissive_strength).to_array(),
        metallic: m.metallic,
        roughness: m.roughness,
        specular: m.specular,
        normal_scale: m.normal_scale,
        alpha_cutoff: match m.alpha_mode {
            AlphaMode::Mask { cutoff } => cutoff,
            // Blended surfaces are drawn as alpha-tested at ½ (no sorting yet).
            AlphaMode::Blend => 0.5,
            AlphaMode::Opaque => -1.0,
        },
        transmission: m.transmission,
        model: match m.brdf {
            lightlab_scene::BrdfModel::Pbr => 0,
            lightlab_scene::BrdfModel::Lambert => 1,
            lightlab_scene::BrdfModel::Phong => 2,
            lightlab_scene::BrdfModel::BlinnPhong => 3,
            lightlab_scene::BrdfModel::TorranceSparrow => 4,
            lightlab_scene::BrdfModel::CookTorrance => 5,
            lightlab_scene::BrdfModel::Ward => 6,
            lightlab_scene::BrdfModel::Banks => 7,
            lightlab_scene::BrdfModel::Lafortune => 8,
        },
        flags,
        uv_sets,
        sway: m.sway,
        ior: m.ior,
        spec_transmission: if m.brdf == lightlab_scene::BrdfModel::Pbr {
            m.specular_transmission
        } else {
            0.0
        },
        thickness: m.thickness,
        uv_transform,
        conductor_eta: m
            .conductor
            .map_or([0.0; 4], |c| c.eta.extend(1.0).to_array()),
        conductor_k: m.conductor.map_or([0.0; 4], |c| c.k.extend(1.0).to_array()),
        anisotropy: [
            m.anisotropy.clamp(0.0, 1.0),
            m.anisotropy_rotation.cos(),
            m.anisotropy_rotation.sin(),
            0.0,
        ],
        lafortune: m.lafortune.extend(0.0).to_array(),
        tables: crate::brdf_tables::gpu_entry(m, table_layer),
    }
}

/// A material's bind group: uniforms, its four maps, the sampler, its transmission map.
fn material_binding(
    device: &wgpu::Device,
    t: &MaterialTextures,
    m: &lightlab_scene::Material,
    table_layer: Option<u32>,
) -> GpuMaterialBinding {
    let ubuf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(&m.name),
        contents: bytemuck::bytes_of(&gpu_material(m, table_layer)),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let view = |r: Option<lightlab_scene::TextureRef>| {
        let v = r.and_then(|r| t.textures[r.texture].as_ref());
        wgpu::BindingResource::TextureView(v.unwrap_or(t.white))
    };
    let normal = m.normal_texture.and_then(|r| t.normals[r.texture].as_ref());
    let e = |binding, resource| wgpu::BindGroupEntry { binding, resource };
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(&m.name),
        layout: t.layout,
        entries: &[
            e(0, ubuf.as_entire_binding()),
            e(1, view(m.base_color_texture)),
            e(2, view(m.metallic_roughness_texture)),
            e(
                3,
                wgpu::BindingResource::TextureView(normal.unwrap_or(t.white)),
            ),
            e(4, view(m.emissive_texture)),
            e(5, wgpu::BindingResource::Sampler(t.sampler)),
            e(6, view(m.transmission_texture)),
        ],
    });
    GpuMaterialBinding {
        bind_group,
        double_sided: m.double_sided,
        alpha_masked: m.alpha_mode != AlphaMode::Opaque,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 4 normal map whose texels tilt by ±θ about x in a checkerboard, as 8-bit texels
    /// (not unit length once decoded).
    fn checker(theta: f32) -> Texture {
        let texels = (0..16)
            .map(|k| {
                let s = if (k % 4 + k / 4) % 2 == 0 { 1.0 } else { -1.0 };
                let n = Vec3::new(0.0, s * theta.sin(), theta.cos());
                let c = (n * 0.5 + Vec3::splat(0.5)) * 255.0;
                c.round().extend(255.0) / 255.0
            })
            .collect();
        Texture {
            name: "checker".into(),
            width: 4,
            height: 4,
            texels: lightlab_scene::Texels::Rgba32F(texels),
            srgb: false,
        }
    }

    #[test]
    fn normal_mips_hold_the_spread_of_the_finest_normals() {
        let theta = 0.4f32;
        let levels = normal_mip_chain(&checker(theta));
        assert_eq!(levels.len(), 3);
        let texel = |l: usize, i: usize| -> [f32; 4] {
            std::array::from_fn(|c| levels[l].2[4 * i + c].to_f32())
        };
        // The finest level: unit normals, no spread (8-bit rounding is not bumpiness).
        for i in 0..16 {
            let t = texel(0, i);
            let n = Vec3::new(t[0], t[1], t[2]) * 2.0 - Vec3::ONE;
            assert!((n.length() - 1.0).abs() < 2e-3, "{n}");
            assert_eq!(t[3], 0.0);
        }
        // Coarser levels: the mean is cos θ long (θ as the 8-bit texels have it), straight up;
        // σ² = (1 − r)/r.
        let t0 = texel(0, 0);
        let r = (Vec3::new(t0[0], t0[1], t0[2]) * 2.0 - Vec3::ONE)
            .normalize()
            .z;
        assert!((r - theta.cos()).abs() < 5e-3);
        for l in 1..3 {
            let t = texel(l, 0);
            let n = Vec3::new(t[0], t[1], t[2]) * 2.0 - Vec3::ONE;
            assert!((n - Vec3::Z * r).length() < 5e-3, "level {l}: {n}");
            assert!(
                ((t[3] - (1.0 - r) / r) / t[3]).abs() < 5e-3,
                "level {l}: {}",
                t[3]
            );
        }
    }
}
