//! `lightlab bench`: benchmark commands that print figures (never timed tests).
//!
//! `bench trace` measures closest-hit throughput in Mrays/s for coherent rays (primary camera
//! rays over the default camera's image) and incoherent rays (cosine-distributed diffuse
//! bounces from the primary hit points), on one thread and on all threads. The same ray sets
//! can be handed to a peer (see `bench/embree_trace.py`) with `--dump-rays`.
//!
//! `bench env` is the equal-memory study of Heidrich's §8.1–8.2: the scene's environment
//! held as a mirror map in each parameterisation at the same texel budgets, and the error of
//! its reads against the source over evenly spread directions (by angle from the sphere map's
//! viewer, and the worst 1 %), with the prefiltering time of a full set of levels.
//!
//! `bench bake` bakes the scene's light-maps with both bakers (radiosity and path-traced
//! gathering) at the given settings and reports, for each, the wall time by stage, the texels,
//! the rays cast (counted by the BVH) and rays per second, and the peak resident memory of the
//! process during that bake (Linux: `VmHWM`, reset through `/proc/self/clear_refs` before
//! each bake). `bench/bake_vs_cycles.py` runs Blender's Cycles baker on the same scene at the
//! same texel count and samples per texel and prints the time ratio.

use crate::load_scene;
use crate::options::{BakeArgs, LoadArgs, TechniqueArgs};
use crate::technique::{Family, Technique};
use crate::techniques::{Bakes, Request};
use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use glam::Vec2;
use lightlab_core::sampling::{Frame, Rng, cosine_hemisphere};
use lightlab_trace::Accel;
use lightlab_trace::accel::RayQuery;
use lightlab_trace::render::surface;
use std::time::Instant;

/// The benchmarks (parsed once per run: the variants' sizes do not matter).
#[derive(Subcommand)]
#[allow(clippy::large_enum_variant)]
pub enum BenchCommand {
    /// Closest-hit ray casting: coherent and incoherent rays, one thread and all.
    Trace {
        /// A built-in scene name or a .gltf/.glb path.
        #[arg(long)]
        scene: String,
        /// Rays per measurement.
        #[arg(long, default_value_t = 1_000_000)]
        rays: usize,
        /// Also write the triangles and rays to this folder (for peers).
        #[arg(long)]
        dump: Option<std::path::PathBuf>,
        /// Ignore alpha (treat alpha-tested triangles as opaque).
        #[arg(long)]
        opaque: bool,
        /// How the BVH is built: PRESET[:KEY=VALUE,...], PRESET one of very-fast, fast,
        /// medium, slow, very-slow (obvhs's, with leaves of up to 16 triangles and collapse
        /// cost 4) or default; keys search (1, 2, 6, 14, 24, 32), depth, reinsert, post, leaf
        /// (1–16), collapse, presplit (true/false), and the 8-wide collapse's costs node and
        /// block (of a node visit and of a block of eight triangle tests; default 1 and 1).
        #[arg(long, default_value = "default")]
        bvh: lightlab_trace::BvhSettings,
        #[command(flatten)]
        load: LoadArgs,
        /// Print one JSON object with the figures as the last line.
        #[arg(long)]
        json: bool,
    },
    /// Both light-map bakers: time, texels, rays/s, peak memory.
    Bake {
        #[arg(long)]
        scene: String,
        #[command(flatten)]
        bake: BakeArgs,
        #[command(flatten)]
        load: LoadArgs,
        #[arg(long)]
        json: bool,
    },
    /// Environment maps at equal memory: error against the source per parameterisation and
    /// texel budget, and prefiltering time.
    Env {
        /// A built-in scene name or a .gltf/.glb path (its environment, or `--env`).
        #[arg(long)]
        scene: String,
        /// Directions per measurement.
        #[arg(long, default_value_t = 20_000)]
        directions: u32,
        #[command(flatten)]
        load: LoadArgs,
        #[arg(long)]
        json: bool,
    },
    /// Hierarchical PRT's variants against the reference on an animated scene (CPU): error,
    /// stability, filter time against moving objects.
    Hprt {
        #[arg(long, default_value = "prt-dynamic")]
        scene: String,
        #[command(flatten)]
        bake: BakeArgs,
        #[command(flatten)]
        hprt: crate::bench_hprt::HprtBenchArgs,
        #[command(flatten)]
        load: LoadArgs,
        #[arg(long)]
        json: bool,
    },
    /// A canned light's error, memory and frame time against its slab's resolution (the
    /// scene's first luminaire alone, direct light).
    Canned {
        #[arg(long, default_value = "luminaire")]
        scene: String,
        #[command(flatten)]
        slab: crate::options::SlabArgs,
        #[command(flatten)]
        canned: crate::bench_canned::CannedBenchArgs,
        #[command(flatten)]
        load: LoadArgs,
        #[arg(long)]
        json: bool,
    },
    /// A geometry light field's error, memory and frame time against its resolution (the
    /// scene's largest solid glass object in its environment).
    Refraction {
        #[arg(long, default_value = "glass")]
        scene: String,
        #[command(flatten)]
        field: crate::options::FieldArgs,
        #[command(flatten)]
        refraction: crate::bench_refraction::RefractionBenchArgs,
        #[command(flatten)]
        load: LoadArgs,
        #[arg(long)]
        json: bool,
    },
    /// Normal-map filters on bumps smaller than a pixel: error against a supersampled render
    /// and shimmer under a sub-pixel camera turn, per reflection model and roughness.
    NormalFilter {
        #[command(flatten)]
        normals: crate::bench_normals::NormalFilterBenchArgs,
        #[arg(long)]
        json: bool,
    },
    /// Milliseconds per pass of a GPU technique (GPU timestamps where the adapter has them).
    Frame {
        #[arg(long)]
        scene: String,
        #[arg(long)]
        technique: Technique,
        #[command(flatten)]
        frame: FrameBenchArgs,
        #[command(flatten)]
        gpu: TechniqueArgs,
        #[command(flatten)]
        load: LoadArgs,
        #[arg(long)]
        json: bool,
    },
}

