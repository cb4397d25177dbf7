//! Building a [`Renderer`]: checked settings, the camera, the light-map page layout, the
//! lights and their shadow views, uniforms, pipelines, targets and bind groups.

use super::ambient::{AmbientSource, LightmapInput, environment_sun, page_layout, sh_irradiance};
use super::bindings::{GroupLayouts, PipelineLayouts, entry};
use super::light_set::LightSet;
use super::pipelines::Pipelines;
use super::settings::{
    Ambient, NormalFilter, RasterError, RasterSettings, ShadowMethod, projection,
};
use super::targets::{
    ShadowArrays, ShadowMaps, Targets, env_texture, gbuffer_formats, renderable_or,
};
use super::{Renderer, SLOT, shader_source};
use crate::GpuContext;
use crate::gpu_scene::GpuScene;
use crate::lpv::{Lpv, LpvSettings};
use crate::prt::ShInput;
use crate::uniforms::{FrameUniforms, PassUniforms, ShadowView};
use bytemuck::Zeroable;
use glam::Mat4;
use lightlab_scene::{Camera, Scene};
use wgpu::BindingResource as R;
use wgpu::util::DeviceExt;

/// What the ambient term reads besides the environment's SH irradiance (at most one).
#[derive(Clone, Copy)]
pub(super) enum AmbientInput<'a> {
    None,
    Lightmap(&'a LightmapInput<'a>),
    Sh(&'a ShInput<'a>),
    /// The volume's settings, and whether to render its indirect light alone.
    Lpv(&'a LpvSettings, bool),
    /// The shading normals, unlit.
    Normals,
}

impl<'a> AmbientInput<'a> {
    fn lightmap(self) -> Option<&'a LightmapInput<'a>> {
        match self {
            AmbientInput::Lightmap(l) => Some(l),
            _ => None,
        }
    }
    fn sh(self) -> Option<&'a ShInput<'a>> {
        match self {
            AmbientInput::Sh(s) => Some(s),
            _ => None,
        }
    }
}

/// The frame's buffers: uniforms, lights, shadow views (then planar projections) and the
/// per-pass slots (light i → slot i; shadow view v → lights + v).
struct FrameBuffers {
    frame: wgpu::Buffer,
    lights: wgpu::Buffer,
    views: wgpu::Buffer,
    passes: wgpu::Buffer,
    /// The goniometric lights' candela tables.
    profiles: wgpu::TextureView,
    /// A canned light's (s,t) slices and their sampler.
    slab: wgpu::TextureView,
    slab_sampler: wgpu::Sampler,
    /// Heidrich's lookup tables of the materials (`brdf_tables`).
    brdf_tables: wgpu::TextureView,
}

