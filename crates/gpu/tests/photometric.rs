//! Goniometric lights (issue 24): the GPU's candela tables and cube shadow maps against the
//! path tracer evaluating the same IES/EULUMDAT distributions, direct light only.

use lightlab_core::metrics::relmse;
use lightlab_gpu::raster::{Ambient, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::test_context;
use lightlab_scene::{LightKind, Scene, builtin};
use lightlab_trace::{Accel, PathTracer, RenderSettings};

fn reference(scene: &Scene, w: u32, h: u32) -> lightlab_core::image::Image {
    let accel = Accel::new(scene);
    PathTracer::new(scene, &accel)
        .render(
            &RenderSettings {
                width: w,
                height: h,
                spp: 64,
                max_depth: 1,
                ..Default::default()
            },
            &|_, _| true,
        )
        .unwrap()
}

fn gpu(scene: &Scene, w: u32, h: u32, shadows: ShadowMethod) -> lightlab_core::image::Image {
    let ctx = test_context().expect("GPU");
    let settings = RasterSettings {
        width: w,
        height: h,
        shadows,
        ambient: Ambient::None,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, scene, settings).unwrap();
    r.render(&ctx);
    r.read_hdr(&ctx).unwrap()
}

#[test]
fn measured_lamps_on_the_gpu_match_the_path_tracer() {
    if test_context().is_none() {
        return;
    }
    // The goniometric lamps only: the luminaires' geometry (the reflector lamp, the
    // projector, whose diffuser the path tracer's direct light would reach through its lens)
    // lights the room through their windows, which `canned.rs` tests.
    let scene =
        lightlab_trace::luminaire::without_luminaires(&builtin::builtin("luminaire").unwrap());
    assert_eq!(
        scene
            .lights
            .iter()
            .filter(|l| matches!(l.kind, LightKind::Goniometric { .. }))
            .count(),
        3
    );
    let (w, h) = (128, 96);
    let want = reference(&scene, w, h);
    let shadowed = relmse(&gpu(&scene, w, h, ShadowMethod::Map), &want).unwrap();
    println!("luminaire, shadow maps against the path tracer (direct): relMSE {shadowed:.5}");
    assert!(shadowed <= 0.01, "{shadowed}");

    // Each lamp alone, turned and without occluders' shadows in the way of the comparison:
    // a wrong frame (C0 axis, type B lateral axis) or table would light the wrong walls.
    for i in 0..scene.lights.len() {
        let mut one = scene.clone();
        one.lights = vec![one.lights[i].clone()];
        let l = &mut one.lights[0];
        if let LightKind::Goniometric { c0, .. } = &mut l.kind {
            let turn = glam::Quat::from_axis_angle(l.direction, 0.7);
            *c0 = turn * *c0;
        }
        let want = reference(&one, w, h);
        let got = relmse(&gpu(&one, w, h, ShadowMethod::Map), &want).unwrap();
        // Against the lamp turned a quarter round its axis: the frame matters.
        let mut wrong = one.clone();
        let axis = wrong.lights[0].direction;
        if let LightKind::Goniometric { c0, .. } = &mut wrong.lights[0].kind {
            *c0 = axis.cross(*c0);
        }
        let off = relmse(&gpu(&wrong, w, h, ShadowMethod::Map), &want).unwrap();
        println!(
            "{}: relMSE {got:.5} (turned 90°: {off:.4})",
            one.lights[0].name
        );
        assert!(got <= 0.01, "{got}");
        assert!(off > 5.0 * got.max(1e-3), "{off} against {got}");
    }
}

/// The luminaire's lamps with flat profiles of `k` candela, and the same as point lights of
/// intensity k × the lamps' scale: every GPU path must light them alike.
fn flat_and_point(k: f32) -> (Scene, Scene) {
    use lightlab_scene::photometry::{Goniometric, PhotometryType};
    let mut flat = builtin::builtin("luminaire").unwrap();
    let mut point = flat.clone();
    for l in &mut flat.lights {
        if let LightKind::Goniometric { profile, .. } = &mut l.kind {
            *profile = std::sync::Arc::new(Goniometric {
                kind: PhotometryType::C,
                vertical: vec![0.0, 180.0],
                horizontal: vec![0.0],
                candela: vec![k, k],
                tilt: vec![],
                opening: glam::Vec3::ZERO,
            });
        }
    }
    for l in &mut point.lights {
        l.kind = LightKind::Point;
        l.intensity *= k;
    }
    (flat, point)
}

#[test]
fn a_flat_profile_lights_like_a_point_light_in_every_gpu_path() {
    let Some(ctx) = test_context() else { return };
    let (flat, point) = flat_and_point(300.0);
    let (w, h) = (64, 48);
    let raster = |s: &Scene| gpu(s, w, h, ShadowMethod::Map);
    let e = relmse(&raster(&flat), &raster(&point)).unwrap();
    assert!(e < 1e-5, "shadow-mapped Phong: {e}");
    // The LPV's indirect light: the RSM's cube faces scaled by the table (kind 4).
    let lpv = |s: &Scene| {
        let rs = RasterSettings {
            width: w,
            height: h,
            shadows: ShadowMethod::None,
            ambient: Ambient::None,
            ..Default::default()
        };
        let settings = lightlab_gpu::lpv::LpvSettings::default();
        let mut r = Renderer::with_lpv(&ctx, s, rs, &settings, true).unwrap();
        r.render(&ctx);
        r.read_hdr(&ctx).unwrap()
    };
    let (a, b) = (lpv(&flat), lpv(&point));
    let mean = b.data.iter().map(|p| p.x).sum::<f32>() / b.data.len() as f32;
    assert!(mean > 1e-3, "the point lights' indirect light is {mean}");
    let e = relmse(&a, &b).unwrap();
    println!("LPV indirect, flat profile against point lights: relMSE {e:.2e} (mean {mean:.4})");
    assert!(e < 1e-4, "LPV: {e}");
}
