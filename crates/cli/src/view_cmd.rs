//! `lightlab view`: the interactive viewer (crate `lightlab-viewer`) with the GPU techniques
//! of `render`, built by the same settings code.

use crate::load_scene;
use crate::options::{TechniqueArgs, apply_brdf};
use crate::technique::Technique;
use crate::techniques::{Bakes, Request, build};
use anyhow::{Context, Result};
use clap::Args;
use lightlab_core::color::ToneMap;

use lightlab_viewer::{Made, ViewerConfig, run};
use std::path::PathBuf;

#[derive(Args)]
pub struct ViewArgs {
    /// A built-in scene name or a .gltf/.glb path.
    #[arg(long)]
    pub scene: String,
    /// The technique shown first (keys 1–9 or the panel switch between the GPU techniques;
    /// those that bake do so when first shown, unless `--baked` has their data).
    #[arg(long, default_value = "phong-shadow-volumes")]
    pub technique: Technique,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Scene camera the view starts from.
    #[arg(long, default_value_t = 0)]
    pub camera: usize,
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Tone operator: clamp, reinhard or filmic.
    #[arg(long, default_value = "filmic")]
    pub tonemap: ToneMap,
    /// Close after this many frames (scripts, tests, timing).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Start with the mirror-like objects (those `--dynamic-env` maps) circling where they
    /// stand (key M or the panel toggles it), so that their reflections change as they move.
    #[arg(long)]
    pub animate: bool,
    /// Screenshot file (key P; with --frames also written when the run ends).
    #[arg(long, default_value = "lightlab-view.png")]
    pub screenshot: PathBuf,
    #[command(flatten)]
    pub load: crate::options::LoadArgs,
    #[command(flatten)]
    pub gpu: TechniqueArgs,
}

pub fn view(a: &ViewArgs) -> Result<()> {
    let mut scene = load_scene(&a.scene, &a.load)?;
    apply_brdf(&mut scene, a.gpu.raster.brdf);
    // `canned-light` needs a luminaire to bake, or a slab.
    let canned =
        !a.gpu.light_field.is_empty() || !lightlab_trace::luminaire::names(&scene).is_empty();
    // `lightfield-refraction` needs solid glass to bake, or a field.
    let glass = a.gpu.refraction_field.is_some()
        || !lightlab_trace::refraction_field::glass_instances(&scene).is_empty();
    let glossy = a.gpu.radiance_field.is_some()
        || !lightlab_trace::radiance_field::glossy_instances(&scene).is_empty();
    let techniques: Vec<Technique> = Technique::gpu()
        .filter(|t| canned || *t != Technique::CannedLight)
        .filter(|t| glass || *t != Technique::LightfieldRefraction)
        .filter(|t| glossy || *t != Technique::LightfieldGlossy)
        .collect();
    let first = techniques
        .iter()
        .position(|t| *t == a.technique)
        .with_context(|| {
            let names: Vec<&str> = techniques.iter().map(|t| t.name()).collect();
            format!(
                "the viewer shows GPU techniques ({}), not '{}'",
                names.join(", "),
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
    // Check the options of the first technique before a window opens.
    a.technique.check_options(&a.gpu, false)?;
    a.gpu.raster.settings(
        a.technique.shadows(a.gpu.raster.shadow_variant)?,
        64,
        64,
        a.camera,
    )?;
    let args = a.gpu.clone();
    let mut bakes = Bakes::default();
    let scene_for_make = scene.clone();
    let camera = a.camera;
    let make = Box::new(
        move |ctx: &lightlab_gpu::GpuContext,
              name: &str,
              width: u32,
              height: u32|
              -> Result<Made, lightlab_viewer::MakeError> {
            let mut go = || -> Result<Made> {
                let req = Request {
                    scene: &scene_for_make,
                    technique: name.parse()?,
                    args: &args,
                    width,
                    height,
                    camera,
                };
                let mut tr = build(ctx, &req, &mut bakes)?;
                tr.update(ctx)?;
                let animation: Option<Box<dyn lightlab_viewer::Animation>> = if tr.frames.animated()
                {
                    Some(Box::new(tr.frames))
                } else {
                    None
                };
                Ok((tr.renderer, tr.lens, animation))
            };
            go().map_err(|e| format!("{e:#}").into())
        },
    );
    let stats = run(
        ViewerConfig {
            scene,
            techniques: techniques.iter().map(|t| t.name().to_string()).collect(),
            technique: first,
            camera: a.camera,
            width: a.width,
            height: a.height,
            exposure: a.exposure,
            tone: a.tonemap,
            frames: a.frames,
            screenshot: a.screenshot.clone(),
            screenshot_at_end: a.frames.is_some(),
            animate: a.animate,
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