impl FrameBuffers {
    fn new(
        ctx: &crate::GpuContext,
        frame: &FrameUniforms,
        ls: &LightSet,
        (scene, s): (&Scene, &RasterSettings),
    ) -> FrameBuffers {
        let device = &ctx.device;
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let mut all_views: Vec<ShadowView> = if ls.views.is_empty() {
            vec![ShadowView::zeroed()]
        } else {
            ls.views.iter().map(|v| v.gpu()).collect()
        };
        let planar_base = all_views.len();
        for p in &ls.planar {
            all_views.push(ShadowView {
                view_proj: p.unwrap_or(Mat4::ZERO).to_cols_array_2d(),
                ..ShadowView::zeroed()
            });
        }
        let n = ls.lights.len();
        let mut slots = vec![0u8; (n + ls.views.len()).max(1) * SLOT as usize];
        let mut put = |slot: usize, light: usize, view: usize| {
            let p = PassUniforms {
                light_index: light as u32,
                shadow_view: view as u32,
                ..Default::default()
            };
            slots[slot * SLOT as usize..][..16].copy_from_slice(bytemuck::bytes_of(&p));
        };
        for i in 0..n {
            put(i, i, planar_base + i);
        }
        for (v, &li) in ls.view_light.iter().enumerate() {
            put(n + v, li, v);
        }
        let storage = wgpu::BufferUsages::STORAGE;
        let (slab, slab_sampler) = crate::canned::slab_texture(ctx, &s.light_field);
        FrameBuffers {
            frame: init(
                "frame",
                bytemuck::bytes_of(frame),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            lights: init("lights", bytemuck::cast_slice(&ls.lights), storage),
            views: init("shadow views", bytemuck::cast_slice(&all_views), storage),
            passes: init("pass slots", &slots, wgpu::BufferUsages::UNIFORM),
            profiles: crate::photometric::profile_texture(
                ctx,
                &ls.profiles.iter().map(|p| &**p).collect::<Vec<_>>(),
            ),
            slab,
            slab_sampler,
            brdf_tables: crate::brdf_tables::texture(ctx, scene, s.brdf_eval),
        }
    }
}

/// Sampled textures the LPV techniques' fragment stage binds (materials, shadow maps,
/// environment maps and their extras (mirrors, light field), the volume's three, the sky
/// occlusion's depth maps, the RSM's positions for `lpv-faithful`'s composite).
const LPV_SAMPLED_TEXTURES: u32 = 19;

/// The `sky` and `lpv` sources' occlusion: the sky's diffuse light (without the sun taken out of it, or
/// a constant ambient's uniform sky) over `s.sky_occlusion` shadow-mapped directions.
fn sky_occlusion(
    ctx: &GpuContext,
    scene: &Scene,
    s: &RasterSettings,
    gscene: &GpuScene,
    sun: Option<&lightlab_core::sh_env::EnvSun>,
) -> super::ambient::SkyOcclusion {
    let env = sky_radiance(scene, s, sun);
    let env = env.as_ref().map(|(img, k)| (img.as_ref(), *k));
    super::ambient::SkyOcclusion::new(ctx, gscene, env, s.sky_occlusion)
}

/// The sky's diffuse light as a lat-long image and its scale: the environment without the sun
/// taken out of it, or a constant ambient's uniform sky; None without ambient light.
fn sky_radiance<'a>(
    scene: &'a Scene,
    s: &RasterSettings,
    sun: Option<&'a lightlab_core::sh_env::EnvSun>,
) -> Option<(std::borrow::Cow<'a, lightlab_core::image::Image>, f32)> {
    use std::borrow::Cow;
    match s.ambient {
        Ambient::None => None,
        Ambient::Constant(c) => Some((
            Cow::Owned(lightlab_core::image::Image::from_fn(64, 32, |_, _| c)),
            1.0,
        )),
        Ambient::Environment => scene.environment.as_ref().map(|e| {
            (
                Cow::Borrowed(sun.map_or(&e.image, |s| &s.remainder)),
                e.intensity,
            )
        }),
    }
}

/// The frame uniforms: camera, shadow settings and the sky's SH irradiance.
fn frame_uniforms(
    scene: &Scene,
    s: &RasterSettings,
    camera: &Camera,
    lights: usize,
    sun: Option<&lightlab_core::sh_env::EnvSun>,
) -> FrameUniforms {
    let aspect = s.width as f32 / s.height as f32;
    let view = camera.transform.inverse();
    let view_proj = projection(camera, aspect) * view;
    FrameUniforms {
        view_proj: view_proj.to_cols_array_2d(),
        inv_view_proj: view_proj.inverse().to_cols_array_2d(),
        view: view.to_cols_array_2d(),
        camera_pos: camera.position().to_array(),
        exposure: s.exposure,
        wind_a: s.wind.uniform()[0],
        wind_b: s.wind.uniform()[1],
        viewport: [s.width as f32, s.height as f32],
        light_count: lights as u32,
        shadow_mode: match s.shadows {
            ShadowMethod::Map => 1,
            ShadowMethod::MapLinear => 2,
            _ => 0,
        },
        ambient_sh: sh_irradiance(scene, s.ambient, sun),
        pcf_radius: s.pcf_radius,
        normal_offset: s.normal_offset,
        linear_bias: s.linear_bias,
        shadow_size: s.shadow_size as f32,
        clip_plane: [0.0; 4],
        brdf_tables: u32::from(s.brdf_eval != crate::brdf_tables::BrdfEval::Analytic),
        normal_filter: match s.normal_filter {
            NormalFilter::Box => 0,
            NormalFilter::Variance => 1,
            NormalFilter::None => 2,
            NormalFilter::Lit => 3,
            NormalFilter::Rook => 4,
        },
        _pad1: 0,
        _pad2: 0,
    }
}

