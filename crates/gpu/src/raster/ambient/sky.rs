//! Occluded sky light for the Phong techniques (issue 22): the environment's diffuse light is
//! split into cells around K directions (a spherical Fibonacci set moved towards the sky's light
//! by Lloyd's relaxation, [`importance_directions`]; each environment texel goes to its nearest
//! direction), each cell kept as one small source (its E⊥ and mean direction, [`SkyDir`]), and
//! each direction gets an orthographic depth map of the scene seen from it. A surface point's sky
//! light is then Σ_k V_k(p)·E_k(n), V_k read from map k with a small PCF kernel, applied as the
//! ratio Σ V_k E_k / Σ E_k to the unshadowed term (SH or irradiance map), so that an open sky
//! is unchanged.
//!
//! The maps are made with the renderer, and again in the frame after objects move
//! (`Renderer::move_instance`); they cost K depth passes. Many shadow-mapped directions rather
//! than screen-space occlusion: they see occluders off screen and behind the camera, and the
//! same code serves any camera (dynamic environment maps' cube faces included). The sun taken
//! out of the environment (`extract_sun`) is not in the cells: it is a light of its own.

use crate::GpuContext;
use crate::gpu_scene::{GpuScene, vertex_layout};
use bytemuck::{Pod, Zeroable};
use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_to_mat4;
use glam::{Mat4, Vec3};
use lightlab_core::image::Image;
use lightlab_core::sh_env::{EnvFormat, for_each_texel};
use wgpu::util::DeviceExt;

/// Directions by default (`--sky-occlusion`). Each cell's visibility is read along one
/// direction, all or nothing, so the sky through a window or a gallery's arcade falls as
/// overlapping hard polygons, one per cell; more cells make them smaller. `phong-shadow-maps`'
/// relMSE against the path tracer's direct light (2048 spp; 320 × 240, `--ssaa 2`) with 64 /
/// 128 / 256 directions: room 0.0032 / 0.0021 / 0.0016, atrium 0.0089 / 0.0068 / 0.0060; the frame on
/// lavapipe (atrium, 640 × 480 before the 2 × 2 downsample) 1114 / 1432 / 1819 ms against
/// 950 ms without occlusion. 128 is the first count at which `phong-shadow-maps` reaches
/// `direct`'s error against the reference on room and the atrium (issue 22; docs/phong-and-shadows.md).
pub const DEFAULT_DIRECTIONS: u32 = 128;
/// At most this many directions: each is a layer of one depth texture array, and WebGPU's
/// default limit on array layers is 256.
pub const MAX_DIRECTIONS: u32 = 256;
/// Lloyd steps that move the directions towards the sky's light, and the share of the mean
/// luminance every texel counts with besides its own ([`importance_directions`]). Measured on
/// the sky's error against `direct` (320 × 240, `--ssaa 2`): room 0.0044 → 0.0042, atrium 0.0142
/// → 0.0138, bush 0.0109 → 0.0107 against uniform directions; a floor of 0.02 or 0.5 within 2 %
/// of 0.1.
const LLOYD_STEPS: usize = 8;
const DARK_FLOOR: f64 = 0.1;
/// Side of each direction's depth map. The maps span the scene's bounding sphere, and a point
/// sees past occluders within about a texel of it (sky_occlusion.wgsl's bias and offset): in
/// the bush's canopy, leaves a few centimetres apart under texels of 5.5 cm (256², over the
/// 10 m ground) took 1.35 times the path tracer's sky light; 512² brings it to 1.17 (1024²:
/// 1.09, with a constant bias). `phong-shadow-maps` against `direct` on bush (2048 spp, 320 ×
/// 240, `--ssaa 2`): relMSE 0.0039 at 256², 0.0034 at 512²; the depth and ambient pass on
/// lavapipe (640 × 480) about 6 % slower on bush and on the atrium.
const MAP_SIZE: u32 = 512;
/// 16 bits of depth over the maps' 3 radii: 1/65536 of them is under a thirtieth of the
/// smallest bias (a tenth of a texel, 2/512 radii); 64 MiB for 128 directions.
const SKY_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth16Unorm;

