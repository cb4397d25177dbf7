//! Helpers shared by the GPU tests.

use lightlab_bake::Lightmaps;
use lightlab_gpu::gpu_scene::UvRect;

/// The GPU's per-instance light-map rectangles of a bake.
#[allow(dead_code)]
pub fn uv_rects(lm: &Lightmaps) -> Vec<Option<UvRect>> {
    layout_rects(&lm.layout)
}

/// The GPU's per-instance rectangles of a light-map layout.
#[allow(dead_code)]
pub fn layout_rects(layout: &lightlab_bake::layout::Layout) -> Vec<Option<UvRect>> {
    layout
        .instances
        .iter()
        .map(|r| {
            r.map(|r| UvRect {
                page: r.page,
                offset: r.offset,
                scale: r.scale,
            })
        })
        .collect()
}

/// The path tracer's direct light (emission seen + one scattering event) from the scene's
/// first camera.
#[allow(dead_code)]
pub fn traced_direct(
    scene: &lightlab_scene::Scene,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
) -> lightlab_core::image::Image {
    let accel = lightlab_trace::Accel::new(scene);
    lightlab_trace::PathTracer::new(scene, &accel)
        .render(
            &lightlab_trace::RenderSettings {
                width,
                height,
                spp,
                max_depth: 1,
                min_depth: 0,
                seed,
                camera: 0,
                lens: Default::default(),
            },
            &|_, _| true,
        )
        .unwrap()
}

/// `scene` on the GPU with shadow maps and the occluded sky, 2 × 2 supersampled.
#[allow(dead_code)]
pub fn shadow_mapped_sky(
    ctx: &lightlab_gpu::GpuContext,
    scene: &lightlab_scene::Scene,
    w: u32,
    h: u32,
) -> lightlab_core::image::Image {
    use lightlab_gpu::raster::{Ambient, RasterSettings, Renderer, ShadowMethod};
    let mut r = Renderer::new(
        ctx,
        scene,
        RasterSettings {
            width: w * 2,
            height: h * 2,
            shadows: ShadowMethod::Map,
            ambient: Ambient::Environment,
            ..Default::default()
        },
    )
    .unwrap();
    r.render(ctx);
    r.read_hdr(ctx).unwrap().downsample(2)
}