/// The bind groups of the lighting passes and of the full-screen passes.
struct Groups {
    frame: wgpu::BindGroup,
    lighting: wgpu::BindGroup,
    gbuffer: wgpu::BindGroup,
    tonemap: wgpu::BindGroup,
}

/// Group 2: the shadow maps, then the ambient source's resources.
fn lighting_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    shadow: &ShadowArrays,
    ambient: &AmbientSource,
    env: &super::env::EnvResources,
) -> wgpu::BindGroup {
    let cmp = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("shadow compare"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        compare: Some(wgpu::CompareFunction::LessEqual),
        ..Default::default()
    });
    let mut entries = vec![
        entry(0, R::TextureView(&shadow.depth)),
        entry(1, R::Sampler(&cmp)),
        entry(2, R::TextureView(&shadow.linear)),
    ];
    entries.extend(ambient.entries());
    entries.extend(env.entries());
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("lighting"),
        layout,
        entries: &entries,
    })
}

fn groups(
    device: &wgpu::Device,
    layouts: &GroupLayouts,
    buffers: &FrameBuffers,
    targets: &Targets,
    lighting: wgpu::BindGroup,
) -> Groups {
    let group = |label, layout, entries: &[wgpu::BindGroupEntry]| {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries,
        })
    };
    let pass_slot = R::Buffer(wgpu::BufferBinding {
        buffer: &buffers.passes,
        offset: 0,
        size: wgpu::BufferSize::new(16),
    });
    let g = &targets.gbuffer;
    Groups {
        frame: group(
            "frame",
            &layouts.frame,
            &[
                entry(0, buffers.frame.as_entire_binding()),
                entry(1, buffers.lights.as_entire_binding()),
                entry(2, buffers.views.as_entire_binding()),
                entry(3, pass_slot),
                entry(16, R::TextureView(&buffers.profiles)),
                entry(17, R::TextureView(&buffers.slab)),
                entry(18, R::Sampler(&buffers.slab_sampler)),
                entry(19, R::TextureView(&buffers.brdf_tables)),
            ],
        ),
        lighting,
        gbuffer: group(
            "g-buffer",
            &layouts.gbuffer,
            &[
                entry(0, R::TextureView(&g[0])),
                entry(1, R::TextureView(&g[1])),
                entry(2, R::TextureView(&g[2])),
                entry(3, R::TextureView(&g[3])),
                entry(4, R::TextureView(&g[4])),
            ],
        ),
        tonemap: group(
            "tonemap",
            &layouts.tonemap,
            &[entry(4, R::TextureView(&targets.hdr_view))],
        ),
    }
}

/// Timestamp queries for every pass of a frame: the set, its resolve and read buffers.
pub(super) fn queries(
    ctx: &GpuContext,
    passes: usize,
) -> Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)> {
    let device = &ctx.device;
    ctx.has_timestamps().then(|| {
        let count = 2 * passes as u32;
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: count as u64 * 8,
                usage,
                mapped_at_creation: false,
            })
        };
        let resolve = buffer(
            "timestamp resolve",
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        );
        let read = buffer(
            "timestamp read",
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        (set, resolve, read)
    })
}

/// Whether a renderer with this ambient input draws the specular environment term (not the
/// debug and indirect-only views).
fn env_on(ambient: AmbientInput) -> bool {
    !matches!(ambient, AmbientInput::Normals | AmbientInput::Lpv(_, true))
}

impl Renderer {
    /// A renderer, and for each planar mirror of the scene (`settings.planar_mirrors`) the
    /// renderer of its reflected view (`raster::mirror`).
    pub(super) fn build(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        ambient: AmbientInput,
    ) -> Result<Renderer, RasterError> {
        let found = if settings.planar_mirrors && env_on(ambient) {
            super::mirror::find(scene)
        } else {
            vec![]
        };
        let mut r = Self::build_one(ctx, scene, settings.clone(), ambient, &found, false)?;
        for f in found {
            let child_settings = RasterSettings {
                planar_mirrors: false,
                ..settings.clone()
            };
            let mut child = Self::build_one(ctx, scene, child_settings, ambient, &[], true)?;
            child.hidden = Some(f.instance);
            r.mirrors.push(super::mirror::Mirror {
                found: f,
                child: Box::new(child),
                active: false,
            });
        }
        if !r.mirrors.is_empty() {
            r.set_camera(ctx, r.camera.clone());
        }
        Ok(r)
    }

