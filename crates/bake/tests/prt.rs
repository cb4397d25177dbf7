//! Transfer vectors (issue 6, first layer): the analytic limits and the inter-reflection
//! against the path tracer's multi-bounce light.

use glam::{DVec3, Mat4, Vec2, Vec3};
use lightlab_bake::prt::{TransferKind, TransferSettings, point_transfer, shade, vertex_transfer};
use lightlab_core::image::Image;
use lightlab_core::sampling::Rng;
use lightlab_core::sh;
use lightlab_scene::builtin::geom::aabb_box;
use lightlab_scene::{Environment, Material, Mesh, Scene};
use lightlab_trace::{Accel, PathTracer, RenderSettings};

/// An n×n grid of quads from `o` spanning `u` and `v`, facing u × v.
fn grid(name: &str, o: Vec3, u: Vec3, v: Vec3, n: u32, material: usize) -> Mesh {
    let normal = u.cross(v).normalize();
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    for j in 0..=n {
        for i in 0..=n {
            let (a, b) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions.push(o + u * a + v * b);
            m.normals.push(normal);
            m.uv0.push(Vec2::new(a, b));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let k = j * (n + 1) + i;
            m.indices
                .extend([k, k + 1, k + n + 2, k, k + n + 2, k + n + 1]);
        }
    }
    m
}

/// The scene's environment projected on `bands` bands (× its intensity).
fn env_sh(scene: &Scene, bands: usize) -> Vec<DVec3> {
    use lightlab_core::sh_env::{EnvFormat, project_env};
    let env = scene
        .environment
        .as_ref()
        .expect("an environment-lit scene");
    project_env(&env.image, EnvFormat::LatLong, bands)
        .into_iter()
        .map(|c| c * env.intensity as f64)
        .collect()
}

/// The path-traced reference at w×w, 256 spp, at most `depth` scattering events.
fn path_traced(scene: &Scene, w: u32, depth: u32) -> Image {
    let accel = Accel::new(scene);
    PathTracer::new(scene, &accel)
        .render(
            &RenderSettings {
                width: w,
                height: w,
                spp: 256,
                max_depth: depth,
                ..Default::default()
            },
            &|_, _| true,
        )
        .unwrap()
}

/// The path tracer's mean E/π over points (position, normal) of a white receiver, 2048 paths
/// each, at most `depth` scattering events.
fn tracer_mean_e(scene: &Scene, accel: &Accel, pts: &[(Vec3, Vec3)], depth: u32, seed: u64) -> f64 {
    let tracer = PathTracer::new(scene, accel);
    let rs = RenderSettings {
        max_depth: depth,
        min_depth: 0,
        ..Default::default()
    };
    let mut sum = 0.0;
    for (k, &(p, n)) in pts.iter().enumerate() {
        let mut rng = Rng::new(seed, k as u64);
        for _ in 0..2048 {
            sum += tracer.surface_radiance(p, n, n, Vec3::ONE, &rs, &mut rng).x as f64;
        }
    }
    sum / (2048.0 * pts.len() as f64)
}

fn uniform_sky(radiance: f32) -> Environment {
    Environment {
        image: Image::from_fn(16, 8, |_, _| Vec3::splat(radiance)),
        intensity: 1.0,
    }
}

/// Uniform radiance 1 in SH: only l₀ = √(4π).
fn uniform_light(bands: usize) -> Vec<DVec3> {
    let mut l = vec![DVec3::ZERO; sh::num_coeffs(bands)];
    l[0] = DVec3::splat((4.0 * std::f64::consts::PI).sqrt());
    l
}

