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
        light_field: Some(CannedLight {
            slab: slab.clone(),
            passes,
        }),
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
