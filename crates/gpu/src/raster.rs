//! The rasterising renderer of the `phong*` techniques: forward or deferred Phong lighting after
//! Fuchs (2005) §4.1 with one additive pass per light (§4.4), and shadows by stencil shadow
//! volumes (z-fail or z-pass), shadow maps (depth comparison or Heidrich's linear depth, PCF,
//! slope-scaled and normal-offset bias, cascades) or projected planar shadows.
//!
//! Depth is reversed (1 near, 0 at infinity) with an infinite far plane, so shadow-volume
//! vertices at infinity (w = 0) land exactly on the far plane and are never clipped: z-fail
//! needs no depth clamping.
//!
//! Frame structure, each pass timed with GPU timestamps where the adapter has them:
//! 1. `shadow maps`: one depth pass per shadow view (map methods only);
//! 2. `depth+ambient` (forward) or `g-buffer` (deferred): depth, ambient and emission;
//! 3. per light: `volumes` (stencil cleared, volumes or planar projections drawn, scissored to
//!    the light) then `lighting` (additive, where the stencil is 0);
//! 4. `tonemap`: the displayed 8-bit frame.

use crate::gpu_scene::{GpuScene, UvRect, vertex_layout};
use crate::lights::{self, Attenuation, ShadowProjection};
use crate::shadow_volume::{LightPos, build_volume};
use crate::uniforms::*;
use crate::{GpuContext, GpuError};
use bytemuck::Zeroable;
use glam::camera::rh::proj::directx;
use glam::{Mat4, Vec3, Vec4};
use lightlab_core::image::Image;
use lightlab_scene::emitters::PlanarEmitter;
use lightlab_scene::{Camera, Light, LightKind, Scene};
use std::collections::BTreeMap;
use std::time::Instant;
use wgpu::util::DeviceExt;

/// WGSL of the renderer: common.wgsl, material.wgsl, raster.wgsl.
pub static SHADER_SOURCE: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!(
        "{}\n{}\n{}",
        crate::uniforms::COMMON_WGSL,
        crate::uniforms::MATERIAL_WGSL,
        include_str!("shaders/raster.wgsl")
    )
});

const HDR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;
const SHADOW_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const MASK: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// G-buffer formats: diffuse + dielectric F0, normal + roughness, F0 + model, and the
/// camera-relative position (32-bit float where renderable, else 16-bit: GLES).
fn gbuffer_formats(ctx: &GpuContext) -> [wgpu::TextureFormat; 4] {
    let f16 = wgpu::TextureFormat::Rgba16Float;
    [
        f16,
        f16,
        f16,
        renderable_or(ctx, wgpu::TextureFormat::Rgba32Float, f16),
    ]
}

/// `want` if the adapter can render to it, else `fallback`.
fn renderable_or(
    ctx: &GpuContext,
    want: wgpu::TextureFormat,
    fallback: wgpu::TextureFormat,
) -> wgpu::TextureFormat {
    let f = ctx.adapter.get_texture_format_features(want);
    if f.allowed_usages
        .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
    {
        want
    } else {
        fallback
    }
}

const SLOT: u64 = 256;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderPath {
    Forward,
    Deferred,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowMethod {
    None,
    /// Stencil shadow volumes, z-fail (Carmack's reverse) with capped volumes.
    VolumesZFail,
    /// Stencil shadow volumes, z-pass (wrong when the camera is inside a volume).
    VolumesZPass,
    /// Shadow maps with hardware depth comparison.
    Map,
    /// Shadow maps with Heidrich's (1999, ch. 6) linear-depth comparison.
    MapLinear,
    /// Projected planar shadows on one receiver plane (Heidrich 1999 §6.1).
    Planar,
}

impl ShadowMethod {
    fn stencil(self) -> bool {
        matches!(
            self,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass | ShadowMethod::Planar
        )
    }
    fn map(self) -> bool {
        matches!(self, ShadowMethod::Map | ShadowMethod::MapLinear)
    }
}

/// Baked light-maps for [`Renderer::with_lightmap`]: pages of E/π and, per scene instance, where
/// its TEXCOORD_1 lands (page coordinates `offset + uv1 · scale`).
pub struct LightmapInput<'a> {
    pub pages: &'a [Image],
    pub rects: &'a [Option<UvRect>],
    /// Cubic B-spline filtering (four bilinear taps) instead of bilinear.
    pub bicubic: bool,
    /// Directional light-maps: per page, the luminance ratios of the three basis directions
    /// (`lightlab_bake::gather`); normal-mapped surfaces then respond to the baked light.
    pub directional: Option<&'a [Image]>,
}

/// An Rgba16Float array texture of `layers` layers (at least two: GL decides a texture's target
/// at creation and makes a one-layer texture a plain 2D texture that cannot be bound as an
/// array), each filled by `fill(layer, texels)` from zero, and a clamping linear sampler.
fn upload_array(
    ctx: &GpuContext,
    size: [u32; 2],
    layers: u32,
    mut fill: impl FnMut(u32, &mut [half::f16]),
) -> (wgpu::TextureView, wgpu::Sampler) {
    let layers = layers.max(2);
    let tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("light-maps"),
        size: wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let mut data = vec![half::f16::ZERO; (size[0] * size[1] * 4) as usize];
    for layer in 0..layers {
        data.fill(half::f16::ZERO);
        fill(layer, &mut data);
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &tex,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&data),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(size[0] * 8),
                rows_per_image: Some(size[1]),
            },
            wgpu::Extent3d {
                width: size[0],
                height: size[1],
                depth_or_array_layers: 1,
            },
        );
    }
    let view = tex.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("light-map"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    (view, sampler)
}

/// Light-map pages (E/π, then the directional ratios at layer pages + k) or textured SH
/// transfer (layer page·layers + j) in one array; a black array when there are none.
fn upload_lightmaps(
    ctx: &GpuContext,
    lightmap: Option<&LightmapInput>,
    sh: Option<&crate::prt::ShInput>,
    size: [u32; 2],
) -> (wgpu::TextureView, wgpu::Sampler) {
    let put = |data: &mut [half::f16], w: u32, h: u32, f: &dyn Fn(u32, u32) -> [f32; 4]| {
        for y in 0..h {
            for x in 0..w {
                let v = f(x, y);
                let o = ((y * size[0] + x) * 4) as usize;
                for c in 0..4 {
                    data[o + c] = half::f16::from_f32(v[c].clamp(-65000.0, 65000.0));
                }
            }
        }
    };
    if let Some(crate::prt::ShInput {
        bands,
        transfer: crate::prt::ShTransfer::Textured { pages },
        ..
    }) = sh
    {
        let l = crate::prt::layers(*bands);
        let layers = (pages.len() * l) as u32;
        return upload_array(ctx, size, layers, |layer, data| {
            if layer < layers {
                let p = &pages[layer as usize / l][0];
                put(data, p.width, p.height, &|x, y| {
                    crate::prt::textured_texel(pages, *bands, layer as usize, x, y)
                });
            }
        });
    }
    let pages = lightmap.map_or(0, |lm| lm.pages.len() as u32);
    let dir = lightmap.and_then(|lm| lm.directional);
    // Directional pages follow the E/π pages (layer pages + k).
    let layers = pages * if dir.is_some() { 2 } else { 1 };
    upload_array(ctx, size, layers, |layer, data| {
        let page = match (lightmap, dir) {
            (Some(lm), _) if layer < pages => Some(&lm.pages[layer as usize]),
            (Some(_), Some(d)) if layer < 2 * pages => d.get((layer - pages) as usize),
            _ => None,
        };
        if let Some(p) = page {
            put(data, p.width, p.height, &|x, y| {
                let v = p.get(x, y);
                [v.x.max(0.0), v.y.max(0.0), v.z.max(0.0), 1.0]
            });
        }
    })
}

/// The constant or environment light of the ambient term (Fuchs's ambient uses the light-map;
/// until light-maps exist it is this irradiance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ambient {
    None,
    /// A uniform sky of this radiance (unshadowed).
    Constant(Vec3),
    /// The scene's environment map, projected on 9 SH coefficients (unshadowed).
    Environment,
}

#[derive(Clone, Debug)]
pub struct RasterSettings {
    pub width: u32,
    pub height: u32,
    pub camera: usize,
    pub path: RenderPath,
    pub shadows: ShadowMethod,
    pub attenuation: Attenuation,
    /// Override of the light radius r of the Fuchs attenuation functions.
    pub light_radius: Option<f32>,
    pub ambient: Ambient,
    pub shadow_size: u32,
    pub pcf_radius: i32,
    /// Normal offset in texels.
    pub normal_offset: f32,
    /// Slope-scaled depth bias of the shadow-map pass.
    pub slope_bias: f32,
    /// Constant depth bias (depth-buffer units) of the shadow-map pass.
    pub constant_bias: i32,
    /// Bias on the normalised linear depth (Heidrich's variant).
    pub linear_bias: f32,
    pub cascades: usize,
    /// Receiver plane (n, d) with n·x + d = 0 of planar shadows; None = the largest up-facing
    /// plane of the scene.
    pub planar_plane: Option<Vec4>,
    /// Scissor each light's passes to its screen rectangle, and cull objects outside its radius.
    pub scissor: bool,
    pub exposure: f32,
    /// Wind sway of foliage, the same in every pass (amplitude 0: none). Shadow volumes are
    /// built on the CPU from the rest pose, so wind needs another shadow method.
    pub wind: lightlab_core::wind::Wind,
    /// Draw the scene's environment map where no surface is seen, as the path tracer does
    /// (so that renders compare pixel by pixel); false leaves the background black.
    pub background: bool,
    /// Light with the scene's planar emitters as Lambertian rectangle lights (after its
    /// punctual lights; at most [`MAX_AREA_LIGHTS`], brightest first). Renderers built
    /// `with_lightmap` (a light-map already holds the emitters' light) or `with_sh` (lit by
    /// their SH light alone) ignore it.
    pub area_lights: bool,
}