#[test]
fn unoccluded_up_facing_point_is_the_clamped_cosine() {
    let mut scene = Scene::default();
    let white = scene.add_material(Material::diffuse("white", Vec3::splat(0.8)));
    scene.add_mesh(
        grid(
            "floor",
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::X * 2.0,
            -Vec3::Z * 2.0,
            2,
            white,
        ),
        Mat4::IDENTITY,
    );
    let accel = Accel::new(&scene);
    let pts = [(Vec3::ZERO, Vec3::Y), (Vec3::new(0.3, 0.0, -0.2), Vec3::Y)];
    for bands in [3, 4, 5, 6] {
        let exact = TransferSettings {
            bands,
            kind: TransferKind::Unshadowed,
            ..Default::default()
        };
        let cosine = point_transfer(&scene, &accel, &pts, &exact, &[]).unwrap();
        // The clamped cosine about +y: t₀ = Y₀₀ (∫max(cos,0) = π), E/π = 1 under radiance 1.
        assert!((cosine[0] - 0.282_095).abs() < 1e-5);
        let e = shade(&cosine[..sh::num_coeffs(bands)], &uniform_light(bands));
        assert!((e.x - 1.0).abs() < 1e-5, "{e}");
        let est = TransferSettings {
            samples: 4096,
            kind: TransferKind::Shadowed,
            ..exact
        };
        let shadowed = point_transfer(&scene, &accel, &pts, &est, &[]).unwrap();
        let worst = shadowed
            .iter()
            .zip(&cosine)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 5e-3, "{bands} bands: largest difference {worst}");
    }
}

#[test]
fn fully_occluded_point_is_zero() {
    let mut scene = Scene::default();
    let white = scene.add_material(Material::diffuse("white", Vec3::splat(0.8)));
    scene.add_mesh(
        aabb_box("box", Vec3::splat(-1.0), Vec3::splat(1.0), white),
        Mat4::IDENTITY,
    );
    let accel = Accel::new(&scene);
    let s = TransferSettings {
        bands: 5,
        samples: 256,
        kind: TransferKind::Shadowed,
        seed: 1,
        ..Default::default()
    };
    let t = point_transfer(&scene, &accel, &[(Vec3::ZERO, Vec3::Y)], &s, &[]).unwrap();
    assert!(t.iter().all(|x| *x == 0.0), "{t:?}");
}

/// A 2 m open-top box of albedo 0.7 under a uniform sky: the floor sees the sky through the
/// opening and the walls' inter-reflected light.
fn open_box() -> Scene {
    let mut s = Scene::default();
    let white = s.add_material(Material::diffuse("white", Vec3::splat(0.7)));
    let n = 12;
    let (x, y, z) = (Vec3::X * 2.0, Vec3::Y * 1.2, Vec3::Z * 2.0);
    let o = Vec3::new(-1.0, 0.0, -1.0);
    for m in [
        grid("floor", o, z, x, n, white),
        grid("west", o, y, z, n, white),
        grid("east", o + x, z, y, n, white),
        grid("north", o, x, y, n, white),
        grid("south", o + z, y, x, n, white),
    ] {
        s.add_mesh(m, Mat4::IDENTITY);
    }
    s.environment = Some(uniform_sky(1.0));
    s
}

#[test]
fn interreflection_approaches_the_multi_bounce_reference() {
    let scene = open_box();
    let accel = Accel::new(&scene);
    let bands = 4;
    let light = uniform_light(bands);
    let nc = sh::num_coeffs(bands);
    // Floor points between vertices.
    let pts: Vec<(Vec3, Vec3)> = (0..5)
        .flat_map(|i| (0..5).map(move |j| (i, j)))
        .map(|(i, j)| {
            (
                Vec3::new(-0.83 + 0.41 * i as f32, 0.0, -0.79 + 0.4 * j as f32),
                Vec3::Y,
            )
        })
        .collect();
    let mean = |t: &[f32]| -> f64 {
        t.chunks(nc).map(|c| shade(c, &light).x as f64).sum::<f64>() / pts.len() as f64
    };
    let shadowed_s = TransferSettings {
        bands,
        samples: 512,
        kind: TransferKind::Shadowed,
        seed: 3,
        ..Default::default()
    };
    let shadowed = mean(&point_transfer(&scene, &accel, &pts, &shadowed_s, &[]).unwrap());
    let inter_s = TransferSettings {
        kind: TransferKind::Interreflected { bounces: 3 },
        ..shadowed_s
    };
    let (_, sources) = vertex_transfer(&scene, &accel, &inter_s).unwrap();
    assert_eq!(sources.len(), 3);
    let inter = mean(&point_transfer(&scene, &accel, &pts, &inter_s, &sources).unwrap());
    // The reference tracer's E/π at the same points: 1 scattering event (sky only) and 4.
    let reference = |depth: u32| tracer_mean_e(&scene, &accel, &pts, depth, 11);
    let (ref1, ref4) = (reference(1), reference(4));
    println!(
        "floor E/π: shadowed {shadowed:.4} (tracer, sky only {ref1:.4}); \
         inter-reflected 3 bounces {inter:.4} (tracer, depth 4 {ref4:.4})"
    );
    assert!((shadowed / ref1 - 1.0).abs() < 0.02, "{shadowed} vs {ref1}");
    assert!((inter / ref4 - 1.0).abs() < 0.03, "{inter} vs {ref4}");
    assert!((inter - ref4).abs() < 0.25 * (shadowed - ref4).abs());
    // Bad settings are errors.
    let bad = TransferSettings {
        bands: 9,
        ..shadowed_s
    };
    assert!(point_transfer(&scene, &accel, &pts, &bad, &[]).is_err());
}

