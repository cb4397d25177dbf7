//! `lightlab bench canned`: a canned light's error, memory and frame time against its slab's
//! resolution (Heidrich ch. 7; issue 24). The scene's first luminaire alone (its other lights
//! removed), direct light only: the reference is the path tracer tracing the lamp's real
//! geometry through its window; for each (u,v) × (s,t) resolution the slab is baked, then
//! - the GPU's `canned-light` (shadow maps, 2 × 2 supersampled) against the reference;
//! - the path tracer with the slab as its emitter (§7.2.1) against the reference;
//! - the slab's GPU memory, and the frame time of one pass per grid point against one pass
//!   over the texture array (the fastest of three frames, read back).

use crate::load_scene;
use crate::options::{LoadArgs, SlabArgs};
use anyhow::{Context, Result};
use lightlab_core::image::Image;
use lightlab_core::light_slab::{LightSlab, SlabEmitter};
use lightlab_core::metrics::relmse;
use lightlab_gpu::GpuContext;
use lightlab_gpu::raster::{
    Ambient, CannedLight, CannedPasses, RasterSettings, Renderer, ShadowMethod,
};
use lightlab_scene::Scene;
use lightlab_trace::luminaire::{self, LampEmitter};
use lightlab_trace::{Accel, PathTracer, RenderSettings, WindowEmitter};
use std::sync::Arc;
use std::time::Instant;

/// Options of `bench canned`.
#[derive(clap::Args, Clone, Debug)]
pub struct CannedBenchArgs {
    /// (u,v) resolutions measured.
    #[arg(long, value_delimiter = ',', default_value = "4x4,8x8,16x16")]
    pub uv: Vec<String>,
    /// (s,t) resolutions measured.
    #[arg(long, value_delimiter = ',', default_value = "32x32,64x64,128x128")]
    pub st: Vec<String>,
    #[arg(long, default_value_t = 96)]
    pub width: u32,
    #[arg(long, default_value_t = 72)]
    pub height: u32,
    /// Samples per pixel of the path-traced images.
    #[arg(long, default_value_t = 1024)]
    pub spp: u32,
}

fn grid(s: &str) -> Result<[usize; 2]> {
    let (a, b) = s
        .split_once('x')
        .with_context(|| format!("'{s}' must be NxM"))?;
    Ok([a.trim().parse()?, b.trim().parse()?])
}

fn path_traced(room: &Scene, w: Arc<dyn WindowEmitter>, a: &CannedBenchArgs) -> Result<Image> {
    let accel = Accel::new(room);
    let mut pt = PathTracer::new(room, &accel);
    pt.windows = vec![w];
    let s = RenderSettings {
        width: a.width,
        height: a.height,
        spp: a.spp,
        max_depth: 1,
        ..Default::default()
    };
    Ok(pt.render(&s, &|_, _| true)?)
}

/// The GPU image (2 × 2 supersampled) and the fastest of three frames in milliseconds.
fn gpu(
    ctx: &GpuContext,
    room: &Scene,
    slab: &Arc<LightSlab>,
    passes: CannedPasses,
    a: &CannedBenchArgs,
) -> Result<(Image, f64)> {
    let settings = RasterSettings {
        width: 2 * a.width,
        height: 2 * a.height,
        shadows: ShadowMethod::Map,
        ambient: Ambient::None,
        light_field: vec![CannedLight {
            slab: slab.clone(),
            passes,
        }],
        ..Default::default()
    };
    best_of_three(ctx, &mut Renderer::new(ctx, room, settings)?)
}

/// Three frames of `r`, each read back: the last image halved (the benches render 2 × 2
/// supersampled) and the fastest frame in milliseconds.
pub fn best_of_three(ctx: &GpuContext, r: &mut Renderer) -> Result<(Image, f64)> {
    let mut best = f64::MAX;
    let mut img = None;
    for _ in 0..3 {
        let t = Instant::now();
        r.render(ctx);
        img = Some(r.read_hdr(ctx)?);
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    Ok((img.expect("three frames").downsample(2), best))
}

pub fn run(
    scene: (&str, &LoadArgs),
    slab: &SlabArgs,
    a: &CannedBenchArgs,
    json: bool,
) -> Result<()> {
    let mut scene = load_scene(scene.0, scene.1)?;
    scene.lights.clear();
    scene.environment = None;
    let name = crate::techniques::canned::chosen(&scene, slab, false)?.remove(0);
    let lamp = Arc::new(
        LampEmitter::new(&scene, &name, crate::techniques::canned::LAMP_DEPTH)
            .context("the luminaire has no geometry")?,
    );
    let room = luminaire::without_luminaires(&scene);
    let ctx = crate::gpu_context()?;
    let t = Instant::now();
    let reference = path_traced(&room, lamp.clone(), a)?;
    eprintln!(
        "reference: {} lamp traced through its window, {}×{}, {} spp, {:.1} s",
        name,
        a.width,
        a.height,
        a.spp,
        t.elapsed().as_secs_f64()
    );
    println!(
        "slab (u,v × s,t) | bake s | GPU MB | canned-light relMSE | slab emitter relMSE | per-point ms | array ms"
    );
    let mut rows = vec![];
    for uv in &a.uv {
        for st in &a.st {
            let mut s = slab.clone();
            s.slab_uv = grid(uv)?;
            s.slab_st = grid(st)?;
            let t = Instant::now();
            let baked = crate::techniques::canned::bake(&scene, &name, &s, 0)?;
            let bake_s = t.elapsed().as_secs_f64();
            let baked = Arc::new(baked);
            let (img, per_point_ms) = gpu(&ctx, &room, &baked, CannedPasses::PerPoint, a)?;
            let (_, array_ms) = gpu(&ctx, &room, &baked, CannedPasses::Array, a)?;
            let e_gpu = relmse(&img, &reference)?;
            let emitter = path_traced(&room, Arc::new(SlabEmitter::new(baked.clone())), a)?;
            let e_pt = relmse(&emitter, &reference)?;
            let mb = baked.gpu_bytes() as f64 / 1e6;
            println!(
                "{uv} × {st} | {bake_s:.1} | {mb:.2} | {e_gpu:.5} | {e_pt:.5} | {per_point_ms:.0} | {array_ms:.0}"
            );
            rows.push(serde_json::json!({
                "uv": uv, "st": st, "bake_s": bake_s, "gpu_mb": mb,
                "canned_light_relmse": e_gpu, "slab_emitter_relmse": e_pt,
                "per_point_ms": per_point_ms, "array_ms": array_ms,
            }));
        }
    }
    println!("device: {}", ctx.info.name);
    if json {
        println!(
            "{}",
            serde_json::json!({ "scene": scene.name, "luminaire": name, "rows": rows })
        );
    }
    Ok(())
}
