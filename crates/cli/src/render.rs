//! `lightlab render`: one image of a scene with a technique.

use crate::{ToneArg, load_scene, not_implemented};
use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightlab_core::image::{Image, LdrSettings};
use lightlab_scene::Scene;
use lightlab_trace::{Accel, PathTracer, RenderSettings};
use std::path::PathBuf;
use std::time::Instant;

/// Techniques `lightlab render` knows of, with whether they are built yet.
pub const TECHNIQUES: [(&str, bool); 14] = [
    ("reference", true),
    ("direct", true),
    ("phong", true),
    ("phong-shadow-volumes", true),
    ("phong-shadow-maps", true),
    ("lightmap", true),
    ("lightmap+phong", true),
    ("prt-vertex", true),
    ("prt-textured", true),
    ("shl", true),
    ("shl-compressed", true),
    ("shl-normalmapped", true),
    ("lpv", true),
    ("lpv-faithful", true),
];

#[derive(Args)]
pub struct RenderArgs {
    /// A built-in scene name or a .gltf/.glb path.
    #[arg(long)]
    pub scene: String,
    /// `reference` (path-traced ground truth), `direct` (direct light only), or a GPU
    /// technique: `phong`, `phong-shadow-volumes`, `phong-shadow-maps`, `lightmap` (baked
    /// light only) or `lightmap+phong` (baked indirect light plus dynamic lights and shadow
    /// volumes); the SH techniques `prt-vertex`, `prt-textured`, `shl`, `shl-compressed`,
    /// `shl-normalmapped` (transfer × the scene's lights projected on SH); the light propagation volumes `lpv`
    /// and `lpv-faithful` (shadow-mapped direct light + one bounce from the volume). The
    /// light-map and SH light-map techniques read `--baked DIR` or bake first.
    #[arg(long, default_value = "reference")]
    pub technique: String,
    /// Folder of baked data, for techniques that use it.
    #[arg(long)]
    pub baked: Option<PathBuf>,
    #[arg(long, default_value_t = 256)]
    pub width: u32,
    /// Defaults to the width divided by the camera's aspect ratio of 1 (square).
    #[arg(long)]
    pub height: Option<u32>,
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Largest number of scattering events per path.
    #[arg(long, default_value_t = 16)]
    pub max_depth: u32,
    /// `reference`: only light that bounced exactly `--bounces` times (default 1) off surfaces
    /// before reaching the surface seen: no emission, no direct light.
    #[arg(long)]
    pub indirect_only: bool,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Scene camera index.
    #[arg(long, default_value_t = 0)]
    pub camera: usize,
    /// Exposure multiplier for PNG output.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    #[arg(long, value_enum, default_value_t = ToneArg::Filmic)]
    pub tonemap: ToneArg,
    /// Light the scene with this equirectangular environment map (.hdr or .exr), replacing any
    /// environment the scene has.
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Multiplier on `--env`.
    #[arg(long, default_value_t = 1.0)]
    pub env_intensity: f32,
    /// Drop zero-area triangles of glTF input instead of rejecting the file.
    #[arg(long)]
    pub drop_degenerate: bool,
    /// Print one JSON object with the timings as the last line.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub raster: crate::raster_cmd::RasterArgs,
    #[command(flatten)]
    pub bake: crate::bake_cmd::BakeArgs,
    #[command(flatten)]
    pub sh: crate::prt_cmd::ShArgs,
    #[command(flatten)]
    pub lpv: crate::lpv_cmd::LpvArgs,
    /// Output image: .exr (linear) or .png (tone-mapped sRGB).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Render with the reference path tracer (technique `reference` or `direct`), with a progress
/// bar on stderr.
pub fn render_reference(
    scene: &Scene,
    technique: &str,
    settings: &RenderSettings,
) -> Result<Image> {
    let mut s = settings.clone();
    if technique == "direct" {
        s.max_depth = 1;
    }
    let accel = Accel::new(scene);
    let pt = PathTracer::new(scene, &accel);
    let bar = ProgressBar::new(s.height as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} rows, {elapsed} (eta {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_prefix(format!("{} {}", scene.name, technique));
    let img = pt.render(&s, &|done, _| {
        bar.set_position(done as u64);
        true
    })?;
    bar.finish_and_clear();
    Ok(img)
}

pub fn run(a: RenderArgs) -> Result<()> {
    let known = TECHNIQUES.iter().find(|(t, _)| *t == a.technique);
    match known {
        None => bail!(
            "unknown technique '{}' (known: {})",
            a.technique,
            TECHNIQUES
                .iter()
                .map(|t| t.0)
                .collect::<Vec<_>>()
                .join(", ")
        ),
        Some((_, false)) => return Err(not_implemented(format!("technique '{}'", a.technique))),
        Some(_) => {}
    }
    let ext = lightlab_core::image::extension(&a.output);
    if ext != "exr" && ext != "png" {
        bail!("{}: the output must be .exr or .png", a.output.display());
    }
    let mut scene = load_scene(&a.scene, a.drop_degenerate)?;
    if let Some(env) = &a.env {
        anyhow::ensure!(
            a.env_intensity.is_finite() && a.env_intensity >= 0.0,
            "--env-intensity must be a finite, non-negative number"
        );
        let image = Image::read(env)?;
        scene.environment = Some(lightlab_scene::Environment {
            image,
            intensity: a.env_intensity,
        });
    }
    crate::raster_cmd::apply_brdf(&mut scene, a.raster.brdf.as_deref())?;
    if crate::raster_cmd::RASTER_TECHNIQUES.contains(&a.technique.as_str())
        || crate::bake_cmd::LIGHTMAP_TECHNIQUES.contains(&a.technique.as_str())
        || crate::prt_cmd::SH_TECHNIQUES.contains(&a.technique.as_str())
        || crate::lpv_cmd::LPV_TECHNIQUES.contains(&a.technique.as_str())
    {
        return run_raster(&a, &scene);
    }
    let (min_depth, max_depth) = depth_range(&a)?;
    let settings = RenderSettings {
        width: a.width,
        height: a.height.unwrap_or(a.width),
        spp: a.spp,
        max_depth,
        min_depth,
        seed: a.seed,
        camera: a.camera,
    };
    settings.validate()?;
    let t0 = Instant::now();
    let img = render_reference(&scene, &a.technique, &settings)?;
    let secs = t0.elapsed().as_secs_f64();
    write_output(&a, &img)?;
    let paths = settings.width as f64 * settings.height as f64 * settings.spp as f64;
    eprintln!(
        "wrote {} ({}×{}, {} spp, {:.2} s, {:.2} Msamples/s)",
        a.output.display(),
        settings.width,
        settings.height,
        settings.spp,
        secs,
        paths / secs / 1e6
    );
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "technique": a.technique, "width": settings.width,
                "height": settings.height, "spp": settings.spp, "seconds": secs,
                "msamples_per_s": paths / secs / 1e6,
            })
        );
    }
    Ok(())
}