/// `lightlab bench ...`.
pub fn run(cmd: BenchCommand) -> Result<()> {
    match cmd {
        BenchCommand::Trace {
            scene,
            rays,
            dump,
            opaque,
            bvh,
            load,
            json,
        } => bench_trace((&scene, &load), json, rays, dump, opaque, bvh),
        BenchCommand::Bake {
            scene,
            bake,
            load,
            json,
        } => bench_bake((&scene, &load), &bake, json),
        BenchCommand::Env {
            scene,
            directions,
            load,
            json,
        } => bench_env((&scene, &load), directions, json),
        BenchCommand::Hprt {
            scene,
            bake,
            hprt,
            load,
            json,
        } => crate::bench_hprt::run((&scene, &load), &bake, &hprt, json),
        BenchCommand::Canned {
            scene,
            slab,
            canned,
            load,
            json,
        } => crate::bench_canned::run((&scene, &load), &slab, &canned, json),
        BenchCommand::Refraction {
            scene,
            field,
            refraction,
            load,
            json,
        } => crate::bench_refraction::run((&scene, &load), &field, &refraction, json),
        BenchCommand::NormalFilter { normals, json } => crate::bench_normals::run(&normals, json),
        BenchCommand::Frame {
            scene,
            technique,
            frame,
            gpu,
            load,
            json,
        } => bench_frame((&scene, &load), technique, &gpu, &frame, json),
    }
}