/// The `prt` scene under its low-frequency sky, diffuse, environment light only: SH light-maps
/// (per-texel transfer) against the path-traced reference, for 3–6 bands, shadowed (vs one
/// scattering event) and inter-reflected (vs three).
#[test]
fn sh_lightmaps_match_the_reference_on_prt() {
    use lightlab_bake::layout::LayoutSettings;
    use lightlab_bake::prt::{bake_sh_lightmaps, render_sh_lightmaps};
    use lightlab_bake::sh_light::ShLighting;
    use lightlab_core::metrics::relmse;
    let mut scene = lightlab_scene::builtin::builtin("prt").unwrap();
    scene.lights.clear();
    let layout = LayoutSettings {
        texels_per_metre: 12.0,
        ..Default::default()
    };
    let (w, spp) = (72u32, 8u32);
    let reference = |depth: u32| path_traced(&scene, w, depth);
    let light_full = env_sh(&scene, 6);
    let truncated = |bands: usize| -> Vec<DVec3> {
        let mut l = light_full.clone();
        l[sh::num_coeffs(bands)..].fill(DVec3::ZERO);
        l
    };
    let (r1, r3) = (reference(1), reference(3));
    let mut table = vec![];
    for kind in [
        TransferKind::Shadowed,
        TransferKind::Interreflected { bounces: 2 },
    ] {
        let s = TransferSettings {
            bands: 6,
            samples: 192,
            kind,
            seed: 5,
            // The ground's dune normal map, as the reference shades it; the decimated knot as
            // it is (the reference renders its own geometry, not its high-poly source).
            normal_mapped: true,
            detail: None,
            self_only: false,
        };
        let sl = bake_sh_lightmaps(&scene, &layout, &s, &lightlab_bake::no_progress).unwrap();
        for bands in [3, 4, 5, 6] {
            let img =
                render_sh_lightmaps(&sl, &ShLighting::uniform(truncated(bands), 0), w, w, 0, spp)
                    .unwrap();
            let (e1, e3) = (relmse(&img, &r1).unwrap(), relmse(&img, &r3).unwrap());
            println!(
                "{kind:?}, {bands} bands: relMSE vs 1-bounce reference {e1:.4}, vs 3-bounce {e3:.4}"
            );
            table.push((kind, bands, e1, e3));
        }
    }
    let get =
        |kind: TransferKind, bands| *table.iter().find(|t| t.0 == kind && t.1 == bands).unwrap();
    // The bound: 5 bands shadowed ≤ 0.03 against the single-bounce reference.
    let s5 = get(TransferKind::Shadowed, 5);
    assert!(s5.2 <= 0.03, "{table:?}");
    // Inter-reflected transfer is closer to the multi-bounce reference than shadowed transfer.
    let i5 = get(TransferKind::Interreflected { bounces: 2 }, 5);
    assert!(i5.3 < s5.3, "{table:?}");
}

