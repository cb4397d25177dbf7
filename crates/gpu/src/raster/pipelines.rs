//! The render pipelines of the renderer, all from the one WGSL module: the scene passes
//! (ambient, G-buffer, lighting), the stencil passes (volumes, planar projections, test
//! masks), and the shadow-map and full-screen passes (tonemap, sky).

use super::bindings::PipelineLayouts;
use super::settings::RasterSettings;
use super::targets::{DEPTH, HDR, MASK, SHADOW_DEPTH};
use crate::gpu_scene::vertex_layout;
use std::sync::{Arc, OnceLock};
use wgpu::CompareFunction as C;
use wgpu::StencilOperation as Op;

/// Every render pipeline of a renderer, `[single-sided, double-sided]` where materials choose.
/// Each is compiled on first use ([`Lazy`]).
pub(super) struct Pipelines {
    pub(super) ambient: [Lazy; 2],
    pub(super) light: [Lazy; 2],
    pub(super) gbuffer: [Lazy; 2],
    pub(super) deferred_light: Lazy,
    pub(super) zfail: [Lazy; 2],
    pub(super) zpass: [Lazy; 2],
    pub(super) planar: [Lazy; 2],
    pub(super) mask: Lazy,
    pub(super) map_mask: Lazy,
    pub(super) shadow_depth: Lazy,
    pub(super) shadow_linear: Lazy,
    pub(super) tonemap: Lazy,
    pub(super) sky: Lazy,
}

/// A render pipeline compiled when a frame first needs it. A renderer has twenty pipelines and
/// a frame uses a handful (the forward path never draws the G-buffer, a shadow-map frame no
/// stencil volumes); software drivers (lavapipe) spend seconds compiling each fragment stage
/// of the lighting module, so making them all up front dominated a renderer's start-up.
pub(super) struct Lazy {
    made: OnceLock<wgpu::RenderPipeline>,
    maker: Arc<Maker>,
    desc: Desc,
}

impl Lazy {
    pub(super) fn get(&self) -> &wgpu::RenderPipeline {
        self.made.get_or_init(|| self.maker.make(&self.desc))
    }
}

/// One render pipeline from the shared module.
#[derive(Clone)]
struct Desc {
    label: &'static str,
    layout: wgpu::PipelineLayout,
    vs: &'static str,
    buffers: Vec<wgpu::VertexBufferLayout<'static>>,
    fs: Option<&'static str>,
    targets: Vec<Option<wgpu::ColorTargetState>>,
    depth: Option<wgpu::DepthStencilState>,
    cull: Option<wgpu::Face>,
}

/// The device, module and winding every pipeline is made with.
struct Maker {
    device: wgpu::Device,
    module: wgpu::ShaderModule,
    /// Clockwise in a planar mirror's reflected view (the reflection flips the winding).
    front_face: wgpu::FrontFace,
}

impl Maker {
    fn make(&self, d: &Desc) -> wgpu::RenderPipeline {
        let buffers: Vec<_> = d.buffers.iter().cloned().map(Some).collect();
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(d.label),
                layout: Some(&d.layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some(d.vs),
                    compilation_options: Default::default(),
                    buffers: &buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: self.front_face,
                    cull_mode: d.cull,
                    ..Default::default()
                },
                depth_stencil: d.depth.clone(),
                multisample: Default::default(),
                fragment: d.fs.map(|fs| wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &d.targets,
                }),
                multiview_mask: None,
                cache: None,
            })
    }
}

/// Recipes for lazy pipelines.
struct Lazies(Arc<Maker>);

impl Lazies {
    fn lazy(&self, desc: Desc) -> Lazy {
        Lazy {
            made: OnceLock::new(),
            maker: self.0.clone(),
            desc,
        }
    }

    /// A scene pass over the mesh vertices, single- and double-sided.
    fn scene_pass(
        &self,
        label: &'static str,
        layout: &wgpu::PipelineLayout,
        fs: &'static str,
        targets: &[Option<wgpu::ColorTargetState>],
        depth: Option<wgpu::DepthStencilState>,
    ) -> [Lazy; 2] {
        [false, true].map(|ds| {
            self.lazy(Desc {
                label,
                layout: layout.clone(),
                vs: "scene_vs",
                buffers: vec![vertex_layout()],
                fs: Some(fs),
                targets: targets.to_vec(),
                depth: depth.clone(),
                cull: cull(ds),
            })
        })
    }

