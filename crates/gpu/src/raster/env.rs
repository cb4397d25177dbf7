//! The specular environment term (Heidrich 1999 ch. 8): the prefiltered maps of
//! `lightlab_core::envmap` on the GPU (`shaders/env.wgsl`, group 2 bindings 20–23), in the
//! parameterisation of `--env-map`, with the GGX split-sum table.
//!
//! Every lighting pass adds it to glossy and metallic surfaces (`base_radiance`), whatever the
//! ambient source: an environment seen in a mirror is not shadowed by anything (no occlusion;
//! the light-map and SH techniques keep their diffuse ambient and gain this term).

use super::bindings::{buffer, entry, filtered_texture, sampler};
use super::settings::{Ambient, EnvDiffuse, EnvMapKind, EnvPrefilter, RasterSettings};
use crate::GpuContext;
use bytemuck::{Pod, Zeroable};
use lightlab_core::envmap::{self, EnvMaps, EnvSettings, Lobe};
use lightlab_core::param::Param;
use lightlab_scene::{BrdfModel, Camera, Scene};
use wgpu::BindGroupLayoutEntry as LayoutEntry;
use wgpu::BindingResource as R;
use wgpu::TextureViewDimension as Dim;
use wgpu::util::DeviceExt;

/// The most roughness levels a map holds (the uniform's array).
pub const MAX_LEVELS: usize = 16;
/// Side of the split-sum table.
const LUT_SIZE: u32 = 32;

/// WGSL `EnvUniforms`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct EnvUniforms {
    /// World → map rotation, by rows.
    pub row0: [f32; 4],
    pub row1: [f32; 4],
    pub row2: [f32; 4],
    /// The constant environment's radiance (mode 4).
    pub constant: [f32; 4],
    /// The levels' roughness values, four per vector.
    pub roughness: [[f32; 4]; 4],
    /// 0 none, 1 dual paraboloid, 2 cube, 3 sphere map, 4 constant.
    pub mode: u32,
    pub levels: u32,
    pub phong_set: u32,
    pub ggx_set: u32,
    /// 0 auto (by material model), 1 Phong, 2 GGX.
    pub prefilter: u32,
    pub faces: u32,
    pub mips: f32,
    pub texel_angle: f32,
    /// Whether glossy surfaces reflect the maps (or the constant).
    pub specular: u32,
    /// The irradiance map's first layer; u32::MAX without one.
    pub irradiance_layer: u32,
    /// How many instances have dynamic maps (their layers follow the static ones, in the
    /// same layout; [`EnvInstance`] says where).
    pub dynamic_objects: u32,
    pub pad0: u32,
    pub pad1: u32,
    /// 1: glass refracts through one interface; 2: through two (the instance's bounding
    /// sphere).
    pub refraction: u32,
    pub pad2: u32,
    pub pad3: u32,
}

/// Per scene instance (WGSL `EnvInstance`, binding 24): its bounding sphere and its dynamic
/// maps' first colour layer, first inverse-distance layer and whether it has them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct EnvInstance {
    pub sphere: [f32; 4],
    pub dynamic: [u32; 4],
}

/// At most this many objects get dynamic maps (each costs six renders and a CPU prefilter).
pub const MAX_DYNAMIC_OBJECTS: usize = 4;

/// Group 2's entries of the term.
pub(super) fn layout_entries() -> Vec<LayoutEntry> {
    vec![
        filtered_texture(20, Dim::D2Array),
        sampler(21, wgpu::SamplerBindingType::Filtering),
        filtered_texture(22, Dim::D2),
        buffer(23, wgpu::BufferBindingType::Uniform, false),
        super::bindings::storage(24),
    ]
}

/// The term's GPU resources.
pub(super) struct EnvResources {
    maps: wgpu::TextureView,
    sampler: wgpu::Sampler,
    lut: wgpu::TextureView,
    uniforms: wgpu::Buffer,
    /// Per instance, its bounding sphere (centre, radius): glass's second interface.
    spheres: wgpu::Buffer,
    /// What the term reflects, for reports: None when it is off.
    pub summary: Option<String>,
}