/// CaSHL's shooting (Fuchs §5.4.3) on SH light-maps of the open box: the floor's mean E/π
/// converges to the path tracer's all-bounce light, as the gathering variant reaches its
/// bounce count's; both far from shadowed transfer.
#[test]
fn shooting_converges_to_the_multi_bounce_reference() {
    use lightlab_bake::cashl::ShootSettings;
    use lightlab_bake::layout::LayoutSettings;
    use lightlab_bake::prt::bake_sh_lightmaps;
    use lightlab_bake::view::layout_hit;
    let scene = open_box();
    let bands = 4;
    let light = uniform_light(bands);
    let nc = sh::num_coeffs(bands);
    let layout = LayoutSettings {
        texels_per_metre: 16.0,
        ..Default::default()
    };
    let floor: Vec<(Vec3, Vec3)> = (0..5)
        .flat_map(|i| (0..5).map(move |j| (i, j)))
        .map(|(i, j)| {
            (
                Vec3::new(-0.8 + 0.4 * i as f32, 0.0, -0.8 + 0.4 * j as f32),
                Vec3::Y,
            )
        })
        .collect();
    let mean_floor = |kind: TransferKind| -> (f64, Option<lightlab_bake::cashl::ShootStats>) {
        let s = TransferSettings {
            bands,
            samples: 256,
            kind,
            seed: 6,
            ..Default::default()
        };
        let sl = bake_sh_lightmaps(&scene, &layout, &s, &lightlab_bake::no_progress).unwrap();
        let accel = Accel::new(&sl.scene);
        let mut t = vec![0.0f32; nc];
        let sum: f64 = floor
            .iter()
            .map(|&(p, _)| {
                let h = layout_hit(&sl.scene, &sl.layout, &accel, p + Vec3::Y, -Vec3::Y).unwrap();
                sl.sample(h.page, h.uv, &mut t);
                shade(&t, &light).x as f64
            })
            .sum();
        (sum / floor.len() as f64, sl.shooting)
    };
    let (shadowed, _) = mean_floor(TransferKind::Shadowed);
    let (gathered, _) = mean_floor(TransferKind::Interreflected { bounces: 3 });
    let (shot, st) = mean_floor(TransferKind::Shooting(ShootSettings::default()));
    let st = st.expect("shooting reports its figures");
    let accel = Accel::new(&scene);
    let reference = |depth: u32| tracer_mean_e(&scene, &accel, &floor, depth, 12);
    let (ref4, ref_all) = (reference(4), reference(32));
    println!(
        "open box floor E/π: shadowed {shadowed:.4}; gathered 3 bounces {gathered:.4} (tracer \
         depth 4 {ref4:.4}); shot {shot:.4} in {} shots, {} patches, unshot {:.1e} (tracer \
         depth 32 {ref_all:.4})",
        st.shots, st.patches, st.unshot_fraction
    );
    assert!(!st.hit_shot_limit && st.unshot_fraction < 0.01, "{st:?}");
    assert!((shot / ref_all - 1.0).abs() < 0.02, "{shot} vs {ref_all}");
    assert!((gathered / ref4 - 1.0).abs() < 0.03, "{gathered} vs {ref4}");
    assert!(
        shot - shadowed > 0.9 * (ref_all - shadowed),
        "{shot} {shadowed} {ref_all}"
    );
}

