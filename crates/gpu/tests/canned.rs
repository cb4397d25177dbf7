//! Canned light sources (Heidrich ch. 7): the reflector lamp of the built-in `luminaire` baked
//! into an 8 × 8 × 64 × 64 slab, drawn by the GPU as projective-texture spot lights (§7.2.2)
//! and by the path tracer as micro lights (§7.2.1), against the path tracer tracing the lamp's
//! real geometry through its window; direct light of the lamp only.

use glam::Vec2;
use lightlab_core::light_slab::{Far, LightSlab, SlabEmitter};
use lightlab_core::metrics::relmse;
use lightlab_gpu::raster::{
    Ambient, CannedLight, CannedPasses, RasterSettings, Renderer, ShadowMethod,
};
use lightlab_gpu::test_context;
use lightlab_scene::{Scene, builtin};
use lightlab_trace::luminaire::{self, LampEmitter};
use lightlab_trace::{Accel, PathTracer, RenderSettings};
use std::sync::Arc;

fn gpu(
    room: &Scene,
    slab: &Arc<LightSlab>,
    passes: CannedPasses,
    w: u32,
    h: u32,
) -> lightlab_core::image::Image {
    let ctx = test_context().expect("GPU");
    let settings = RasterSettings {
        width: w,
        height: h,
        shadows: ShadowMethod::Map,
        ambient: Ambient::None,
        light_field: vec![CannedLight {
            slab: slab.clone(),
            passes,
        }],
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, room, settings).unwrap();
    r.render(&ctx);
    r.read_hdr(&ctx).unwrap()
}

#[test]
fn the_canned_reflector_lamp_matches_its_real_geometry() {
    if test_context().is_none() {
        return;
    }
    let mut scene = builtin::builtin("luminaire").unwrap();
    scene.lights.clear();
    let lamp = Arc::new(LampEmitter::new(&scene, "reflector", 16).unwrap());
    let room = luminaire::without_luminaires(&scene);
    let (w, h) = (64, 48);
    let accel = Accel::new(&room);
    let traced = |light: Arc<dyn lightlab_trace::WindowEmitter>| {
        let mut pt = PathTracer::new(&room, &accel);
        pt.windows = vec![light];
        let s = RenderSettings {
            width: w,
            height: h,
            spp: 1024,
            max_depth: 1,
            ..Default::default()
        };
        pt.render(&s, &|_, _| true).unwrap()
    };
    let real = traced(lamp.clone());
    let mean = real.data.iter().map(|p| p.x).sum::<f32>() / real.data.len() as f32;
    assert!(mean > 0.003, "the lamp lights the room: {mean}");
    let slab = Arc::new(luminaire::bake_slab(
        &lamp,
        [8, 8],
        Far::Infinity,
        Vec2::splat(3.0),
        [64, 64],
        8,
        1,
    ));
    // 2 × 2 supersampling, as the demo renders.
    let per_point = gpu(&room, &slab, CannedPasses::PerPoint, 2 * w, 2 * h).downsample(2);
    let array = gpu(&room, &slab, CannedPasses::Array, 2 * w, 2 * h).downsample(2);
    let emitter = traced(Arc::new(SlabEmitter::new(slab.clone())));
    let e_pt = relmse(&emitter, &real).unwrap();
    println!("the slab as the path tracer's emitter against the real lamp: relMSE {e_pt:.5}");
    assert!(e_pt <= 0.005, "{e_pt}");
    let same = relmse(&array, &per_point).unwrap();
    let e = relmse(&per_point, &real).unwrap();
    println!(
        "canned light 8×8×64×64 on the GPU against the real lamp: relMSE {e:.5} (array against per-point {same:.1e})"
    );
    if let Ok(dir) = std::env::var("LIGHTLAB_DUMP") {
        let p = std::path::Path::new(&dir);
        real.write(&p.join("real.exr"), Default::default()).unwrap();
        per_point
            .write(&p.join("gpu.exr"), Default::default())
            .unwrap();
    }
    assert!(same < 1e-6, "{same}");
    assert!(e <= 0.02, "{e}");
}

