//! The GPU techniques `phong`, `phong-shadow-volumes` and `phong-shadow-maps` for `render`,
//! `demo` and `bench frame`.

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use lightlab_core::image::Image;
use lightlab_gpu::GpuContext;
use lightlab_gpu::lights::Attenuation;
use lightlab_gpu::raster::{
    Ambient, FrameTimes, RasterSettings, RenderPath, Renderer, ShadowMethod,
};
use lightlab_scene::{BrdfModel, Scene};

/// The rasterised techniques.
pub const RASTER_TECHNIQUES: [&str; 3] = ["phong", "phong-shadow-volumes", "phong-shadow-maps"];

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum PathArg {
    Forward,
    Deferred,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum VariantArg {
    /// Shadow volumes: z-fail with capped volumes (robust; the default).
    Zfail,
    /// Shadow volumes: z-pass (wrong when the camera is inside a volume).
    Zpass,
    /// Shadow maps: hardware depth comparison (the default).
    Depth,
    /// Shadow maps: Heidrich's linear-depth comparison.
    Linear,
    /// Projected planar shadows on the largest floor plane (Heidrich §6.1).
    Planar,
}

/// Options of the GPU techniques.
#[derive(Args, Clone, Debug)]
pub struct RasterArgs {
    /// Wind sway of foliage [m at the tips] (materials' `extras.lightlab.sway`), the same in
    /// every pass; needs shadow maps, not volumes. `bench frame` animates it at 60 Hz.
    #[arg(long, default_value_t = 0.0)]
    pub wind: f32,
    /// The wind's time [s] (its gusts' phase).
    #[arg(long, default_value_t = 0.0)]
    pub wind_time: f32,
    /// Forward (one scene pass per light) or deferred (G-buffer, one screen pass per light).
    #[arg(long, value_enum, default_value_t = PathArg::Forward)]
    pub path: PathArg,
    /// Attenuation of point and spot lights: inverse-square (physical, as the reference) or
    /// Fuchs's atten₁..₄ (fuchs4 = 1 − (d/r)², the thesis's choice).
    #[arg(long, default_value = "fuchs4")]
    pub attenuation: String,
    /// Radius r of the Fuchs attenuation functions (default: the glTF range, else
    /// √(I/0.05 lx)).
    #[arg(long)]
    pub light_radius: Option<f32>,
    /// Shade every material with this model: pbr, lambert, phong or blinn-phong (default: each
    /// material's own). Applies to the reference techniques too.
    #[arg(long)]
    pub brdf: Option<String>,
    /// Shadow variant: zfail|zpass (shadow volumes), depth|linear|planar (shadow maps).
    #[arg(long, value_enum)]
    pub shadow_variant: Option<VariantArg>,
    /// Light-map sampling of `lightmap` and `lightmap+phong`: bilinear or bicubic.
    #[arg(long, default_value = "bilinear")]
    pub lightmap_filter: String,
    /// Ambient term: `env` (the scene's environment as 9 SH coefficients), `none`, or a
    /// constant sky radiance `r,g,b`.
    #[arg(long, default_value = "env")]
    pub ambient: String,
    /// Shadow-map resolution (per layer).
    #[arg(long, default_value_t = 2048)]
    pub shadow_size: u32,
    /// PCF kernel half-width in texels (0 = one bilinear comparison).
    #[arg(long, default_value_t = 1)]
    pub pcf: i32,
    /// Supersampling factor per axis (renders ssaa² samples per pixel).
    #[arg(long, default_value_t = 1)]
    pub ssaa: u32,
    /// Leave the background black instead of drawing the environment where no surface is
    /// seen (the path tracer draws it, so the default keeps renders comparable).
    #[arg(long)]
    pub no_background: bool,
    /// Do not light with the scene's planar emitters as area lights (cornell's lamp): only its
    /// punctual lights light the surfaces directly. Light-map and SH techniques never use them
    /// (their bakes hold that light).
    #[arg(long)]
    pub no_area_lights: bool,
}

impl Default for RasterArgs {
    fn default() -> Self {
        RasterArgs {
            wind: 0.0,
            wind_time: 0.0,
            path: PathArg::Forward,
            attenuation: "fuchs4".into(),
            light_radius: None,
            brdf: None,
            shadow_variant: None,
            lightmap_filter: "bilinear".into(),
            ambient: "env".into(),
            shadow_size: 2048,
            pcf: 1,
            ssaa: 1,
            no_background: false,
            no_area_lights: false,
        }
    }
}

/// Apply `--brdf` to the scene (before any technique renders it).
pub fn apply_brdf(scene: &mut Scene, brdf: Option<&str>) -> Result<()> {
    if let Some(name) = brdf {
        let m = BrdfModel::parse(name).with_context(|| {
            format!(
                "unknown --brdf '{name}' (known: {})",
                BrdfModel::NAMES.join(", ")
            )
        })?;
        scene.set_brdf(m);
    }
    Ok(())
}

/// The renderer settings of a technique and its options.
pub fn settings(
    technique: &str,
    a: &RasterArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<RasterSettings> {
    let attenuation = Attenuation::parse(&a.attenuation).with_context(|| {
        format!(
            "unknown --attenuation '{}' (known: {})",
            a.attenuation,
            Attenuation::NAMES.join(", ")
        )
    })?;
    let shadows = match (technique, a.shadow_variant) {
        ("phong", None) => ShadowMethod::None,
        ("phong-shadow-volumes", None | Some(VariantArg::Zfail)) => ShadowMethod::VolumesZFail,
        ("phong-shadow-volumes", Some(VariantArg::Zpass)) => ShadowMethod::VolumesZPass,
        ("phong-shadow-maps", None | Some(VariantArg::Depth)) => ShadowMethod::Map,
        ("phong-shadow-maps", Some(VariantArg::Linear)) => ShadowMethod::MapLinear,
        ("phong-shadow-maps", Some(VariantArg::Planar)) => ShadowMethod::Planar,
        (t, Some(v)) => bail!("--shadow-variant {v:?} does not apply to technique '{t}'"),
        (t, None) => bail!("'{t}' is not a GPU technique"),
    };
    let ambient = match a.ambient.as_str() {
        "env" => Ambient::Environment,
        "none" => Ambient::None,
        s => {
            let v: Vec<f32> = s
                .split(',')
                .map(|x| x.trim().parse::<f32>())
                .collect::<Result<_, _>>()
                .ok()
                .filter(|v: &Vec<f32>| v.len() == 3 && v.iter().all(|x| x.is_finite() && *x >= 0.0))
                .with_context(|| {
                    format!("--ambient must be env, none or r,g,b (non-negative), not '{s}'")
                })?;
            Ambient::Constant(glam::Vec3::new(v[0], v[1], v[2]))
        }
    };
    if !(1..=8).contains(&a.ssaa) {
        bail!("--ssaa must be 1 to 8");
    }
    if let Some(r) = a.light_radius
        && !(r.is_finite() && r > 0.0)
    {
        bail!("--light-radius must be a positive number");
    }
    Ok(RasterSettings {
        width: width * a.ssaa,
        height: height * a.ssaa,
        camera,
        path: match a.path {
            PathArg::Forward => RenderPath::Forward,
            PathArg::Deferred => RenderPath::Deferred,
        },
        shadows,
        attenuation,
        light_radius: a.light_radius,
        ambient,
        shadow_size: a.shadow_size,
        pcf_radius: a.pcf,
        wind: {
            let w = lightlab_core::wind::Wind::breeze(
                glam::Vec3::new(1.0, 0.0, 0.4),
                a.wind,
                a.wind_time,
            );
            w.validate().map_err(|e| anyhow::anyhow!("--wind: {e}"))?;
            w
        },
        background: !a.no_background,
        area_lights: !a.no_area_lights,
        ..Default::default()
    })
}

/// Render one image with a GPU technique; also returns the frame's timings.
pub fn render_raster(
    ctx: &GpuContext,
    scene: &Scene,
    technique: &str,
    a: &RasterArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<(Image, FrameTimes)> {
    let s = settings(technique, a, width, height, camera)?;
    let mut r = Renderer::new(ctx, scene, s)?;
    timed_frame(ctx, &mut r, a.ssaa)
}

/// Render two frames (the first compiles pipelines and uploads), return the second's image,
/// downsampled by the supersampling factor, and its times.
pub fn timed_frame(ctx: &GpuContext, r: &mut Renderer, ssaa: u32) -> Result<(Image, FrameTimes)> {
    r.render(ctx);
    let times = r.render(ctx);
    let img = r.read_hdr(ctx)?;
    Ok((img.downsample(ssaa), times))
}

/// A GPU context, with the CLI's advice when none exists.
pub fn context() -> Result<GpuContext> {
    let ctx = GpuContext::headless()?;
    eprintln!(
        "GPU: {} ({:?}, {})",
        ctx.info.name, ctx.info.backend, ctx.info.driver
    );
    Ok(ctx)
}

/// Options of `bench frame`.
#[derive(Args, Clone, Debug)]
pub struct FrameBenchArgs {
    #[arg(long, default_value_t = 1920)]
    pub width: u32,
    #[arg(long, default_value_t = 1080)]
    pub height: u32,
    /// Frames measured (after two warm-up frames); medians are reported.
    #[arg(long, default_value_t = 30)]
    pub frames: usize,
    /// Use exactly this many lights: extra white point lights on a circle (r = 3 m, 3 m high)
    /// are added, or the scene's list is cut.
    #[arg(long)]
    pub lights: Option<usize>,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `lightlab bench frame`: milliseconds per pass of a GPU technique.
#[allow(clippy::too_many_arguments)]
pub fn bench_frame(
    scene: &mut Scene,
    technique: &str,
    a: &RasterArgs,
    f: &FrameBenchArgs,
    bake: &crate::bake_cmd::BakeArgs,
    baked: Option<&std::path::Path>,
    sh: &crate::prt_cmd::ShArgs,
    lpv: &crate::lpv_cmd::LpvArgs,
    json: bool,
) -> Result<()> {
    let lpv_technique = crate::lpv_cmd::LPV_TECHNIQUES.contains(&technique);
    let lightmapped = crate::bake_cmd::LIGHTMAP_TECHNIQUES.contains(&technique);
    let sh_technique = crate::prt_cmd::SH_TECHNIQUES.contains(&technique);
    anyhow::ensure!(
        RASTER_TECHNIQUES.contains(&technique) || lightmapped || sh_technique || lpv_technique,
        "bench frame needs a GPU technique ({}, {}, {}, {})",
        RASTER_TECHNIQUES.join(", "),
        crate::bake_cmd::LIGHTMAP_TECHNIQUES.join(", "),
        crate::prt_cmd::SH_TECHNIQUES.join(", "),
        crate::lpv_cmd::LPV_TECHNIQUES.join(", ")
    );
    anyhow::ensure!(
        (1..=10_000).contains(&f.frames),
        "--frames must be 1 to 10000"
    );
    apply_brdf(scene, a.brdf.as_deref())?;
    if let Some(n) = f.lights {
        anyhow::ensure!(n <= 256, "--lights must be at most 256");
        let extra = n.saturating_sub(scene.lights.len());
        for i in 0..extra {
            let phi = i as f32 * 2.399_963; // golden angle
            scene.lights.push(lightlab_scene::Light {
                name: format!("bench_{i}"),
                kind: lightlab_scene::LightKind::Point,
                color: glam::Vec3::ONE,
                intensity: 5.0,
                position: glam::Vec3::new(3.0 * phi.cos(), 3.0, 3.0 * phi.sin()),
                direction: -glam::Vec3::Y,
                range: None,
            });
        }
        scene.lights.truncate(n);
    }
    let ctx = context()?;
    // SH techniques re-project the scene's lights every frame (CPU time reported).
    let mut projector = None;
    let mut r = if lightmapped {
        let lm = crate::bake_cmd::lightmaps_for(scene, technique, baked, bake)?;
        crate::bake_cmd::lightmap_renderer(&ctx, &lm, technique, a, f.width, f.height, 0)?
    } else if sh_technique {
        let data = crate::prt_cmd::sh_data_for(scene, technique, baked, bake, sh)?;
        let (r, p) =
            crate::prt_cmd::sh_renderer(&ctx, &data, technique, a, sh, f.width, f.height, 0)?;
        projector = Some((p, data.scene().clone()));
        r
    } else if lpv_technique {
        crate::lpv_cmd::lpv_renderer(&ctx, scene, technique, a, lpv, f.width, f.height, 0)?
    } else {
        Renderer::new(&ctx, scene, settings(technique, a, f.width, f.height, 0)?)?
    };
    r.render(&ctx);
    r.render(&ctx);
    let mut per_pass: std::collections::BTreeMap<&'static str, Vec<f64>> = Default::default();
    let (mut gpu, mut wall, mut cpu) = (vec![], vec![], vec![]);
    let mut projection = vec![];
    for frame in 0..f.frames {
        if r.settings.wind.amplitude > 0.0 {
            let mut w = r.settings.wind;
            w.time = a.wind_time + frame as f32 / 60.0;
            r.set_wind(&ctx, w)?;
        }
        if let Some((p, sc)) = &projector {
            let t0 = std::time::Instant::now();
            let light = p.project(sc, None);
            crate::prt_cmd::set_light(&ctx, &mut r, &light)?;
            projection.push(t0.elapsed().as_secs_f64() * 1e3);
        }
        let t = r.render(&ctx);
        for (k, v) in &t.gpu_ms {
            per_pass.entry(k).or_default().push(*v);
        }
        gpu.push(t.gpu_ms.values().sum());
        wall.push(t.wall_ms);
        cpu.push(t.cpu_volumes_ms);
    }
    let passes: std::collections::BTreeMap<&str, f64> =
        per_pass.into_iter().map(|(k, v)| (k, median(v))).collect();
    let (gpu, wall, cpu) = (median(gpu), median(wall), median(cpu));
    println!(
        "{} on {} at {}×{}, {} lights, {} triangles, {} ({:?}); median of {} frames",
        technique,
        scene.name,
        f.width,
        f.height,
        r.light_count(),
        r.scene.triangles,
        ctx.info.name,
        ctx.info.backend,
        f.frames
    );
    if passes.is_empty() {
        println!("(no GPU timestamps on this adapter: wall-clock frame time only)");
    }
    for (k, v) in &passes {
        println!("  {k:<16} {v:>9.3} ms");
    }
    if !passes.is_empty() {
        println!("  {:<16} {gpu:>9.3} ms", "GPU total");
    }
    println!("  {:<16} {cpu:>9.3} ms", "CPU volumes");
    let lpv_bytes = r.lpv().map(|l| l.memory_bytes());
    if let Some(b) = lpv_bytes {
        println!(
            "  {:<16} {:>9.3} MiB",
            "LPV memory",
            b as f64 / (1 << 20) as f64
        );
    }
    let projection = median(projection);
    if projector.is_some() {
        println!("  {:<16} {projection:>9.3} ms", "CPU SH light");
    }
    println!(
        "  {:<16} {wall:>9.3} ms (submit to idle, incl. readback of timings)",
        "wall"
    );
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "technique": technique, "width": f.width,
                "height": f.height, "lights": r.light_count(), "triangles": r.scene.triangles,
                "adapter": ctx.info.name, "backend": format!("{:?}", ctx.info.backend),
                "frames": f.frames, "passes_ms": passes, "gpu_ms": gpu,
                "cpu_volumes_ms": cpu, "cpu_sh_light_ms": projection, "wall_ms": wall,
                "lpv_bytes": lpv_bytes, "grid": r.lpv().map(|l| l.settings.grid),
                "rsm": r.lpv().map(|l| l.settings.rsm_size),
            })
        );
    }
    Ok(())
}