/// Primary rays on a square grid over the default camera, and diffuse bounce rays from their
/// hits.
pub fn ray_sets(
    scene: &lightlab_scene::Scene,
    accel: &Accel,
    n: usize,
) -> Result<(Vec<RayQuery>, Vec<RayQuery>)> {
    let cam = scene.default_camera().context("the scene has no camera")?;
    let side = (n as f64).sqrt().ceil() as u32;
    let mut primary = Vec::with_capacity(n);
    'outer: for y in 0..side {
        for x in 0..side {
            if primary.len() == n {
                break 'outer;
            }
            let ndc = Vec2::new(
                (x as f32 + 0.5) / side as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / side as f32 * 2.0,
            );
            primary.push(RayQuery {
                origin: cam.position(),
                dir: cam.ray_direction(ndc, 1.0),
                tmax: f32::INFINITY,
            });
        }
    }
    let hits = accel.intersect_batch(&primary);
    let mut rng = Rng::new(7, 0);
    let mut secondary = Vec::with_capacity(n);
    let valid: Vec<(usize, lightlab_trace::accel::Hit)> = hits
        .iter()
        .enumerate()
        .filter_map(|(i, h)| h.map(|h| (i, h)))
        .collect();
    anyhow::ensure!(!valid.is_empty(), "no primary ray hits the scene");
    let mut k = 0;
    while secondary.len() < n {
        let (i, h) = valid[k % valid.len()];
        k += 1;
        let sf = surface(scene, accel, &h);
        let ng = if sf.ng.dot(primary[i].dir) < 0.0 {
            sf.ng
        } else {
            -sf.ng
        };
        let d = Frame::from_normal(ng).to_world(cosine_hemisphere(rng.next_vec2()));
        let o = sf.p + ng * 1e-4 * (1.0 + sf.p.abs().max_element());
        secondary.push(RayQuery {
            origin: o,
            dir: d,
            tmax: f32::INFINITY,
        });
    }
    Ok((primary, secondary))
}

fn mrays(accel: &Accel, rays: &[RayQuery], threads: usize) -> Result<f64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    // Warm up once, then take the best of three.
    pool.install(|| accel.intersect_batch(&rays[..rays.len().min(10_000)]));
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        let hits = pool.install(|| accel.intersect_batch(rays));
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(hits);
    }
    Ok(rays.len() as f64 / best / 1e6)
}

/// Write the world-space triangles and both ray sets as little-endian f32 arrays (triangles:
/// 9 floats each; rays: origin and direction, 6 floats each) for peer benchmarks.
fn dump(
    dir: &std::path::Path,
    scene: &lightlab_scene::Scene,
    primary: &[RayQuery],
    secondary: &[RayQuery],
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut tris: Vec<f32> = Vec::with_capacity(scene.triangle_count() * 9);
    for inst in &scene.instances {
        let m = &scene.meshes[inst.mesh];
        for &i in &m.indices {
            tris.extend(
                inst.transform
                    .transform_point3(m.positions[i as usize])
                    .to_array(),
            );
        }
    }
    let write = |name: &str, data: &[f32]| -> Result<()> {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        lightlab_core::image::write_atomic(&dir.join(name), |mut f| -> Result<()> {
            use std::io::Write;
            Ok(f.write_all(&bytes)?)
        })
    };
    let rays = |r: &[RayQuery]| -> Vec<f32> {
        r.iter()
            .flat_map(|q| q.origin.to_array().into_iter().chain(q.dir.to_array()))
            .collect()
    };
    write("triangles.f32", &tris)?;
    write("primary.f32", &rays(primary))?;
    write("secondary.f32", &rays(secondary))?;
    Ok(())
}