impl Default for RasterSettings {
    fn default() -> Self {
        RasterSettings {
            width: 256,
            height: 256,
            camera: 0,
            path: RenderPath::Forward,
            shadows: ShadowMethod::VolumesZFail,
            attenuation: Attenuation::Fuchs4,
            light_radius: None,
            ambient: Ambient::Environment,
            shadow_size: 2048,
            pcf_radius: 1,
            normal_offset: 1.5,
            slope_bias: 1.5,
            constant_bias: 2,
            linear_bias: 0.002,
            cascades: 4,
            planar_plane: None,
            scissor: true,
            exposure: 1.0,
            wind: Default::default(),
            background: true,
            area_lights: true,
        }
    }
}

/// At most this many emitters become area lights (each costs a light's passes and shadows).
pub const MAX_AREA_LIGHTS: usize = 8;

/// How far an area light's point for shadows sits in front of its emitter: 1 % of the
/// emitter's size, so that the emitter (and a ceiling it is mounted on) lies behind it.
fn area_light_offset(e: &PlanarEmitter) -> f32 {
    (0.01 * e.area.sqrt()).max(1e-5)
}

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum RasterError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("the scene has no camera {0}")]
    NoCamera(usize),
    #[error("invalid settings: {0}")]
    Settings(String),
    #[error("GPU readback failed: {0}")]
    Readback(String),
}

/// GPU and CPU times of one frame, by pass category (milliseconds).
#[derive(Clone, Debug, Default)]
pub struct FrameTimes {
    /// Sum of GPU timestamp intervals per category; empty without timestamp support.
    pub gpu_ms: BTreeMap<&'static str, f64>,
    /// CPU time building shadow volumes / planar data this frame.
    pub cpu_volumes_ms: f64,
    /// Wall time from recording to the GPU being idle.
    pub wall_ms: f64,
}

struct Pipelines {
    ambient: [wgpu::RenderPipeline; 2],
    light: [wgpu::RenderPipeline; 2],
    gbuffer: [wgpu::RenderPipeline; 2],
    deferred_light: wgpu::RenderPipeline,
    zfail: [wgpu::RenderPipeline; 2],
    zpass: [wgpu::RenderPipeline; 2],
    planar: [wgpu::RenderPipeline; 2],
    mask: wgpu::RenderPipeline,
    map_mask: wgpu::RenderPipeline,
    shadow_depth: wgpu::RenderPipeline,
    shadow_linear: wgpu::RenderPipeline,
    tonemap: wgpu::RenderPipeline,
    sky: wgpu::RenderPipeline,
}

struct Targets {
    hdr: wgpu::Texture,
    hdr_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    gbuffer: Vec<wgpu::TextureView>,
    gbuffer_textures: Vec<wgpu::Texture>,
    mask: wgpu::Texture,
    mask_view: wgpu::TextureView,
    ldr_view: wgpu::TextureView,
}

/// Shadow-map storage: one layer per shadow view.
struct ShadowMaps {
    layers: Vec<wgpu::TextureView>,
    linear_layers: Vec<wgpu::TextureView>,
    linear_depth: wgpu::TextureView,
}

/// A renderer for one scene at one resolution.
pub struct Renderer {
    pub settings: RasterSettings,
    pub scene: GpuScene,
    camera: Camera,
    lights: Vec<GpuLight>,
    light_pos: Vec<LightPos>,
    light_radius: Vec<Option<f32>>,
    views: Vec<ShadowProjection>,
    /// (light, view) of every shadow view.
    view_light: Vec<usize>,
    planar: Vec<Option<Mat4>>,
    plane: Option<Vec4>,
    pipelines: Pipelines,
    targets: Targets,
    shadow: ShadowMaps,
    frame_buf: wgpu::Buffer,
    _pass_buf: wgpu::Buffer,
    group0: wgpu::BindGroup,
    group2: wgpu::BindGroup,
    group3: wgpu::BindGroup,
    tonemap_group: wgpu::BindGroup,
    /// The environment map (Rgba32Float, read texel by texel as the CPU's `radiance`), when
    /// the scene has one and a background is drawn.
    sky_group: Option<wgpu::BindGroup>,
    volume_buf: Option<wgpu::Buffer>,
    volume_ranges: Vec<std::ops::Range<u32>>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    frame: FrameUniforms,
    sh: ShResources,
    lpv: Option<crate::lpv::Lpv>,
}

/// GPU data of the SH techniques (dummies when there are none).
struct ShResources {
    bands: usize,
    vertex: wgpu::Buffer,
    /// Sample points then coefficients; rewritten by `set_sh_light`.
    light: wgpu::Buffer,
    index: wgpu::TextureView,
    relit: wgpu::Buffer,
    /// The relighting compute pass of compressed transfer: pipeline, bind group, workgroups.
    relight: Option<(wgpu::ComputePipeline, wgpu::BindGroup, [u32; 2])>,
}

impl ShResources {
    fn new(
        ctx: &GpuContext,
        sh: Option<&crate::prt::ShInput>,
        frame: &FrameUniforms,
        size: [u32; 2],
        frame_buf: &wgpu::Buffer,
    ) -> ShResources {
        use crate::prt::{ShTransfer, pack_representatives, pack_vertex_transfer};
        let device = &ctx.device;
        let storage = |label: &str, data: &[[f32; 4]], extra: wgpu::BufferUsages| {
            let dummy = [[0.0f32; 4]];
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(if data.is_empty() { &dummy } else { data }),
                usage: wgpu::BufferUsages::STORAGE | extra,
            })
        };
        let bands = sh.map_or(1, |s| s.bands);
        let vertex = match sh.map(|s| &s.transfer) {
            Some(ShTransfer::Vertex { instances }) => pack_vertex_transfer(instances, bands),
            _ => vec![],
        };
        let vertex = storage("sh vertex transfer", &vertex, wgpu::BufferUsages::empty());
        let gp = (frame.sh_groups * frame.sh_points) as usize;
        let light = vec![[0.0f32; 4]; gp + gp * 4 * frame.sh_layers as usize];
        let light = storage("sh light", &light, wgpu::BufferUsages::COPY_DST);
        let relit = vec![[0.0f32; 4]; gp * frame.sh_reps as usize];
        let relit = storage("sh relit", &relit, wgpu::BufferUsages::empty());
        let (pages, reps): (&[crate::prt::IndexPage], &[f32]) = match sh.map(|s| &s.transfer) {
            Some(ShTransfer::Compressed {
                pages,
                representatives,
                ..
            }) => (pages, representatives),
            _ => (&[], &[]),
        };
        let isize = if pages.is_empty() { [1, 1] } else { size };
        let tex = texture(
            device,
            "sh index",
            isize[0],
            isize[1],
            (pages.len() as u32).max(2),
            wgpu::TextureFormat::R16Uint,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        for (k, p) in pages.iter().enumerate() {
            // Indices are checked below 65536 (`ShInput::validate`).
            let idx: Vec<u16> = p.indices.iter().map(|&i| i as u16).collect();
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &tex,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: k as u32,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(&idx),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(p.width * 2),
                    rows_per_image: Some(p.height),
                },
                wgpu::Extent3d {
                    width: p.width,
                    height: p.height,
                    depth_or_array_layers: 1,
                },
            );
        }
        let index = array_view(&tex);
        let relight = (!pages.is_empty()).then(|| {
            let reps = storage(
                "sh representatives",
                &pack_representatives(reps, bands),
                wgpu::BufferUsages::empty(),
            );
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("prt relit"),
                source: wgpu::ShaderSource::Wgsl(crate::prt::RELIT_SOURCE.as_str().into()),
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("sh relight"),
                layout: None,
                module: &module,
                entry_point: Some("relight_cs"),
                compilation_options: Default::default(),
                cache: None,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sh relight"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: frame_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: reps.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: light.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: relit.as_entire_binding(),
                    },
                ],
            });
            let wg = ((gp * frame.sh_reps as usize).div_ceil(64) as u32).max(1);
            let x = wg.min(65535);
            (pipeline, group, [x, wg.div_ceil(x)])
        });
        ShResources {
            bands,
            vertex,
            light,
            index,
            relit,
            relight,
        }
    }
}

/// The next pair of timestamp queries for a pass named `label` (recorded in `labels`), if the
/// adapter has timestamps and the query set has room.
fn timestamp_slot<'q>(
    queries: Option<&'q (wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    labels: &mut Vec<&'static str>,
    label: &'static str,
) -> Option<(&'q wgpu::QuerySet, u32, u32)> {
    let (set, _, _) = queries?;
    let i = labels.len() as u32;
    if 2 * i + 1 >= set.count() {
        return None;
    }
    labels.push(label);
    Some((set, 2 * i, 2 * i + 1))
}