/// Per direction (WGSL `SkyDir`, 64 bytes): the x, y and z rows of its orthographic
/// view-projection (an affine map: the fourth row is (0, 0, 0, 1)), and its cell's
/// E⊥ = Σ L·ΔΩ (RGB) with the cell's solid angle (w). The unit direction towards the sky (the
/// cell's flux-weighted mean direction) is −z row × the depth range (the projection's depth is
/// the distance along it over 3 radii). A surface's weight for the cell is E⊥·⟨n, dir⟩₊ per
/// channel, the cell's irradiance as one small source.
///
/// The directions are a uniform buffer, not a storage buffer: they are read by every fragment
/// in the same order, and on lavapipe the sky term of `phong-shadow-maps` on room (640 × 480,
/// 128 directions) took 515 ms from storage and 313 ms from a uniform buffer. 64 bytes × 256
/// fill WebGPU's 16 KiB default limit on a uniform binding exactly; the header (count, texel,
/// radius) is a binding of its own.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct SkyDir {
    pub rows: [[f32; 4]; 3],
    pub cell: [f32; 4],
}

/// Rec. 709 luminance: the weight that places the directions.
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// The occlusion's resources (group 2, bindings 8–10 and 12 of the `sky` and `lpv` sources).
pub struct SkyOcclusion {
    depth: wgpu::TextureView,
    sampler: wgpu::Sampler,
    data: wgpu::Buffer,
    header: wgpu::Buffer,
    texture: wgpu::Texture,
    /// Each direction's view-projection, to render its depth map.
    view_projs: Vec<Mat4>,
}

/// `n` unit directions spread evenly over the sphere (spherical Fibonacci points).
pub fn fibonacci_directions(n: u32) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), y, r * phi.sin())
        })
        .collect()
}

/// The index of the direction of `dirs` nearest to `d` (0 when there are none).
fn nearest(dirs: &[Vec3], d: Vec3) -> usize {
    (0..dirs.len())
        .max_by(|&a, &b| dirs[a].dot(d).total_cmp(&dirs[b].dot(d)))
        .unwrap_or(0)
}

/// `n` directions placed by the light of `env` (lat-long, × `scale`): spherical Fibonacci
/// points moved by `iterations` steps of Lloyd's relaxation on the sphere, each texel weighted
/// by its luminance·ΔΩ plus `floor` × the mean luminance·ΔΩ (so that dark parts of the sphere
/// keep some directions). Weighted Lloyd places points with a density ∝ √weight: bright parts
/// of the sky get smaller cells.
pub fn importance_directions(
    env: &Image,
    scale: f32,
    n: u32,
    iterations: usize,
    floor: f64,
) -> Vec<Vec3> {
    let mut dirs = fibonacci_directions(n);
    // (direction, luminance·ΔΩ, ΔΩ), then (direction, weight).
    let mut texels = vec![];
    for_each_texel(env, EnvFormat::LatLong, |d, omega, v| {
        let w = omega * v.dot(LUMINANCE).max(0.0) as f64 * scale as f64;
        texels.push((d.as_vec3(), w, omega));
    });
    let total_w: f64 = texels.iter().map(|t| t.1).sum();
    let total_o: f64 = texels.iter().map(|t| t.2).sum();
    if dirs.is_empty() || texels.is_empty() || total_w <= 0.0 {
        return dirs;
    }
    let dark = floor * total_w / total_o;
    let texels: Vec<(Vec3, f64)> = texels
        .into_iter()
        .map(|(d, w, omega)| (d, w + dark * omega))
        .collect();
    for _ in 0..iterations {
        let mut sum = vec![glam::DVec3::ZERO; dirs.len()];
        for &(d, w) in &texels {
            sum[nearest(&dirs, d)] += d.as_dvec3() * w;
        }
        for (d, s) in dirs.iter_mut().zip(&sum) {
            if let Some(m) = s.as_vec3().try_normalize() {
                *d = m;
            }
        }
    }
    dirs
}

/// Each direction's cell of `env` (lat-long, × `scale`; each texel goes to its nearest
/// direction): the cell's flux-weighted mean direction (its own direction when the cell is
/// dark) and E⊥ = Σ L·ΔΩ, the irradiance it gives a surface facing it (RGB). The E⊥ of all
/// cells sum to the environment's ∫ L dω.
pub fn sky_cells(env: &Image, scale: f32, dirs: &[Vec3]) -> Vec<(Vec3, Vec3)> {
    let mut flux = vec![glam::DVec3::ZERO; dirs.len()];
    let mut mean = vec![glam::DVec3::ZERO; dirs.len()];
    if dirs.is_empty() {
        return vec![];
    }
    for_each_texel(env, EnvFormat::LatLong, |d, omega, v| {
        let k = nearest(dirs, d.as_vec3());
        let e = v.as_dvec3() * (omega * scale as f64);
        flux[k] += e;
        mean[k] += d * (e.x + e.y + e.z);
    });
    flux.iter()
        .zip(&mean)
        .zip(dirs)
        .map(|((f, m), d)| (m.as_vec3().try_normalize().unwrap_or(*d), f.as_vec3()))
        .collect()
}