    /// A full-screen triangle pass.
    fn screen_pass(
        &self,
        label: &'static str,
        layout: &wgpu::PipelineLayout,
        fs: &'static str,
        targets: &[Option<wgpu::ColorTargetState>],
        depth: Option<wgpu::DepthStencilState>,
    ) -> Lazy {
        self.lazy(Desc {
            label,
            layout: layout.clone(),
            vs: "fullscreen_vs",
            buffers: vec![],
            fs: Some(fs),
            targets: targets.to_vec(),
            depth,
            cull: None,
        })
    }
}

impl Pipelines {
    pub(super) fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        s: &RasterSettings,
        layouts: &PipelineLayouts,
        gb_formats: [wgpu::TextureFormat; 5],
        linear_format: wgpu::TextureFormat,
        mirrored: bool,
    ) -> Pipelines {
        let m = Lazies(Arc::new(Maker {
            device: device.clone(),
            module: module.clone(),
            front_face: if mirrored {
                wgpu::FrontFace::Cw
            } else {
                wgpu::FrontFace::Ccw
            },
        }));
        let no_bias = wgpu::DepthBiasState::default();
        let gb_targets: Vec<_> = std::iter::once(hdr(None))
            .chain(gb_formats.iter().map(|f| plain(*f)))
            .collect();
        let write = depth_state(true, C::Greater, keep(), keep(), 0, no_bias);
        let lit = depth_state(false, C::Equal, eq0(), eq0(), 0, no_bias);
        let [zfail, zpass, planar] = stencil_pipelines(&m, layouts);
        let [shadow_depth, shadow_linear] = shadow_pipelines(&m, layouts, s, linear_format);
        let l = layouts;
        Pipelines {
            ambient: m.scene_pass(
                "ambient",
                &l.scene,
                "ambient_fs",
                &[hdr(None)],
                write.clone(),
            ),
            gbuffer: m.scene_pass("g-buffer", &l.scene, "gbuffer_fs", &gb_targets, write),
            light: m.scene_pass("light", &l.scene, "light_fs", &[hdr(Some(ADD))], lit),
            deferred_light: m.screen_pass(
                "deferred light",
                &l.deferred,
                "deferred_light_fs",
                &[hdr(Some(ADD))],
                depth_state(false, C::Always, eq0(), eq0(), 0, no_bias),
            ),
            zfail,
            zpass,
            planar,
            mask: m.screen_pass(
                "stencil mask",
                &l.frame,
                "mask_fs",
                &[plain(MASK)],
                depth_state(false, C::Always, eq0(), eq0(), 0, no_bias),
            ),
            map_mask: m.screen_pass(
                "shadow-map mask",
                &l.deferred,
                "shadow_map_mask_fs",
                &[plain(MASK)],
                None,
            ),
            shadow_depth,
            shadow_linear,
            tonemap: m.screen_pass(
                "tonemap",
                &l.tonemap,
                "tonemap_fs",
                &[plain(wgpu::TextureFormat::Rgba8Unorm)],
                None,
            ),
            // Where the depth buffer is still clear (reversed depth: 0), the environment.
            sky: m.screen_pass(
                "sky",
                &l.sky,
                "sky_fs",
                &[hdr(None)],
                depth_state(false, C::Equal, keep(), keep(), 0, no_bias),
            ),
        }
    }
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

/// Stencil always passes and keeps; stencil must be 0.
fn keep() -> wgpu::StencilFaceState {
    stencil_face(C::Always, Op::Keep, Op::Keep)
}
fn eq0() -> wgpu::StencilFaceState {
    stencil_face(C::Equal, Op::Keep, Op::Keep)
}

/// The HDR target, with `blend`.
fn hdr(blend: Option<wgpu::BlendState>) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format: HDR,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A target written as is.
fn plain(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// Additive blending (one lighting pass per light).
const ADD: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent::REPLACE,
};

