//! Helpers shared by the light-map GPU tests.

use lightlab_bake::Lightmaps;
use lightlab_gpu::gpu_scene::UvRect;

/// The GPU's per-instance light-map rectangles of a bake.
pub fn uv_rects(lm: &Lightmaps) -> Vec<Option<UvRect>> {
    lm.layout
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