    /// One renderer: `mirrors` are the planar mirrors whose reflected views its environment
    /// term reads; `mirrored` draws a reflected view (clockwise front faces).
    fn build_one(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        ambient: AmbientInput,
        mirrors: &[super::mirror::PlanarMirror],
        mirrored: bool,
    ) -> Result<Renderer, RasterError> {
        let s = &settings;
        let camera = checked_camera(ctx, scene, s, ambient)?;
        let device = &ctx.device;
        let (page_size, rects) = page_layout(ambient.lightmap(), ambient.sh());
        let gscene = GpuScene::with_lightmap_uvs(device, &ctx.queue, scene, rects.as_deref());
        let sun = (s.env_sun && matches!(ambient, AmbientInput::None | AmbientInput::Lpv(..)))
            .then(|| environment_sun(scene, s.ambient))
            .flatten();
        let inputs = SourceInputs {
            gscene: &gscene,
            sun: sun.as_ref(),
            camera: &camera,
            page_size,
        };
        let source = ambient_source(ctx, scene, s, ambient, &inputs)?;
        // A light-map holds the emitters' light already; SH transfer is lit by its SH light only.
        let area_lights =
            s.area_lights && matches!(ambient, AmbientInput::None | AmbientInput::Lpv(..));
        let ls = LightSet::new(
            scene,
            s,
            &camera,
            gscene.bounds,
            area_lights,
            sun.as_ref().map(|(l, _)| l),
        );
        let frame = frame_uniforms(
            scene,
            s,
            &camera,
            ls.light_pos.len(),
            sun.as_ref().map(|(_, e)| e),
        );
        let buffers = FrameBuffers::new(ctx, &frame, &ls, (scene, s));
        let kind = source.kind();
        let layouts = GroupLayouts::new(device, &kind.layout_entries());
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster"),
            source: wgpu::ShaderSource::Wgsl(shader_source(kind).into()),
        });
        let linear_format = renderable_or(
            ctx,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureFormat::R16Float,
        );
        let pipelines = Pipelines::new(
            device,
            &module,
            s,
            &PipelineLayouts::new(device, &layouts),
            gbuffer_formats(ctx),
            linear_format,
            mirrored,
        );
        let targets = Targets::new(ctx, s);
        let (shadow, arrays) = ShadowMaps::new(ctx, s, ls.views.len(), linear_format);
        // The specular environment term, except on the debug and indirect-only views.
        let env = super::env::EnvResources::new(
            ctx,
            scene,
            s,
            &camera,
            env_on(ambient),
            sun.as_ref().map(|(_, e)| e),
            mirrors,
        );
        let lighting = lighting_group(device, &layouts.lighting, &arrays, &source, &env);
        let g = groups(device, &layouts, &buffers, &targets, lighting);
        let sky_group = background_group(ctx, scene, s, &layouts);
        let prepasses = source.prepass_count();
        let queries = queries(ctx, 5 + 2 * ls.lights.len() + ls.views.len() + prepasses);
        Ok(Renderer {
            env_summary: env.summary.clone(),
            settings,
            scene: gscene,
            camera,
            lights: ls.lights,
            light_pos: ls.light_pos,
            light_radius: ls.light_radius,
            views: ls.views,
            view_light: ls.view_light,
            planar: ls.planar,
            plane: ls.plane,
            pipelines,
            targets,
            shadow,
            frame_buf: buffers.frame,
            _pass_buf: buffers.passes,
            group0: g.frame,
            group2: g.lighting,
            group3: g.gbuffer,
            tonemap_group: g.tonemap,
            sky_group,
            volume_buf: None,
            volume_ranges: vec![],
            queries,
            frame,
            ambient: source,
            env,
            hidden: None,
            moved: false,
            lens: None,
            mirrors: vec![],
            clip_rect: None,
        })
    }
}

