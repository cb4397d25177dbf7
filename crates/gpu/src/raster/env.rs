//! The specular environment term (Heidrich 1999 ch. 8): the prefiltered maps of
//! `lightlab_core::envmap` on the GPU (`shaders/env.wgsl`, group 2 bindings 20, 21, 23–25; 25 the extras: the split-sum table, the planar mirrors'
//! views and the object light field), in the
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
    /// The scene's own punctual lights (the first lights; the ones after them are derived:
    /// area lights, the environment's sun, a canned light). A radiance field's object takes
    /// only the scene's own lights per frame.
    pub scene_lights: u32,
    /// The object light field's first layer in the extras array (after the mirrors').
    pub field_layer: u32,
    /// The object light field's box (`ObjectField::min`, `max`) and (instance + 1 or 0,
    /// n_uv, n_st, kind: 0 geometry, 1 radiance).
    pub field_min: [f32; 4],
    pub field_max: [f32; 4],
    pub field: [u32; 4],
}

/// Per scene instance (WGSL `EnvInstance`, binding 24): its bounding sphere and its dynamic
/// maps' first colour layer, first inverse-distance layer and whether it has them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct EnvInstance {
    pub sphere: [f32; 4],
    pub dynamic: [u32; 4],
}

/// Group 2's entries of the term.
pub(super) fn layout_entries() -> Vec<LayoutEntry> {
    vec![
        filtered_texture(20, Dim::D2Array),
        sampler(21, wgpu::SamplerBindingType::Filtering),
        buffer(23, wgpu::BufferBindingType::Uniform, false),
        super::bindings::storage(24),
        filtered_texture(25, Dim::D2Array),
    ]
}

/// The term's GPU resources.
pub(super) struct EnvResources {
    maps: wgpu::TextureView,
    /// The dynamic maps' updater (`--dynamic-env`).
    pub dynamic: Option<super::env_dynamic::DynamicEnv>,
    sampler: wgpu::Sampler,
    uniforms: wgpu::Buffer,
    /// Per instance, its bounding sphere (centre, radius): glass's second interface.
    spheres: wgpu::Buffer,
    /// What the term reflects, for reports: None when it is off.
    pub summary: Option<String>,
    /// The planar mirrors' reflected views (layer k: mirror k, `raster::mirror`), then the
    /// object light field's six slabs (`extra_texture`).
    pub extra: wgpu::Texture,
    extra_view: wgpu::TextureView,
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
            if mats.iter().any(|m| m.brdf.microfacet()) {
                l.push(Lobe::Ggx);
            }
            if mats.iter().any(|m| !m.brdf.microfacet()) {
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
        mirrors: &[super::mirror::PlanarMirror],
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
        // Dynamic maps: their layers follow the static ones, written on the GPU.
        let objects = dynamic_layers(scene, s, maps.as_ref());
        let extra = maps.as_ref().map_or(0, |m| {
            objects.len() as u32 * super::env_dynamic::layers_per_object(m)
        });
        fill_uniforms(&mut u, maps.as_ref(), s, enabled);
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
        let (tex, view) = upload_maps(ctx, maps.as_ref(), extra);
        let dynamic = maps
            .as_ref()
            .filter(|_| !objects.is_empty())
            .and_then(|m| dynamic_maps(ctx, scene, s, m, &tex, &objects));
        if let (Some(_), Some(m)) = (&dynamic, &maps) {
            let colour = super::env_dynamic::layers_per_object(m) - m.faces() as u32;
            for &(i, base) in &objects {
                instances[i].dynamic = [base, base + colour, 1, 0];
            }
            u.dynamic_objects = objects.len() as u32;
        }
        // Planar mirror k's fragments read layer k + 1 of the extras (w = k + 1).
        for (k, m) in mirrors.iter().enumerate() {
            instances[m.instance].dynamic[3] = k as u32 + 1;
        }
        let (extra, extra_view) = extra_texture(
            ctx,
            (s.width, s.height),
            mirrors.len(),
            s.object_field.as_ref(),
            &mut u,
        );
        u.scene_lights = scene.lights.len() as u32;
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
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        });
        EnvResources {
            maps: view,
            dynamic,
            spheres,
            sampler,
            uniforms,
            summary,
            extra,
            extra_view,
        }
    }

    /// Instance `i` of `scene` has moved: its bounding sphere (glass's second interface, the
    /// dynamic maps' centre) and the dynamic maps' renderer follow.
    pub fn moved(&mut self, ctx: &GpuContext, scene: &Scene, i: usize) {
        ctx.queue.write_buffer(
            &self.spheres,
            (i * std::mem::size_of::<EnvInstance>()) as u64,
            bytemuck::bytes_of(&bounding_sphere(scene, i)),
        );
        if let Some(d) = &mut self.dynamic {
            d.moved(ctx, scene, i);
        }
    }

    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        vec![
            entry(20, R::TextureView(&self.maps)),
            entry(21, R::Sampler(&self.sampler)),
            entry(23, self.uniforms.as_entire_binding()),
            entry(24, self.spheres.as_entire_binding()),
            entry(25, R::TextureView(&self.extra_view)),
        ]
    }
}

