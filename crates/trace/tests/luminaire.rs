//! Canned light sources (Heidrich ch. 7): the light slab of the built-in `luminaire`'s
//! reflector lamp, as an emitter of the path tracer, against the lamp's real geometry traced
//! through its window; direct light of the lamp only.

use lightlab_core::light_slab::{Far, SlabEmitter};
use lightlab_core::metrics::relmse;
use lightlab_scene::builtin;
use lightlab_trace::luminaire::{self, LampEmitter};
use lightlab_trace::{Accel, PathTracer, RenderSettings, WindowEmitter};
use std::sync::Arc;

#[test]
fn the_slab_emitter_matches_the_lamp_it_was_baked_from() {
    let mut scene = builtin::builtin("luminaire").unwrap();
    scene.lights.clear();
    assert_eq!(luminaire::names(&scene), ["reflector"]);
    let lamp = LampEmitter::new(&scene, "reflector", 16).unwrap();
    let room = luminaire::without_luminaires(&scene);
    let accel = Accel::new(&room);
    let settings = RenderSettings {
        width: 64,
        height: 48,
        spp: 1024,
        max_depth: 1,
        ..Default::default()
    };
    let render = |w: Arc<dyn WindowEmitter>| {
        let mut pt = PathTracer::new(&room, &accel);
        pt.windows = vec![w];
        pt.render(&settings, &|_, _| true).unwrap()
    };
    let t = std::time::Instant::now();
    let slab = luminaire::bake_slab(
        &lamp,
        [8, 8],
        Far::Infinity,
        glam::Vec2::splat(3.0),
        [64, 64],
        8,
        1,
    );
    let bake_s = t.elapsed().as_secs_f64();
    let lamp = Arc::new(lamp);
    let real = render(lamp.clone());
    let canned = render(Arc::new(SlabEmitter::new(Arc::new(slab))));
    let e = relmse(&canned, &real).unwrap();
    let mean = real.data.iter().map(|p| p.x).sum::<f32>() / real.data.len() as f32;
    println!(
        "slab 8×8×64×64 (bake {bake_s:.1} s) against the real lamp: relMSE {e:.5}, mean {mean:.4}"
    );
    if let Ok(dir) = std::env::var("LIGHTLAB_DUMP") {
        let p = std::path::Path::new(&dir);
        real.write(&p.join("real.exr"), Default::default()).unwrap();
        canned
            .write(&p.join("canned.exr"), Default::default())
            .unwrap();
    }
    assert!(mean > 0.003, "the lamp lights the room: {mean}");
    assert!(e <= 0.005, "{e}");
}
