//! Object light fields (Heidrich 1999 ch. 10). The geometry light field (§10.2): the built-in
//! `glass` torus's exit directions
//! baked once by the path tracer's geometry, looked up on the GPU with the environment map;
//! against the path tracer with the same environment, on the glass's pixels, before and after
//! swapping the environment (no re-bake).

use glam::Vec3;
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse_masked;
use lightlab_core::object_field::ObjectField;
use lightlab_gpu::raster::{Ambient, FieldObject, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::test_context;
use lightlab_scene::builtin::glass::studio;
use lightlab_scene::{Scene, builtin};
use lightlab_trace::refraction_field::{bake, glass_instances};
use lightlab_trace::render::coverage_mask;
use lightlab_trace::{Accel, PathTracer, RenderSettings};
use std::sync::Arc;

const W: u32 = 96;
const H: u32 = 72;

/// 2 × 2 supersampled; `field` None: the bounding sphere's two refractions.
fn gpu(scene: &Scene, field: Option<FieldObject>) -> Image {
    let ctx = test_context().expect("GPU");
    let settings = RasterSettings {
        width: 2 * W,
        height: 2 * H,
        shadows: ShadowMethod::None,
        ambient: Ambient::Environment,
        object_field: field,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, scene, settings).unwrap();
    r.render(&ctx);
    r.read_hdr(&ctx).unwrap().downsample(2)
}

fn reference(scene: &Scene) -> Image {
    let accel = Accel::new(scene);
    let pt = PathTracer::new(scene, &accel);
    let s = RenderSettings {
        width: W,
        height: H,
        spp: 256,
        max_depth: 16,
        ..Default::default()
    };
    pt.render(&s, &|_, _| true).unwrap()
}

/// (light field, bounding sphere) relMSE on the glass's pixels.
fn measure(scene: &Scene, field: &FieldObject, label: &str) -> (f64, f64) {
    let glass = glass_instances(scene);
    let mask = coverage_mask(scene, &scene.cameras[0], W, H, &glass);
    let count = mask.iter().filter(|m| **m).count();
    assert!(count > 500, "the camera sees the glass ({count} pixels)");
    let want = reference(scene);
    let with = gpu(scene, Some(field.clone()));
    let sphere = gpu(scene, None);
    if let Ok(dir) = std::env::var("LIGHTLAB_TEST_IMAGES") {
        let dir = std::path::Path::new(&dir);
        for (name, img) in [("reference", &want), ("field", &with), ("sphere", &sphere)] {
            img.write(
                &dir.join(format!("glass-{label}-{name}.png")),
                Default::default(),
            )
            .unwrap();
        }
    }
    let (a, b) = (
        relmse_masked(&with, &want, &mask).unwrap(),
        relmse_masked(&sphere, &want, &mask).unwrap(),
    );
    eprintln!("{label}: {count} glass pixels: light field relMSE {a:.4}, bounding sphere {b:.4}");
    (a, b)
}

#[test]
fn the_glass_torus_refracts_through_its_light_field_in_any_environment() {
    if test_context().is_none() {
        return;
    }
    let mut scene = builtin::builtin("glass").unwrap();
    let instance = glass_instances(&scene)[0];
    let t = std::time::Instant::now();
    let field: Arc<ObjectField> = Arc::new(bake(&scene, instance, 64, 8).unwrap());
    eprintln!(
        "baked 6 × 64² × 8² in {:.1} s, {:.1} MB on the GPU",
        t.elapsed().as_secs_f64(),
        field.gpu_bytes() as f64 / 1e6
    );
    let glass = FieldObject { instance, field };
    let (a, b) = measure(&scene, &glass, "studio");
    assert!(
        a < 0.5 * b,
        "the light field ({a}) beats the bounding sphere ({b})"
    );
    // Another environment: the same field, no re-bake.
    scene.environment = Some(studio(
        512,
        Vec3::new(0.2, 0.75, 0.3),
        Vec3::new(0.85, 0.2, 0.5),
        Vec3::new(0.3, 0.35, 0.6),
    ));
    let (a2, b2) = measure(&scene, &glass, "swapped");
    assert!(
        a2 < 0.5 * b2,
        "swapped: the light field ({a2}) beats the sphere ({b2})"
    );
    assert!(a.max(a2) < 0.05, "light field relMSE {a}, {a2}");
}

/// The radiance light field (§10.1) of `spheres`'s polished silver ball: its light but the
/// scene's punctual lights from the field, which holds its neighbours' reflections that the
/// environment map cannot; against the path tracer on the ball's pixels.
#[test]
fn a_glossy_ball_takes_its_indirect_light_from_its_light_field() {
    if test_context().is_none() {
        return;
    }
    let scene = builtin::builtin("spheres").unwrap();
    let instance = lightlab_trace::radiance_field::glossy_instances(&scene)[0];
    assert_eq!(scene.instances[instance].name, "sphere_silver_polished");
    let t = std::time::Instant::now();
    let field = lightlab_trace::radiance_field::bake(&scene, instance, [16, 32], 16, 1).unwrap();
    eprintln!(
        "baked 6 × 16² × 32² × 16 spp in {:.1} s, {:.1} MB",
        t.elapsed().as_secs_f64(),
        field.gpu_bytes() as f64 / 1e6
    );
    let object = FieldObject {
        instance,
        field: Arc::new(field),
    };
    let mask = coverage_mask(&scene, &scene.cameras[0], W, H, &[instance]);
    let count = mask.iter().filter(|m| **m).count();
    assert!(count > 100, "the camera sees the ball ({count} pixels)");
    let want = reference(&scene);
    let with = gpu(&scene, Some(object));
    let without = gpu(&scene, None);
    let a = relmse_masked(&with, &want, &mask).unwrap();
    let b = relmse_masked(&without, &want, &mask).unwrap();
    eprintln!("{count} ball pixels: light field relMSE {a:.4}, environment map {b:.4}");
    assert!(
        a < 0.5 * b,
        "the light field ({a}) beats the environment map ({b})"
    );
}