/// The path depths (scattering events) `reference` and `direct` keep: `--bounces k` limits light
/// to k bounces before the visible surface (depth k + 1), `--indirect-only` keeps exactly that.
fn depth_range(a: &RenderArgs) -> Result<(u32, u32)> {
    if a.technique == "direct" && (a.indirect_only || a.bake.bounces.is_some()) {
        bail!("--bounces and --indirect-only apply to --technique reference, not direct");
    }
    if a.indirect_only {
        let k = a.bake.bounces.unwrap_or(1);
        anyhow::ensure!(
            (1..=1023).contains(&k),
            "--indirect-only needs --bounces in 1..=1023 (got {k})"
        );
        return Ok((k + 1, k + 1));
    }
    match a.bake.bounces {
        Some(k) if k < 1024 => Ok((0, k + 1)),
        Some(k) => bail!("--bounces {k} must be below 1024"),
        None => Ok((0, a.max_depth)),
    }
}

fn run_raster(a: &RenderArgs, scene: &Scene) -> Result<()> {
    let t = a.technique.as_str();
    let lpv = crate::lpv_cmd::LPV_TECHNIQUES.contains(&t);
    if a.indirect_only {
        bail!(
            "--indirect-only applies to --technique reference{}",
            if lpv {
                "; the volume's indirect light alone is --debug-view indirect"
            } else {
                ""
            }
        );
    }
    if a.bake.bounces.is_some() && (lpv || crate::raster_cmd::RASTER_TECHNIQUES.contains(&t)) {
        bail!("--bounces applies to --technique reference and to baked techniques, not {t}");
    }
    if a.lpv.debug_view != crate::lpv_cmd::DebugView::Final && !lpv {
        bail!(
            "--debug-view applies to the LPV techniques ({})",
            crate::lpv_cmd::LPV_TECHNIQUES.join(", ")
        );
    }
    if a.raster.no_area_lights
        && (crate::bake_cmd::LIGHTMAP_TECHNIQUES.contains(&t)
            || crate::prt_cmd::SH_TECHNIQUES.contains(&t))
    {
        bail!(
            "--no-area-lights applies to the Phong and LPV techniques; {t} never lights with \
             emitters as area lights (its bake holds their light)"
        );
    }
    let ctx = crate::raster_cmd::context()?;
    let (w, h) = (a.width, a.height.unwrap_or(a.width));
    let t0 = Instant::now();
    let (img, times) = if crate::bake_cmd::LIGHTMAP_TECHNIQUES.contains(&a.technique.as_str()) {
        let lm = crate::bake_cmd::lightmaps_for(scene, &a.technique, a.baked.as_deref(), &a.bake)?;
        crate::bake_cmd::render_lightmap(&ctx, &lm, &a.technique, &a.raster, w, h, a.camera)?
    } else if crate::prt_cmd::SH_TECHNIQUES.contains(&a.technique.as_str()) {
        let data =
            crate::prt_cmd::sh_data_for(scene, &a.technique, a.baked.as_deref(), &a.bake, &a.sh)?;
        crate::prt_cmd::render_sh(&ctx, &data, &a.technique, &a.raster, &a.sh, w, h, a.camera)?
    } else if crate::lpv_cmd::LPV_TECHNIQUES.contains(&a.technique.as_str()) {
        crate::lpv_cmd::render_lpv(&ctx, scene, &a.technique, &a.raster, &a.lpv, w, h, a.camera)?
    } else {
        crate::raster_cmd::render_raster(&ctx, scene, &a.technique, &a.raster, w, h, a.camera)?
    };
    let secs = t0.elapsed().as_secs_f64();
    write_output(a, &img)?;
    let gpu: f64 = times.gpu_ms.values().sum();
    eprintln!(
        "wrote {} ({w}×{h}, {}, frame {:.2} ms wall{}, {:.2} s in all)",
        a.output.display(),
        a.technique,
        times.wall_ms,
        if times.gpu_ms.is_empty() {
            String::new()
        } else {
            format!(", {gpu:.3} ms GPU")
        },
        secs
    );
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "technique": a.technique, "width": w, "height": h,
                "seconds": secs, "frame_wall_ms": times.wall_ms, "gpu_ms": times.gpu_ms,
            })
        );
    }
    Ok(())
}

/// Write the rendered image to `--output` with the PNG tone settings.
fn write_output(a: &RenderArgs, img: &Image) -> Result<()> {
    img.write(
        &a.output,
        LdrSettings {
            exposure: a.exposure,
            tone: a.tonemap.into(),
        },
    )
    .with_context(|| format!("writing {}", a.output.display()))
}