/// Which lobes the scene's materials need under `prefilter`.
fn lobes(scene: &Scene, prefilter: EnvPrefilter) -> Vec<Lobe> {
    let glossy = |m: &&lightlab_scene::Material| {
        m.brdf != BrdfModel::Lambert && (m.metallic > 0.0 || m.specular > 0.0)
    };
    let mats: Vec<_> = scene.materials.iter().filter(glossy).collect();
    match prefilter {
        EnvPrefilter::Phong => vec![Lobe::Phong],
        EnvPrefilter::Ggx => vec![Lobe::Ggx],
        EnvPrefilter::Auto => {
            let mut l = vec![];
            if mats.iter().any(|m| m.brdf == BrdfModel::Pbr) {
                l.push(Lobe::Ggx);
            }
            if mats.iter().any(|m| m.brdf != BrdfModel::Pbr) {
                l.push(Lobe::Phong);
            }
            l
        }
    }
}

/// The levels' roughness values: those the materials use (a Blinn-Phong material's Phong
/// equivalent, a quarter of its exponent, too), and a ladder where a texture varies them.
fn roughness_levels(scene: &Scene) -> Vec<f32> {
    let mut used = vec![];
    let mut ladder = false;
    for m in &scene.materials {
        used.push(m.roughness);
        if m.brdf == BrdfModel::BlinnPhong {
            let e = envmap::phong_exponent(m.roughness) / 4.0;
            used.push(envmap::roughness_of_exponent(e));
        }
        ladder |= m.metallic_roughness_texture.is_some();
    }
    envmap::level_roughness(&used, ladder, MAX_LEVELS)
}

fn param_of(kind: EnvMapKind) -> Option<(Param, u32)> {
    match kind {
        EnvMapKind::DualParaboloid => Some((Param::DualParaboloid, 1)),
        EnvMapKind::Cube => Some((Param::Cube, 2)),
        EnvMapKind::Sphere => Some((Param::SphereMap, 3)),
        EnvMapKind::None => None,
    }
}

/// The prefiltered maps of the scene's environment for `s`, or None when neither the specular
/// term nor the irradiance map needs them (a constant ambient needs no map). `sun`: the sun the
/// renderer took out of the environment as a light (`--env-sun`), which the irradiance map
/// leaves out as the SH coefficients do.
pub fn prefiltered(
    scene: &Scene,
    s: &RasterSettings,
    camera: &Camera,
    sun: Option<&lightlab_core::sh_env::EnvSun>,
) -> Option<EnvMaps> {
    let env = scene.environment.as_ref()?;
    if s.ambient != Ambient::Environment {
        return None;
    }
    let settings = env_settings(scene, s, camera)?;
    // The specular levels keep the sun; the irradiance map holds the sky without it.
    let Some(sun) = sun.filter(|_| settings.irradiance) else {
        return Some(envmap::prefilter(&env.image, env.intensity, &settings));
    };
    let mut maps = envmap::prefilter(
        &env.image,
        env.intensity,
        &EnvSettings {
            irradiance: false,
            ..settings.clone()
        },
    );
    let irradiance = envmap::prefilter(
        &sun.remainder,
        env.intensity,
        &EnvSettings {
            lobes: vec![],
            ..settings
        },
    );
    maps.layers.extend(irradiance.layers);
    maps.irradiance = true;
    Some(maps)
}

/// The maps' parameterisation, frame, size, levels and lobes for `s`; None when nothing needs
/// them.
fn env_settings(scene: &Scene, s: &RasterSettings, camera: &Camera) -> Option<EnvSettings> {
    let irradiance = s.env_diffuse == EnvDiffuse::Map;
    let lobes = match s.env_map {
        EnvMapKind::None => vec![],
        _ => lobes(scene, s.env_prefilter),
    };
    if lobes.is_empty() && !irradiance {
        return None;
    }
    let (param, _) = param_of(s.env_map).unwrap_or((Param::DualParaboloid, 1));
    let frame = match param {
        // Made for the camera's viewing direction: view space, viewer on +z.
        Param::SphereMap => glam::Mat3::from_mat4(camera.transform).transpose(),
        _ => envmap::WORLD_TO_MAP,
    };
    let settings = EnvSettings {
        param,
        frame,
        size: EnvSettings::equal_memory_size(param, s.env_texels),
        roughness: roughness_levels(scene),
        lobes,
        samples: 128,
        irradiance,
    };
    Some(settings)
}