#[test]
fn sh_lightmap_folder_round_trips() {
    use lightlab_bake::layout::LayoutSettings;
    use lightlab_bake::prt::bake_sh_lightmaps;
    use lightlab_bake::sh_folder::{read_sh, write_sh};
    let scene = lightlab_scene::builtin::builtin("cornell").unwrap();
    let layout = LayoutSettings {
        texels_per_metre: 8.0,
        ..Default::default()
    };
    let s = TransferSettings {
        bands: 4,
        samples: 16,
        kind: TransferKind::Shadowed,
        seed: 2,
        ..Default::default()
    };
    let sl = bake_sh_lightmaps(&scene, &layout, &s, &lightlab_bake::no_progress).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let c = lightlab_bake::sh_compress::compress(
        &sl,
        &lightlab_bake::sh_compress::CompressSettings {
            representatives: 32,
            ..Default::default()
        },
    )
    .unwrap();
    let m = write_sh(&sl, Some(&c), dir.path(), "cornell", 0.0).unwrap();
    assert_eq!(m.pages[0].len(), 6, "16 coefficients in 6 RGB images");
    // Normal and occlusion maps beside the coefficients.
    assert_eq!(m.normal_pages, ["normal-0.exr"]);
    assert_eq!(m.occlusion_pages, ["occlusion-0.exr"]);
    let occ = Image::read(&dir.path().join("occlusion-0.exr")).unwrap();
    assert!(occ.data.iter().all(|v| (0.0..=1.0).contains(&v.x)));
    assert!(occ.mean().x < 1.0 && occ.mean().x > 0.2, "{:?}", occ.mean());
    let back = read_sh(dir.path(), &scene).unwrap();
    // The compressed copy comes back exactly.
    let (_, cb) = lightlab_bake::sh_folder::read_sh_with_compressed(dir.path(), &scene).unwrap();
    let cb = cb.expect("the folder holds the compressed copy");
    assert_eq!(cb.representatives, c.representatives);
    assert_eq!(cb.pages, c.pages);
    // A truncated index page is a clear error naming the file.
    let idx = dir.path().join("indices-0.bin");
    let bytes = std::fs::read(&idx).unwrap();
    std::fs::write(&idx, &bytes[..bytes.len() - 2]).unwrap();
    let e = lightlab_bake::sh_folder::read_sh_with_compressed(dir.path(), &scene).unwrap_err();
    assert!(e.to_string().contains("indices-0.bin"), "{e}");
    std::fs::write(&idx, &bytes).unwrap();
    // A manifest with 0 bands is refused by name (it panicked the compressed reader and made
    // `shl` blame `--sh-window-size`).
    let mpath = dir.path().join(lightlab_bake::output::MANIFEST);
    let text = std::fs::read_to_string(&mpath).unwrap();
    let mut j: serde_json::Value = serde_json::from_str(&text).unwrap();
    j["bands"] = serde_json::json!(0);
    std::fs::write(&mpath, serde_json::to_string(&j).unwrap()).unwrap();
    let e = lightlab_bake::sh_folder::read_sh_with_compressed(dir.path(), &scene).unwrap_err();
    assert!(e.to_string().contains("0 SH bands"), "{e}");
    std::fs::write(&mpath, &text).unwrap();
    assert_eq!(back.bands, 4);
    assert_eq!(back.layout, sl.layout);
    for (a, b) in back.pages.iter().flatten().zip(sl.pages.iter().flatten()) {
        assert_eq!(a.data, b.data);
    }
    let room = lightlab_scene::builtin::builtin("room").unwrap();
    assert!(matches!(
        read_sh(dir.path(), &room),
        Err(lightlab_bake::BakeError::Scene(_))
    ));
    // Progress reaches the caller, and returning false cancels.
    assert!(matches!(
        bake_sh_lightmaps(&scene, &layout, &s, &|_, _, _| false),
        Err(lightlab_bake::BakeError::Cancelled)
    ));
}

