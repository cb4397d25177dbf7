//! Planar mirrors (Heidrich 1999 ch. 10 intro): the built-in `mirror` scene's wall mirror drawn
//! from the mirrored eye, against the path tracer on the mirror's pixels. Direct light only on
//! both sides (no environment, no ambient term): what the mirror shows is then each visible
//! point's direct light, which the path tracer reaches at depth 2 (the mirror, then the point).

use glam::Vec3;
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse_masked;
use lightlab_gpu::raster::{Ambient, RasterSettings, RenderPath, Renderer, ShadowMethod};
use lightlab_gpu::test_context;
use lightlab_scene::{Camera, Scene, builtin};
use lightlab_trace::render::coverage_mask;
use lightlab_trace::{Accel, PathTracer, RenderSettings};

const W: u32 = 96;
const H: u32 = 72;

fn scene() -> Scene {
    let mut s = builtin::builtin("mirror").unwrap();
    s.environment = None;
    s
}

/// 2 × 2 supersampled, as the demo renders.
fn gpu(scene: &Scene, path: RenderPath, planar_mirrors: bool) -> Image {
    let ctx = test_context().expect("GPU");
    let settings = RasterSettings {
        width: 2 * W,
        height: 2 * H,
        path,
        shadows: ShadowMethod::Map,
        ambient: Ambient::None,
        planar_mirrors,
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
        max_depth: 2,
        ..Default::default()
    };
    pt.render(&s, &|_, _| true).unwrap()
}

/// Pixels whose 3 × 3 sub-pixel rays all hit the mirror (its inside, not its edges).
fn mirror_pixels(scene: &Scene) -> Vec<bool> {
    let mirror = scene
        .instances
        .iter()
        .position(|i| i.name == "mirror")
        .unwrap();
    coverage_mask(scene, &scene.cameras[0], W, H, &[mirror])
}

fn check_view(scene: &Scene, label: &str) -> f64 {
    let mask = mirror_pixels(scene);
    let count = mask.iter().filter(|m| **m).count();
    assert!(
        count > 300,
        "{label}: the camera sees the mirror ({count} pixels)"
    );
    let want = reference(scene);
    let mean: f32 = want
        .data
        .iter()
        .zip(&mask)
        .filter(|(_, m)| **m)
        .map(|(p, _)| p.x + p.y + p.z)
        .sum::<f32>()
        / count as f32;
    assert!(mean > 0.05, "{label}: the mirror shows lit things ({mean})");
    let planar = gpu(scene, RenderPath::Forward, true);
    if let Ok(dir) = std::env::var("LIGHTLAB_TEST_IMAGES") {
        let ldr = Default::default();
        let dir = std::path::Path::new(&dir);
        want.write(&dir.join(format!("mirror-{label}-reference.png")), ldr)
            .unwrap();
        planar
            .write(&dir.join(format!("mirror-{label}-gpu.png")), ldr)
            .unwrap();
    }
    let err = relmse_masked(&planar, &want, &mask).unwrap();
    let without = relmse_masked(&gpu(scene, RenderPath::Forward, false), &want, &mask).unwrap();
    eprintln!(
        "{label}: mirror pixels {count}: planar mirror relMSE {err:.5}, without {without:.4}"
    );
    assert!(err <= 0.01, "{label}: planar mirror relMSE {err}");
    assert!(
        without > 0.3,
        "{label}: without the reflection the mirror is wrong: {without}"
    );
    err
}

#[test]
fn a_planar_mirror_shows_the_path_traced_reflection() {
    if test_context().is_none() {
        return;
    }
    let mut scene = scene();
    check_view(&scene, "default camera");
    // From the other side of the room, looking at the mirror across the objects.
    scene.cameras[0] = Camera::look_at(
        "left",
        Vec3::new(-2.2, 1.3, 2.6),
        Vec3::new(0.6, 1.2, -1.9),
        Vec3::Y,
        50f32.to_radians(),
    );
    check_view(&scene, "left camera");
    // The deferred path reads the same reflected view.
    let mask = mirror_pixels(&scene);
    let fwd = gpu(&scene, RenderPath::Forward, true);
    let def = gpu(&scene, RenderPath::Deferred, true);
    let d = relmse_masked(&def, &fwd, &mask).unwrap();
    eprintln!("deferred against forward on the mirror: {d:.6}");
    assert!(d < 1e-3, "deferred {d}");
}
