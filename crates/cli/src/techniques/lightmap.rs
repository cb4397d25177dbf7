//! `lightmap` (baked light only) and `lightmap+phong` (baked indirect light plus the real-time
//! lights with shadow volumes): Fuchs 2005 §3.4 on the GPU, with light-maps from `--baked` or
//! baked now with path-traced gathering.

use super::{Bakes, Request};
use crate::options::BakeArgs;
use crate::progress::with_progress_bar;
use anyhow::Result;
use lightlab_bake::{BakeSettings, LightMode, Lightmaps, Method, bake_lightmaps, output};
use lightlab_gpu::GpuContext;
use lightlab_gpu::gpu_scene::UvRect;
use lightlab_gpu::raster::{LightmapInput, Renderer};
use lightlab_scene::Scene;

/// Bake light-maps with a progress bar on stderr.
pub fn bake_with_progress(scene: &Scene, settings: &BakeSettings) -> Result<Lightmaps> {
    let lm = with_progress_bar(
        format!("{} {}", scene.name, settings.method.name()),
        |progress| bake_lightmaps(scene, settings, progress),
    )?;
    warn_regenerated(&lm.layout);
    Ok(lm)
}

/// Print the layout's notes on authored TEXCOORD_1 sets it did not use as warnings.
pub fn warn_regenerated(layout: &lightlab_bake::layout::Layout) {
    for r in &layout.regenerated {
        eprintln!("lightlab: warning: {r}");
    }
}

/// The bake settings of a light-map technique: all lights baked for `lightmap`; for
/// `lightmap+phong` punctual lights bake only their indirect light, since their direct light
/// is drawn in real time (unless `--light-mode` says otherwise).
fn bake_settings(scene: &Scene, real_time_lights: bool, args: &BakeArgs) -> Result<BakeSettings> {
    let mut settings = args.settings(scene, Method::Path)?;
    if real_time_lights && args.light_mode.is_empty() {
        settings.light_modes = vec![LightMode::IndirectOnly; scene.lights.len()];
    }
    Ok(settings)
}

/// The light-maps of the request: read from `--baked`, or baked now; either way once per
/// folder or settings in `bakes`.
pub fn lightmaps<'b>(req: &Request, bakes: &'b mut Bakes) -> Result<&'b Lightmaps> {
    let real_time_lights = req.technique == crate::technique::Technique::LightmapPhong;
    let key = match &req.args.baked {
        Some(dir) => format!("dir {}", dir.display()),
        None => {
            serde_json::to_string(&bake_settings(req.scene, real_time_lights, &req.args.bake)?)?
        }
    };
    if !bakes.lightmaps.contains_key(&key) {
        let lm = match &req.args.baked {
            Some(dir) => output::read(dir, req.scene)?,
            None => {
                let a = &req.args.bake;
                eprintln!(
                    "no --baked folder: baking {} light-maps now (path, {} texels/m, {} samples)",
                    req.scene.name,
                    a.density(req.scene),
                    a.samples
                );
                bake_with_progress(req.scene, &bake_settings(req.scene, real_time_lights, a)?)?
            }
        };
        bakes.lightmaps.insert(key.clone(), lm);
    }
    Ok(&bakes.lightmaps[&key])
}

/// The GPU renderer of a light-map technique: the light-maps' ambient term, and for
/// `lightmap+phong` the scene's lights with shadow volumes (`lightmap` has no lights).
pub fn renderer(ctx: &GpuContext, req: &Request, lm: &Lightmaps) -> Result<Renderer> {
    let a = &req.args.raster;
    let shadows = req.technique.shadows(a.shadow_variant)?;
    let s = a.settings(shadows, req.width, req.height, req.camera)?;
    let mut scene = lm.scene.clone();
    if req.technique == crate::technique::Technique::Lightmap {
        scene.lights.clear();
    }
    let rects = layout_rects(&lm.layout);
    let input = LightmapInput {
        pages: &lm.pages,
        rects: &rects,
        bicubic: a.lightmap_filter == lightlab_bake::view::Filter::Bicubic,
        directional: lm.directional.as_deref(),
    };
    Ok(Renderer::with_lightmap(ctx, &scene, s, Some(&input))?)
}

/// The GPU's per-instance page rectangles of a light-map layout (light-maps, SH light-maps).
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
