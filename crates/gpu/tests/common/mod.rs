//! Helpers shared by the light-map and SH GPU tests.

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
