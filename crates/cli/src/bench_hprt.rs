//! `lightlab bench hprt`: McKenzie Chapter's comparison of hierarchical PRT's choices (ch. 5,
//! §6.3) made quantitative, on the CPU: the SH light-maps baked once (rest pose, each moving
//! object its own occlusion group), then for each variant and frame the light filtered and
//! the image rendered by the CPU view of textured PRT (`render_sh_lightmaps`, what the GPU's
//! `prt-textured` shader computes), against the path-traced reference of the same frame:
//! - relMSE per frame of `prt-textured` (no filters) and of each variant: the three combining
//!   operators, per-point against per-node filters, face against blob occlusion, the thesis's
//!   descent against the occluder-set mask, black occluders;
//! - stability: how much each image changes from frame K to K + 1, over how much the
//!   reference changes (1 = the motion's own change; more is flicker or warping);
//! - filter time per frame against the number of moving objects, with and without caching.

use crate::load_scene;
use crate::options::{BakeArgs, LoadArgs};
use anyhow::{Context, Result};
use lightlab_bake::hprt::{Combine, FilterMode, Hierarchy, HprtSettings, Occlusion, Scope, Tree};
use lightlab_bake::prt::{ShLightmaps, bake_sh_lightmaps, render_sh_lightmaps};
use lightlab_bake::sh_light::{SamplePoints, ShLightSettings, ShLighting, ShProjector};
use lightlab_core::image::Image;
use lightlab_core::sh::Window;
use lightlab_scene::Scene;
use lightlab_trace::{Accel, PathTracer, RenderSettings};
use std::time::Instant;

/// Options of `bench hprt`.
#[derive(clap::Args, Clone, Debug)]
pub struct HprtBenchArgs {
    /// Frames measured (each also against the next frame, for stability).
    #[arg(long, value_delimiter = ',', default_value = "0,12,24")]
    pub frames: Vec<u32>,
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    #[arg(long, default_value_t = 120)]
    pub height: u32,
    /// Samples per pixel of the references.
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
}