pub(crate) fn texture(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// The environment map as an Rgba32Float texture of radiance × intensity.
fn env_texture(ctx: &GpuContext, env: &lightlab_scene::Environment) -> wgpu::TextureView {
    let (w, h) = (env.image.width, env.image.height);
    let tex = texture(
        &ctx.device,
        "environment",
        w,
        h,
        1,
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    let data: Vec<f32> = env
        .image
        .data
        .iter()
        .flat_map(|c| (*c * env.intensity).extend(1.0).to_array())
        .collect();
    ctx.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &tex,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(&data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 16),
            rows_per_image: Some(h),
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    tex.create_view(&Default::default())
}

fn layer_view(t: &wgpu::Texture, layer: u32) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// Valid wind parameters, and a shadow method that sways with them.
fn check_wind(wind: &lightlab_core::wind::Wind, shadows: ShadowMethod) -> Result<(), RasterError> {
    wind.validate().map_err(RasterError::Settings)?;
    if wind.amplitude > 0.0
        && matches!(
            shadows,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass
        )
    {
        return Err(RasterError::Settings(
            "wind sway needs shadow maps: shadow volumes are built on the CPU from the rest pose"
                .into(),
        ));
    }
    Ok(())
}

/// The camera projection: reversed depth with an infinite far plane.
pub fn projection(camera: &Camera, aspect: f32) -> Mat4 {
    directx::perspective_infinite_reverse(camera.yfov, aspect, camera.znear.max(1e-4))
}

/// The largest up-facing plane of the scene (area-weighted histogram of heights), as (n, d).
fn dominant_floor(scene: &Scene) -> Option<Vec4> {
    let mut heights: BTreeMap<i64, f32> = BTreeMap::new();
    for inst in &scene.instances {
        let m = &scene.meshes[inst.mesh];
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]]
                .map(|i| inst.transform.transform_point3(m.positions[i as usize]));
            let n = (b - a).cross(c - a);
            let area = 0.5 * n.length();
            if area > 0.0 && n.normalize().y > 0.999 {
                *heights.entry((a.y * 1000.0).round() as i64).or_default() += area;
            }
        }
    }
    let (h, _) = heights.into_iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(Vec4::new(0.0, 1.0, 0.0, -(h as f32) / 1000.0))
}

fn sh_irradiance(scene: &Scene, ambient: Ambient) -> [[f32; 4]; 9] {
    let mut out = [[0.0; 4]; 9];
    match ambient {
        Ambient::None => {}
        Ambient::Constant(c) => {
            // E = π·c for every normal; c₀·Y₀₀ = E.
            let e = c * std::f32::consts::PI / 0.282_094_8;
            out[0] = e.extend(0.0).to_array();
        }
        Ambient::Environment => {
            if let Some(env) = &scene.environment {
                let l = lightlab_core::sh_env::project_env(
                    &env.image,
                    lightlab_core::sh_env::EnvFormat::LatLong,
                    3,
                );
                let e = lightlab_core::sh::irradiance_from_radiance(&l);
                for (o, c) in out.iter_mut().zip(e) {
                    *o = (c * env.intensity as f64).as_vec3().extend(0.0).to_array();
                }
            }
        }
    }
    out
}