impl EnvResources {
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        s: &RasterSettings,
        camera: &Camera,
        enabled: bool,
        sun: Option<&lightlab_core::sh_env::EnvSun>,
    ) -> EnvResources {
        let mut maps = if enabled {
            prefiltered(scene, s, camera, sun)
        } else {
            None
        };
        // Dynamic maps in a scene without an environment: beside black static maps.
        if maps.is_none() && enabled && s.dynamic_env && !matches!(s.ambient, Ambient::Constant(_))
        {
            maps = env_settings(scene, s, camera).map(|e| EnvMaps::black(&e));
        }
        let mut u = EnvUniforms::zeroed();
        // The irradiance map ends the static layers (the dynamic ones follow them).
        u.irradiance_layer = maps
            .as_ref()
            .filter(|m| m.irradiance)
            .map_or(u32::MAX, |m| (m.layers.len() - m.faces()) as u32);
        let mut instances: Vec<EnvInstance> = (0..scene.instances.len().max(1))
            .map(|i| EnvInstance {
                sphere: bounding_sphere(scene, i),
                dynamic: [0; 4],
            })
            .collect();
        if let (Some(m), true) = (maps.as_mut(), s.dynamic_env) {
            for i in dynamic_instances(scene) {
                match dynamic(ctx, scene, s, i, m) {
                    Ok(d) => {
                        let colour = m.layers.len() as u32;
                        m.layers.extend(d.layers);
                        instances[i].dynamic = [colour, m.layers.len() as u32, 1, 0];
                        m.layers.extend(d.distance);
                        u.dynamic_objects += 1;
                    }
                    Err(e) => eprintln!("warning: no dynamic environment map: {e}"),
                }
            }
        }
        if let Some(m) = &maps {
            for (i, r) in m.roughness.iter().enumerate() {
                u.roughness[i / 4][i % 4] = *r;
            }
            let rows = m.frame.transpose();
            [u.row0, u.row1, u.row2] =
                [rows.x_axis, rows.y_axis, rows.z_axis].map(|r| r.extend(0.0).to_array());
            u.mode = param_of(s.env_map).map_or(1, |p| p.1);
            u.specular = u32::from(!m.lobes.is_empty());
            u.levels = m.roughness.len() as u32;
            u.phong_set = m.lobes.iter().position(|l| *l == Lobe::Phong).unwrap_or(0) as u32;
            u.ggx_set = m.lobes.iter().position(|l| *l == Lobe::Ggx).unwrap_or(0) as u32;
            u.faces = m.faces() as u32;
            u.mips = m.layers[0].len() as f32;
            u.texel_angle = m.texel_angle;
        } else if let (true, Ambient::Constant(c), Some(_)) =
            (enabled, s.ambient, param_of(s.env_map))
        {
            u.mode = 4;
            u.specular = 1;
            u.constant = c.extend(1.0).to_array();
        }
        u.refraction = match s.refraction {
            super::Refraction::One => 1,
            super::Refraction::Two => 2,
        };
        u.prefilter = match s.env_prefilter {
            EnvPrefilter::Auto => 0,
            EnvPrefilter::Phong => 1,
            EnvPrefilter::Ggx => 2,
        };
        let device = &ctx.device;
        let summary = match (&maps, u.mode) {
            (Some(m), _) => Some(format!(
                "{:?} environment map, {} face(s) of {}², roughness levels {:?}, lobes {:?}, \
                 irradiance map {}, {:.1} MB",
                m.param,
                m.faces(),
                m.size,
                m.roughness,
                m.lobes,
                m.irradiance,
                m.bytes() as f64 / 1e6
            )),
            (None, 4) => Some("constant environment".into()),
            _ => None,
        };
        let maps = upload_maps(ctx, maps.as_ref());
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("environment"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("environment uniforms"),
            contents: bytemuck::bytes_of(&u),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let spheres = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("environment instances"),
            contents: bytemuck::cast_slice(&instances),
            usage: wgpu::BufferUsages::STORAGE,
        });
        EnvResources {
            maps,
            spheres,
            sampler,
            lut: upload_lut(ctx),
            uniforms,
            summary,
        }
    }

    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        vec![
            entry(20, R::TextureView(&self.maps)),
            entry(21, R::Sampler(&self.sampler)),
            entry(22, R::TextureView(&self.lut)),
            entry(23, self.uniforms.as_entire_binding()),
            entry(24, self.spheres.as_entire_binding()),
        ]
    }
}

