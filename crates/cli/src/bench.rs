//! `lightlab bench`: benchmark commands that print figures (never timed tests).
//!
//! `bench trace` measures closest-hit throughput in Mrays/s for coherent rays (primary camera
//! rays over the default camera's image) and incoherent rays (cosine-distributed diffuse
//! bounces from the primary hit points), on one thread and on all threads. The same ray sets
//! can be handed to a peer (see `bench/embree_trace.py`) with `--dump-rays`.

use crate::{load_scene, not_implemented};
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
        BenchKind::Bake => {
            return Err(not_implemented(
                "bench bake (the light-map bakers are planned)",
            ));
        }
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