impl Renderer {
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
    ) -> Result<Renderer, RasterError> {
        Self::with_lightmap(ctx, scene, settings, None)
    }

    /// A renderer whose ambient term is diffuse × light-map (Fuchs §3.4) instead of the SH
    /// ambient: the `lightmap` and `lightmap+phong` techniques.
    pub fn with_lightmap(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        lightmap: Option<&LightmapInput>,
    ) -> Result<Renderer, RasterError> {
        Self::build(ctx, scene, settings, lightmap, None, None)
    }

    /// A renderer whose ambient term is diffuse × SH transfer · SH light (the PRT techniques,
    /// `crate::prt`). The light is black until [`Renderer::set_sh_light`].
    pub fn with_sh(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        sh: &crate::prt::ShInput,
    ) -> Result<Renderer, RasterError> {
        sh.validate(scene).map_err(RasterError::Settings)?;
        Self::build(ctx, scene, settings, None, Some(sh), None)
    }

    /// A renderer whose diffuse surfaces also receive the indirect light of a light propagation
    /// volume (`crate::lpv`), recomputed every frame; `indirect_only` renders only that light
    /// (the `--debug-view indirect` of the `lpv` techniques).
    pub fn with_lpv(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        lpv: &crate::lpv::LpvSettings,
        indirect_only: bool,
    ) -> Result<Renderer, RasterError> {
        Self::build(ctx, scene, settings, None, None, Some((lpv, indirect_only)))
    }

    /// The light propagation volume, if this renderer has one.
    pub fn lpv(&self) -> Option<&crate::lpv::Lpv> {
        self.lpv.as_ref()
    }

    fn build(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        lightmap: Option<&LightmapInput>,
        sh: Option<&crate::prt::ShInput>,
        lpv: Option<(&crate::lpv::LpvSettings, bool)>,
    ) -> Result<Renderer, RasterError> {
        let s = &settings;
        if let Some(lm) = lightmap
            && (lm.pages.is_empty()
                || lm.rects.len() != scene.instances.len()
                || lm.pages.iter().any(|p| p.width == 0 || p.height == 0)
                || lm.directional.is_some_and(|d| {
                    d.len() != lm.pages.len()
                        || d.iter()
                            .zip(lm.pages)
                            .any(|(a, b)| (a.width, a.height) != (b.width, b.height))
                }))
        {
            return Err(RasterError::Settings(
                "light-maps do not match the scene (one rect per instance, non-empty pages)".into(),
            ));
        }
        check_wind(&s.wind, s.shadows)?;
        if s.width == 0 || s.height == 0 || s.width > 16384 || s.height > 16384 {
            return Err(RasterError::Settings(format!(
                "image size {}×{} must be within 1..=16384",
                s.width, s.height
            )));
        }
        if !(64..=8192).contains(&s.shadow_size) {
            return Err(RasterError::Settings(format!(
                "shadow map size {} must be within 64..=8192",
                s.shadow_size
            )));
        }
        if !(1..=4).contains(&s.cascades) {
            return Err(RasterError::Settings("cascades must be 1 to 4".into()));
        }
        if !(0..=4).contains(&s.pcf_radius) {
            return Err(RasterError::Settings("PCF radius must be 0 to 4".into()));
        }
        let camera = scene
            .cameras
            .get(s.camera)
            .cloned()
            .or_else(|| (s.camera == 0).then(|| scene.framing_camera()).flatten())
            .ok_or(RasterError::NoCamera(s.camera))?;
        let device = &ctx.device;
        // Pages may differ in size: the array takes the largest, each page's UVs are scaled.
        let (page_sizes, page_rects): (Vec<[u32; 2]>, Option<&[Option<UvRect>]>) =
            match (lightmap, sh) {
                (Some(lm), _) => (
                    lm.pages.iter().map(|p| [p.width, p.height]).collect(),
                    Some(lm.rects),
                ),
                (None, Some(sh)) if sh.mode() != 2 => (sh.page_sizes(), Some(sh.rects)),
                _ => (vec![], None),
            };
        let lm_size = [
            page_sizes.iter().map(|p| p[0]).max().unwrap_or(1),
            page_sizes.iter().map(|p| p[1]).max().unwrap_or(1),
        ];
        let lm_rects: Option<Vec<Option<UvRect>>> = page_rects.map(|rects| {
            rects
                .iter()
                .map(|r| {
                    r.map(|r| {
                        let p = page_sizes[r.page as usize];
                        let k = [
                            p[0] as f32 / lm_size[0] as f32,
                            p[1] as f32 / lm_size[1] as f32,
                        ];
                        UvRect {
                            page: r.page,
                            offset: [r.offset[0] * k[0], r.offset[1] * k[1]],
                            scale: [r.scale[0] * k[0], r.scale[1] * k[1]],
                        }
                    })
                })
                .collect()
        });
        let gscene = GpuScene::with_lightmap_uvs(device, &ctx.queue, scene, lm_rects.as_deref());
        let lpv_res = lpv
            .map(|(l, _)| {
                let aspect = s.width as f32 / s.height as f32;
                crate::lpv::Lpv::new(ctx, scene, l.clone(), &camera, aspect, &s.wind)
            })
            .transpose()
            .map_err(RasterError::Settings)?;
        let aspect = s.width as f32 / s.height as f32;

        // Lights and their shadow views.
        let mut lights = vec![];
        let mut light_pos = vec![];
        let mut light_radius = vec![];
        let mut views: Vec<ShadowProjection> = vec![];
        let mut view_light = vec![];
        let mut planar = vec![];
        let plane = if s.shadows == ShadowMethod::Planar {
            s.planar_plane.or_else(|| dominant_floor(scene))
        } else {
            None
        };
        // The scene's lights, then (when enabled) its planar emitters as area lights: each a
        // point light at the emitter's centre, moved off it along its normal, for the shadows,
        // and a Lambertian rectangle for the shading (kind 3).
        let mut sources: Vec<(Light, Option<(PlanarEmitter, f32)>)> =
            scene.lights.iter().map(|l| (l.clone(), None)).collect();
        // A light-map holds the emitters' light already; SH transfer is lit by its SH light only.
        if s.area_lights && lightmap.is_none() && sh.is_none() {
            for e in scene.planar_emitters().into_iter().take(MAX_AREA_LIGHTS) {
                let offset = area_light_offset(&e);
                let l = Light {
                    name: format!("emitter {}", e.instance),
                    kind: LightKind::Point,
                    color: e.radiance,
                    intensity: e.area,
                    position: e.centre + e.normal * offset,
                    direction: e.normal,
                    range: None,
                };
                sources.push((l, Some((e, offset))));
            }
        }
        for (li, (l, area)) in sources.iter().enumerate() {
            let radius = match area {
                None => lights::light_radius(l, s.attenuation, s.light_radius),
                // Area lights fall off physically (their exact irradiance): never culled.
                Some(_) => None,
            };
            let mut g = lights::gpu_light(l, s.attenuation, radius);
            if let Some((e, offset)) = area {
                g.kind = 3;
                g.attenuation = 0;
                g.atten_scale = 1.0;
                g.edge_u = e.half_u.to_array();
                g.edge_v = e.half_v.to_array();
                g.area_offset = *offset;
                g.two_sided = e.double_sided as u32;
            }
            let first = views.len();
            if s.shadows.map() {
                match l.kind {
                    LightKind::Spot { outer_cone, .. } => {
                        let far = lights::shadow_far(l, radius, gscene.bounds);
                        views.push(lights::spot_view(l, outer_cone, far, s.shadow_size));
                    }
                    LightKind::Point => {
                        let far = lights::shadow_far(l, radius, gscene.bounds);
                        views.extend(lights::point_views(l, far, s.shadow_size));
                    }
                    LightKind::Directional { .. } => {
                        let far_cam = lights::box_corners(gscene.bounds)
                            .iter()
                            .map(|c| (*c - camera.position()).length())
                            .fold(1.0f32, f32::max);
                        let near = camera.znear.max(0.05);
                        let ends = lights::cascade_ends(near, far_cam, s.cascades, 0.7);
                        views.extend(lights::cascade_views(
                            l.direction,
                            &camera,
                            aspect,
                            &ends,
                            near,
                            gscene.bounds,
                            s.shadow_size,
                        ));
                        let mut ce = [f32::MAX; 4];
                        ce[..ends.len()].copy_from_slice(&ends);
                        g.cascade_ends = ce;
                    }
                }
                g.shadow_first = first as u32;
                g.shadow_count = (views.len() - first) as u32;
                view_light.extend(std::iter::repeat_n(li, views.len() - first));
            }
            let (lp, hom) = match l.kind {
                LightKind::Directional { .. } => (
                    LightPos::Directional(l.direction.normalize()),
                    (-l.direction.normalize()).extend(0.0),
                ),
                _ => (LightPos::Point(l.position), l.position.extend(1.0)),
            };
            planar.push(
                plane.and_then(|p| (p.dot(hom) > 0.0).then(|| lights::planar_projection(p, hom))),
            );
            lights.push(g);
            light_pos.push(lp);
            light_radius.push(radius);
        }
        if lights.is_empty() {
            lights.push(GpuLight::default());
        }
        let view_gpu: Vec<ShadowView> = if views.is_empty() {
            vec![ShadowView::zeroed()]
        } else {
            views.iter().map(|v| v.gpu()).collect()
        };

        // Uniforms.
        let view = camera.transform.inverse();
        let view_proj = projection(&camera, aspect) * view;
        let frame = FrameUniforms {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            view: view.to_cols_array_2d(),
            camera_pos: camera.position().to_array(),
            exposure: s.exposure,
            wind_a: s.wind.uniform()[0],
            wind_b: s.wind.uniform()[1],
            viewport: [s.width as f32, s.height as f32],
            light_count: light_pos.len() as u32,
            shadow_mode: match s.shadows {
                ShadowMethod::Map => 1,
                ShadowMethod::MapLinear => 2,
                _ => 0,
            },
            ambient_sh: sh_irradiance(scene, s.ambient),
            pcf_radius: s.pcf_radius,
            normal_offset: s.normal_offset,
            linear_bias: s.linear_bias,
            shadow_size: s.shadow_size as f32,
            lightmap_mode: match lightmap {
                None => 0,
                Some(lm) if lm.bicubic => 2,
                Some(_) => 1,
            } | lightmap
                .map_or(0, |lm| if lm.directional.is_some() { 4 } else { 0 }),
            lightmap_pages: lightmap.map_or(0, |lm| lm.pages.len() as u32),
            lightmap_size: [lm_size[0] as f32, lm_size[1] as f32],
            sh_mode: sh.map_or(0, |sh| sh.mode()),
            sh_layers: sh.map_or(0, |sh| crate::prt::layers(sh.bands) as u32),
            sh_points: sh.map_or(0, |sh| sh.points as u32),
            sh_per_object: sh.is_some_and(|sh| sh.per_object) as u32,
            sh_filter: match sh.map(|sh| &sh.transfer) {
                Some(crate::prt::ShTransfer::Compressed { filter, .. }) => filter.code(),
                _ => 0,
            },
            sh_reps: sh.map_or(0, |sh| sh.representatives() as u32),
            sh_coeff_base: sh.map_or(0, |sh| {
                (sh.groups(scene.instances.len()) * sh.points) as u32
            }),
            sh_groups: sh.map_or(0, |sh| sh.groups(scene.instances.len()) as u32),
            lpv_mode: lpv_res.as_ref().map_or(0, |l| match l.settings.scheme {
                crate::lpv::LpvScheme::Kaplanyan => 1,
                crate::lpv::LpvScheme::Wpi => 2,
            }),
            lpv_size: lpv_res.as_ref().map_or(1.0, |l| l.grids[0].n as f32),
            lpv_indirect_only: lpv.is_some_and(|l| l.1) as u32,
            lpv_cascades: lpv_res.as_ref().map_or(1, |l| l.grids.len() as u32),
            lpv_pad0: 0,
            lpv_pad1: 0,
            lpv_pad2: 0,
            lpv_grids: {
                let mut g = [[0.0, 0.0, 0.0, 1.0]; 4];
                for (k, grid) in lpv_res.iter().flat_map(|l| &l.grids).enumerate() {
                    g[k] = grid.origin.extend(grid.cell).to_array();
                }
                g
            },
            lpv_damping: lpv_res.as_ref().map_or(0.0, |l| match l.settings.scheme {
                crate::lpv::LpvScheme::Kaplanyan => l.settings.damping,
                crate::lpv::LpvScheme::Wpi => 0.0,
            }),
        };
        let frame_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame"),
            contents: bytemuck::bytes_of(&frame),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let light_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lights"),
            contents: bytemuck::cast_slice(&lights),
            usage: wgpu::BufferUsages::STORAGE,
        });
        // Shadow views, then planar projections (one slot per light) in the same array.
        let mut all_views = view_gpu.clone();
        let planar_base = all_views.len();
        for p in &planar {
            all_views.push(ShadowView {
                view_proj: p.unwrap_or(Mat4::ZERO).to_cols_array_2d(),
                ..ShadowView::zeroed()
            });
        }
        let view_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shadow views"),
            contents: bytemuck::cast_slice(&all_views),
            usage: wgpu::BufferUsages::STORAGE,
        });
        // Pass slots: light i → slot i (planar view in shadow_view); shadow view v → n + v.
        let n = lights.len();
        let mut slots = vec![0u8; (n + views.len()).max(1) * SLOT as usize];
        for i in 0..n {
            let p = PassUniforms {
                light_index: i as u32,
                shadow_view: (planar_base + i) as u32,
                ..Default::default()
            };
            slots[i * SLOT as usize..][..16].copy_from_slice(bytemuck::bytes_of(&p));
        }
        for (v, &li) in view_light.iter().enumerate() {
            let p = PassUniforms {
                light_index: li as u32,
                shadow_view: v as u32,
                ..Default::default()
            };
            slots[(n + v) * SLOT as usize..][..16].copy_from_slice(bytemuck::bytes_of(&p));
        }
        let pass_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pass slots"),
            contents: &slots,
            usage: wgpu::BufferUsages::UNIFORM,
        });

        // Layouts.
        let buf = |binding, ty, dynamic| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: dynamic,
                min_binding_size: None,
            },
            count: None,
        };
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let bgl0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[
                buf(0, wgpu::BufferBindingType::Uniform, false),
                buf(1, ro, false),
                buf(2, ro, false),
                buf(3, wgpu::BufferBindingType::Uniform, true),
            ],
        });
        let bgl1 = crate::gpu_scene::material_layout(device);
        let tex_entry = |binding, sample_type, dim| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: dim,
                multisampled: false,
            },
            count: None,
        };
        let unfilt = wgpu::TextureSampleType::Float { filterable: false };
        let bgl2 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow maps"),
            entries: &[
                tex_entry(
                    0,
                    wgpu::TextureSampleType::Depth,
                    wgpu::TextureViewDimension::D2Array,
                ),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
                tex_entry(2, unfilt, wgpu::TextureViewDimension::D2Array),
                tex_entry(
                    3,
                    wgpu::TextureSampleType::Float { filterable: true },
                    wgpu::TextureViewDimension::D2Array,
                ),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                buf(5, ro, false),
                buf(6, ro, false),
                tex_entry(
                    7,
                    wgpu::TextureSampleType::Uint,
                    wgpu::TextureViewDimension::D2Array,
                ),
                buf(8, ro, false),
                tex_entry(
                    9,
                    wgpu::TextureSampleType::Float { filterable: true },
                    wgpu::TextureViewDimension::D3,
                ),
                tex_entry(
                    10,
                    wgpu::TextureSampleType::Float { filterable: true },
                    wgpu::TextureViewDimension::D3,
                ),
                tex_entry(
                    11,
                    wgpu::TextureSampleType::Float { filterable: true },
                    wgpu::TextureViewDimension::D3,
                ),
                wgpu::BindGroupLayoutEntry {
                    binding: 12,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let d2 = wgpu::TextureViewDimension::D2;
        let bgl3 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("g-buffer"),
            entries: &[
                tex_entry(0, unfilt, d2),
                tex_entry(1, unfilt, d2),
                tex_entry(2, unfilt, d2),
                tex_entry(3, unfilt, d2),
            ],
        });
        let bgl_tm = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tonemap"),
            entries: &[tex_entry(4, unfilt, d2)],
        });
        let pl = |label, groups: &[&wgpu::BindGroupLayout]| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &groups.iter().map(|g| Some(*g)).collect::<Vec<_>>(),
                immediate_size: 0,
            })
        };
        let pl_scene = pl("scene", &[&bgl0, &bgl1, &bgl2]);
        let pl_deferred = pl("deferred", &[&bgl0, &bgl1, &bgl2, &bgl3]);
        let pl_shadow = pl("shadow", &[&bgl0, &bgl1]);
        let pl_frame = pl("frame only", &[&bgl0]);
        let pl_tonemap = pl("tonemap", &[&bgl0, &bgl1, &bgl2, &bgl_tm]);
        let bgl_sky = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("sky"),
            entries: &[tex_entry(5, unfilt, d2)],
        });
        let pl_sky = pl("sky", &[&bgl0, &bgl1, &bgl2, &bgl_sky]);

        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster"),
            source: wgpu::ShaderSource::Wgsl(SHADER_SOURCE.as_str().into()),
        });
        let gb_formats = gbuffer_formats(ctx);
        let linear_format = renderable_or(
            ctx,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureFormat::R16Float,
        );
        let pipelines = Pipelines::new(
            device,
            &module,
            s,
            [
                &pl_scene,
                &pl_deferred,
                &pl_shadow,
                &pl_frame,
                &pl_tonemap,
                &pl_sky,
            ],
            gb_formats,
            linear_format,
        );

        // Targets.
        let rt = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
        let hdr = texture(
            device,
            "hdr",
            s.width,
            s.height,
            1,
            HDR,
            rt | sampled | wgpu::TextureUsages::COPY_SRC,
        );
        let depth = texture(device, "depth", s.width, s.height, 1, DEPTH, rt);
        let gbuffer_textures: Vec<wgpu::Texture> = gb_formats
            .iter()
            .map(|f| {
                texture(
                    device,
                    "g-buffer",
                    s.width,
                    s.height,
                    1,
                    *f,
                    rt | sampled | wgpu::TextureUsages::COPY_SRC,
                )
            })
            .collect();
        let gbuffer: Vec<wgpu::TextureView> = gbuffer_textures
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let mask = texture(
            device,
            "mask",
            s.width,
            s.height,
            1,
            MASK,
            rt | wgpu::TextureUsages::COPY_SRC,
        );
        let ldr = texture(
            device,
            "ldr",
            s.width,
            s.height,
            1,
            wgpu::TextureFormat::Rgba8Unorm,
            rt,
        );
        let targets = Targets {
            hdr_view: hdr.create_view(&Default::default()),
            hdr,
            depth_view: depth.create_view(&Default::default()),
            gbuffer,
            gbuffer_textures,
            mask_view: mask.create_view(&Default::default()),
            mask,
            ldr_view: ldr.create_view(&Default::default()),
        };
        // GL decides a texture's target at creation and makes a six-layer texture a cube map,
        // which cannot be read as an array: one spare layer for a scene whose only shadows are
        // one point (or area) light's six faces.
        let layers = match views.len().max(1) as u32 {
            6 => 7,
            n => n,
        };
        let ss = if s.shadows.map() { s.shadow_size } else { 1 };
        let linear_layers = if s.shadows == ShadowMethod::MapLinear {
            layers
        } else {
            1
        };
        let sd = texture(
            device,
            "shadow depth",
            ss,
            ss,
            layers,
            SHADOW_DEPTH,
            rt | sampled,
        );
        let sl = texture(
            device,
            "shadow linear",
            ss,
            ss,
            linear_layers,
            linear_format,
            rt | sampled,
        );
        let sld = texture(device, "linear z", ss, ss, 1, SHADOW_DEPTH, rt);
        let shadow = ShadowMaps {
            layers: (0..layers).map(|i| layer_view(&sd, i)).collect(),
            linear_layers: (0..linear_layers).map(|i| layer_view(&sl, i)).collect(),
            linear_depth: sld.create_view(&Default::default()),
        };
        let cmp = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow compare"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let group0 = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &bgl0,
            entries: &[
                entry(0, frame_buf.as_entire_binding()),
                entry(1, light_buf.as_entire_binding()),
                entry(2, view_buf.as_entire_binding()),
                entry(
                    3,
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &pass_buf,
                        offset: 0,
                        size: wgpu::BufferSize::new(16),
                    }),
                ),
            ],
        });
        let (sd_view, sl_view) = (array_view(&sd), array_view(&sl));
        let (lm_view, lm_sampler) = upload_lightmaps(ctx, lightmap, sh, lm_size);
        let sh_res = ShResources::new(ctx, sh, &frame, lm_size, &frame_buf);
        let lpv_views: Vec<wgpu::TextureView> = match &lpv_res {
            Some(l) => l
                .textures
                .iter()
                .map(|t| t.create_view(&Default::default()))
                .collect(),
            None => {
                let t = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("no lpv"),
                    size: wgpu::Extent3d {
                        width: 1,
                        height: 1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D3,
                    format: wgpu::TextureFormat::Rgba16Float,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                });
                (0..3).map(|_| t.create_view(&Default::default())).collect()
            }
        };
        let lpv_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("lpv"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let group2 = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow maps"),
            layout: &bgl2,
            entries: &[
                entry(0, wgpu::BindingResource::TextureView(&sd_view)),
                entry(1, wgpu::BindingResource::Sampler(&cmp)),
                // Without Heidrich's linear depths, the same binding reads the raw depths of
                // the shadow maps (Depth32Float as unfilterable float; GLSL cannot read a
                // `texture_depth` binding texel by texel): the area lights' blocker search.
                entry(
                    2,
                    wgpu::BindingResource::TextureView(if s.shadows == ShadowMethod::MapLinear {
                        &sl_view
                    } else {
                        &sd_view
                    }),
                ),
                entry(3, wgpu::BindingResource::TextureView(&lm_view)),
                entry(4, wgpu::BindingResource::Sampler(&lm_sampler)),
                entry(5, sh_res.vertex.as_entire_binding()),
                entry(6, sh_res.light.as_entire_binding()),
                entry(7, wgpu::BindingResource::TextureView(&sh_res.index)),
                entry(8, sh_res.relit.as_entire_binding()),
                entry(9, wgpu::BindingResource::TextureView(&lpv_views[0])),
                entry(10, wgpu::BindingResource::TextureView(&lpv_views[1])),
                entry(11, wgpu::BindingResource::TextureView(&lpv_views[2])),
                entry(12, wgpu::BindingResource::Sampler(&lpv_sampler)),
            ],
        });
        let group3 = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("g-buffer"),
            layout: &bgl3,
            entries: &[
                entry(0, wgpu::BindingResource::TextureView(&targets.gbuffer[0])),
                entry(1, wgpu::BindingResource::TextureView(&targets.gbuffer[1])),
                entry(2, wgpu::BindingResource::TextureView(&targets.gbuffer[2])),
                entry(3, wgpu::BindingResource::TextureView(&targets.gbuffer[3])),
            ],
        });
        let sky_group = scene
            .environment
            .as_ref()
            .filter(|_| settings.background)
            .map(|env| {
                let view = env_texture(ctx, env);
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("sky"),
                    layout: &bgl_sky,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(&view),
                    }],
                })
            });
        let tonemap_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tonemap"),
            layout: &bgl_tm,
            entries: &[entry(
                4,
                wgpu::BindingResource::TextureView(&targets.hdr_view),
            )],
        });
        let queries = ctx.has_timestamps().then(|| {
            let lpv_passes = lpv_res.as_ref().map_or(0, |l| 2 * l.light_count() + 1);
            let count = 2 * (5 + 2 * n + views.len() + lpv_passes) as u32;
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: count as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp read"),
                size: count as u64 * 8,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (set, resolve, read)
        });
        Ok(Renderer {
            settings,
            scene: gscene,
            camera,
            lights,
            light_pos,
            light_radius,
            views,
            view_light,
            planar,
            plane,
            pipelines,
            targets,
            shadow,
            frame_buf,
            _pass_buf: pass_buf,
            group0,
            group2,
            group3,
            tonemap_group,
            sky_group,
            volume_buf: None,
            volume_ranges: vec![],
            queries,
            frame,
            sh: sh_res,
            lpv: lpv_res,
        })
    }

    /// The SH light of the next frame: `points` (groups × sample points) and per point its
    /// bands² RGB coefficients (`lightlab_bake::sh_light::ShLighting`, flattened).
    pub fn set_sh_light(
        &mut self,
        ctx: &GpuContext,
        points: &[Vec3],
        coeffs: &[Vec3],
    ) -> Result<(), RasterError> {
        let gp = (self.frame.sh_groups * self.frame.sh_points) as usize;
        let nc = self.sh.bands * self.sh.bands;
        if self.frame.sh_mode == 0 || points.len() != gp || coeffs.len() != gp * nc {
            return Err(RasterError::Settings(format!(
                "the SH light needs {gp} sample points and {} coefficients (got {} and {})",
                gp * nc,
                points.len(),
                coeffs.len()
            )));
        }
        let data = crate::prt::pack_light(points, coeffs, self.sh.bands);
        ctx.queue
            .write_buffer(&self.sh.light, 0, bytemuck::cast_slice(&data));
        Ok(())
    }

    /// The linear HDR colour target of the last frame (Rgba16Float, `width`×`height`), for a
    /// viewer's own display pass.
    pub fn hdr_view(&self) -> &wgpu::TextureView {
        &self.targets.hdr_view
    }

    /// The camera of the next frame.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Number of lights rendered (the scene's, then its area lights).
    pub fn light_count(&self) -> usize {
        self.light_pos.len()
    }

    /// Set the wind (e.g. its time, for animation): every pass sways from the next frame on.
    pub fn set_wind(
        &mut self,
        ctx: &GpuContext,
        wind: lightlab_core::wind::Wind,
    ) -> Result<(), RasterError> {
        check_wind(&wind, self.settings.shadows)?;
        self.settings.wind = wind;
        [self.frame.wind_a, self.frame.wind_b] = wind.uniform();
        ctx.queue
            .write_buffer(&self.frame_buf, 0, bytemuck::bytes_of(&self.frame));
        if let Some(l) = &mut self.lpv {
            l.set_wind(ctx, &wind);
        }
        Ok(())
    }

    /// Move the camera (the next frame uses it). Cascades follow only on a new renderer.
    pub fn set_camera(&mut self, ctx: &GpuContext, camera: Camera) {
        let aspect = self.settings.width as f32 / self.settings.height as f32;
        let view = camera.transform.inverse();
        let view_proj = projection(&camera, aspect) * view;
        self.frame.view_proj = view_proj.to_cols_array_2d();
        self.frame.inv_view_proj = view_proj.inverse().to_cols_array_2d();
        self.frame.view = view.to_cols_array_2d();
        self.frame.camera_pos = camera.position().to_array();
        self.camera = camera;
        ctx.queue
            .write_buffer(&self.frame_buf, 0, bytemuck::bytes_of(&self.frame));
    }

    /// Whether light `li`'s sphere of influence can touch the box `b`.
    fn reaches(&self, li: usize, b: &(Vec3, Vec3)) -> bool {
        if !self.settings.scissor {
            return true;
        }
        match (self.light_pos[li], self.light_radius[li]) {
            (LightPos::Point(p), Some(r)) => p.clamp(b.0, b.1).distance_squared(p) <= r * r,
            _ => true,
        }
    }

    /// The light's screen rectangle (x, y, w, h), or None when it covers nothing.
    fn scissor(&self, li: usize) -> Option<(u32, u32, u32, u32)> {
        let (w, h) = (self.settings.width, self.settings.height);
        let full = Some((0, 0, w, h));
        if !self.settings.scissor {
            return full;
        }
        let (LightPos::Point(p), Some(r)) = (self.light_pos[li], self.light_radius[li]) else {
            return full;
        };
        let vp = Mat4::from_cols_array_2d(&self.frame.view_proj);
        let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
        for c in lights::box_corners((p - Vec3::splat(r), p + Vec3::splat(r))) {
            let q = vp * c.extend(1.0);
            if q.w <= 1e-4 {
                return full;
            }
            let ndc = glam::Vec2::new(q.x, q.y) / q.w;
            lo = lo.min(ndc);
            hi = hi.max(ndc);
        }
        let x0 = (((lo.x + 1.0) * 0.5 * w as f32).floor().max(0.0) as u32).min(w);
        let x1 = (((hi.x + 1.0) * 0.5 * w as f32).ceil().max(0.0) as u32).min(w);
        let y0 = (((1.0 - hi.y) * 0.5 * h as f32).floor().max(0.0) as u32).min(h);
        let y1 = (((1.0 - lo.y) * 0.5 * h as f32).ceil().max(0.0) as u32).min(h);
        (x1 > x0 && y1 > y0).then_some((x0, y0, x1 - x0, y1 - y0))
    }

    /// Build every light's shadow volume on the CPU and upload it.
    fn build_volumes(&mut self, ctx: &GpuContext) {
        let mut verts: Vec<Vec4> = vec![];
        self.volume_ranges.clear();
        for li in 0..self.light_pos.len() {
            let start = verts.len() as u32;
            for d in &self.scene.draws {
                if let Some(vm) = &d.volume
                    && self.reaches(li, &d.bounds)
                {
                    build_volume(vm, self.light_pos[li], &mut verts);
                }
            }
            self.volume_ranges.push(start..verts.len() as u32);
        }
        if verts.is_empty() {
            verts.push(Vec4::ZERO);
        }
        let bytes = (verts.len() * 16) as u64;
        if self.volume_buf.as_ref().is_none_or(|b| b.size() < bytes) {
            self.volume_buf = Some(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow volumes"),
                size: bytes.next_power_of_two(),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        ctx.queue.write_buffer(
            self.volume_buf.as_ref().expect("allocated above"),
            0,
            bytemuck::cast_slice(&verts),
        );
    }

    fn draw_scene<'a>(
        &'a self,
        pass: &mut wgpu::RenderPass<'a>,
        pipes: &'a [wgpu::RenderPipeline; 2],
        li: Option<usize>,
    ) {
        pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
        pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        let mut current: Option<bool> = None;
        for (ii, d) in self.scene.draws.iter().enumerate() {
            if li.is_some_and(|li| !self.reaches(li, &d.bounds)) {
                continue;
            }
            let m = &self.scene.materials[d.material];
            if current != Some(m.double_sided) {
                pass.set_pipeline(&pipes[m.double_sided as usize]);
                current = Some(m.double_sided);
            }
            pass.set_bind_group(1, &m.bind_group, &[]);
            // The instance index is the scene instance (per-object SH light groups).
            pass.draw_indexed(
                d.first_index..d.first_index + d.index_count,
                0,
                ii as u32..ii as u32 + 1,
            );
        }
    }

    fn timestamps<'q>(
        &'q self,
        labels: &mut Vec<&'static str>,
        label: &'static str,
    ) -> Option<wgpu::RenderPassTimestampWrites<'q>> {
        let (set, begin, end) = timestamp_slot(self.queries.as_ref(), labels, label)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(begin),
            end_of_pass_write_index: Some(end),
        })
    }

    /// Compressed SH light-maps: relight every representative under this frame's light.
    fn relight_pass(&self, enc: &mut wgpu::CommandEncoder, labels: &mut Vec<&'static str>) {
        let Some((pipeline, group, wg)) = &self.sh.relight else {
            return;
        };
        let ts = self.timestamps(labels, "sh relight");
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("sh relight"),
            timestamp_writes: ts.map(|t| wgpu::ComputePassTimestampWrites {
                query_set: t.query_set,
                beginning_of_pass_write_index: t.beginning_of_pass_write_index,
                end_of_pass_write_index: t.end_of_pass_write_index,
            }),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(wg[0], wg[1], 1);
    }

    fn shadow_map_passes(&self, enc: &mut wgpu::CommandEncoder, labels: &mut Vec<&'static str>) {
        let n = self.lights.len();
        let linear = self.settings.shadows == ShadowMethod::MapLinear;
        for v in 0..self.views.len() {
            let ts = self.timestamps(labels, "shadow maps");
            let color = linear.then(|| wgpu::RenderPassColorAttachment {
                view: &self.shadow.linear_layers[v],
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 1e30,
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            });
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map"),
                color_attachments: if color.is_some() {
                    std::slice::from_ref(&color)
                } else {
                    &[]
                },
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: if linear {
                        &self.shadow.linear_depth
                    } else {
                        &self.shadow.layers[v]
                    },
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: ts,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(if linear {
                &self.pipelines.shadow_linear
            } else {
                &self.pipelines.shadow_depth
            });
            pass.set_bind_group(0, &self.group0, &[((n + v) as u64 * SLOT) as u32]);
            pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
            pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            let li = self.view_light[v];
            for d in &self.scene.draws {
                if !self.reaches(li, &d.bounds) {
                    continue;
                }
                pass.set_bind_group(1, &self.scene.materials[d.material].bind_group, &[]);
                pass.draw_indexed(d.first_index..d.first_index + d.index_count, 0, 0..1);
            }
        }
    }

    /// Stencil marks of light `li` (volumes or planar projections) into the current pass.
    fn stencil_marks<'a>(&'a self, pass: &mut wgpu::RenderPass<'a>, li: usize, mask_target: bool) {
        let m = mask_target as usize;
        match self.settings.shadows {
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass => {
                let r = self.volume_ranges[li].clone();
                if r.is_empty() {
                    return;
                }
                pass.set_pipeline(if self.settings.shadows == ShadowMethod::VolumesZFail {
                    &self.pipelines.zfail[m]
                } else {
                    &self.pipelines.zpass[m]
                });
                pass.set_stencil_reference(0);
                pass.set_vertex_buffer(0, self.volume_buf.as_ref().expect("built").slice(..));
                pass.draw(r, 0..1);
            }
            ShadowMethod::Planar => {
                if self.planar[li].is_none() {
                    return;
                }
                pass.set_pipeline(&self.pipelines.planar[m]);
                pass.set_stencil_reference(1);
                pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
                pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
                let Some(p) = self.plane else {
                    return;
                };
                for d in &self.scene.draws {
                    // Only objects wholly above the plane cast onto it (the receiver would
                    // project onto itself).
                    let lowest = lights::box_corners(d.bounds)
                        .iter()
                        .map(|c| p.truncate().dot(*c) + p.w)
                        .fold(f32::INFINITY, f32::min);
                    if lowest < -1e-3 {
                        continue;
                    }
                    pass.set_bind_group(1, &self.scene.materials[d.material].bind_group, &[]);
                    pass.draw_indexed(d.first_index..d.first_index + d.index_count, 0, 0..1);
                }
            }
            _ => {}
        }
    }

    /// Record and submit one frame; returns its timings.
    pub fn render(&mut self, ctx: &GpuContext) -> FrameTimes {
        let t0 = Instant::now();
        let mut times = FrameTimes::default();
        if matches!(
            self.settings.shadows,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass
        ) {
            let tv = Instant::now();
            self.build_volumes(ctx);
            times.cpu_volumes_ms = tv.elapsed().as_secs_f64() * 1e3;
        }
        let mut labels = vec![];
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        self.relight_pass(&mut enc, &mut labels);
        if let Some(lpv) = &self.lpv {
            let queries = self.queries.as_ref();
            let labels = &mut labels;
            lpv.record(&mut enc, &self.scene, &mut |label| {
                timestamp_slot(queries, labels, label)
            });
        }
        if self.settings.shadows.map() {
            self.shadow_map_passes(&mut enc, &mut labels);
        }
        self.base_pass(
            &mut enc,
            &mut labels,
            self.settings.path == RenderPath::Deferred,
        );
        if self.frame.lpv_indirect_only == 0 {
            self.sky_pass(&mut enc, &mut labels);
            self.light_passes(&mut enc, &mut labels);
        }
        // Tonemap: the 8-bit frame a viewer would display.
        {
            let ts = self.timestamps(&mut labels, "tonemap");
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("tonemap"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.targets.ldr_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: ts,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipelines.tonemap);
            pass.set_bind_group(0, &self.group0, &[0]);
            pass.set_bind_group(1, &self.scene.materials[0].bind_group, &[]);
            pass.set_bind_group(2, &self.group2, &[]);
            pass.set_bind_group(3, &self.tonemap_group, &[]);
            pass.draw(0..3, 0..1);
        }
        if let Some((set, resolve, read)) = &self.queries
            && !labels.is_empty()
        {
            let count = 2 * labels.len() as u32;
            enc.resolve_query_set(set, 0..count, resolve, 0);
            enc.copy_buffer_to_buffer(resolve, 0, read, 0, count as u64 * 8);
        }
        ctx.queue.submit([enc.finish()]);
        if let Some((_, _, read)) = &self.queries
            && !labels.is_empty()
        {
            let slice = read.slice(..labels.len() as u64 * 16);
            slice.map_async(wgpu::MapMode::Read, |_| {});
            let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
            if let Ok(data) = slice.get_mapped_range() {
                let ticks: &[u64] = bytemuck::cast_slice(&data);
                let period = ctx.queue.get_timestamp_period() as f64;
                for (i, l) in labels.iter().enumerate() {
                    let dt = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period * 1e-6;
                    *times.gpu_ms.entry(l).or_default() += dt;
                }
            }
            read.unmap();
        } else {
            let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
        }
        times.wall_ms = t0.elapsed().as_secs_f64() * 1e3;
        times
    }

    /// Depth, ambient and emission (and the G-buffer when `deferred`).
    fn base_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        labels: &mut Vec<&'static str>,
        deferred: bool,
    ) {
        let clear = wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        };
        let depth_clear = Some(wgpu::RenderPassDepthStencilAttachment {
            view: &self.targets.depth_view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(0.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(0),
                store: wgpu::StoreOp::Store,
            }),
        });
        {
            let ts = self.timestamps(
                labels,
                if deferred {
                    "g-buffer"
                } else {
                    "depth+ambient"
                },
            );
            let att = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear,
                })
            };
            let mut colors = vec![att(&self.targets.hdr_view)];
            if deferred {
                colors.extend(self.targets.gbuffer.iter().map(att));
            }
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("base"),
                color_attachments: &colors,
                depth_stencil_attachment: depth_clear,
                timestamp_writes: ts,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.group0, &[0]);
            pass.set_bind_group(2, &self.group2, &[]);
            let pipes = if deferred {
                &self.pipelines.gbuffer
            } else {
                &self.pipelines.ambient
            };
            self.draw_scene(&mut pass, pipes, None);
        }
    }

    /// A pass adding to the HDR target over the frame's depth and stencil (kept).
    fn hdr_pass_loading_depth<'e>(
        &self,
        enc: &'e mut wgpu::CommandEncoder,
        labels: &mut Vec<&'static str>,
        label: &'static str,
    ) -> wgpu::RenderPass<'e> {
        let ts = self.timestamps(labels, label);
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.targets.hdr_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.targets.depth_view,
                depth_ops: Some(load_f32()),
                stencil_ops: Some(load_u32()),
            }),
            timestamp_writes: ts,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// The environment where no surface was drawn.
    fn sky_pass(&self, enc: &mut wgpu::CommandEncoder, labels: &mut Vec<&'static str>) {
        let Some(group) = &self.sky_group else {
            return;
        };
        let mut pass = self.hdr_pass_loading_depth(enc, labels, "sky");
        pass.set_pipeline(&self.pipelines.sky);
        pass.set_bind_group(0, &self.group0, &[0]);
        pass.set_bind_group(1, &self.scene.materials[0].bind_group, &[]);
        pass.set_bind_group(2, &self.group2, &[]);
        pass.set_bind_group(3, group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Per light: stencil marks, then its additive lighting pass.
    fn light_passes(&self, enc: &mut wgpu::CommandEncoder, labels: &mut Vec<&'static str>) {
        let deferred = self.settings.path == RenderPath::Deferred;
        for li in 0..self.light_pos.len() {
            let Some(sc) = self.scissor(li) else {
                continue;
            };
            let slot = [(li as u64 * SLOT) as u32];
            if self.settings.shadows.stencil() {
                let ts = self.timestamps(labels, "volumes");
                // Depth and stencil only: no colour target to load and store.
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("volumes"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &self.targets.depth_view,
                        depth_ops: Some(load_f32()),
                        stencil_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(0),
                            store: wgpu::StoreOp::Store,
                        }),
                    }),
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_scissor_rect(sc.0, sc.1, sc.2, sc.3);
                pass.set_bind_group(0, &self.group0, &slot);
                self.stencil_marks(&mut pass, li, false);
            }
            let mut pass = self.hdr_pass_loading_depth(enc, labels, "lighting");
            pass.set_scissor_rect(sc.0, sc.1, sc.2, sc.3);
            pass.set_stencil_reference(0);
            pass.set_bind_group(0, &self.group0, &slot);
            pass.set_bind_group(2, &self.group2, &[]);
            if deferred {
                pass.set_pipeline(&self.pipelines.deferred_light);
                pass.set_bind_group(1, &self.scene.materials[0].bind_group, &[]);
                pass.set_bind_group(3, &self.group3, &[]);
                pass.draw(0..3, 0..1);
            } else {
                self.draw_scene(&mut pass, &self.pipelines.light, Some(li));
            }
        }
    }
}