/// Instance `i`'s bounding sphere: the centre of its bounds and the farthest vertex from it
/// (a ball's own sphere); zeros for an empty or missing instance.
fn bounding_sphere(scene: &Scene, i: usize) -> [f32; 4] {
    let Some((lo, hi)) = (i < scene.instances.len())
        .then(|| scene.instance_bounds(i))
        .flatten()
    else {
        return [0.0; 4];
    };
    let c = (lo + hi) * 0.5;
    let inst = &scene.instances[i];
    let r = scene.meshes[inst.mesh]
        .positions
        .iter()
        .map(|p| inst.transform.transform_point3(*p).distance(c))
        .fold(0.0f32, f32::max);
    [c.x, c.y, c.z, r]
}

/// The instances whose surroundings matter most in their reflections, most first: the
/// mirror-like ones (metallic or glass, roughness under 0.3), smoothest metals first; at most
/// [`MAX_DYNAMIC_OBJECTS`].
pub fn dynamic_instances(scene: &Scene) -> Vec<usize> {
    let score = |i: usize| {
        let m = &scene.materials[scene.meshes[scene.instances[i].mesh].material];
        // Metal mirrors first: glass shows more of what is behind it than what is around it.
        let mirror = m.metallic.max(0.9 * m.specular_transmission);
        (mirror >= 0.5 && m.roughness < 0.3).then_some(m.roughness - mirror)
    };
    let mut found: Vec<(usize, f32)> = (0..scene.instances.len())
        .filter_map(|i| score(i).map(|s| (i, s)))
        .collect();
    found.sort_by(|a, b| a.1.total_cmp(&b.1));
    found
        .into_iter()
        .take(MAX_DYNAMIC_OBJECTS)
        .map(|(i, _)| i)
        .collect()
}

/// Face size of the dynamic cube renders.
const DYNAMIC_FACE: u32 = 128;

/// The dynamic maps of one object, centred on its bounding sphere's centre: colour layers (the
/// static maps' layout) and inverse-distance layers (mirror level, in every channel).
pub struct DynamicMaps {
    pub layers: Vec<Vec<Vec<glam::Vec3>>>,
    pub distance: Vec<Vec<Vec<glam::Vec3>>>,
}

