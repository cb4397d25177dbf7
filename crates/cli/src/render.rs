//! `lightlab render`: one image of a scene with a technique.

use crate::load_scene;
use crate::options::TechniqueArgs;
use crate::technique::{Family, Technique};
use crate::techniques::{Bakes, Request};
use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightlab_core::color::ToneMap;
use lightlab_core::image::{Image, LdrSettings};
use lightlab_core::light_slab::{LightSlab, SlabEmitter};
use lightlab_scene::Scene;
use lightlab_trace::WindowEmitter;
use lightlab_trace::{Accel, PathTracer, RenderSettings};
use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

#[derive(Args)]
pub struct RenderArgs {
    /// A built-in scene name or a .gltf/.glb path.
    #[arg(long)]
    pub scene: String,
    /// `reference` (path-traced ground truth), `direct` (direct light only), or a GPU
    /// technique: `phong`, `phong-shadow-volumes`, `phong-shadow-maps`, `canned-light` (the
    /// scene's luminaire as a light slab, `--light-field DIR` or baked first),
    /// `lightfield-refraction` (glass through its geometry light field, `--refraction-field
    /// DIR` or baked first), `lightfield-glossy` (a glossy object's indirect light from its
    /// radiance light field, `--radiance-field DIR` or baked first), `lightmap` (baked light
    /// only) or `lightmap+phong` (baked indirect light plus dynamic lights and shadow volumes);
    /// the SH techniques `prt-vertex`, `prt-textured`, `prt-hierarchical`, `shl`,
    /// `shl-compressed`, `shl-normalmapped` (transfer × the scene's lights projected on SH);
    /// the light propagation volumes `lpv` and `lpv-faithful` (shadow-mapped direct light +
    /// the volume's indirect light: `lpv` multiple bounces by default, `lpv-faithful` one); the debug view `normals`. Every GPU technique draws planar
    /// mirrors from the mirrored eye (`--planar-mirrors`). The light-map and SH techniques read
    /// `--baked DIR` or bake first.
    /// The sky's diffuse light: traced (reference, direct); SH irradiance occluded through
    /// shadow-mapped sky directions (the Phong and LPV techniques, `--sky-occlusion`), and
    /// its bounce injected into `lpv`'s volume (`--lpv-sky-lights`); baked (lightmap,
    /// lightmap+phong); in the SH transfer (prt-*, shl*). The sky's glossy reflection is
    /// occluded in `lpv` only (by the sky directions in the lobe, the volume's light where
    /// they are hidden).
    #[arg(long, default_value = "reference")]
    pub technique: Technique,
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
    /// Tone operator of PNG output: clamp, reinhard or filmic.
    #[arg(long, default_value = "filmic")]
    pub tonemap: ToneMap,
    #[command(flatten)]
    pub load: crate::options::LoadArgs,
    /// Print one JSON object with the timings as the last line.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub gpu: TechniqueArgs,
    /// Output image: .exr (linear) or .png (tone-mapped sRGB); with --shard, the part folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// `reference` and `direct`: render only shard I of N (counted from 0; every N-th row from
    /// row I) into the part folder --output, for `lightlab merge`; `auto/N` reads I from
    /// JOB_COMPLETION_INDEX (Kubernetes) or SLURM_ARRAY_TASK_ID (Slurm).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
}

/// The path tracer's settings for `technique`: `direct` stops at the first scattering event.
fn path_settings(technique: Technique, settings: &RenderSettings) -> RenderSettings {
    let mut s = settings.clone();
    if technique == Technique::Direct {
        s.max_depth = 1;
    }
    s
}