/// The settings and the ambient input checked against the scene and the adapter; the camera
/// the renderer looks through (the scene's `s.camera`, or a framing one when it has none).
fn checked_camera(
    ctx: &GpuContext,
    scene: &Scene,
    s: &RasterSettings,
    ambient: AmbientInput,
) -> Result<Camera, RasterError> {
    if let AmbientInput::Lightmap(lm) = ambient
        && !super::ambient::lightmap_fits(lm, scene)
    {
        return Err(RasterError::Settings(
            "light-maps do not match the scene (one rect per instance, non-empty pages)".into(),
        ));
    }
    if let AmbientInput::Sh(sh) = ambient {
        sh.validate(scene)?;
    }
    s.validate()?;
    let max = ctx.device.limits().max_texture_dimension_2d;
    if s.width.max(s.height) > max || s.shadow_size > max {
        return Err(RasterError::Settings(format!(
            "a {}×{} frame (after supersampling) with {}² shadow maps exceeds the adapter's \
             largest texture, {max}²: lower --width/--height, --ssaa or --shadow-size",
            s.width, s.height, s.shadow_size
        )));
    }
    scene
        .cameras
        .get(s.camera)
        .cloned()
        .or_else(|| (s.camera == 0).then(|| scene.framing_camera()).flatten())
        .ok_or(RasterError::NoCamera(s.camera))
}

/// What the ambient sources read besides the settings: the scene on the GPU, the sun taken out
/// of the environment, the camera and the light-map or SH pages' size.
struct SourceInputs<'a> {
    gscene: &'a GpuScene,
    sun: Option<&'a (lightlab_scene::Light, lightlab_core::sh_env::EnvSun)>,
    camera: &'a Camera,
    page_size: [u32; 2],
}

/// The ambient term's source: the occluded sky, the debug normals, a light-map, SH transfer or a
/// light propagation volume (with the sky's occlusion beside it).
fn ambient_source(
    ctx: &GpuContext,
    scene: &Scene,
    s: &RasterSettings,
    ambient: AmbientInput,
    inputs: &SourceInputs,
) -> Result<AmbientSource, RasterError> {
    let SourceInputs {
        gscene,
        sun,
        camera,
        page_size,
    } = *inputs;
    Ok(match ambient {
        AmbientInput::None => AmbientSource::Sky(Box::new(sky_occlusion(
            ctx,
            scene,
            s,
            gscene,
            sun.map(|(_, e)| e),
        ))),
        AmbientInput::Normals => AmbientSource::Normals,
        AmbientInput::Lightmap(lm) => AmbientSource::lightmap(ctx, lm, page_size),
        AmbientInput::Sh(sh) => AmbientSource::sh(ctx, sh, scene.instances.len(), page_size),
        AmbientInput::Lpv(l, indirect_only) => {
            // The volume's three textures beside the sky occlusion's depth maps.
            let have = ctx.device.limits().max_sampled_textures_per_shader_stage;
            if have < LPV_SAMPLED_TEXTURES {
                return Err(RasterError::Settings(format!(
                    "the LPV techniques read {LPV_SAMPLED_TEXTURES} textures in one shader \
                     stage; this adapter ({}) allows {have}",
                    ctx.info.name
                )));
            }
            let aspect = s.width as f32 / s.height as f32;
            let sun_light = sun.map(|(l, _)| l);
            let sky_lights = sky_radiance(scene, s, sun.map(|(_, e)| e))
                .map_or(vec![], |(img, k)| {
                    super::ambient::sky_lights(&img, k, l.sky_lights)
                });
            let env = crate::lpv::EnvLights {
                sun: sun_light,
                sky: &sky_lights,
            };
            let v = Lpv::new(ctx, scene, env, l.clone(), camera, aspect, &s.wind)?;
            let sky = sky_occlusion(ctx, scene, s, gscene, sun.map(|(_, e)| e));
            AmbientSource::lpv(ctx, v, sky, indirect_only)
        }
    })
}

/// The environment drawn as the background (with `s.background` and an environment).
fn background_group(
    ctx: &GpuContext,
    scene: &Scene,
    s: &RasterSettings,
    layouts: &GroupLayouts,
) -> Option<wgpu::BindGroup> {
    scene
        .environment
        .as_ref()
        .filter(|_| s.background)
        .map(|env| {
            let view = env_texture(ctx, env);
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sky"),
                layout: &layouts.sky,
                entries: &[entry(5, R::TextureView(&view))],
            })
        })
}