/// Dynamic environment maps (issue 20): the scene around instance `i` rendered from its
/// centre into the six faces of a cube (wgpu has no geometry shaders, so six passes of the
/// whole renderer, one camera each, with shadow volumes, which hold for any camera), resampled
/// into a lat-long image and prefiltered like the static maps (`maps`' layout); the layers to
/// append. The faces' distances (from the deferred path's positions) go into a distance map,
/// with which the shader corrects the parallax of a map projected from the centre (distance
/// impostors, Szirmay-Kalos et al. 2005).
pub fn dynamic(
    ctx: &GpuContext,
    scene: &Scene,
    s: &RasterSettings,
    i: usize,
    maps: &EnvMaps,
) -> Result<DynamicMaps, super::RasterError> {
    use glam::Vec3;
    let (lo, hi) = scene
        .instance_bounds(i)
        .ok_or_else(|| super::RasterError::Settings("the dynamic object is empty".into()))?;
    let centre = (lo + hi) * 0.5;
    // Seen from its centre, a closed single-sided object shows only back faces, which the
    // rasteriser culls: it stays, invisible, and still casts its shadow on its neighbours. A
    // double-sided one would hide everything, so it goes.
    let mut sub = scene.clone();
    if scene.materials[scene.meshes[scene.instances[i].mesh].material].double_sided {
        sub.instances.remove(i);
    }
    let axes = [
        (Vec3::X, Vec3::Y),
        (-Vec3::X, Vec3::Y),
        (Vec3::Y, Vec3::Z),
        (-Vec3::Y, Vec3::Z),
        (Vec3::Z, Vec3::Y),
        (-Vec3::Z, Vec3::Y),
    ];
    let cameras: Vec<Camera> = axes
        .iter()
        .map(|&(f, up)| {
            let mut c = Camera::look_at("cube face", centre, centre + f, up, 90f32.to_radians());
            c.znear = 1e-3 * (hi - lo).length().max(1e-3);
            c
        })
        .collect();
    sub.cameras = cameras.clone();
    let face_settings = RasterSettings {
        width: DYNAMIC_FACE,
        height: DYNAMIC_FACE,
        camera: 0,
        shadows: super::ShadowMethod::VolumesZFail,
        path: super::RenderPath::Deferred,
        dynamic_env: false,
        ..s.clone()
    };
    let mut r = super::Renderer::new(ctx, &sub, face_settings)?;
    let mut faces = vec![];
    let mut depths = vec![];
    for cam in &cameras {
        r.set_camera(ctx, cam.clone());
        r.render(ctx);
        faces.push(r.read_hdr(ctx)?);
        // Camera-relative positions, w = 0 where nothing was drawn (the sky: infinitely far).
        // The map holds inverse distances: filtering across an edge between a near object and
        // the sky then blends to a finite distance near the object's, where blended distances
        // put the edge's texels halfway to infinity (a bright band of sky reflected at the
        // floor's far edge, a stepped outline at the box's).
        let g = r.read_gbuffer(ctx)?;
        depths.push(
            g[3].iter()
                .map(|p| {
                    if p[3] > 0.0 {
                        1.0 / Vec3::new(p[0], p[1], p[2]).length().max(1e-4)
                    } else {
                        0.0
                    }
                })
                .collect::<Vec<f32>>(),
        );
    }
    // Lat-long resampling: each direction from the face whose axis it is closest to.
    let (w, h) = (4 * DYNAMIC_FACE, 2 * DYNAMIC_FACE);
    let mut latlong = lightlab_core::image::Image::new(w, h);
    let mut distance = lightlab_core::image::Image::new(w, h);
    let t = (45f32.to_radians()).tan();
    for y in 0..h {
        for x in 0..w {
            let uv = glam::Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let d = lightlab_scene::Environment::uv_to_dir(uv);
            let k = (0..6)
                .max_by(|&a, &b| d.dot(axes[a].0).total_cmp(&d.dot(axes[b].0)))
                .unwrap_or(0);
            let v = cameras[k].transform.inverse().transform_vector3(d);
            let ndc = glam::Vec2::new(v.x, v.y) / (-v.z * t);
            let px =
                ((ndc.x + 1.0) * 0.5 * DYNAMIC_FACE as f32).clamp(0.0, DYNAMIC_FACE as f32 - 1.0);
            let py =
                ((1.0 - ndc.y) * 0.5 * DYNAMIC_FACE as f32).clamp(0.0, DYNAMIC_FACE as f32 - 1.0);
            let at = (py as u32 * DYNAMIC_FACE + px as u32) as usize;
            latlong.data[(y * w + x) as usize] = faces[k].data[at];
            distance.data[(y * w + x) as usize] = Vec3::splat(depths[k][at]);
        }
    }
    let settings = EnvSettings {
        param: maps.param,
        frame: maps.frame,
        size: maps.size,
        roughness: maps.roughness.clone(),
        lobes: maps.lobes.clone(),
        samples: 128,
        irradiance: false,
    };
    let distances = EnvSettings {
        roughness: vec![0.0],
        lobes: vec![Lobe::Ggx],
        ..settings.clone()
    };
    Ok(DynamicMaps {
        layers: envmap::prefilter(&latlong, 1.0, &settings).layers,
        distance: envmap::prefilter(&distance, 1.0, &distances).layers,
    })
}

