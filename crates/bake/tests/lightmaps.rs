//! Acceptance tests of the light-map bakers (issue 5). Run with `--nocapture` for the figures.

use glam::{Mat4, Vec3, Vec4};
use lightlab_bake::*;
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse;
use lightlab_core::sampling::{Rng, uniform_sphere};
use lightlab_scene::builtin::geom::{aabb_box, quad_facing};
use lightlab_scene::{Light, LightKind, Material, Scene};
use lightlab_trace::{Accel, PathTracer, RenderSettings};

fn settings(method: Method, tpm: f32, samples: u32) -> BakeSettings {
    let mut s = BakeSettings {
        method,
        ..Default::default()
    };
    s.layout.texels_per_metre = tpm;
    s.gather.samples = samples;
    s
}

/// A closed 1 m box of inward-facing quads, all emitting L_e = 1 with albedo ρ.
fn furnace(rho: f32) -> Scene {
    let mut s = Scene::default();
    let m = s.add_material(Material {
        name: "furnace".into(),
        base_color: Vec4::new(rho, rho, rho, 1.0),
        specular: 0.0,
        emissive: Vec3::ONE,
        emissive_strength: 1.0,
        ..Default::default()
    });
    let c = Vec3::splat(0.5);
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let faces = [
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
        [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
        [v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
        [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
    ];
    for (i, f) in faces.into_iter().enumerate() {
        s.add_mesh(quad_facing(&format!("face{i}"), f, c, m), Mat4::IDENTITY);
    }
    s
}

/// Valid texels' values (those the sample rasteriser covered).
fn inside_values(lm: &Lightmaps) -> Vec<Vec3> {
    let texels = texels::rasterize(&lm.scene, &lm.layout);
    let mut out = vec![];
    for (page, img) in texels.pages.iter().zip(&lm.pages) {
        for (s, v) in page.samples.iter().zip(&img.data) {
            if s.as_ref().is_some_and(|s| s.coverage > 0.99) {
                out.push(*v);
            }
        }
    }
    out
}

#[test]
fn furnace_converges_to_e_over_one_minus_rho() {
    let rho = 0.5;
    let expected = 1.0 / (1.0 - rho);
    let scene = furnace(rho);
    for method in [Method::Radiosity, Method::Path] {
        let lm = bake_lightmaps(&scene, &settings(method, 16.0, 64), &no_progress).unwrap();
        let v = inside_values(&lm);
        let mean = v.iter().map(|c| c.x as f64).sum::<f64>() / v.len() as f64;
        let mut err: Vec<f32> = v
            .iter()
            .map(|c| ((c.x - expected) / expected).abs())
            .collect();
        err.sort_by(f32::total_cmp);
        let p95 = err[err.len() * 95 / 100];
        let worst = err[err.len() - 1];
        println!(
            "furnace {}: {} texels, mean {mean:.4} (expected {expected}), mean error {:.3} %, \
             95th percentile texel {:.2} %, worst texel {:.2} % (corners), {:.1} s, {:?}",
            method.name(),
            v.len(),
            (mean / expected as f64 - 1.0) * 100.0,
            p95 * 100.0,
            worst * 100.0,
            lm.stats.seconds_total,
            lm.stats.radiosity
        );
        assert!(
            (mean / expected as f64 - 1.0).abs() < 0.01,
            "{method:?}: mean {mean}"
        );
        // Radiosity: point-to-disc form factors are least accurate in corners; the path
        // tracer's per-texel error is its noise at 64 samples.
        let tol = if method == Method::Radiosity {
            0.05
        } else {
            0.15
        };
        assert!(p95 < tol, "{method:?}: 95th percentile texel {p95}");
    }
}

/// Two 2 × 2 × 2 m rooms sharing a 0.3 m wall (4.8 texels at 16 per metre: bicubic sampling
/// needs walls four texels thick, bilinear two), every part a closed box and the floor one slab
/// running under the wall; a point light in the left room only.
fn two_rooms() -> Scene {
    let mut s = Scene::default();
    let m = s.add_material(Material::diffuse("plaster", Vec3::splat(0.7)));
    let t = 0.3;
    let b = |name: &str, lo: Vec3, hi: Vec3| aabb_box(name, lo, hi, m);
    let parts = [
        b(
            "floor",
            Vec3::new(-2.0 - t, -t, -1.0 - t),
            Vec3::new(2.0 + t, 0.0, 1.0 + t),
        ),
        b(
            "ceiling",
            Vec3::new(-2.0 - t, 2.0, -1.0 - t),
            Vec3::new(2.0 + t, 2.0 + t, 1.0 + t),
        ),
        b(
            "west",
            Vec3::new(-2.0 - t, 0.0, -1.0 - t),
            Vec3::new(-2.0, 2.0, 1.0 + t),
        ),
        b(
            "east",
            Vec3::new(2.0, 0.0, -1.0 - t),
            Vec3::new(2.0 + t, 2.0, 1.0 + t),
        ),
        b(
            "north",
            Vec3::new(-2.0, 0.0, -1.0 - t),
            Vec3::new(2.0, 2.0, -1.0),
        ),
        b(
            "south",
            Vec3::new(-2.0, 0.0, 1.0),
            Vec3::new(2.0, 2.0, 1.0 + t),
        ),
        b(
            "middle",
            Vec3::new(-t / 2.0, 0.0, -1.0),
            Vec3::new(t / 2.0, 2.0, 1.0),
        ),
    ];
    for p in parts {
        s.add_mesh(p, Mat4::IDENTITY);
    }
    s.lights.push(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        color: Vec3::ONE,
        intensity: 20.0,
        position: Vec3::new(-0.3, 1.5, 0.0),
        direction: Vec3::NEG_Y,
        range: None,
    });
    s
}

/// Mean light-map value seen from `eye` over many directions (what a camera there would read),
/// and the largest.
fn seen_from(lm: &Lightmaps, eye: Vec3, filter: view::Filter) -> (f32, f32) {
    let accel = Accel::new(&lm.scene);
    let mut rng = Rng::new(3, 0);
    let (mut sum, mut max, mut n) = (0.0f64, 0.0f32, 0);
    for _ in 0..20000 {
        let d = uniform_sphere(rng.next_vec2());
        if let Some(h) = view::lightmap_hit(lm, &accel, eye, d) {
            let v = view::sample(lm, h.page, h.uv, filter).max_element();
            sum += v as f64;
            max = max.max(v);
            n += 1;
        }
    }
    ((sum / n as f64) as f32, max)
}

#[test]
fn no_light_leaks_through_a_thin_wall() {
    let scene = two_rooms();
    for method in [Method::Radiosity, Method::Path] {
        let lm = bake_lightmaps(&scene, &settings(method, 16.0, 32), &no_progress).unwrap();
        for filter in [view::Filter::Bilinear, view::Filter::Bicubic] {
            let (lit, _) = seen_from(&lm, Vec3::new(-1.0, 1.0, 0.0), filter);
            let (_, dark_max) = seen_from(&lm, Vec3::new(1.0, 1.0, 0.0), filter);
            println!(
                "two rooms, {} {filter:?}: lit room mean {lit:.4}, unlit room max {dark_max:.2e} \
                 ({:.2e} of the lit mean), bake {:.1} s {:?}",
                method.name(),
                dark_max / lit,
                lm.stats.seconds_total,
                lm.stats.radiosity
            );
            assert!(lit > 0.1);
            assert!(
                dark_max < 1e-3 * lit,
                "{method:?} {filter:?}: leak {dark_max}"
            );
        }
    }
}

#[test]
fn seams_are_continuous_on_cornell_and_room() {
    for (name, tpm) in [("cornell", 32.0), ("room", 10.0)] {
        let scene = lightlab_scene::builtin::builtin(name).unwrap();
        let lm = bake_lightmaps(&scene, &settings(Method::Path, tpm, 16), &no_progress).unwrap();
        println!(
            "{name}: {} seam sample pairs stitched, largest light-map difference across them \
             {:.3} %",
            lm.stats.seam_pairs,
            lm.stats.seam_max_difference * 100.0
        );
        assert!(lm.stats.seam_max_difference < 0.02);
        // The pairs are real: the room's east wall pieces around the window are coplanar
        // neighbours.
        if name == "room" {
            assert!(lm.stats.seam_pairs > 100);
        }
    }
}

fn reference(scene: &Scene, size: u32, spp: u32) -> Image {
    let accel = Accel::new(scene);
    PathTracer::new(scene, &accel)
        .render(
            &RenderSettings {
                width: size,
                height: size,
                spp,
                ..Default::default()
            },
            &|_, _| true,
        )
        .unwrap()
}

#[test]
fn lightmap_renders_match_the_reference() {
    // (scene, method, texels per metre, samples, relMSE bound)
    let cases = [
        ("cornell", Method::Radiosity, 32.0, 0, 0.02),
        ("cornell", Method::Path, 32.0, 256, 0.01),
        ("room", Method::Radiosity, 10.0, 0, 0.02),
        ("room", Method::Path, 16.0, 256, 0.01),
    ];
    let size = 96;
    let mut refs: std::collections::HashMap<&str, Image> = Default::default();
    for (name, method, tpm, samples, bound) in cases {
        let scene = lightlab_scene::builtin::builtin(name).unwrap();
        let r = refs
            .entry(name)
            .or_insert_with(|| reference(&scene, size, 1024));
        let lm =
            bake_lightmaps(&scene, &settings(method, tpm, samples.max(1)), &no_progress).unwrap();
        for filter in [view::Filter::Bilinear, view::Filter::Bicubic] {
            let img = view::render(&lm, size, size, 0, filter, 16).unwrap();
            let e = relmse(&img, r).unwrap();
            println!(
                "{name} {} {tpm} texels/m {filter:?}: relMSE {e:.4} (bound {bound}), bake {:.1} s, \
                 {} texels",
                method.name(),
                lm.stats.seconds_total,
                lm.stats.valid_texels
            );
            if filter == view::Filter::Bilinear {
                assert!(e <= bound, "{name} {method:?}: relMSE {e}");
            }
        }
    }
}

#[test]
fn baked_folder_round_trips_and_rejects_another_scene() {
    let scene = lightlab_scene::builtin::builtin("cornell").unwrap();
    let mut s = settings(Method::Path, 16.0, 4);
    s.gather.directional = true;
    let lm = bake_lightmaps(&scene, &s, &no_progress).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let m = output::write(
        &lm,
        dir.path(),
        "cornell",
        output::Outputs {
            png: true,
            gltf: false,
        },
    )
    .unwrap();
    assert_eq!(m.pages.len(), lm.pages.len());
    assert!(dir.path().join("lightmap-0.png").exists());
    let back = output::read(dir.path(), &scene).unwrap();
    assert_eq!(back.layout, lm.layout);
    for (a, b) in back.pages.iter().zip(&lm.pages) {
        assert_eq!(a.data, b.data);
    }
    let (da, db) = (back.directional.unwrap(), lm.directional.clone().unwrap());
    assert_eq!(da.len(), db.len());
    for (a, b) in da.iter().zip(&db) {
        assert_eq!(a.data, b.data);
    }
    // Radiosity has no directional output: asking for it is an error, not a silent flat map.
    let mut r = settings(Method::Radiosity, 16.0, 4);
    r.gather.directional = true;
    assert!(matches!(
        bake_lightmaps(&scene, &r, &no_progress),
        Err(BakeError::Settings(_))
    ));
    let other = lightlab_scene::builtin::builtin("room").unwrap();
    assert!(matches!(
        output::read(dir.path(), &other),
        Err(BakeError::Scene(_))
    ));
    assert!(matches!(
        output::read(&dir.path().join("missing"), &scene),
        Err(BakeError::Io(_))
    ));
    // A manifest listing more pages than the layout has is an error, not an index past the
    // layout's pages (it panicked).
    let path = dir.path().join(output::MANIFEST);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut j: serde_json::Value = serde_json::from_str(&text).unwrap();
    let first = j["pages"][0].clone();
    j["pages"].as_array_mut().unwrap().push(first);
    std::fs::write(&path, serde_json::to_string(&j).unwrap()).unwrap();
    let e = output::read(dir.path(), &scene).unwrap_err().to_string();
    assert!(e.contains("pages") && e.contains("manifest"), "{e}");
}

#[test]
fn light_modes_split_direct_and_indirect() {
    // The shadows scene has only punctual lights: indirect-only leaves the bounce light,
    // realtime leaves nothing, and baked = direct + indirect.
    let scene = lightlab_scene::builtin::builtin("shadows").unwrap();
    let n = scene.lights.len();
    let mean = |modes: LightMode, method: Method| {
        let mut s = settings(method, 8.0, 16);
        s.light_modes = vec![modes; n];
        let lm = bake_lightmaps(&scene, &s, &no_progress).unwrap();
        let v = inside_values(&lm);
        v.iter().map(|c| c.x as f64).sum::<f64>() / v.len() as f64
    };
    for method in [Method::Radiosity, Method::Path] {
        let all = mean(LightMode::Baked, method);
        let indirect = mean(LightMode::IndirectOnly, method);
        let none = mean(LightMode::Realtime, method);
        println!("{method:?}: baked {all:.4}, indirect only {indirect:.4}, realtime {none:.4}");
        assert!(none < 1e-6);
        assert!(indirect > 0.0 && indirect < 0.5 * all);
    }
    let mut bad = settings(Method::Path, 8.0, 1);
    bad.light_modes = vec![LightMode::Baked; n + 1];
    assert!(matches!(
        bake_lightmaps(&scene, &bad, &no_progress),
        Err(BakeError::Settings(_))
    ));
}

#[test]
fn cancellation_stops_a_bake() {
    let scene = lightlab_scene::builtin::builtin("cornell").unwrap();
    let r = bake_lightmaps(&scene, &settings(Method::Path, 32.0, 64), &|stage, _, _| {
        stage != "gather"
    });
    assert!(matches!(r, Err(BakeError::Cancelled)));
    let r = bake_lightmaps(
        &scene,
        &settings(Method::Radiosity, 32.0, 1),
        &|stage, _, _| !stage.starts_with("radiosity: shooting"),
    );
    assert!(matches!(r, Err(BakeError::Cancelled)));
}

/// The glTF export carries everything another engine needs: page-space TEXCOORD_1 on one mesh
/// per instance, the pages as images, and node extras naming page, texture and EXR. Rendering
/// the re-imported file with identity rects (what an engine that only reads UV1 + an image
/// does) gives the same picture as the bake.
#[test]
fn gltf_export_renders_like_the_bake() {
    let scene = lightlab_scene::builtin::builtin("room").unwrap();
    let lm = bake_lightmaps(&scene, &settings(Method::Path, 8.0, 4), &no_progress).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let m = output::write(
        &lm,
        dir.path(),
        "room",
        output::Outputs {
            png: false,
            gltf: true,
        },
    )
    .unwrap();
    assert_eq!(m.gltf.as_deref(), Some(output::GLTF));
    let glb = dir.path().join(output::GLTF);
    let bytes = std::fs::read(&glb).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    let imported =
        lightlab_scene::gltf_io::import(&glb, lightlab_scene::LoadOptions::default()).unwrap();
    assert_eq!(imported.instances.len(), scene.instances.len());
    let images = doc["images"].as_array().unwrap().len();
    assert_eq!(images, scene.textures.len() + lm.pages.len());
    let mut layout = lm.layout.clone();
    let mut mapped = 0;
    for (i, rect) in layout.instances.iter_mut().enumerate() {
        let extras = &doc["nodes"][i]["extras"]["lightmap"];
        let Some(r) = *rect else {
            assert!(extras.is_null());
            continue;
        };
        mapped += 1;
        assert_eq!(extras["page"].as_u64(), Some(r.page as u64), "node {i}");
        let tex = extras["texture"].as_u64().unwrap() as usize;
        assert_eq!(tex, scene.textures.len() + r.page as usize);
        assert!(dir.path().join(extras["exr"].as_str().unwrap()).exists());
        // The exported UVs are the page UVs of the bake.
        let ours = &lm.scene.meshes[lm.scene.instances[i].mesh];
        let theirs = &imported.meshes[imported.instances[i].mesh];
        for (a, b) in ours
            .uv1
            .as_ref()
            .unwrap()
            .iter()
            .zip(theirs.uv1.as_ref().unwrap())
        {
            assert!((r.page_uv(*a) - *b).length() < 1e-6);
        }
        *rect = Some(layout::InstanceRect {
            page: r.page,
            offset: [0.0, 0.0],
            scale: [1.0, 1.0],
        });
    }
    assert!(mapped >= 5, "{mapped} light-mapped instances");
    let theirs = Lightmaps {
        scene: imported,
        layout,
        pages: lm.pages.clone(),
        directional: None,
        settings: lm.settings.clone(),
        stats: lm.stats.clone(),
    };
    let a = view::render(&lm, 64, 64, 0, view::Filter::Bilinear, 1).unwrap();
    let b = view::render(&theirs, 64, 64, 0, view::Filter::Bilinear, 1).unwrap();
    let e = relmse(&b, &a).unwrap();
    println!("glTF export vs bake: relMSE {e:.2e}");
    assert!(e < 1e-6, "relMSE {e}");
}

/// Culling the receiver clusters that a shot cannot reach skips work and changes nothing: the
/// light-maps are the same bit for bit with culling on and off, on a room of planar faces (where
/// it skips more than half the transfers: a shooter's own face, the faces behind it) and on a
/// scene with curved knots on a plane (`prt`), and it always skips some.
#[test]
fn radiosity_cluster_culling_is_exact() {
    for (name, tpm, stop, most) in [("room", 5.0, 1e-3, 0.5), ("prt", 4.0, 1e-2, 1.0)] {
        let scene = lightlab_scene::builtin::builtin(name).unwrap();
        let mut s = settings(Method::Radiosity, tpm, 1);
        s.radiosity.sky_samples = 16;
        s.radiosity.sun_samples = 4;
        s.radiosity.stop = stop;
        let on = bake_lightmaps(&scene, &s, &no_progress).unwrap();
        s.radiosity.cull_clusters = false;
        let off = bake_lightmaps(&scene, &s, &no_progress).unwrap();
        let (a, b) = (on.stats.radiosity.unwrap(), off.stats.radiosity.unwrap());
        println!(
            "{name}: {} patches, {} shots, transfers {} culled / {} not ({:.3}), {:.2} s / {:.2} s",
            a.patches,
            a.shots,
            a.transfers,
            b.transfers,
            a.transfers as f64 / b.transfers as f64,
            on.stats.seconds_total,
            off.stats.seconds_total
        );
        assert_eq!(a.shots, b.shots, "{name}");
        assert!(a.shots > 10, "{name}: {} shots", a.shots);
        for (p, q) in on.pages.iter().zip(&off.pages) {
            assert!(p.data == q.data, "{name}: culling changed the light-map");
        }
        assert!(
            (a.transfers as f64) < most * b.transfers as f64,
            "{name}: {} of {} transfers",
            a.transfers,
            b.transfers
        );
    }
}
