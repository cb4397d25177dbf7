//! Heidrich §9.1.1 on the GPU (issue 21): a bump-mapped plane and torus seen from far enough
//! that a normal-map texel is smaller than a pixel. The variance filter (Toksvig) and the lit
//! one (Heidrich's order: light, then average) must halve the box filter's error against a
//! 64×-supersampled render of the finest normals, and flicker at most half as much under a
//! quarter-pixel camera turn. Runs on lavapipe in CI.

use lightlab_gpu::normal_filter::{FilterStudy, measure};
use lightlab_gpu::raster::NormalFilter;
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