/// The maps as one mip-mapped RGBA16F array (a 1×1 pair of layers without maps). Radiance is
/// clamped to 65,000, under the format's largest value.
fn upload_maps(ctx: &GpuContext, maps: Option<&EnvMaps>) -> wgpu::TextureView {
    let (size, layers, mips) = match maps {
        Some(m) => (m.size, m.layers.len() as u32, m.layers[0].len() as u32),
        None => (1, 2, 1),
    };
    // At least two layers: GL makes a one-layer texture a plain 2D texture.
    let tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("environment maps"),
        size: wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: layers.max(2),
        },
        mip_level_count: mips,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    if let Some(m) = maps {
        for (layer, chain) in m.layers.iter().enumerate() {
            for (mip, texels) in chain.iter().enumerate() {
                let n = (m.size >> mip).max(1);
                let data: Vec<half::f16> = texels
                    .iter()
                    .flat_map(|c| {
                        let c = c.clamp(glam::Vec3::ZERO, glam::Vec3::splat(65000.0));
                        [c.x, c.y, c.z, 1.0].map(half::f16::from_f32)
                    })
                    .collect();
                crate::resources::write_mip(
                    ctx,
                    &tex,
                    layer as u32,
                    mip as u32,
                    bytemuck::cast_slice(&data),
                    n * 8,
                    [n, n],
                );
            }
        }
    }
    tex.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(Dim::D2Array),
        ..Default::default()
    })
}

/// The split-sum table (A, B in red and green), computed once per process.
fn upload_lut(ctx: &GpuContext) -> wgpu::TextureView {
    static LUT: std::sync::LazyLock<Vec<[f32; 2]>> =
        std::sync::LazyLock::new(|| envmap::split_sum_lut(LUT_SIZE, 512));
    let data: Vec<half::f16> = LUT
        .iter()
        .flat_map(|[a, b]| [*a, *b, 0.0, 1.0].map(half::f16::from_f32))
        .collect();
    let tex = crate::resources::texture(
        &ctx.device,
        "split-sum table",
        LUT_SIZE,
        LUT_SIZE,
        1,
        wgpu::TextureFormat::Rgba16Float,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    crate::resources::write_layer(
        ctx,
        &tex,
        0,
        bytemuck::cast_slice(&data),
        LUT_SIZE * 8,
        [LUT_SIZE, LUT_SIZE],
    );
    tex.create_view(&Default::default())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::check_struct;
    use crate::rust_layout;

    /// `spheres`: the chrome mirror, the polished silver and the clear glass get dynamic maps
    /// (smoothest metals first); the rough gold and the plastics do not.
    #[test]
    fn the_mirror_like_objects_get_dynamic_maps() {
        let scene = lightlab_scene::builtin::builtin("spheres").unwrap();
        let names: Vec<&str> = dynamic_instances(&scene)
            .into_iter()
            .map(|i| {
                scene.materials[scene.meshes[scene.instances[i].mesh].material]
                    .name
                    .as_str()
            })
            .collect();
        assert_eq!(names, ["chrome_mirror", "silver_polished", "glass_clear"]);
        let check = crate::raster::shader_source(crate::raster::SourceKind::Sky);
        let layout = rust_layout!(EnvInstance, sphere, dynamic);
        check_struct(check, "EnvInstance", &layout).unwrap_or_else(|e| panic!("{e}"));
    }

    #[test]
    fn env_uniforms_match_the_wgsl_layout() {
        let src = crate::raster::shader_source(crate::raster::SourceKind::Sky);
        let layout = rust_layout!(
            EnvUniforms,
            row0,
            row1,
            row2,
            constant,
            roughness,
            mode,
            levels,
            phong_set,
            ggx_set,
            prefilter,
            faces,
            mips,
            texel_angle,
            specular,
            irradiance_layer,
            dynamic_objects,
            pad0,
            pad1,
            refraction,
            pad2,
            pad3
        );
        check_struct(src, "EnvUniforms", &layout).unwrap_or_else(|e| panic!("{e}"));
    }
}