fn load_f32() -> wgpu::Operations<f32> {
    wgpu::Operations {
        load: wgpu::LoadOp::Load,
        store: wgpu::StoreOp::Store,
    }
}

fn load_u32() -> wgpu::Operations<u32> {
    wgpu::Operations {
        load: wgpu::LoadOp::Load,
        store: wgpu::StoreOp::Store,
    }
}

/// One render pipeline from the shared module.
struct PipeDesc<'a> {
    label: &'a str,
    layout: &'a wgpu::PipelineLayout,
    vs: &'a str,
    buffers: &'a [wgpu::VertexBufferLayout<'a>],
    fs: Option<&'a str>,
    targets: &'a [Option<wgpu::ColorTargetState>],
    depth: Option<wgpu::DepthStencilState>,
    cull: Option<wgpu::Face>,
}

fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    d: PipeDesc,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(d.label),
        layout: Some(d.layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(d.vs),
            compilation_options: Default::default(),
            buffers: &d.buffers.iter().cloned().map(Some).collect::<Vec<_>>(),
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            front_face: wgpu::FrontFace::Ccw,
            cull_mode: d.cull,
            ..Default::default()
        },
        depth_stencil: d.depth,
        multisample: Default::default(),
        fragment: d.fs.map(|fs| wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: Default::default(),
            targets: d.targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn stencil_face(
    compare: wgpu::CompareFunction,
    depth_fail: wgpu::StencilOperation,
    pass: wgpu::StencilOperation,
) -> wgpu::StencilFaceState {
    wgpu::StencilFaceState {
        compare,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: depth_fail,
        pass_op: pass,
    }
}

fn depth_state(
    write: bool,
    compare: wgpu::CompareFunction,
    front: wgpu::StencilFaceState,
    back: wgpu::StencilFaceState,
    write_mask: u32,
    bias: wgpu::DepthBiasState,
) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState {
            front,
            back,
            read_mask: 0xff,
            write_mask,
        },
        bias,
    })
}