fn cull(double_sided: bool) -> Option<wgpu::Face> {
    (!double_sided).then_some(wgpu::Face::Back)
}

/// z-fail volumes, z-pass volumes and planar projections, each `[frame, test mask]`: the
/// frame's stencil passes have no fragment stage and no colour target; the test masks write
/// a silent mask target.
fn stencil_pipelines(m: &Lazies, layouts: &PipelineLayouts) -> [[Lazy; 2]; 3] {
    const VOLUME_ATTRIBUTES: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x4];
    let no_bias = wgpu::DepthBiasState::default();
    let silent = vec![Some(wgpu::ColorTargetState {
        format: MASK,
        blend: None,
        write_mask: wgpu::ColorWrites::empty(),
    })];
    let volume_layout = wgpu::VertexBufferLayout {
        array_stride: 16,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VOLUME_ATTRIBUTES,
    };
    // Volumes: two-sided stencil with wrapping counts (one pass, both faces).
    let volume = |label, front, back| {
        [0, 1].map(|k| {
            m.lazy(Desc {
                label,
                layout: layouts.frame.clone(),
                vs: "volume_vs",
                buffers: vec![volume_layout.clone()],
                fs: (k == 1).then_some("volume_fs"),
                targets: if k == 1 { silent.clone() } else { vec![] },
                depth: depth_state(false, C::Greater, front, back, 0xff, no_bias),
                cull: None,
            })
        })
    };
    let zfail = volume(
        "z-fail volumes",
        stencil_face(C::Always, Op::DecrementWrap, Op::Keep),
        stencil_face(C::Always, Op::IncrementWrap, Op::Keep),
    );
    let zpass = volume(
        "z-pass volumes",
        stencil_face(C::Always, Op::Keep, Op::IncrementWrap),
        stencil_face(C::Always, Op::Keep, Op::DecrementWrap),
    );
    let replace = stencil_face(C::Always, Op::Keep, Op::Replace);
    // Projected casters lie on the receiver: pull them towards the viewer (reversed depth:
    // a positive bias is nearer) so they pass against the receiver's own depth.
    let toward = wgpu::DepthBiasState {
        constant: 16,
        slope_scale: 2.0,
        clamp: 0.0,
    };
    let planar = [0, 1].map(|k| {
        m.lazy(Desc {
            label: "planar shadows",
            // The material group: the vertex stage sways foliage like the other passes.
            layout: layouts.shadow.clone(),
            vs: "planar_vs",
            buffers: vec![vertex_layout()],
            fs: (k == 1).then_some("volume_fs"),
            targets: if k == 1 { silent.clone() } else { vec![] },
            depth: depth_state(false, C::GreaterEqual, replace, replace, 0xff, toward),
            cull: None,
        })
    });
    [zfail, zpass, planar]
}

/// The shadow-map passes: hardware depth (with the settings' bias), and Heidrich's linear
/// depth into a colour target.
fn shadow_pipelines(
    m: &Lazies,
    layouts: &PipelineLayouts,
    s: &RasterSettings,
    linear_format: wgpu::TextureFormat,
) -> [Lazy; 2] {
    let shadow_ds = |bias| {
        Some(wgpu::DepthStencilState {
            format: SHADOW_DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(C::Less),
            stencil: Default::default(),
            bias,
        })
    };
    let depth_bias = wgpu::DepthBiasState {
        constant: s.constant_bias,
        slope_scale: s.slope_bias,
        clamp: 0.0,
    };
    let pass = |label, fs, targets: Vec<Option<wgpu::ColorTargetState>>, bias| {
        m.lazy(Desc {
            label,
            layout: layouts.shadow.clone(),
            vs: "shadow_vs",
            buffers: vec![vertex_layout()],
            fs: Some(fs),
            targets,
            depth: shadow_ds(bias),
            cull: None,
        })
    };
    [
        pass("shadow depth", "shadow_depth_fs", vec![], depth_bias),
        pass(
            "shadow linear depth",
            "shadow_linear_fs",
            vec![plain(linear_format)],
            wgpu::DepthBiasState::default(),
        ),
    ]
}
