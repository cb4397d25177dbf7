//! The renderer's render targets (HDR colour, depth and stencil, G-buffer, the mask of the
//! shadow tests, the 8-bit frame), its shadow-map layers, and the environment texture of the
//! sky pass.

use super::settings::{RasterSettings, ShadowMethod};
use crate::GpuContext;
use crate::resources::{array_view, layer_view, texture, write_layer};

pub(super) const HDR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub(super) const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;
pub(super) const SHADOW_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
pub(super) const MASK: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// G-buffer formats: diffuse + dielectric F0, normal + roughness, F0 + model, the
/// camera-relative position (32-bit float where renderable, else 16-bit: GLES), and the
/// anisotropic lobes' tangent angle and parameters.
pub(super) fn gbuffer_formats(ctx: &GpuContext) -> [wgpu::TextureFormat; 5] {
    let f16 = wgpu::TextureFormat::Rgba16Float;
    [
        f16,
        f16,
        f16,
        renderable_or(ctx, wgpu::TextureFormat::Rgba32Float, f16),
        f16,
    ]
}

/// `want` if the adapter can render to it, else `fallback`.
pub(super) fn renderable_or(
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

/// The colour, depth and G-buffer targets at the frame's size.
pub(super) struct Targets {
    pub(super) hdr: wgpu::Texture,
    pub(super) hdr_view: wgpu::TextureView,
    pub(super) depth_view: wgpu::TextureView,
    pub(super) gbuffer: Vec<wgpu::TextureView>,
    pub(super) gbuffer_textures: Vec<wgpu::Texture>,
    pub(super) mask: wgpu::Texture,
    pub(super) mask_view: wgpu::TextureView,
    pub(super) ldr_view: wgpu::TextureView,
}

/// Shadow-map storage: one layer per shadow view.
pub(super) struct ShadowMaps {
    pub(super) layers: Vec<wgpu::TextureView>,
    pub(super) linear_layers: Vec<wgpu::TextureView>,
    pub(super) linear_depth: wgpu::TextureView,
}

impl Targets {
    pub(super) fn new(ctx: &GpuContext, s: &RasterSettings) -> Targets {
        let device = &ctx.device;
        let rt = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
        let copy = wgpu::TextureUsages::COPY_SRC;
        let target =
            |label, format, usage| texture(device, label, s.width, s.height, 1, format, usage);
        let hdr = target("hdr", HDR, rt | sampled | copy);
        let depth = target("depth", DEPTH, rt);
        let gbuffer_textures: Vec<wgpu::Texture> = gbuffer_formats(ctx)
            .iter()
            .map(|f| target("g-buffer", *f, rt | sampled | copy))
            .collect();
        let gbuffer = gbuffer_textures
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let mask = target("mask", MASK, rt | copy);
        let ldr = target("ldr", wgpu::TextureFormat::Rgba8Unorm, rt);
        Targets {
            hdr_view: hdr.create_view(&Default::default()),
            hdr,
            depth_view: depth.create_view(&Default::default()),
            gbuffer,
            gbuffer_textures,
            mask_view: mask.create_view(&Default::default()),
            mask,
            ldr_view: ldr.create_view(&Default::default()),
        }
    }
}

/// The shadow maps' arrays as the lighting passes bind them: depths, and the linear depths of
/// Heidrich's variant (else the depths again: the area lights' blocker search reads them).
pub(super) struct ShadowArrays {
    pub depth: wgpu::TextureView,
    pub linear: wgpu::TextureView,
}

impl ShadowMaps {
    /// One layer per shadow view (at least one), at the settings' size when maps are used.
    pub(super) fn new(
        ctx: &GpuContext,
        s: &RasterSettings,
        views: usize,
        linear_format: wgpu::TextureFormat,
    ) -> (ShadowMaps, ShadowArrays) {
        let device = &ctx.device;
        let rt = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
        // GL decides a texture's target at creation and makes a six-layer texture a cube map,
        // which cannot be read as an array: one spare layer for a scene whose only shadows are
        // one point (or area) light's six faces.
        let layers = match views.max(1) as u32 {
            6 => 7,
            n => n,
        };
        let ss = if s.shadows.map() { s.shadow_size } else { 1 };
        let linear = s.shadows == ShadowMethod::MapLinear;
        let linear_layers = if linear { layers } else { 1 };
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
        let maps = ShadowMaps {
            layers: (0..layers).map(|i| layer_view(&sd, i)).collect(),
            linear_layers: (0..linear_layers).map(|i| layer_view(&sl, i)).collect(),
            linear_depth: sld.create_view(&Default::default()),
        };
        let depth = array_view(&sd);
        // Without Heidrich's linear depths, the linear binding reads the raw depths of the
        // shadow maps (Depth32Float as unfilterable float; GLSL cannot read a `texture_depth`
        // binding texel by texel): the area lights' blocker search.
        let linear = if linear {
            array_view(&sl)
        } else {
            array_view(&sd)
        };
        (maps, ShadowArrays { depth, linear })
    }
}

/// The environment map as an Rgba32Float texture of radiance × intensity.
pub(super) fn env_texture(
    ctx: &GpuContext,
    env: &lightlab_scene::Environment,
) -> wgpu::TextureView {
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
    write_layer(ctx, &tex, 0, bytemuck::cast_slice(&data), w * 16, [w, h]);
    tex.create_view(&Default::default())
}
