//! `lightlab bench normal-filter`: how each normal-map filter (Heidrich §9.1.1; issue 21)
//! lights bumps smaller than a pixel. For each shape of `builtin::bumps::filter_scene` (a plane
//! and a torus under two octaves of Perlin bumps, seen from afar) and each reflection model
//! and roughness asked for, the error of `box`, `variance` and the unfiltered finest level
//! against a render of the finest normals supersampled 8 × 8, and the shimmer under a
//! quarter-pixel camera turn (`lightlab_gpu::normal_filter`).

use anyhow::Result;
use lightlab_gpu::normal_filter::{FilterStudy, measure};
use lightlab_gpu::raster::NormalFilter;
use lightlab_scene::BrdfModel;
use lightlab_scene::builtin::bumps::{BumpShape, filter_scene};

/// Options of `bench normal-filter`.
#[derive(clap::Args, Clone, Debug)]
pub struct NormalFilterBenchArgs {
    /// Shapes measured.
    #[arg(long, value_delimiter = ',', default_value = "plane,torus")]
    pub shapes: Vec<BumpShape>,
    /// Reflection models measured (the names of `--brdf`).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "blinn-phong,pbr,torrance-sparrow,ward,phong"
    )]
    pub models: Vec<BrdfModel>,
    /// Roughnesses measured.
    #[arg(long, value_delimiter = ',', default_value = "0.2,0.3,0.5")]
    pub roughness: Vec<f32>,
    #[arg(long, default_value_t = 128)]
    pub width: u32,
    #[arg(long, default_value_t = 96)]
    pub height: u32,
    /// The reference's supersampling per axis.
    #[arg(long, default_value_t = 8)]
    pub supersample: u32,
}

pub fn run(a: &NormalFilterBenchArgs, json: bool) -> Result<()> {
    let ctx = crate::gpu_context()?;
    let study = FilterStudy {
        width: a.width,
        height: a.height,
        supersample: a.supersample,
        ..Default::default()
    };
    let filters = [
        NormalFilter::Box,
        NormalFilter::Variance,
        NormalFilter::Lit,
        NormalFilter::None,
        NormalFilter::Rook,
    ];
    println!(
        "shape | model | roughness | relMSE box / variance / lit / none / rook | shimmer box / \
         variance / lit / none / rook (reference) | error ratio box/variance, box/lit | shimmer \
         ratio box/variance, box/lit"
    );
    let mut rows = vec![];
    for &shape in &a.shapes {
        for &model in &a.models {
            for &roughness in &a.roughness {
                let scene = filter_scene(shape, model, roughness);
                let (f, moved) = measure(&ctx, &scene, &scene.cameras[0], &study, &filters)?;
                let ratio = |k: usize| (f[0].relmse / f[k].relmse, f[0].flicker / f[k].flicker);
                let ((ev, sv), (el, sl)) = (ratio(1), ratio(2));
                println!(
                    "{shape} | {model} | {roughness} | {:.4} / {:.4} / {:.4} / {:.4} / {:.4} | \
                     {:.4} / {:.4} / {:.4} / {:.4} / {:.4} ({moved:.4}) | {ev:.1}, {el:.1} | \
                     {sv:.1}, {sl:.1}",
                    f[0].relmse,
                    f[1].relmse,
                    f[2].relmse,
                    f[3].relmse,
                    f[4].relmse,
                    f[0].flicker,
                    f[1].flicker,
                    f[2].flicker,
                    f[3].flicker,
                    f[4].flicker
                );
                rows.push(serde_json::json!({
                    "shape": shape.to_string(), "model": model.to_string(),
                    "roughness": roughness, "reference_shimmer": moved,
                    "filters": f.iter().map(|x| serde_json::json!({
                        "filter": x.filter.to_string(), "relmse": x.relmse,
                        "shimmer": x.flicker, "frame_ms": x.frame_ms,
                    })).collect::<Vec<_>>(),
                }));
            }
        }
    }
    println!("device: {}", ctx.info.name);
    if json {
        println!("{}", serde_json::json!({ "rows": rows }));
    }
    Ok(())
}