fn bench_trace(
    scene: (&str, &LoadArgs),
    json: bool,
    n: usize,
    dump_dir: Option<std::path::PathBuf>,
    opaque: bool,
    bvh: lightlab_trace::BvhSettings,
) -> Result<()> {
    anyhow::ensure!(
        (1..=100_000_000).contains(&n),
        "--rays must be in 1..=100000000"
    );
    let s = load_scene(scene.0, scene.1)?;
    let t = Instant::now();
    let accel = Accel::with_settings(&s, !opaque, bvh);
    let build = t.elapsed().as_secs_f64();
    let (primary, secondary) = ray_sets(&s, &accel, n)?;
    if let Some(dir) = &dump_dir {
        dump(dir, &s, &primary, &secondary)?;
    }
    let all = rayon::current_num_threads();
    let c1 = mrays(&accel, &primary, 1)?;
    let cn = mrays(&accel, &primary, all)?;
    let i1 = mrays(&accel, &secondary, 1)?;
    let i_n = mrays(&accel, &secondary, all)?;
    println!(
        "scene {} ({} triangles), BVH build {:.3} s",
        s.name,
        s.triangle_count(),
        build
    );
    println!(
        "{:<12} {:>14} {:>14}",
        "Mrays/s",
        "1 thread",
        format!("{all} threads")
    );
    println!("{:<12} {:>14.2} {:>14.2}", "coherent", c1, cn);
    println!("{:<12} {:>14.2} {:>14.2}", "incoherent", i1, i_n);
    if json {
        println!(
            "{}",
            serde_json::json!({
                "alpha_test": !opaque,
                "scene": s.name, "triangles": s.triangle_count(), "build_s": build, "rays": n,
                "threads": all,
                "coherent_mrays_1t": c1, "coherent_mrays_mt": cn,
                "incoherent_mrays_1t": i1, "incoherent_mrays_mt": i_n,
            })
        );
    }
    Ok(())
}

/// Resident-memory figures of this process in MiB: (current, peak since the last reset).
/// None where /proc is not available.
pub(crate) fn memory_mib() -> Option<(f64, f64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| -> Option<f64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb / 1024.0)
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// Reset the peak-RSS counter (Linux ≥ 4.0); harmless where it is not supported.
pub(crate) fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// `lightlab bench bake`: both light-map bakers on one scene.
fn bench_bake(scene: (&str, &LoadArgs), args: &BakeArgs, json: bool) -> Result<()> {
    use lightlab_bake::{Method, bake_lightmaps, no_progress};
    let s = load_scene(scene.0, scene.1)?;
    let threads = rayon::current_num_threads();
    let mut rows = serde_json::Map::new();
    println!(
        "bench bake {} at {} texels/m, {} threads",
        s.name,
        args.density(&s),
        threads
    );
    println!(
        "{:<10} {:>9} {:>9} {:>9} {:>10} {:>10} {:>12} {:>10} {:>9}",
        "baker", "total s", "layout s", "solve s", "texels", "valid", "rays", "Mrays/s", "peak MiB"
    );
    for method in [Method::Radiosity, Method::Path] {
        let settings = args.settings(&s, method)?;
        reset_peak_memory();
        let before = memory_mib();
        let t = Instant::now();
        let lm = bake_lightmaps(&s, &settings, &no_progress)?;
        let wall = t.elapsed().as_secs_f64();
        let after = memory_mib();
        let st = &lm.stats;
        let mrays = st.rays as f64 / wall / 1e6;
        let peak = after.map(|m| m.1);
        println!(
            "{:<10} {:>9.2} {:>9.2} {:>9.2} {:>10} {:>10} {:>12} {:>10.2} {:>9}",
            method.name(),
            wall,
            st.seconds_layout,
            st.seconds_solve,
            st.page_texels,
            st.valid_texels,
            st.rays,
            mrays,
            peak.map_or("n/a".to_string(), |p| format!("{p:.0}"))
        );
        let mut row = serde_json::json!({
            "seconds": wall, "seconds_layout": st.seconds_layout,
            "seconds_solve": st.seconds_solve, "page_texels": st.page_texels,
            "texels": st.texels, "valid_texels": st.valid_texels, "pages": st.pages,
            "rays": st.rays, "mrays_per_s": mrays,
            "rss_before_mib": before.map(|m| m.0), "peak_rss_mib": peak,
        });
        match method {
            Method::Path => {
                row["samples_per_texel"] = settings.gather.samples.into();
                row["max_depth"] = settings.gather.max_depth.into();
            }
            Method::Radiosity => {
                if let Some(r) = &st.radiosity {
                    row["shots"] = r.shots.into();
                    row["unshot_fraction"] = r.unshot_fraction.into();
                    row["block_size"] = settings.radiosity.block_size.into();
                }
            }
        }
        rows.insert(method.name().to_string(), row);
    }
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": s.name, "threads": threads, "texels_per_metre": args.density(&s),
                "bakers": rows,
            })
        );
    }
    Ok(())
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