/// Heidrich's Fig 7.3: the slide projector of `luminaire` focused on its screen, its slab's
/// (s,t) plane on the screen (the scene's focus) and fitted to the beam; then both canned
/// lamps of the scene drawn together (their slices share one texture array).
#[test]
fn the_canned_projector_focuses_its_slide_and_shares_the_array_with_the_reflector() {
    if test_context().is_none() {
        return;
    }
    let mut scene = builtin::builtin("luminaire").unwrap();
    scene.lights.clear();
    let lamp = |name: &str| Arc::new(LampEmitter::new(&scene, name, 16).unwrap());
    let (projector, reflector) = (lamp("projector"), lamp("reflector"));
    let far = luminaire::default_far(&scene, "projector", &projector.window);
    let Far::Plane(d) = far else {
        panic!("the projector's slab ends on its screen: {far:?}")
    };
    assert!((d - 3.38).abs() < 0.02, "{d}");
    let half = luminaire::fit_far_half(&projector, far, 1).unwrap();
    // The picture is 36 × 24 mm magnified ~26×: about 0.94 × 0.63 m on the screen.
    assert!(
        (0.45..0.56).contains(&half.x) && (0.31..0.42).contains(&half.y),
        "{half}"
    );
    let slab = |lamp: &LampEmitter, far, half| {
        Arc::new(luminaire::bake_slab(
            lamp,
            [8, 8],
            far,
            half,
            [64, 64],
            4,
            1,
        ))
    };
    let p_slab = slab(&projector, far, half);
    let r_slab = slab(&reflector, Far::Infinity, Vec2::splat(3.0));
    let room = luminaire::without_luminaires(&scene);
    let (w, h) = (64, 48);
    let accel = Accel::new(&room);
    let traced = |lights: Vec<Arc<dyn lightlab_trace::WindowEmitter>>, camera| {
        let mut pt = PathTracer::new(&room, &accel);
        pt.windows = lights;
        let s = RenderSettings {
            width: w,
            height: h,
            spp: 512,
            max_depth: 1,
            camera,
            ..Default::default()
        };
        pt.render(&s, &|_, _| true).unwrap()
    };
    let canned = |slabs: &[&Arc<LightSlab>], camera| {
        let ctx = test_context().unwrap();
        let settings = RasterSettings {
            width: 2 * w,
            height: 2 * h,
            camera,
            shadows: ShadowMethod::Map,
            ambient: Ambient::None,
            light_field: slabs
                .iter()
                .map(|s| CannedLight {
                    slab: (*s).clone(),
                    passes: CannedPasses::Array,
                })
                .collect(),
            ..Default::default()
        };
        let mut r = Renderer::new(&ctx, &room, settings).unwrap();
        r.render(&ctx);
        r.read_hdr(&ctx).unwrap().downsample(2)
    };
    // The screen, seen from in front of the projector (camera 1).
    let real = traced(vec![projector.clone()], 1);
    let gpu = canned(&[&p_slab], 1);
    let e = relmse(&gpu, &real).unwrap();
    let emitter = traced(vec![Arc::new(SlabEmitter::new(p_slab.clone()))], 1);
    let e_pt = relmse(&emitter, &real).unwrap();
    println!(
        "projector {:.0}×{:.0} cm at {d:.2} m: canned light on the GPU {e:.5}, the slab as emitter {e_pt:.5}",
        200.0 * half.x,
        200.0 * half.y
    );
    // Both lamps at once, the room's camera.
    let real2 = traced(vec![projector, reflector], 0);
    let gpu2 = canned(&[&r_slab, &p_slab], 0);
    let e2 = relmse(&gpu2, &real2).unwrap();
    println!("projector and reflector together on the GPU: relMSE {e2:.5}");
    if let Ok(dir) = std::env::var("LIGHTLAB_DUMP") {
        let p = std::path::Path::new(&dir);
        for (name, img) in [
            ("projector_real", &real),
            ("projector_gpu", &gpu),
            ("both_real", &real2),
            ("both_gpu", &gpu2),
        ] {
            img.write(&p.join(format!("{name}.exr")), Default::default())
                .unwrap();
        }
    }
    assert!(e <= 0.02, "{e}");
    assert!(e_pt <= 0.01, "{e_pt}");
    assert!(e2 <= 0.02, "{e2}");
}
