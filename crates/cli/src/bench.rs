//! `lightlab bench`: benchmark commands that print figures (never timed tests).
//!
//! `bench trace` measures closest-hit throughput in Mrays/s for coherent rays (primary camera
//! rays over the default camera's image) and incoherent rays (cosine-distributed diffuse
//! bounces from the primary hit points), on one thread and on all threads. The same ray sets
//! can be handed to a peer (see `bench/embree_trace.py`) with `--dump-rays`.
//!
//! `bench bake` bakes the scene's light-maps with both bakers (radiosity and path-traced
//! gathering) at the given settings and reports, for each, the wall time by stage, the texels,
//! the rays cast (counted by the BVH) and rays per second, and the peak resident memory of the
//! process during that bake (Linux: `VmHWM`, reset through `/proc/self/clear_refs` before
//! each bake). `bench/bake_vs_cycles.py` runs Blender's Cycles baker on the same scene at the
//! same texel count and samples per texel and prints the time ratio.

use crate::load_scene;
use anyhow::{Context, Result};
use clap::ValueEnum;
use glam::Vec2;
use lightlab_core::sampling::{Frame, Rng, cosine_hemisphere};
use lightlab_trace::Accel;
use lightlab_trace::accel::RayQuery;
use lightlab_trace::render::surface;
use std::time::Instant;

#[derive(Clone, Copy, ValueEnum, Debug)]
pub enum BenchKind {
    Trace,
    Bake,
    Frame,
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

pub fn run(
    kind: BenchKind,
    scene: &str,
    json: bool,
    n: usize,
    dump_dir: Option<std::path::PathBuf>,
    opaque: bool,
) -> Result<()> {
    match kind {
        BenchKind::Bake => anyhow::bail!("bench bake is handled by bench::bench_bake"),
        BenchKind::Frame => anyhow::bail!("bench frame is handled by raster_cmd::bench_frame"),
        BenchKind::Trace => {}
    }
    anyhow::ensure!(
        (1..=100_000_000).contains(&n),
        "--rays must be in 1..=100000000"
    );
    let s = load_scene(scene, false)?;
    let t = Instant::now();
    let accel = Accel::with_alpha_test(&s, !opaque);
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
        accel.triangle_count(),
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
                "scene": s.name, "triangles": accel.triangle_count(), "build_s": build, "rays": n,
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
fn memory_mib() -> Option<(f64, f64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| -> Option<f64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb / 1024.0)
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// Reset the peak-RSS counter (Linux ≥ 4.0); harmless where it is not supported.
fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// `lightlab bench bake`: both light-map bakers on one scene.
pub fn bench_bake(scene: &str, args: &crate::bake_cmd::BakeArgs, json: bool) -> Result<()> {
    use lightlab_bake::{Method, bake_lightmaps, no_progress};
    let s = load_scene(scene, false)?;
    let threads = rayon::current_num_threads();
    let mut rows = serde_json::Map::new();
    println!(
        "bench bake {} at {} texels/m, {} threads",
        s.name, args.texels_per_metre, threads
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
                "scene": s.name, "threads": threads, "texels_per_metre": args.texels_per_metre,
                "bakers": rows,
            })
        );
    }
    Ok(())
}