/// Textured (per-texel) against per-vertex transfer on the decimated knot (meshopt, ≈2 % of the
/// high-poly triangles), all judged against the path-traced high-poly knot in the same place:
/// McKenzie Chapter's comparison (§6.2), with and without detail (position, normal and
/// occlusion) baked from the high-poly source onto the decimated copy's texels.
#[test]
fn textured_transfer_beats_per_vertex_on_the_decimated_mesh() {
    use lightlab_bake::detail::detail_scene;
    use lightlab_bake::layout::LayoutSettings;
    use lightlab_bake::prt::{bake_sh_lightmaps, render_sh_lightmaps, render_vertex_transfer};
    use lightlab_bake::sh_light::ShLighting;
    use lightlab_core::metrics::relmse;
    let mut full = lightlab_scene::builtin::builtin("prt").unwrap();
    // The knot is what is compared: a flat ground (no dune normal map) keeps the plane out of it.
    full.materials
        .iter_mut()
        .for_each(|m| m.normal_texture = None);
    let idx = |name: &str| full.instances.iter().position(|i| i.name == name).unwrap();
    let (plane, high, low) = (idx("plane"), idx("knot_high"), idx("knot_low"));
    let low_mesh = &full.meshes[full.instances[low].mesh];
    let high_mesh = &full.meshes[full.instances[high].mesh];
    assert_eq!(low_mesh.detail_source, Some(full.instances[high].mesh));
    println!(
        "decimated knot: {} triangles from {}",
        low_mesh.triangle_count(),
        high_mesh.triangle_count()
    );
    // The decimated knot in the high-poly knot's place, and the high-poly scene it stands for.
    let mut low_scene = full.clone();
    low_scene.lights.clear();
    low_scene.instances = vec![
        full.instances[plane].clone(),
        lightlab_scene::Instance {
            transform: full.instances[high].transform,
            ..full.instances[low].clone()
        },
    ];
    let high_scene = detail_scene(&low_scene);
    let bands = 5;
    let light = env_sh(&full, bands);
    let w = 72;
    let reference = path_traced(&high_scene, w, 1);
    let s = TransferSettings {
        bands,
        samples: 192,
        kind: TransferKind::Shadowed,
        seed: 9,
        ..Default::default()
    };
    let low_accel = Accel::new(&low_scene);
    let (vt, _) = vertex_transfer(&low_scene, &low_accel, &s).unwrap();
    let lighting = ShLighting::uniform(light, 0);
    let per_vertex = render_vertex_transfer(&low_scene, &vt, &lighting, w, w, 0, 8).unwrap();
    let layout = LayoutSettings {
        texels_per_metre: 12.0,
        ..Default::default()
    };
    let textured = |detail| {
        let s = TransferSettings { detail, ..s };
        let sl = bake_sh_lightmaps(&low_scene, &layout, &s, &lightlab_bake::no_progress).unwrap();
        if let Some(st) = sl.detail {
            println!("detail projection: {st:?}");
            assert!(st.misses * 100 <= st.texels, "{st:?}");
        }
        // The baked occlusion map over the knot's (instance 1) rectangle; its normal map
        // holds unit normals.
        let rect = sl.layout.instances[1].unwrap();
        let page = &sl.detail_pages[rect.page as usize];
        let size = glam::Vec2::new(page.occlusion.width as f32, page.occlusion.height as f32);
        let lo = (glam::Vec2::from(rect.offset) * size).as_uvec2();
        let hi = ((glam::Vec2::from(rect.offset) + glam::Vec2::from(rect.scale)) * size)
            .as_uvec2()
            .min(size.as_uvec2());
        let mut ao = vec![];
        for y in lo.y..hi.y {
            for x in lo.x..hi.x {
                let n = page.normal.get(x, y);
                assert!((n.length() - 1.0).abs() < 1e-3, "normal {n}");
                ao.push(page.occlusion.get(x, y).x);
            }
        }
        (render_sh_lightmaps(&sl, &lighting, w, w, 0, 8).unwrap(), ao)
    };
    let (plain, ao_plain) = textured(None);
    let (detailed, ao_detail) = textured(Some(Default::default()));
    let mean = |v: &[f32]| v.iter().map(|a| *a as f64).sum::<f64>() / v.len() as f64;
    let differs = ao_plain
        .iter()
        .zip(&ao_detail)
        .map(|(a, b)| (a - b).abs() as f64)
        .sum::<f64>()
        / ao_plain.len() as f64;
    println!(
        "knot occlusion map: mean decimated {:.3}, with high-poly detail {:.3}, mean |difference| {differs:.3}",
        mean(&ao_plain),
        mean(&ao_detail)
    );
    // The source's ridges and grooves show in the occlusion map texel by texel (not on average:
    // grooves occlude more, ridge tops less than the smoothed tube).
    assert_eq!(ao_plain.len(), ao_detail.len());
    assert!(differs > 0.03, "mean |difference| {differs}");
    assert!((0.1..0.9).contains(&mean(&ao_detail)));
    lightlab_core::image::Image::write(
        &detailed,
        &std::env::temp_dir().join("lightlab-prt-detail.png"),
        Default::default(),
    )
    .ok();
    let ev = relmse(&per_vertex, &reference).unwrap();
    let et = relmse(&plain, &reference).unwrap();
    let ed = relmse(&detailed, &reference).unwrap();
    println!(
        "decimated knot vs high-poly reference, 5 bands shadowed: per-vertex {ev:.4}, textured {et:.4}, textured with high-poly detail {ed:.4}"
    );
    assert!(et < 0.5 * ev, "per-vertex {ev}, textured {et}");
    assert!(ed < 0.8 * et, "textured {et}, with detail {ed}");
}

