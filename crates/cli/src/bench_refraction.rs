//! `lightlab bench refraction`: a geometry light field's error, memory and cost against its
//! resolution (Heidrich §10.2; issue 24). The scene's largest solid glass object in its
//! environment: the reference is the path tracer (all bounces); for each (u,v) × (s,t)
//! resolution the field is baked, then the GPU's `lightfield-refraction` (2 × 2 supersampled)
//! is measured against it on the glass's pixels, beside the bounding sphere's two refractions
//! (`--refraction two`, no bake) and the frame time (the fastest of three frames, read back).

use crate::load_scene;
use crate::options::{FieldArgs, LoadArgs};
use anyhow::{Context, Result};
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse_masked;
use lightlab_gpu::GpuContext;
use lightlab_gpu::raster::{FieldObject, RasterSettings, Renderer, ShadowMethod};
use lightlab_scene::Scene;
use lightlab_trace::refraction_field::glass_instances;
use lightlab_trace::render::coverage_mask;
use lightlab_trace::{Accel, PathTracer, RenderSettings};
use std::sync::Arc;
use std::time::Instant;

/// Options of `bench refraction`.
#[derive(clap::Args, Clone, Debug)]
pub struct RefractionBenchArgs {
    /// (u,v) resolutions measured.
    #[arg(long, value_delimiter = ',', default_value = "8,16,32,64")]
    pub uv: Vec<usize>,
    /// (s,t) resolutions measured.
    #[arg(long, value_delimiter = ',', default_value = "8,16,32")]
    pub st: Vec<usize>,
    #[arg(long, default_value_t = 96)]
    pub width: u32,
    #[arg(long, default_value_t = 72)]
    pub height: u32,
    /// Samples per pixel of the reference.
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
}

/// The GPU image (2 × 2 supersampled) and the fastest of three frames in milliseconds.
fn gpu(
    ctx: &GpuContext,
    scene: &Scene,
    field: Option<FieldObject>,
    a: &RefractionBenchArgs,
) -> Result<(Image, f64)> {
    let settings = RasterSettings {
        width: 2 * a.width,
        height: 2 * a.height,
        shadows: ShadowMethod::Map,
        object_field: field,
        ..Default::default()
    };
    crate::bench_canned::best_of_three(ctx, &mut Renderer::new(ctx, scene, settings)?)
}

pub fn run(
    scene: (&str, &LoadArgs),
    field: &FieldArgs,
    a: &RefractionBenchArgs,
    json: bool,
) -> Result<()> {
    let scene = load_scene(scene.0, scene.1)?;
    let glass = glass_instances(&scene);
    anyhow::ensure!(
        !glass.is_empty(),
        "{} has no solid glass object",
        scene.name
    );
    let camera = scene
        .cameras
        .first()
        .cloned()
        .or_else(|| scene.framing_camera())
        .context("the scene has no camera")?;
    let mask = coverage_mask(&scene, &camera, a.width, a.height, &glass[..1]);
    let pixels = mask.iter().filter(|m| **m).count();
    let ctx = crate::gpu_context()?;
    let t = Instant::now();
    let accel = Accel::new(&scene);
    let reference = PathTracer::new(&scene, &accel).render(
        &RenderSettings {
            width: a.width,
            height: a.height,
            spp: a.spp,
            max_depth: 16,
            ..Default::default()
        },
        &|_, _| true,
    )?;
    eprintln!(
        "reference: {}×{}, {} spp, {:.1} s; {pixels} pixels of glass",
        a.width,
        a.height,
        a.spp,
        t.elapsed().as_secs_f64()
    );
    let (sphere, sphere_ms) = gpu(&ctx, &scene, None, a)?;
    let e_sphere = relmse_masked(&sphere, &reference, &mask)?;
    println!("field (u,v × s,t) | bake s | GPU MB | glass relMSE | frame ms");
    println!("bounding sphere | 0 | 0 | {e_sphere:.4} | {sphere_ms:.0}");
    let mut rows = vec![];
    for &uv in &a.uv {
        for &st in &a.st {
            let args = FieldArgs {
                field_uv: Some(uv),
                field_st: Some(st),
                ..field.clone()
            };
            let t = Instant::now();
            let (instance, baked) = crate::techniques::refraction::bake(
                &scene,
                lightlab_core::object_field::FieldKind::Geometry,
                &args,
                0,
            )?;
            let bake_s = t.elapsed().as_secs_f64();
            let mb = baked.gpu_bytes() as f64 / 1e6;
            let g = FieldObject {
                instance,
                field: Arc::new(baked),
            };
            let (img, ms) = gpu(&ctx, &scene, Some(g), a)?;
            let e = relmse_masked(&img, &reference, &mask)?;
            println!("{uv}² × {st}² | {bake_s:.1} | {mb:.1} | {e:.4} | {ms:.0}");
            rows.push(serde_json::json!({
                "uv": uv, "st": st, "bake_s": bake_s, "gpu_mb": mb, "relmse": e, "frame_ms": ms,
            }));
        }
    }
    println!("device: {}", ctx.info.name);
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "pixels": pixels, "sphere_relmse": e_sphere, "rows": rows
            })
        );
    }
    Ok(())
}