/// The scene the path tracer renders and its window lights: the canned lights `slabs` (each
/// slab's micro lights, Heidrich §7.2.1) in place of the luminaires they replace, and every
/// other luminaire's geometry traced through its window (the paths inside a lamp that room
/// paths would almost never find).
pub fn windowed<'a>(
    scene: &'a Scene,
    slabs: &[Arc<LightSlab>],
) -> (Cow<'a, Scene>, Vec<Arc<dyn WindowEmitter>>) {
    use crate::techniques::canned;
    use lightlab_trace::luminaire;
    if slabs.is_empty() && luminaire::names(scene).is_empty() {
        return (Cow::Borrowed(scene), vec![]);
    }
    let room = canned::room(scene, slabs);
    let (room, mut lights) = luminaire::prepare(&room, canned::LAMP_DEPTH);
    lights.extend(
        slabs
            .iter()
            .map(|s| Arc::new(SlabEmitter::new(s.clone())) as Arc<dyn WindowEmitter>),
    );
    (Cow::Owned(room), lights)
}

/// Render with the reference path tracer (technique `reference` or `direct`), with a progress
/// bar on stderr.
pub fn render_reference(
    scene: &Scene,
    technique: Technique,
    settings: &RenderSettings,
    light_field: &[Arc<LightSlab>],
) -> Result<Image> {
    Ok(render_reference_timed(scene, technique, settings, light_field)?.0)
}

/// As [`render_reference`], with the seconds spent before tracing (the BVH, the light tables).
pub fn render_reference_timed(
    scene: &Scene,
    technique: Technique,
    settings: &RenderSettings,
    light_field: &[Arc<LightSlab>],
) -> Result<(Image, f64)> {
    let t0 = Instant::now();
    let s = path_settings(technique, settings);
    let (scene, windows) = windowed(scene, light_field);
    let scene = &*scene;
    let accel = Accel::new(scene);
    let mut pt = PathTracer::new(scene, &accel);
    pt.windows = windows;
    let setup = t0.elapsed().as_secs_f64();
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
    Ok((img, setup))
}

pub fn run(a: RenderArgs) -> Result<()> {
    let ext = lightlab_core::image::extension(&a.output);
    if a.shard.is_some() {
        lightlab_bake::folder::check_destination(&a.output)?;
    } else if ext != "exr" && ext != "png" {
        bail!("{}: the output must be .exr or .png", a.output.display());
    }
    // Before any work: the folder the image goes to exists.
    let folder = lightlab_core::atomic::parent(&a.output);
    if !folder.is_dir() {
        bail!(
            "{}: the folder {} does not exist",
            a.output.display(),
            folder.display()
        );
    }
    // Checked before any work: NaN, infinite or negative exposure gave a black PNG.
    anyhow::ensure!(
        a.exposure.is_finite() && a.exposure > 0.0,
        "--exposure must be a positive number, not {}",
        a.exposure
    );
    let mut scene = load_scene(&a.scene, &a.load)?;
    crate::options::apply_brdf(&mut scene, a.gpu.raster.brdf);
    a.technique.check_options(&a.gpu, a.indirect_only)?;
    if a.technique.family() != Family::PathTraced {
        // The GPU techniques pose the scene themselves (the SH ones after baking its rest).
        return run_raster(&a, &scene);
    }
    if let Some(k) = a.gpu.frame {
        anyhow::ensure!(
            scene.animation.is_some(),
            "--frame poses an animated scene, and {} has no animation",
            scene.name
        );
        scene.pose(k);
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
        lens: a.gpu.lens.model(
            &scene,
            a.camera,
            a.width as f32 / a.height.unwrap_or(a.width) as f32,
        )?,
    };
    settings.validate()?;
    if let Some(shard) = &a.shard {
        return render_shard(&a, &scene, &settings, shard);
    }
    let t0 = Instant::now();
    let slabs = crate::techniques::canned::read(&a.gpu.light_field)?;
    let (img, setup) = render_reference_timed(&scene, a.technique, &settings, &slabs)?;
    let secs = t0.elapsed().as_secs_f64();
    write_output(&a, &img)?;
    let paths = settings.width as f64 * settings.height as f64 * settings.spp as f64;
    // Tracing alone: what a renderer that builds its scene before its timer starts reports.
    let trace = (secs - setup).max(1e-9);
    eprintln!(
        "wrote {} ({}×{}, {} spp, {:.2} s, {:.2} Msamples/s; BVH and light tables {:.2} s, \
         tracing {:.2} Msamples/s)",
        a.output.display(),
        settings.width,
        settings.height,
        settings.spp,
        secs,
        paths / secs / 1e6,
        setup,
        paths / trace / 1e6
    );
    if a.json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "technique": a.technique.name(), "width": settings.width,
                "height": settings.height, "spp": settings.spp, "seconds": secs,
                "msamples_per_s": paths / secs / 1e6, "setup_seconds": setup,
                "trace_msamples_per_s": paths / trace / 1e6,
            })
        );
    }
    Ok(())
}