impl Pipelines {
    fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        s: &RasterSettings,
        layouts: [&wgpu::PipelineLayout; 6],
        gb_formats: [wgpu::TextureFormat; 4],
        linear_format: wgpu::TextureFormat,
    ) -> Pipelines {
        use wgpu::CompareFunction as C;
        use wgpu::StencilOperation as Op;
        let [
            pl_scene,
            pl_deferred,
            pl_shadow,
            pl_frame,
            pl_tonemap,
            pl_sky,
        ] = layouts;
        let keep = stencil_face(C::Always, Op::Keep, Op::Keep);
        let eq0 = stencil_face(C::Equal, Op::Keep, Op::Keep);
        let no_bias = wgpu::DepthBiasState::default();
        let hdr = |blend| {
            Some(wgpu::ColorTargetState {
                format: HDR,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let add = Some(wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent::REPLACE,
        });
        let silent = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::empty(),
            })
        };
        let mask_target = Some(wgpu::ColorTargetState {
            format: MASK,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        });
        let vl = [vertex_layout()];
        let volume_layout = [wgpu::VertexBufferLayout {
            array_stride: 16,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x4],
        }];
        let cull = |double_sided: bool| (!double_sided).then_some(wgpu::Face::Back);
        let both = |f: &dyn Fn(bool) -> wgpu::RenderPipeline| [f(false), f(true)];
        let gb_targets: Vec<Option<wgpu::ColorTargetState>> = std::iter::once(hdr(None))
            .chain(gb_formats.iter().map(|f| {
                Some(wgpu::ColorTargetState {
                    format: *f,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })
            }))
            .collect();
        let ambient = both(&|ds| {
            pipeline(
                device,
                module,
                PipeDesc {
                    label: "ambient",
                    layout: pl_scene,
                    vs: "scene_vs",
                    buffers: &vl,
                    fs: Some("ambient_fs"),
                    targets: &[hdr(None)],
                    depth: depth_state(true, C::Greater, keep, keep, 0, no_bias),
                    cull: cull(ds),
                },
            )
        });
        let gbuffer = both(&|ds| {
            pipeline(
                device,
                module,
                PipeDesc {
                    label: "g-buffer",
                    layout: pl_scene,
                    vs: "scene_vs",
                    buffers: &vl,
                    fs: Some("gbuffer_fs"),
                    targets: &gb_targets,
                    depth: depth_state(true, C::Greater, keep, keep, 0, no_bias),
                    cull: cull(ds),
                },
            )
        });
        let light = both(&|ds| {
            pipeline(
                device,
                module,
                PipeDesc {
                    label: "light",
                    layout: pl_scene,
                    vs: "scene_vs",
                    buffers: &vl,
                    fs: Some("light_fs"),
                    targets: &[hdr(add)],
                    depth: depth_state(false, C::Equal, eq0, eq0, 0, no_bias),
                    cull: cull(ds),
                },
            )
        });
        let deferred_light = pipeline(
            device,
            module,
            PipeDesc {
                label: "deferred light",
                layout: pl_deferred,
                vs: "fullscreen_vs",
                buffers: &[],
                fs: Some("deferred_light_fs"),
                targets: &[hdr(add)],
                depth: depth_state(false, C::Always, eq0, eq0, 0, no_bias),
                cull: None,
            },
        );
        // Volumes: two-sided stencil with wrapping counts (one pass, both faces).
        let zfail_front = stencil_face(C::Always, Op::DecrementWrap, Op::Keep);
        let zfail_back = stencil_face(C::Always, Op::IncrementWrap, Op::Keep);
        let zpass_front = stencil_face(C::Always, Op::Keep, Op::IncrementWrap);
        let zpass_back = stencil_face(C::Always, Op::Keep, Op::DecrementWrap);
        // Variant 0 (the frame's stencil passes) has no fragment stage and no colour target;
        // variant 1 writes the test masks.
        let targets2 = [silent(MASK)];
        let no_targets: &[Option<wgpu::ColorTargetState>] = &[];
        let volume = |label, front, back| {
            [0, 1].map(|m| {
                pipeline(
                    device,
                    module,
                    PipeDesc {
                        label,
                        layout: pl_frame,
                        vs: "volume_vs",
                        buffers: &volume_layout,
                        fs: (m == 1).then_some("volume_fs"),
                        targets: if m == 1 { &targets2 } else { no_targets },
                        depth: depth_state(false, C::Greater, front, back, 0xff, no_bias),
                        cull: None,
                    },
                )
            })
        };
        let zfail = volume("z-fail volumes", zfail_front, zfail_back);
        let zpass = volume("z-pass volumes", zpass_front, zpass_back);
        let replace = stencil_face(C::Always, Op::Keep, Op::Replace);
        // Projected casters lie on the receiver: pull them towards the viewer (reversed depth:
        // a positive bias is nearer) so they pass against the receiver's own depth.
        let toward = wgpu::DepthBiasState {
            constant: 16,
            slope_scale: 2.0,
            clamp: 0.0,
        };
        let planar = [0, 1].map(|m| {
            pipeline(
                device,
                module,
                PipeDesc {
                    label: "planar shadows",
                    // The material group: the vertex stage sways foliage like the other passes.
                    layout: pl_shadow,
                    vs: "planar_vs",
                    buffers: &vl,
                    fs: (m == 1).then_some("volume_fs"),
                    targets: if m == 1 { &targets2 } else { no_targets },
                    depth: depth_state(false, C::GreaterEqual, replace, replace, 0xff, toward),
                    cull: None,
                },
            )
        });
        let mask = pipeline(
            device,
            module,
            PipeDesc {
                label: "stencil mask",
                layout: pl_frame,
                vs: "fullscreen_vs",
                buffers: &[],
                fs: Some("mask_fs"),
                targets: std::slice::from_ref(&mask_target),
                depth: depth_state(false, C::Always, eq0, eq0, 0, no_bias),
                cull: None,
            },
        );
        let map_mask = pipeline(
            device,
            module,
            PipeDesc {
                label: "shadow-map mask",
                layout: pl_deferred,
                vs: "fullscreen_vs",
                buffers: &[],
                fs: Some("shadow_map_mask_fs"),
                targets: &[mask_target],
                depth: None,
                cull: None,
            },
        );
        let shadow_ds = |bias| {
            Some(wgpu::DepthStencilState {
                format: SHADOW_DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(C::Less),
                stencil: Default::default(),
                bias,
            })
        };
        let shadow_depth = pipeline(
            device,
            module,
            PipeDesc {
                label: "shadow depth",
                layout: pl_shadow,
                vs: "shadow_vs",
                buffers: &vl,
                fs: Some("shadow_depth_fs"),
                targets: &[],
                depth: shadow_ds(wgpu::DepthBiasState {
                    constant: s.constant_bias,
                    slope_scale: s.slope_bias,
                    clamp: 0.0,
                }),
                cull: None,
            },
        );
        let shadow_linear = pipeline(
            device,
            module,
            PipeDesc {
                label: "shadow linear depth",
                layout: pl_shadow,
                vs: "shadow_vs",
                buffers: &vl,
                fs: Some("shadow_linear_fs"),
                targets: &[Some(wgpu::ColorTargetState {
                    format: linear_format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                depth: shadow_ds(no_bias),
                cull: None,
            },
        );
        let tonemap = pipeline(
            device,
            module,
            PipeDesc {
                label: "tonemap",
                layout: pl_tonemap,
                vs: "fullscreen_vs",
                buffers: &[],
                fs: Some("tonemap_fs"),
                targets: &[Some(wgpu::ColorTargetState {
                    format: wgpu::TextureFormat::Rgba8Unorm,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                depth: None,
                cull: None,
            },
        );
        // Where the depth buffer is still clear (reversed depth: 0), the environment.
        let sky = pipeline(
            device,
            module,
            PipeDesc {
                label: "sky",
                layout: pl_sky,
                vs: "fullscreen_vs",
                buffers: &[],
                fs: Some("sky_fs"),
                targets: &[hdr(None)],
                depth: depth_state(false, C::Equal, keep, keep, 0, no_bias),
                cull: None,
            },
        );
        Pipelines {
            ambient,
            light,
            gbuffer,
            deferred_light,
            zfail,
            zpass,
            planar,
            mask,
            map_mask,
            shadow_depth,
            shadow_linear,
            tonemap,
            sky,
        }
    }
}

/// Copy a texture (tightly packed texels of `bpp` bytes) to the CPU. The texture needs
/// `COPY_SRC` usage.
pub fn read_texture(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    bpp: u32,
) -> Result<Vec<u8>, RasterError> {
    let (w, h, layers) = (tex.width(), tex.height(), tex.depth_or_array_layers());
    let row = (w * bpp).div_ceil(256) * 256;
    let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: (row * h * layers) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        tex.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buf,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        tex.size(),
    );
    ctx.queue.submit([enc.finish()]);
    let slice = buf.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RasterError::Readback(e.to_string()))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| RasterError::Readback(e.to_string()))?;
    let mut out = Vec::with_capacity((w * h * layers * bpp) as usize);
    for y in 0..h * layers {
        out.extend_from_slice(&data[(y * row) as usize..][..(w * bpp) as usize]);
    }
    Ok(out)
}

impl Renderer {
    /// The last frame's linear radiance.
    pub fn read_hdr(&self, ctx: &GpuContext) -> Result<Image, RasterError> {
        let bytes = read_texture(ctx, &self.targets.hdr, 8)?;
        let halves: &[half::f16] = bytemuck::cast_slice(&bytes);
        let mut img = Image::new(self.settings.width, self.settings.height);
        for (px, c) in img.data.iter_mut().zip(halves.chunks_exact(4)) {
            *px = Vec3::new(c[0].to_f32(), c[1].to_f32(), c[2].to_f32());
        }
        Ok(img)
    }

    /// The last frame's G-buffer (deferred path only), row-major per layer: diffuse
    /// reflectance + dielectric F0, shading normal + roughness, F0 + (model + transmission),
    /// camera-relative position + 1 (0 where nothing was drawn).
    pub fn read_gbuffer(&self, ctx: &GpuContext) -> Result<Vec<Vec<[f32; 4]>>, RasterError> {
        if self.settings.path != RenderPath::Deferred {
            return Err(RasterError::Settings(
                "only the deferred path writes a G-buffer".into(),
            ));
        }
        self.targets
            .gbuffer_textures
            .iter()
            .map(|t| {
                let bytes = read_texture(ctx, t, t.format().block_copy_size(None).unwrap_or(8))?;
                Ok(if t.format() == wgpu::TextureFormat::Rgba32Float {
                    bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec()
                } else {
                    bytemuck::cast_slice::<u8, [half::f16; 4]>(&bytes)
                        .iter()
                        .map(|c| c.map(|v| v.to_f32()))
                        .collect()
                })
            })
            .collect()
    }

    /// Per light, which pixels the shadow method lets the light reach (255) or not (0),
    /// row-major. Renders a G-buffer for it, so call it on its own (not between frames).
    pub fn shadow_masks(&mut self, ctx: &GpuContext) -> Result<Vec<Vec<u8>>, RasterError> {
        if matches!(
            self.settings.shadows,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass
        ) {
            self.build_volumes(ctx);
        }
        let mut labels = vec![];
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        self.relight_pass(&mut enc, &mut labels);
        if self.settings.shadows.map() {
            self.shadow_map_passes(&mut enc, &mut labels);
        }
        self.base_pass(&mut enc, &mut labels, true);
        ctx.queue.submit([enc.finish()]);
        let mut masks = vec![];
        for li in 0..self.light_pos.len() {
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            {
                let map = self.settings.shadows.map();
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("mask"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &self.targets.mask_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: (!map).then(|| {
                        wgpu::RenderPassDepthStencilAttachment {
                            view: &self.targets.depth_view,
                            depth_ops: Some(load_f32()),
                            stencil_ops: Some(wgpu::Operations {
                                load: wgpu::LoadOp::Clear(0),
                                store: wgpu::StoreOp::Store,
                            }),
                        }
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, &self.group0, &[(li as u64 * SLOT) as u32]);
                if map {
                    pass.set_pipeline(&self.pipelines.map_mask);
                    pass.set_bind_group(1, &self.scene.materials[0].bind_group, &[]);
                    pass.set_bind_group(2, &self.group2, &[]);
                    pass.set_bind_group(3, &self.group3, &[]);
                } else {
                    self.stencil_marks(&mut pass, li, true);
                    pass.set_pipeline(&self.pipelines.mask);
                    pass.set_stencil_reference(0);
                }
                pass.draw(0..3, 0..1);
            }
            ctx.queue.submit([enc.finish()]);
            masks.push(read_texture(ctx, &self.targets.mask, 1)?);
        }
        Ok(masks)
    }
}