/// One variant: a name and its settings (None: `prt-textured`, no filters).
type Variant = (&'static str, Option<HprtSettings>);

fn variants(bands: usize) -> Vec<Variant> {
    let d = HprtSettings {
        bands,
        window: Window::Hann { size: bands as f64 },
        ..Default::default()
    };
    vec![
        ("prt-textured", None),
        ("masked (default)", Some(d)),
        (
            "product",
            Some(HprtSettings {
                combine: Combine::Product,
                ..d
            }),
        ),
        (
            "subtract",
            Some(HprtSettings {
                combine: Combine::Subtract,
                ..d
            }),
        ),
        (
            "per-node filters",
            Some(HprtSettings {
                scope: Scope::Node,
                ..d
            }),
        ),
        (
            "blob occlusion",
            Some(HprtSettings {
                occlusion: Occlusion::Blob,
                ..d
            }),
        ),
        (
            "descent (thesis)",
            Some(HprtSettings {
                filters: FilterMode::Descent,
                ..d
            }),
        ),
        ("black occluders", Some(HprtSettings { bounce: false, ..d })),
    ]
}

pub fn run(scene: (&str, &LoadArgs), bake: &BakeArgs, a: &HprtBenchArgs, json: bool) -> Result<()> {
    let scene = load_scene(scene.0, scene.1)?;
    anyhow::ensure!(
        scene.animation.is_some(),
        "bench hprt needs an animated scene (prt-dynamic), and {} has none",
        scene.name
    );
    let s = bake.transfer_settings()?;
    // prt-textured's bake, and prt-hierarchical's (each object's transfer its own).
    let mut bakes = vec![];
    for self_only in [false, true] {
        let t = Instant::now();
        let ts = lightlab_bake::prt::TransferSettings { self_only, ..s };
        let layout = bake.layout(&scene);
        bakes.push(bake_sh_lightmaps(
            &scene,
            &layout,
            &ts,
            &lightlab_bake::no_progress,
        )?);
        eprintln!(
            "baked {} SH light-maps ({} bands, self-only {self_only}) in {:.1} s",
            scene.name,
            s.bands,
            t.elapsed().as_secs_f64()
        );
    }
    let refs = references(&scene, a)?;
    let mut rows = vec![];
    for (name, settings) in variants(s.bands) {
        let sl = &bakes[usize::from(settings.is_some())];
        let mut errors = vec![];
        let mut change = vec![];
        for (k, &f) in a.frames.iter().enumerate() {
            let img = view(sl, settings, f, a)?;
            let next = view(sl, settings, f + 1, a)?;
            errors.push(lightlab_core::metrics::relmse(&img, &refs[k].0)?);
            change.push(mean_change(&img, &next) / mean_change(&refs[k].0, &refs[k].1).max(1e-9));
        }
        println!(
            "{name:<18} relMSE {}  change/reference {}",
            list(&errors),
            list(&change)
        );
        rows.push(serde_json::json!({"variant": name, "relmse": errors, "stability": change}));
    }
    let timing = filter_times(&bakes[1].scene, s.bands)?;
    if json {
        println!(
            "{}",
            serde_json::json!({"scene": scene.name, "frames": a.frames, "variants": rows,
                "filter_ms": timing})
        );
    }
    Ok(())
}

fn list(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.4}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The reference at each frame and at the next.
fn references(scene: &Scene, a: &HprtBenchArgs) -> Result<Vec<(Image, Image)>> {
    let one = |f: u32| -> Result<Image> {
        let posed = scene.posed(f);
        let accel = Accel::new(&posed);
        let s = RenderSettings {
            width: a.width,
            height: a.height,
            spp: a.spp,
            ..Default::default()
        };
        Ok(PathTracer::new(&posed, &accel).render(&s, &|_, _| true)?)
    };
    a.frames
        .iter()
        .map(|&f| {
            eprintln!("reference, frames {f} and {}", f + 1);
            Ok((one(f)?, one(f + 1)?))
        })
        .collect()
}

/// The CPU view of textured PRT at frame `f`, lit through `settings`' filters.
fn view(
    sl: &ShLightmaps,
    settings: Option<HprtSettings>,
    f: u32,
    a: &HprtBenchArgs,
) -> Result<Image> {
    let posed = sl.scene.posed(f);
    let light = frame_light(&sl.scene, &posed, sl.bands, settings);
    let mut at = sl.clone();
    at.scene = posed;
    render_sh_lightmaps(&at, &light, a.width, a.height, 0, 4).context("the scene has no camera")
}

/// The frame's SH light of `prt-textured` (settings None) or `prt-hierarchical`.
fn frame_light(
    rest: &Scene,
    posed: &Scene,
    bands: usize,
    settings: Option<HprtSettings>,
) -> ShLighting {
    let window = Window::Hann { size: bands as f64 };
    let ls = ShLightSettings {
        bands,
        points: SamplePoints::PerObject,
        window: if settings.is_some() {
            Window::None
        } else {
            window
        },
        environment: true,
        punctual: true,
    };
    let rot = crate::techniques::sh::rotations(rest, posed);
    let projector = ShProjector::new(posed, &ls);
    match settings {
        None => projector.project(posed, Some(&rot)),
        Some(hs) => {
            let tree = Tree::from_scene(rest);
            let mut h = Hierarchy::new(rest, tree, hs);
            h.update(posed);
            h.relight(&projector.project(posed, None), Some(&rot))
        }
    }
}

/// Mean over pixels and channels of |a − b| (a zero-spp-noise-free measure of change).
fn mean_change(a: &Image, b: &Image) -> f64 {
    let s: f64 = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(x, y)| ((*x - *y).abs().element_sum() / 3.0) as f64)
        .sum();
    s / a.data.len().max(1) as f64
}

/// Filter time per frame over 24 frames against the number of moving objects (the others
/// held still), with and without caching; prints the table and returns it.
fn filter_times(rest: &Scene, bands: usize) -> Result<serde_json::Value> {
    let tracks = rest.animation.as_ref().map_or(0, |a| a.tracks.len());
    let mut out = vec![];
    println!("moving objects | cached ms/frame (nodes, Mrays) | uncached ms/frame (nodes, Mrays)");
    for n in 1..=tracks {
        let mut scene = rest.clone();
        if let Some(a) = &mut scene.animation {
            a.tracks.truncate(n);
        }
        let mut cells = vec![];
        for cache in [true, false] {
            let hs = HprtSettings {
                bands,
                cache,
                ..Default::default()
            };
            let tree = Tree::from_scene(&scene);
            let mut h = Hierarchy::new(&scene, tree, hs);
            h.update(&scene.posed(0));
            let (mut nodes, mut rays) = (0, 0);
            let t = Instant::now();
            for f in 1..=24 {
                h.update(&scene.posed(f));
                nodes += h.stats.nodes;
                rays += h.stats.rays;
            }
            let ms = t.elapsed().as_secs_f64() * 1e3 / 24.0;
            cells.push((ms, nodes as f64 / 24.0, rays as f64 / 24.0 / 1e6));
        }
        println!(
            "{n:>14} | {:>8.1} ({:>5.1}, {:.3}) | {:>8.1} ({:>5.1}, {:.3})",
            cells[0].0, cells[0].1, cells[0].2, cells[1].0, cells[1].1, cells[1].2
        );
        out.push(
            serde_json::json!({"moving": n, "cached_ms": cells[0].0, "uncached_ms": cells[1].0,
            "cached_nodes": cells[0].1, "uncached_nodes": cells[1].1}),
        );
    }
    Ok(serde_json::Value::Array(out))
}