fn bench_env(scene: (&str, &LoadArgs), directions: u32, json: bool) -> Result<()> {
    use lightlab_core::envmap::{self, EnvSettings, Lobe};
    use lightlab_core::param::Param;
    let s = load_scene(scene.0, scene.1)?;
    let env = s
        .environment
        .as_ref()
        .context("the scene has no environment map: give one with --env FILE")?;
    let params = [
        ("dual-paraboloid", Param::DualParaboloid),
        ("cube", Param::Cube),
        ("sphere", Param::SphereMap),
    ];
    println!(
        "environment {}×{}; relative squared error of mirror reads against the source, {directions} directions",
        env.image.width, env.image.height
    );
    println!(
        "{:<16} {:>9} {:>6} {:>10} {:>10} {:>10} {:>10} {:>10} {:>9}",
        "map", "texels", "face", "0-90°", "90-150°", "150-180°", "all", "worst 1%", "filter s"
    );
    let mut rows = vec![];
    for texels in [2 * 32 * 32, 2 * 64 * 64, 2 * 128 * 128, 2 * 256 * 256] {
        for (name, param) in params {
            let e = envmap::mirror_error(&env.image, param, texels, directions);
            // A full set of levels (mirror + six roughness values, both lobes), timed.
            let t0 = Instant::now();
            let settings = EnvSettings {
                param,
                frame: envmap::WORLD_TO_MAP,
                size: EnvSettings::equal_memory_size(param, texels),
                roughness: vec![0.0, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8],
                lobes: vec![Lobe::Ggx, Lobe::Phong],
                samples: 128,
                irradiance: true,
            };
            let maps = envmap::prefilter(&env.image, env.intensity, &settings);
            let secs = t0.elapsed().as_secs_f64();
            println!(
                "{name:<16} {texels:>9} {:>6} {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e} {secs:>9.2}",
                maps.size, e.bands[0], e.bands[1], e.bands[2], e.all, e.worst_percent
            );
            rows.push(serde_json::json!({
                "map": name, "texels": texels, "face": maps.size, "bands": e.bands,
                "all": e.all, "worst_percent": e.worst_percent, "prefilter_s": secs,
            }));
        }
    }
    if json {
        println!("{}", serde_json::json!({ "scene": s.name, "rows": rows }));
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Exactly `n` lights: extra white point lights on a circle, or the scene's list cut.
fn set_light_count(scene: &mut lightlab_scene::Scene, n: usize) -> Result<()> {
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
    Ok(())
}

/// Per-frame medians of `bench frame`.
#[derive(Default)]
struct FrameSamples {
    per_pass: std::collections::BTreeMap<&'static str, Vec<f64>>,
    gpu: Vec<f64>,
    wall: Vec<f64>,
    cpu: Vec<f64>,
    sh_light: Vec<f64>,
    /// Hierarchical PRT: nodes whose filters were recomputed per frame.
    hprt_nodes: Vec<f64>,
}

/// `lightlab bench frame`: milliseconds per pass of a GPU technique.
fn bench_frame(
    scene: (&str, &LoadArgs),
    technique: Technique,
    a: &TechniqueArgs,
    f: &FrameBenchArgs,
    json: bool,
) -> Result<()> {
    anyhow::ensure!(
        technique.is_gpu(),
        "bench frame needs a GPU technique ({})",
        Technique::gpu()
            .map(|t| t.name())
            .collect::<Vec<_>>()
            .join(", ")
    );
    anyhow::ensure!(
        (1..=10_000).contains(&f.frames),
        "--frames must be 1 to 10000"
    );
    let mut scene = load_scene(scene.0, scene.1)?;
    crate::options::apply_brdf(&mut scene, a.raster.brdf);
    if let Some(n) = f.lights {
        set_light_count(&mut scene, n)?;
    }
    let ctx = crate::gpu_context()?;
    let req = Request {
        scene: &scene,
        technique,
        args: a,
        width: f.width,
        height: f.height,
        camera: 0,
    };
    let mut tr = crate::techniques::build(&ctx, &req, &mut Bakes::default())?;
    tr.renderer.render(&ctx);
    tr.renderer.render(&ctx);
    let mut m = FrameSamples::default();
    for frame in 0..f.frames {
        let r = &mut tr.renderer;
        if r.settings.wind.amplitude > 0.0 {
            let mut w = r.settings.wind;
            w.time = a.raster.wind_time + frame as f32 / 60.0;
            r.set_wind(&ctx, w)?;
        }
        // An animated scene plays: the objects move and the SH techniques relight (for
        // hierarchical PRT, with the filters the move dirtied).
        if scene.animation.is_some() {
            let t0 = Instant::now();
            tr.pose(&ctx, frame as u32 + 1)?;
            if tr.frames.hprt_stats().is_some() || technique.family() == Family::Sh {
                m.sh_light.push(t0.elapsed().as_secs_f64() * 1e3);
            }
        } else if let Some(ms) = tr.update(&ctx)? {
            m.sh_light.push(ms);
        }
        if let Some(st) = tr.frames.hprt_stats() {
            m.hprt_nodes.push(st.nodes as f64);
        }
        let t = tr.renderer.render(&ctx);
        for (k, v) in &t.gpu_ms {
            m.per_pass.entry(k).or_default().push(*v);
        }
        m.gpu.push(t.gpu_ms.values().sum());
        m.wall.push(t.wall_ms);
        m.cpu.push(t.cpu_volumes_ms);
    }
    report_frame(&ctx, &scene, technique, &tr.renderer, f, m, json);
    Ok(())
}

/// Print `bench frame`'s table (and its JSON line).
fn report_frame(
    ctx: &lightlab_gpu::GpuContext,
    scene: &lightlab_scene::Scene,
    technique: Technique,
    r: &lightlab_gpu::raster::Renderer,
    f: &FrameBenchArgs,
    m: FrameSamples,
    json: bool,
) {
    let projector = !m.sh_light.is_empty();
    let passes: std::collections::BTreeMap<&str, f64> = m
        .per_pass
        .into_iter()
        .map(|(k, v)| (k, median(v)))
        .collect();
    let (gpu, wall, cpu) = (median(m.gpu), median(m.wall), median(m.cpu));
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
    let projection = median(m.sh_light);
    if projector {
        println!("  {:<16} {projection:>9.3} ms", "CPU SH light");
    }
    if !m.hprt_nodes.is_empty() {
        println!(
            "  {:<16} {:>9.1} (of the light above: filters of the objects' moves)",
            "filters / frame",
            median(m.hprt_nodes)
        );
    }
    println!(
        "  {:<16} {wall:>9.3} ms (submit to idle, incl. readback of timings)",
        "wall"
    );
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "technique": technique.name(), "width": f.width,
                "height": f.height, "lights": r.light_count(), "triangles": r.scene.triangles,
                "adapter": ctx.info.name, "backend": format!("{:?}", ctx.info.backend),
                "frames": f.frames, "passes_ms": passes, "gpu_ms": gpu,
                "cpu_volumes_ms": cpu, "cpu_sh_light_ms": projection, "wall_ms": wall,
                "lpv_bytes": lpv_bytes, "grid": r.lpv().map(|l| l.settings.grid),
                "rsm": r.lpv().map(|l| l.settings.rsm_size),
            })
        );
    }
}