/// One `Rgba16Float` array for the term's smaller images (one binding: GL allows 16 sampled
/// textures per stage, and the deferred pass is at that limit): layer 0 the split-sum table
/// (`LUT_SIZE`² in its top-left corner), then the planar mirrors' reflected views (`mirrors`
/// layers of `size`, written each frame), then the object light field's six slabs, each an
/// atlas of (u,v) tiles of (s,t) texels as `ObjectField::write` lays it out, in the top-left
/// corner of its layer. The field's box, counts and first layer go into `u`. Layers share the
/// largest size (a field beside mirrors pads to the frame).
fn extra_texture(
    ctx: &GpuContext,
    size: (u32, u32),
    mirrors: usize,
    field: Option<&super::FieldObject>,
    u: &mut EnvUniforms,
) -> (wgpu::Texture, wgpu::TextureView) {
    let side = field.map_or(0, |g| (g.field.n_uv * g.field.n_st) as u32);
    let (mut w, mut h) = if mirrors > 0 { size } else { (1, 1) };
    w = w.max(side).max(LUT_SIZE);
    h = h.max(side).max(LUT_SIZE);
    let layers = 1 + mirrors as u32 + if field.is_some() { 6 } else { 0 };
    let tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("environment extras"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            // Two at least: a one-layer texture may not be viewed as an array everywhere.
            depth_or_array_layers: layers.max(2),
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: super::targets::HDR,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    crate::resources::write_layer(
        ctx,
        &tex,
        0,
        bytemuck::cast_slice(lut_texels()),
        LUT_SIZE * 8,
        [LUT_SIZE, LUT_SIZE],
    );
    if let Some(g) = field {
        let f = &g.field;
        u.field_min = f.min.extend(0.0).to_array();
        u.field_max = f.max.extend(0.0).to_array();
        let kind = match f.kind {
            lightlab_core::object_field::FieldKind::Geometry => 0,
            lightlab_core::object_field::FieldKind::Radiance => 1,
        };
        u.field = [g.instance as u32 + 1, f.n_uv as u32, f.n_st as u32, kind];
        u.field_layer = 1 + mirrors as u32;
        let mut texels = vec![half::f16::ZERO; (side * side * 4) as usize];
        for slab in 0..6 {
            for (k, px) in texels.chunks_exact_mut(4).enumerate() {
                let (x, y) = (k % side as usize, k / side as usize);
                let (iu, is) = (x / f.n_st, x % f.n_st);
                let (iv, it) = (y / f.n_st, y % f.n_st);
                let v = f.data[f.index(slab, [iu, iv, is, it])];
                for c in 0..4 {
                    px[c] = half::f16::from_f32(v[c]);
                }
            }
            crate::resources::write_layer(
                ctx,
                &tex,
                1 + mirrors as u32 + slab as u32,
                bytemuck::cast_slice(&texels),
                side * 8,
                [side, side],
            );
        }
    }
    let view = tex.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (tex, view)
}

/// The instances with dynamic maps (`--dynamic-env`) and each one's first layer, after the
/// static ones.
fn dynamic_layers(scene: &Scene, s: &RasterSettings, maps: Option<&EnvMaps>) -> Vec<(usize, u32)> {
    let Some(m) = maps.filter(|_| s.dynamic_env) else {
        return vec![];
    };
    let per = super::env_dynamic::layers_per_object(m);
    super::env_dynamic::dynamic_instances(scene)
        .into_iter()
        .enumerate()
        .map(|(k, i)| (i, m.layers.len() as u32 + k as u32 * per))
        .collect()
}

/// The dynamic maps' updater for `objects` (their first update made), or None with a warning
/// when it cannot be made.
fn dynamic_maps(
    ctx: &GpuContext,
    scene: &Scene,
    s: &RasterSettings,
    m: &EnvMaps,
    tex: &wgpu::Texture,
    objects: &[(usize, u32)],
) -> Option<super::env_dynamic::DynamicEnv> {
    let settings = EnvSettings {
        param: m.param,
        frame: m.frame,
        size: m.size,
        roughness: m.roughness.clone(),
        lobes: m.lobes.clone(),
        samples: 128,
        irradiance: false,
    };
    super::env_dynamic::DynamicEnv::new(ctx, scene, s, &settings, tex, objects)
        .inspect_err(|e| eprintln!("warning: no dynamic environment maps: {e}"))
        .ok()
}

/// The term's uniforms from the maps (or the constant ambient) and `s`.
fn fill_uniforms(u: &mut EnvUniforms, maps: Option<&EnvMaps>, s: &RasterSettings, enabled: bool) {
    if let Some(m) = maps {
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
    } else if let (true, Ambient::Constant(c), Some(_)) = (enabled, s.ambient, param_of(s.env_map))
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

/// The maps as one mip-mapped RGBA16F array (a 1×1 pair of layers without maps), with `extra`
/// layers after them that compute passes write (the dynamic maps'). Radiance is clamped to
/// 65,000, under the format's largest value.
fn upload_maps(
    ctx: &GpuContext,
    maps: Option<&EnvMaps>,
    extra: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    let (size, layers, mips) = match maps {
        Some(m) => (
            m.size,
            m.layers.len() as u32 + extra,
            m.layers[0].len() as u32,
        ),
        None => (1, 2, 1),
    };
    let storage = if extra > 0 {
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC
    } else {
        wgpu::TextureUsages::empty()
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
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST | storage,
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
    let view = tex.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(Dim::D2Array),
        ..Default::default()
    });
    (tex, view)
}

/// The split-sum table (A, B in red and green), computed once per process.
/// The split-sum table's texels (`LUT_SIZE`², RGBA: A, B, 0, 1), for layer 0 of the extras.
fn lut_texels() -> &'static [half::f16] {
    static LUT: std::sync::LazyLock<Vec<half::f16>> = std::sync::LazyLock::new(|| {
        envmap::split_sum_lut(LUT_SIZE, 512)
            .iter()
            .flat_map(|[a, b]| [*a, *b, 0.0, 1.0].map(half::f16::from_f32))
            .collect()
    });
    &LUT
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
        let names: Vec<&str> = super::super::env_dynamic::dynamic_instances(&scene)
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
            scene_lights,
            field_layer,
            field_min,
            field_max,
            field
        );
        check_struct(src, "EnvUniforms", &layout).unwrap_or_else(|e| panic!("{e}"));
    }
}
