//! Heidrich §5.1–5.2 on the GPU (issue 21): Torrance–Sparrow and Banks shaded from their
//! lookup tables against their formulas, on every surface of the `brdfs` and `shadows` scenes. 16-bit tables
//! stay within 1 % away from grazing; 8-bit ones are measured. Runs on lavapipe in CI.

use lightlab_core::brdf::TableBits;
use lightlab_core::image::Image;
use lightlab_gpu::brdf_tables::BrdfEval;
use lightlab_gpu::raster::{Ambient, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::test_context;
use lightlab_scene::{BrdfModel, builtin};

fn render(ctx: &lightlab_gpu::GpuContext, name: &str, model: BrdfModel, eval: BrdfEval) -> Image {
    let mut scene = builtin::builtin(name).unwrap();
    scene.set_brdf(model);
    let mut r = Renderer::new(
        ctx,
        &scene,
        RasterSettings {
            width: 160,
            height: 120,
            shadows: ShadowMethod::Map,
            ambient: Ambient::None,
            background: false,
            brdf_eval: eval,
            ..Default::default()
        },
    )
    .unwrap();
    r.render(ctx);
    r.read_hdr(ctx).unwrap()
}

/// Relative L1 error (Σ|t − a| / Σ a) and the 95th percentile of per-pixel relative errors,
/// over pixels lit to at least 2 % of the mean (dim pixels lie at grazing light).
fn errors(tables: &Image, analytic: &Image) -> (f64, f64) {
    let lum = |c: glam::Vec3| c.element_sum() as f64;
    let mean = analytic.data.iter().map(|c| lum(*c)).sum::<f64>() / analytic.data.len() as f64;
    let (mut abs, mut total, mut rel) = (0.0, 0.0, vec![]);
    for (t, a) in tables.data.iter().zip(&analytic.data) {
        if lum(*a) < 0.02 * mean {
            continue;
        }
        let d = (*t - *a).abs().element_sum() as f64;
        abs += d;
        total += lum(*a);
        rel.push(d / lum(*a));
    }
    rel.sort_by(f64::total_cmp);
    (abs / total, rel[rel.len() * 95 / 100])
}

#[test]
fn lookup_tables_match_the_formulas() {
    let Some(ctx) = test_context() else { return };
    for (name, model) in [
        ("brdfs", BrdfModel::TorranceSparrow),
        ("brdfs", BrdfModel::Banks),
        ("shadows", BrdfModel::TorranceSparrow),
        ("shadows", BrdfModel::Banks),
    ] {
        let analytic = render(&ctx, name, model, BrdfEval::Analytic);
        let t16 = render(&ctx, name, model, BrdfEval::Tables(TableBits::Sixteen));
        let t8 = render(&ctx, name, model, BrdfEval::Tables(TableBits::Eight));
        let (l16, p16) = errors(&t16, &analytic);
        let (l8, p8) = errors(&t8, &analytic);
        eprintln!(
            "{name} {model:?}: 16-bit tables relative L1 {l16:.4}, p95 {p16:.4}; 8-bit L1 {l8:.4}, \
             p95 {p8:.4}"
        );
        assert!(l16 <= 0.01 && p16 <= 0.01, "{model:?} 16-bit: {l16} {p16}");
        assert!(l8 > l16, "{model:?}: 8-bit tables cost precision");
    }
}