/// The path depths (scattering events) `reference` and `direct` keep: `--bounces k` limits light
/// to k bounces before the visible surface (depth k + 1), `--indirect-only` keeps exactly that.
fn depth_range(a: &RenderArgs) -> Result<(u32, u32)> {
    let bounces = a.gpu.bake.bounces;
    if a.technique == Technique::Direct && (a.indirect_only || bounces.is_some()) {
        bail!("--bounces and --indirect-only apply to --technique reference, not direct");
    }
    if a.indirect_only {
        let k = bounces.unwrap_or(1);
        anyhow::ensure!(
            (1..=1023).contains(&k),
            "--indirect-only needs --bounces in 1..=1023 (got {k})"
        );
        return Ok((k + 1, k + 1));
    }
    match bounces {
        Some(k) if k < 1024 => Ok((0, k + 1)),
        Some(k) => bail!("--bounces {k} must be below 1024"),
        None => Ok((0, a.max_depth)),
    }
}

/// `render --shard I/N`: the shard's rows into a part folder.
fn render_shard(
    a: &RenderArgs,
    scene: &Scene,
    settings: &RenderSettings,
    shard: &str,
) -> Result<()> {
    use lightlab_bake::shard::{RenderSpec, Shard, render_part, write_render_part};
    let shard = Shard::parse(shard)?;
    let s = path_settings(a.technique, settings);
    let spec = RenderSpec {
        technique: a.technique.name().into(),
        width: s.width,
        height: s.height,
        spp: s.spp,
        max_depth: s.max_depth,
        min_depth: s.min_depth,
        seed: s.seed,
        camera: s.camera,
        exposure: a.exposure,
        tonemap: a.tonemap.name().into(),
        camera_model: settings.lens.describe(),
    };
    let slabs = crate::techniques::canned::read(&a.gpu.light_field)?;
    let (traced, windows) = windowed(scene, &slabs);
    let accel = Accel::new(&traced);
    let mut pt = PathTracer::new(&traced, &accel);
    pt.windows = windows;
    let part = render_part(
        &pt,
        &s,
        spec,
        (&a.scene, scene.fingerprint()),
        shard,
        &|_, _| true,
    )?;
    write_render_part(&part, &a.output)?;
    eprintln!(
        "rendered {} shard {shard} ({} rows of {}, {:.2} s); wrote {}",
        scene.name,
        part.pixels.len() / s.width as usize,
        s.height,
        part.manifest.seconds,
        a.output.display()
    );
    Ok(())
}

fn run_raster(a: &RenderArgs, scene: &Scene) -> Result<()> {
    if a.shard.is_some() {
        bail!("--shard splits path-traced renders (reference, direct), not GPU techniques");
    }
    let ctx = crate::gpu_context()?;
    let (w, h) = (a.width, a.height.unwrap_or(a.width));
    let t0 = Instant::now();
    let req = Request {
        scene,
        technique: a.technique,
        args: &a.gpu,
        width: w,
        height: h,
        camera: a.camera,
    };
    let (img, times) = crate::techniques::build(&ctx, &req, &mut Bakes::default())?.image(&ctx)?;
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
                "scene": scene.name, "technique": a.technique.name(), "width": w, "height": h,
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
            tone: a.tonemap,
        },
    )
    .with_context(|| format!("writing {}", a.output.display()))
}