/// The solid angle of each direction's cell (each texel of the lat-long `env` to its nearest
/// direction); they sum to 4π.
pub fn cell_solid_angles(env: &Image, dirs: &[Vec3]) -> Vec<f32> {
    let mut omega = vec![0.0f64; dirs.len()];
    if !dirs.is_empty() {
        for_each_texel(env, EnvFormat::LatLong, |d, o, _| {
            omega[nearest(dirs, d.as_vec3())] += o
        });
    }
    omega.into_iter().map(|o| o as f32).collect()
}

/// The environment (lat-long, × `scale`) as up to `n` directional lights, for the LPV's
/// injection of sky light (issue 22): the sphere split into the cells of `n` spherical Fibonacci
/// directions (each texel to its nearest), each cell a light from its flux-weighted mean
/// direction whose irradiance on a surface facing it is the cell's radiance integrated over its
/// solid angle (E⊥ = Σ L·ΔΩ, RGB). Returned as (unit direction towards the sky, E⊥); cells
/// without light are left out. Their E⊥ sum to the environment's ∫ L dω.
pub fn sky_lights(env: &Image, scale: f32, n: u32) -> Vec<(Vec3, Vec3)> {
    sky_cells(env, scale, &fibonacci_directions(n))
        .into_iter()
        .filter(|(_, e)| e.max_element() > 0.0)
        .collect()
}

/// An orthographic view-projection looking along −`dir` at a sphere (centre, radius), depth
/// 0..1 over the sphere's extent.
fn view_proj(dir: Vec3, centre: Vec3, radius: f32) -> Mat4 {
    let eye = centre + dir * (2.0 * radius);
    let up = if dir.y.abs() > 0.9 { Vec3::X } else { Vec3::Y };
    // Depths 0.5–3.5 radii from the eye (the sphere spans 1–3).
    directx::orthographic(-radius, radius, -radius, radius, radius * 0.5, radius * 3.5)
        * look_to_mat4(eye, -dir, up)
}

impl SkyOcclusion {
    /// Occlusion for `env` (× `scale`) over `gscene` with `directions` directions; with 0 (or
    /// no environment) a dummy that binds but occludes nothing.
    pub fn new(
        ctx: &GpuContext,
        gscene: &GpuScene,
        env: Option<(&Image, f32)>,
        directions: u32,
    ) -> SkyOcclusion {
        let (lo, hi) = gscene.bounds;
        let directions = if env.is_some() && hi.cmpge(lo).all() {
            directions
        } else {
            0
        };
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3) * 1.01;
        let dirs = match env {
            Some((img, s)) => importance_directions(img, s, directions, LLOYD_STEPS, DARK_FLOOR),
            None => vec![],
        };
        let cells = env.map_or(vec![], |(img, s)| sky_cells(img, s, &dirs));
        let omega = env.map_or(vec![], |(img, _)| cell_solid_angles(img, &dirs));
        // Seen along the cell's mean direction, the one its weight is computed for.
        let view_projs: Vec<Mat4> = cells
            .iter()
            .map(|cell| view_proj(cell.0, centre, radius))
            .collect();
        let data: Vec<SkyDir> = omega
            .iter()
            .zip(&cells)
            .zip(&view_projs)
            .map(|((&omega, cell), m)| SkyDir {
                rows: [
                    m.row(0).to_array(),
                    m.row(1).to_array(),
                    m.row(2).to_array(),
                ],
                cell: cell.1.extend(omega).to_array(),
            })
            .collect();
        let device = &ctx.device;
        let layers = directions.max(1);
        let size = if directions == 0 { 1 } else { MAP_SIZE };
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("sky occlusion"),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SKY_DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        render_maps(ctx, gscene, &texture, &view_projs);
        let header = [directions as f32, 2.0 * radius / size as f32, radius, 0.0];
        // The shader's array holds MAX_DIRECTIONS: a uniform binding has a fixed size.
        let mut bytes = bytemuck::cast_slice(&data).to_vec();
        bytes.resize(MAX_DIRECTIONS as usize * std::mem::size_of::<SkyDir>(), 0);
        SkyOcclusion {
            depth: texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            }),
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("sky occlusion"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            }),
            data: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sky occlusion directions"),
                contents: &bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            header: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sky occlusion header"),
                contents: bytemuck::bytes_of(&header),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            texture,
            view_projs,
        }
    }

    /// Render the depth maps again (objects have moved; the directions' frusta keep the
    /// bounds the occlusion was made with).
    /// The number of shadow-mapped sky directions (0: a dummy that occludes nothing).
    pub fn directions(&self) -> usize {
        self.view_projs.len()
    }

    pub fn rerender(&self, ctx: &GpuContext, gscene: &GpuScene) {
        render_maps(ctx, gscene, &self.texture, &self.view_projs);
    }

    /// Group 2's entries 8–10 and 12 (`sky_occlusion.wgsl`).
    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        use super::super::bindings::entry;
        use wgpu::BindingResource as R;
        vec![
            entry(8, R::TextureView(&self.depth)),
            entry(9, R::Sampler(&self.sampler)),
            entry(10, self.data.as_entire_binding()),
            entry(12, self.header.as_entire_binding()),
        ]
    }
}