/// Fuchs §5.7 on `prt`'s dune-mapped ground: SH light-maps whose texel normals average the
/// normal map (and test both cosines) are closer to the path-traced reference — which shades
/// the normal map per hit — than SH light-maps of the flat ground.
#[test]
fn normal_mapped_sh_lightmaps_on_prt() {
    use lightlab_bake::layout::LayoutSettings;
    use lightlab_bake::prt::{bake_sh_lightmaps, render_sh_lightmaps};
    use lightlab_bake::sh_light::ShLighting;
    use lightlab_core::metrics::relmse;
    let mut scene = lightlab_scene::builtin::builtin("prt").unwrap();
    scene.lights.clear();
    assert!(scene.materials.iter().any(|m| m.normal_texture.is_some()));
    let bands = 4;
    let light = env_sh(&scene, bands);
    let w = 72;
    let reference = path_traced(&scene, w, 1);
    let layout = LayoutSettings {
        texels_per_metre: 12.0,
        ..Default::default()
    };
    let lighting = ShLighting::uniform(light, 0);
    let render = |normal_mapped| {
        let s = TransferSettings {
            bands,
            samples: 192,
            kind: TransferKind::Shadowed,
            seed: 4,
            normal_mapped,
            // The reference renders the decimated knot as it is.
            detail: None,
            self_only: false,
        };
        let sl = bake_sh_lightmaps(&scene, &layout, &s, &lightlab_bake::no_progress).unwrap();
        render_sh_lightmaps(&sl, &lighting, w, w, 0, 8).unwrap()
    };
    let (flat, mapped) = (render(false), render(true));
    lightlab_core::image::Image::write(
        &mapped,
        &std::env::temp_dir().join("lightlab-prt-normalmapped.png"),
        Default::default(),
    )
    .ok();
    let (ef, em) = (
        relmse(&flat, &reference).unwrap(),
        relmse(&mapped, &reference).unwrap(),
    );
    println!("prt, 4 bands shadowed vs 1-bounce reference: shl {ef:.4}, shl-normalmapped {em:.4}");
    assert!(em < 0.8 * ef, "flat {ef}, normal-mapped {em}");
}

