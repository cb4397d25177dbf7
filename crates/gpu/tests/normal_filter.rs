//! Heidrich §9.1.1 on the GPU (issue 21): a bump-mapped plane and torus seen from far enough
//! that a normal-map texel is smaller than a pixel. The variance filter (Toksvig) and the lit
//! one (Heidrich's order: light, then average) must halve the box filter's error against a
//! 64×-supersampled render of the finest normals, and flicker at most half as much under a
//! quarter-pixel camera turn. Runs on lavapipe in CI.

use lightlab_gpu::normal_filter::{FilterStudy, measure};
use lightlab_gpu::raster::{Ambient, NormalFilter, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::test_context;
use lightlab_scene::BrdfModel;
use lightlab_scene::builtin::bumps::{BumpShape, filter_scene};

#[test]
fn filtered_bumps_halve_the_box_filters_error_and_flicker() {
    let Some(ctx) = test_context() else { return };
    for (shape, brdf, roughness) in [
        (BumpShape::Plane, BrdfModel::BlinnPhong, 0.3),
        (BumpShape::Torus, BrdfModel::Pbr, 0.3),
    ] {
        let scene = filter_scene(shape, brdf, roughness);
        let (figures, moved) = measure(
            &ctx,
            &scene,
            &scene.cameras[0],
            &FilterStudy::default(),
            &[
                NormalFilter::Box,
                NormalFilter::Variance,
                NormalFilter::Lit,
                NormalFilter::None,
            ],
        )
        .unwrap();
        for f in &figures {
            eprintln!(
                "{shape:?} {brdf:?} {:?}: relMSE {:.4}, flicker {:.4} (reference {moved:.4})",
                f.filter, f.relmse, f.flicker
            );
        }
        let b = &figures[0];
        for f in &figures[1..3] {
            assert!(f.relmse <= 0.5 * b.relmse, "{shape:?}: {f:?} against {b:?}");
            assert!(
                2.0 * f.flicker <= b.flicker,
                "{shape:?}: {f:?} against {b:?}"
            );
        }
    }
}

/// The WPI report's rooks filter (§5.5): a constant normal map comes out unchanged (every tap
/// agrees with the centre), and on Perlin bumps it smooths: less shimmer than the box filter,
/// the same error (it normalises, so it cannot turn bumps into gloss).
#[test]
fn the_rook_filter_keeps_a_constant_map_and_smooths_bumps() {
    let Some(ctx) = test_context() else { return };
    let mut scene = filter_scene(BumpShape::Plane, BrdfModel::BlinnPhong, 0.3);
    let study = FilterStudy::default();
    let (figures, _) = measure(
        &ctx,
        &scene,
        &scene.cameras[0],
        &study,
        &[NormalFilter::Box, NormalFilter::Rook],
    )
    .unwrap();
    let (b, r) = (&figures[0], &figures[1]);
    eprintln!("perlin plane: box {b:?}, rook {r:?}");
    assert!(r.flicker < 0.9 * b.flicker, "rook {r:?} against box {b:?}");
    assert!(
        (r.relmse / b.relmse - 1.0).abs() < 0.1,
        "rook {r:?} against box {b:?}"
    );
    // A constant tilted normal: the filter returns it.
    let tilted = glam::Vec3::new(0.3, -0.2, 0.93).normalize() * 0.5 + glam::Vec3::splat(0.5);
    for t in &mut scene.textures {
        let n = t.texels.len();
        t.texels = lightlab_scene::Texels::Rgba32F(vec![tilted.extend(1.0); n]);
    }
    let image = |filter| {
        let mut r = Renderer::new(
            &ctx,
            &scene,
            RasterSettings {
                width: 96,
                height: 72,
                shadows: ShadowMethod::None,
                ambient: Ambient::None,
                background: false,
                normal_filter: filter,
                ..Default::default()
            },
        )
        .unwrap();
        r.render(&ctx);
        r.read_hdr(&ctx).unwrap()
    };
    let e = lightlab_core::metrics::relmse(&image(NormalFilter::Rook), &image(NormalFilter::Box))
        .unwrap();
    eprintln!("constant map: rook against box relMSE {e:.2e}");
    assert!(e < 1e-6, "{e}");
}