/// Group 2's layout entries 8–10 and 12 of the `sky` and `lpv` sources.
pub fn layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    use super::super::bindings::{buffer, sampler, texture};
    vec![
        texture(
            8,
            wgpu::TextureSampleType::Depth,
            wgpu::TextureViewDimension::D2Array,
        ),
        sampler(9, wgpu::SamplerBindingType::Comparison),
        buffer(10, wgpu::BufferBindingType::Uniform, false),
        buffer(12, wgpu::BufferBindingType::Uniform, false),
    ]
}

const DEPTH_WGSL: &str = "
@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
@vertex
fn vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {
    return view_proj * vec4<f32>(p, 1.0);
}
";

/// One depth pass per direction into layer k (every draw, as opaque, both faces).
fn render_maps(ctx: &GpuContext, gscene: &GpuScene, texture: &wgpu::Texture, view_projs: &[Mat4]) {
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("sky occlusion depth"),
        source: wgpu::ShaderSource::Wgsl(DEPTH_WGSL.into()),
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("sky occlusion depth"),
        entries: &[super::super::bindings::buffer(
            0,
            wgpu::BufferBindingType::Uniform,
            false,
        )],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("sky occlusion depth"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("sky occlusion depth"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(vertex_layout())],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: SKY_DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    for (k, m) in view_projs.iter().enumerate() {
        let ubuf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sky occlusion view"),
            contents: bytemuck::cast_slice(&m.to_cols_array()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sky occlusion view"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: ubuf.as_entire_binding(),
            }],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: k as u32,
            array_layer_count: Some(1),
            ..Default::default()
        });
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sky occlusion depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.set_vertex_buffer(0, gscene.vertices.slice(..));
        pass.set_index_buffer(gscene.indices.slice(..), wgpu::IndexFormat::Uint32);
        for dr in &gscene.draws {
            pass.draw_indexed(dr.first_index..dr.first_index + dr.index_count, 0, 0..1);
        }
    }
    ctx.queue.submit([enc.finish()]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells partition the environment: their E⊥ sum to its ∫ L dω (a sky with a bright
    /// lobe), and as small sources they give a surface of any orientation the sky's irradiance:
    /// Σ E⊥_k ⟨n, ω_k⟩₊ = πL for a uniform sky within 3 % with 64 cells, and the lobe's
    /// irradiance along its axis within 3 %.
    #[test]
    fn cells_sum_to_the_environment() {
        let lobe = Vec3::new(0.3, 0.8, 0.5).normalize();
        let radiance =
            |d: Vec3| Vec3::new(0.3, 0.4, 0.6) + Vec3::splat(5.0 * d.dot(lobe).max(0.0).powi(8));
        let img = Image::from_fn(256, 128, |x, y| {
            radiance(lightlab_core::sh_env::latlong_uv_to_dir(glam::Vec2::new(
                (x as f32 + 0.5) / 256.0,
                (y as f32 + 0.5) / 128.0,
            )))
        });
        let dirs = fibonacci_directions(64);
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-5));
        let cells = sky_cells(&img, 1.0, &dirs);
        let mut whole = glam::DVec3::ZERO;
        for_each_texel(&img, EnvFormat::LatLong, |_, omega, v| {
            whole += v.as_dvec3() * omega
        });
        let sum: Vec3 = cells.iter().map(|c| c.1).sum();
        assert!(
            (sum - whole.as_vec3()).length() < 1e-3 * sum.length(),
            "{sum} vs {whole}"
        );
        let irradiance = |cells: &[(Vec3, Vec3)], n: Vec3| -> Vec3 {
            cells.iter().map(|(d, e)| *e * n.dot(*d).max(0.0)).sum()
        };
        // Along the lobe's axis, against the exact integral over the texels.
        let mut exact = glam::DVec3::ZERO;
        for_each_texel(&img, EnvFormat::LatLong, |d, omega, v| {
            exact += v.as_dvec3() * omega * d.as_vec3().dot(lobe).max(0.0) as f64
        });
        let got = irradiance(&cells, lobe);
        assert!(
            (got - exact.as_vec3()).abs().max_element() < 0.03 * exact.x as f32,
            "{got} vs {exact}"
        );
        let flat = Image::from_fn(128, 64, |_, _| Vec3::ONE);
        let cells = sky_cells(&flat, 1.0, &dirs);
        // The cells' solid angles sum to 4π, about 4π/64 each for evenly spread directions.
        let omega = cell_solid_angles(&flat, &dirs);
        let four_pi = 4.0 * std::f32::consts::PI;
        assert!((omega.iter().sum::<f32>() - four_pi).abs() < 1e-3);
        assert!(
            omega
                .iter()
                .all(|o| (o - four_pi / 64.0).abs() < 0.25 * four_pi / 64.0)
        );
        assert!(cell_solid_angles(&flat, &[]).is_empty());
        for n in fibonacci_directions(40) {
            let e = irradiance(&cells, n).x;
            assert!(
                (e - std::f32::consts::PI).abs() < 0.03 * std::f32::consts::PI,
                "{n}: {e}"
            );
        }
        assert!(sky_cells(&flat, 1.0, &[]).is_empty());
        // As lights: E⊥ sums to ∫ L dω (4π for a uniform unit sky), each cell about 4π/16,
        // each direction near its own cell's.
        let lights = sky_lights(&flat, 2.0, 16);
        assert_eq!(lights.len(), 16);
        let total: Vec3 = lights.iter().map(|l| l.1).sum();
        assert!(
            (total.x - 8.0 * std::f32::consts::PI).abs() < 1e-3 * total.x,
            "{total}"
        );
        for ((d, e), f) in lights.iter().zip(fibonacci_directions(16)) {
            assert!(
                (d.length() - 1.0).abs() < 1e-4 && d.dot(f) > 0.9,
                "{d} vs {f}"
            );
            assert!((e.x - total.x / 16.0).abs() < 0.2 * total.x / 16.0);
        }
        // A sky lit only above the horizon has no cells below it.
        let upper = Image::from_fn(128, 64, |_, y| Vec3::splat((y < 32) as u8 as f32));
        let lights = sky_lights(&upper, 1.0, 16);
        assert!(!lights.is_empty() && lights.len() < 16);
        assert!(lights.iter().all(|(d, _)| d.y > 0.0));
        assert!(sky_lights(&flat, 1.0, 0).is_empty());
    }

    /// Lloyd's relaxation by the sky's light: unit directions, more of them where the sky is
    /// bright (a sky 30× brighter above the horizon gets √30 ≈ 5.5 times the density there,
    /// about 44 of 64 above, against 32 uniformly), and a uniform sky's irradiance still
    /// within 3 % of πL for any normal; no directions for none asked, uniform ones for a black
    /// sky.
    #[test]
    fn directions_follow_the_sky_light() {
        let sky = Image::from_fn(128, 64, |_, y| Vec3::splat(if y < 32 { 30.0 } else { 1.0 }));
        let dirs = importance_directions(&sky, 1.0, 64, LLOYD_STEPS, DARK_FLOOR);
        assert_eq!(dirs.len(), 64);
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-4));
        let above = dirs.iter().filter(|d| d.y > 0.0).count();
        assert!(
            (40..=56).contains(&above),
            "{above} of 64 above the horizon"
        );
        let flat = Image::from_fn(128, 64, |_, _| Vec3::ONE);
        let cells = sky_cells(&flat, 1.0, &importance_directions(&flat, 1.0, 64, 8, 0.1));
        for n in fibonacci_directions(40) {
            let e: f32 = cells.iter().map(|(d, e)| e.x * n.dot(*d).max(0.0)).sum();
            let pi = std::f32::consts::PI;
            assert!((e - pi).abs() < 0.03 * pi, "{n}: {e}");
        }
        assert!(importance_directions(&flat, 1.0, 0, 8, 0.1).is_empty());
        let black = Image::from_fn(16, 8, |_, _| Vec3::ZERO);
        assert_eq!(
            importance_directions(&black, 1.0, 16, 8, 0.1),
            fibonacci_directions(16)
        );
    }
}