/// Fuchs §5.6 on `room`: k-means SH light-maps ≥ 10× smaller than raw f32 transfer, rendering
/// within relMSE 0.005 of the uncompressed light-maps; §5.8 filtering removes the blocks
/// (texture-space error at texel edges vs centres).
#[test]
fn compressed_sh_lightmaps_on_room() {
    use lightlab_bake::layout::LayoutSettings;
    use lightlab_bake::prt::{bake_sh_lightmaps, render_sh_lightmaps};
    use lightlab_bake::sh_compress::{
        CompressSettings, Filter, border_error, compress, render_compressed,
    };
    use lightlab_bake::sh_light::{ShLightSettings, ShLighting};
    use lightlab_core::metrics::relmse;
    let scene = lightlab_scene::builtin::builtin("room").unwrap();
    let s = TransferSettings {
        bands: 4,
        samples: 128,
        kind: TransferKind::Shadowed,
        seed: 3,
        ..Default::default()
    };
    let layout = LayoutSettings {
        texels_per_metre: 8.0,
        ..Default::default()
    };
    let t = std::time::Instant::now();
    let sl = bake_sh_lightmaps(&scene, &layout, &s, &lightlab_bake::no_progress).unwrap();
    let bake_s = t.elapsed().as_secs_f64();
    let c = compress(
        &sl,
        &CompressSettings {
            representatives: 1024,
            ..Default::default()
        },
    )
    .unwrap();
    let st = &c.stats;
    println!(
        "room SH light-maps ({bake_s:.1} s): {} vectors → {} representatives in {} iterations \
         ({:.2} s), {} unused, distance max {:.4} rms {:.4}; {} → {} bytes, ratio {:.1}×",
        st.vectors,
        st.representatives,
        st.iterations,
        st.seconds,
        st.unused,
        st.max_distance,
        st.rms_distance,
        st.raw_bytes,
        st.compressed_bytes,
        st.ratio
    );
    assert!(st.ratio >= 10.0, "ratio {}", st.ratio);
    assert!(
        st.iterations >= 4 && st.iterations < 100,
        "{}",
        st.iterations
    );
    let light = ShLighting::new(
        &sl.scene,
        &ShLightSettings {
            bands: s.bands,
            ..Default::default()
        },
        None,
    );
    let w = 96;
    let full = render_sh_lightmaps(&sl, &light, w, w, 0, 4).unwrap();
    let mut errs = vec![];
    for filter in [Filter::Nearest, Filter::Bilinear, Filter::FourTap] {
        let img = render_compressed(&sl, &c, &light, filter, w, w, 0, 4).unwrap();
        let e = relmse(&img, &full).unwrap();
        let (edge, centre) = border_error(&sl, &c, &light.coeffs[0][0], filter);
        println!(
            "{filter:?}: relMSE vs uncompressed {e:.5}; texture-space error at texel edges \
             {edge:.5}, centres {centre:.5}"
        );
        errs.push((e, edge, centre));
    }
    let (bilinear, nearest, four) = (errs[1], errs[0], errs[2]);
    assert!(bilinear.0 <= 0.005, "bilinear relMSE {}", bilinear.0);
    // Blocks: nearest reads err far more at edges than at centres; bilinear of the relit
    // representatives does not, and beats Fuchs's 4-tap at the edges.
    assert!(nearest.1 > 2.0 * nearest.2, "{nearest:?}");
    assert!(bilinear.1 < 1.5 * bilinear.2, "{bilinear:?}");
    assert!(bilinear.1 < four.1, "{bilinear:?} vs {four:?}");

    // Clustered PCA (Sloan et al. 2003), the optional compression: at a comparable size it
    // reconstructs the transfer far more closely than vector quantisation.
    use lightlab_bake::sh_cpca::{CpcaSettings, cpca};
    for (clusters, components) in [(64, 2), (256, 2), (64, 4)] {
        let p = cpca(
            &sl,
            &CpcaSettings {
                clusters,
                components,
                ..Default::default()
            },
        )
        .unwrap();
        let img = render_sh_lightmaps(&p.reconstruct(&sl), &light, w, w, 0, 4).unwrap();
        let e = relmse(&img, &full).unwrap();
        let ps = &p.stats;
        println!(
            "CPCA {clusters} clusters × {components} components ({:.2} s): ratio {:.1}×, rms \
             error {:.4} (k-means 1024: {:.4}), relMSE vs uncompressed {e:.5}",
            ps.seconds, ps.ratio, ps.rms_error, st.rms_distance
        );
        if (clusters, components) == (256, 2) {
            // Half k-means' ratio (9× against 18×) for a sixth of its error.
            assert!(ps.ratio >= 8.0, "{ps:?}");
            assert!(
                e < 0.2 * bilinear.0,
                "CPCA {e} vs k-means bilinear {}",
                bilinear.0
            );
            assert!(ps.rms_error < 0.5 * st.rms_distance, "{ps:?}");
        }
    }
}
