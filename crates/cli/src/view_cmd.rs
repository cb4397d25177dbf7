//! `lightlab view`: the interactive viewer (crate `lightlab-viewer`) with the GPU techniques
//! of `render`, built by the same settings code.

use crate::bake_cmd::{BakeArgs, LIGHTMAP_TECHNIQUES, lightmap_renderer, lightmaps_for};
use crate::raster_cmd::{RASTER_TECHNIQUES, RasterArgs, apply_brdf, settings};
use crate::{ToneArg, load_scene};
use anyhow::{Context, Result};
use clap::Args;
use lightlab_bake::Lightmaps;
use lightlab_gpu::raster::Renderer;
use lightlab_viewer::{ViewerConfig, run};
use std::collections::HashMap;
use std::path::PathBuf;

#[derive(Args)]
pub struct ViewArgs {
    /// A built-in scene name or a .gltf/.glb path.
    #[arg(long)]
    pub scene: String,
    /// The technique shown first (keys 1–5 or the panel switch between them).
    #[arg(long, default_value = "phong-shadow-volumes")]
    pub technique: String,
    /// Light-maps written by `lightlab bake`, for `lightmap` and `lightmap+phong` (without
    /// it they are baked when first shown).
    #[arg(long)]
    pub baked: Option<PathBuf>,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Scene camera the view starts from.
    #[arg(long, default_value_t = 0)]
    pub camera: usize,
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    #[arg(long, value_enum, default_value_t = ToneArg::Filmic)]
    pub tonemap: ToneArg,
    /// Close after this many frames (scripts, tests, timing).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Screenshot file (key P; with --frames also written when the run ends).
    #[arg(long, default_value = "lightlab-view.png")]
    pub screenshot: PathBuf,
    /// Drop zero-area triangles of glTF input instead of rejecting the file.
    #[arg(long)]
    pub drop_degenerate: bool,
    #[command(flatten)]
    pub raster: RasterArgs,
    #[command(flatten)]
    pub bake: BakeArgs,
}

pub fn view(a: &ViewArgs) -> Result<()> {
    let mut scene = load_scene(&a.scene, a.drop_degenerate)?;
    apply_brdf(&mut scene, a.raster.brdf.as_deref())?;
    let techniques: Vec<String> = RASTER_TECHNIQUES
        .iter()
        .chain(LIGHTMAP_TECHNIQUES.iter())
        .map(|s| s.to_string())
        .collect();
    let first = techniques
        .iter()
        .position(|t| *t == a.technique)
        .with_context(|| {
            format!(
                "the viewer shows GPU techniques ({}), not '{}'",
                techniques.join(", "),
                a.technique
            )
        })?;
    anyhow::ensure!(
        (16..=16384).contains(&a.width) && (16..=16384).contains(&a.height),
        "--width and --height must be 16 to 16384"
    );
    anyhow::ensure!(
        a.exposure.is_finite() && a.exposure > 0.0,
        "--exposure must be a positive number"
    );
    anyhow::ensure!(
        a.camera < scene.cameras.len(),
        "the scene has {} camera(s); --camera {} does not exist",
        scene.cameras.len(),
        a.camera
    );
    // Check the settings of every technique once, before a window opens.
    for t in RASTER_TECHNIQUES {
        if a.raster.shadow_variant.is_none() {
            settings(t, &a.raster, 64, 64, a.camera)?;
        }
    }
    let raster = a.raster.clone();
    let bake = a.bake.clone();
    let baked = a.baked.clone();
    let mut lightmaps: HashMap<String, Lightmaps> = HashMap::new();
    let scene_for_make = scene.clone();
    let camera = a.camera;
    let make = Box::new(
        move |ctx: &lightlab_gpu::GpuContext,
              t: &str,
              w: u32,
              h: u32|
              -> Result<Renderer, String> {
            let mut go = || -> Result<Renderer> {
                if LIGHTMAP_TECHNIQUES.contains(&t) {
                    if !lightmaps.contains_key(t) {
                        let lm = lightmaps_for(&scene_for_make, t, baked.as_deref(), &bake)?;
                        lightmaps.insert(t.to_string(), lm);
                    }
                    let lm = &lightmaps[t];
                    lightmap_renderer(ctx, lm, t, &raster, w, h, camera)
                } else {
                    Ok(Renderer::new(
                        ctx,
                        &scene_for_make,
                        settings(t, &raster, w, h, camera)?,
                    )?)
                }
            };
            go().map_err(|e| format!("{e:#}"))
        },
    );
    let stats = run(
        ViewerConfig {
            scene,
            techniques,
            technique: first,
            camera: a.camera,
            width: a.width,
            height: a.height,
            exposure: a.exposure,
            tone: a.tonemap.into(),
            frames: a.frames,
            screenshot: a.screenshot.clone(),
            screenshot_at_end: a.frames.is_some(),
        },
        make,
    )?;
    eprintln!(
        "viewer: {} frames on {} ({}), {:.2} ms per frame{}",
        stats.frames,
        stats.adapter,
        stats.backend,
        stats.mean_frame_ms,
        stats
            .screenshots
            .iter()
            .map(|p| format!("; wrote {}", p.display()))
            .collect::<String>()
    );
    Ok(())
}
