//! The GPU's specular environment term against the path tracer: a lone sphere (convex, so
//! nothing occludes or inter-reflects) lit by the `spheres` environment only, compared over the
//! sphere's pixels.

use glam::{Mat4, Vec2, Vec3, Vec4};
use lightlab_core::image::Image;
use lightlab_scene::{BrdfModel, Camera, Material, Scene};
use std::path::Path;

mod common;

use common::{lightlab, ok};

fn ball(roughness: f32, brdf: BrdfModel) -> Scene {
    let mut s = Scene {
        environment: lightlab_scene::builtin::builtin("spheres")
            .unwrap()
            .environment,
        ..Default::default()
    };
    let mut m = Material::diffuse("metal", Vec3::ONE);
    m.base_color = Vec4::new(0.95, 0.8, 0.55, 1.0);
    m.metallic = 1.0;
    m.roughness = roughness;
    m.specular = 1.0;
    m.brdf = brdf;
    let mat = s.add_material(m);
    s.add_mesh(
        lightlab_scene::builtin::geom::sphere("ball", 1.0, 128, 64, mat),
        Mat4::IDENTITY,
    );
    s.cameras.push(Camera::look_at(
        "cam",
        Vec3::new(0.0, 0.8, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        0.75,
    ));
    s
}

/// relMSE of `a` against `b` over the pixels whose centre ray hits the unit sphere (shrunk by
/// 3 % to keep the silhouette's partial pixels out).
fn sphere_relmse(scene: &Scene, a: &Path, b: &Path) -> f64 {
    masked_relmse(scene, a, b, true)
}

/// relMSE over the pixels on the unit sphere (`on`) or off it.
fn masked_relmse(scene: &Scene, a: &Path, b: &Path, on: bool) -> f64 {
    relmse_where(scene, a, b, |o, d| {
        let t = -o.dot(d);
        let r = (o + d * t).length();
        if on { r <= 0.97 } else { r >= 1.03 && t >= 0.0 }
    })
}

/// relMSE of `a` against `b` over the pixels whose centre ray (origin, direction) `keep`s.
fn relmse_where(scene: &Scene, a: &Path, b: &Path, keep: impl Fn(Vec3, Vec3) -> bool) -> f64 {
    let (a, b) = (Image::read(a).unwrap(), Image::read(b).unwrap());
    let cam = &scene.cameras[0];
    let (w, h) = (a.width, a.height);
    let (mut s, mut n) = (0.0, 0);
    for y in 0..h {
        for x in 0..w {
            let ndc = Vec2::new(
                (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
            );
            let d = cam.ray_direction(ndc, w as f32 / h as f32);
            if !keep(cam.position(), d) {
                continue;
            }
            let i = (y * w + x) as usize;
            for c in 0..3 {
                let (p, q) = (a.data[i][c] as f64, b.data[i][c] as f64);
                s += (p - q).powi(2) / (q * q + 0.01);
            }
            n += 3;
        }
    }
    assert!(n > 1000, "the mask covers {n} samples");
    s / n as f64
}

fn render(glb: &Path, technique: &str, extra: &[&str], out: &Path) {
    let mut args = vec![
        "render",
        "--scene",
        glb.to_str().unwrap(),
        "--technique",
        technique,
        "--width",
        "96",
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", out.to_str().unwrap()]);
    ok(&lightlab(&args));
}

/// Prefiltered environment reflections (dual paraboloid and cube) against the path tracer on
/// a ball of each (roughness, model, measured metal, allowed relMSE). Three tests share the
/// cases so that they run side by side.
fn prefiltered_reflections_match(cases: &[(f32, BrdfModel, Option<&str>, f64)]) {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    for &(r, brdf, metal, limit) in cases {
        let mut scene = ball(r, brdf);
        if let Some(name) = metal {
            let m = &mut scene.materials[0];
            m.base_color = Vec4::ONE;
            m.conductor = lightlab_scene::Conductor::preset(name);
        }
        let glb = p("ball.glb");
        lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
        let reference = p("ref.exr");
        render(&glb, "reference", &["--spp", "256"], &reference);
        let mut errors = vec![];
        // Metals have no diffuse term, which is all the sky's occlusion maps shade: without
        // them (`--sky-occlusion 0`) the printed figures are the same, and the three tests
        // that share this function took 37 s instead of 63 on lavapipe.
        for map in ["dual-paraboloid", "cube"] {
            let gpu = p(&format!("{map}.exr"));
            render(
                &glb,
                "phong-shadow-maps",
                &["--env-map", map, "--ssaa", "2", "--sky-occlusion", "0"],
                &gpu,
            );
            errors.push(sphere_relmse(&scene, &gpu, &reference));
        }
        let none = p("none.exr");
        render(
            &glb,
            "phong-shadow-maps",
            &["--env-map", "none", "--sky-occlusion", "0"],
            &none,
        );
        let without = sphere_relmse(&scene, &none, &reference);
        let agree = sphere_relmse(&scene, &p("cube.exr"), &p("dual-paraboloid.exr"));
        eprintln!(
            "{brdf:?} {metal:?} roughness {r:.3} (exponent {:.0}): relMSE dual paraboloid {:.4}, \
             cube {:.4} (none {without:.3}); cube vs paraboloid {agree:.4}",
            BrdfModel::exponent(r),
            errors[0],
            errors[1]
        );
        for e in &errors {
            assert!(
                *e <= limit,
                "{brdf:?} {metal:?} roughness {r}: relMSE {e} > {limit}"
            );
        }
        assert!(
            without > 10.0 * limit,
            "the term changes nothing: {without}"
        );
        assert!(agree <= 0.002, "cube and paraboloid differ: {agree}");
    }
}

/// Heidrich's Phong lobe at the exponents the issue names: roughness for exponent n.
fn phong(n: f32) -> f32 {
    (2.0 / (n + 2.0)).powf(0.25)
}

#[test]
fn prefiltered_ggx_reflections_match_the_path_tracer() {
    prefiltered_reflections_match(&[
        (0.0, BrdfModel::Pbr, None, 0.002),
        (0.1, BrdfModel::Pbr, None, 0.01),
        (0.3, BrdfModel::Pbr, None, 0.01),
        (0.6, BrdfModel::Pbr, None, 0.01),
    ]);
}

#[test]
fn prefiltered_phong_lobe_reflections_match_the_path_tracer() {
    prefiltered_reflections_match(&[
        (phong(10.0), BrdfModel::Phong, None, 0.005),
        (phong(100.0), BrdfModel::Phong, None, 0.005),
        (phong(1000.0), BrdfModel::Phong, None, 0.005),
    ]);
}

/// Gold's complex index: exact Fresnel.
#[test]
fn prefiltered_reflections_of_a_measured_metal_match_the_path_tracer() {
    prefiltered_reflections_match(&[
        (0.0, BrdfModel::Pbr, Some("gold"), 0.002),
        (0.3, BrdfModel::Pbr, Some("gold"), 0.01),
    ]);
}

#[test]
fn the_irradiance_map_lights_diffuse_surfaces_like_the_path_tracer() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let mut scene = ball(1.0, BrdfModel::Lambert);
    scene.materials[0].metallic = 0.0;
    scene.materials[0].base_color = Vec4::new(0.8, 0.8, 0.8, 1.0);
    let glb = p("ball.glb");
    lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
    let reference = p("ref.exr");
    // Enough samples that the reference's noise (relMSE ~1e-3 at 256) does not hide the
    // difference between the two.
    render(&glb, "reference", &["--spp", "2048"], &reference);
    let mut e = vec![];
    for diffuse in ["map", "sh"] {
        let gpu = p(&format!("{diffuse}.exr"));
        render(
            &glb,
            "phong-shadow-maps",
            &["--env-diffuse", diffuse, "--ssaa", "2"],
            &gpu,
        );
        e.push(sphere_relmse(&scene, &gpu, &reference));
    }
    eprintln!(
        "diffuse sphere: relMSE irradiance map {:.5}, 9 SH coefficients {:.5}",
        e[0], e[1]
    );
    assert!(e[0] <= 0.002, "irradiance map: relMSE {}", e[0]);
}

/// A clear glass ball (KHR_materials_transmission 1, ior 1.5) in the environment: the GPU's
/// refraction through one interface (no lens inversion) and through two (in and out of the
/// ball's bounding sphere, one bounce) against the path tracer, which follows every bounce.
#[test]
fn glass_refracts_the_environment() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let mut scene = ball(0.0, BrdfModel::Pbr);
    let m = &mut scene.materials[0];
    m.metallic = 0.0;
    m.base_color = Vec4::ONE;
    m.specular_transmission = 1.0;
    m.ior = 1.5;
    // A solid ball (KHR_materials_volume), not a thin-walled bubble.
    m.thickness = 2.0;
    let glb = p("glass.glb");
    lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
    let back = lightlab_scene::load(glb.to_str().unwrap(), Default::default()).unwrap();
    assert_eq!(
        (
            back.materials[0].specular_transmission,
            back.materials[0].ior,
            back.materials[0].thickness
        ),
        (1.0, 1.5, 2.0)
    );
    let reference = p("ref.exr");
    render(
        &glb,
        "reference",
        &["--spp", "256", "--max-depth", "32"],
        &reference,
    );
    let (one, gpu) = (p("one.exr"), p("gpu.exr"));
    // Clear glass has no diffuse term, which is all the sky's occlusion maps shade: without
    // them (`--sky-occlusion 0`) the printed figures are the same (a render on lavapipe: 1.7
    // instead of 2.1 s).
    render(
        &glb,
        "phong-shadow-maps",
        &["--ssaa", "2", "--refraction", "one", "--sky-occlusion", "0"],
        &one,
    );
    render(
        &glb,
        "phong-shadow-maps",
        &["--ssaa", "2", "--sky-occlusion", "0"],
        &gpu,
    );
    let none = p("none.exr");
    render(
        &glb,
        "phong-shadow-maps",
        &["--env-map", "none", "--sky-occlusion", "0"],
        &none,
    );
    let (e1, e, without) = (
        sphere_relmse(&scene, &one, &reference),
        sphere_relmse(&scene, &gpu, &reference),
        sphere_relmse(&scene, &none, &reference),
    );
    eprintln!(
        "glass ball: relMSE refraction through one interface {e1:.4}, two {e:.4} (none {without:.3})"
    );
    if let Ok(keep) = std::env::var("LIGHTLAB_KEEP") {
        for (f, to) in [
            (&reference, "glass-ref.exr"),
            (&gpu, "glass-gpu.exr"),
            (&glb, "glass.glb"),
        ] {
            let _ = std::fs::copy(f, Path::new(&keep).join(to));
        }
    }
    assert!(
        e1 < 0.5 * without,
        "refraction does not help: {e1} vs {without}"
    );
    assert!(e <= 0.01, "two interfaces: relMSE {e}");
    assert!(
        e < 0.5 * e1,
        "two interfaces are no better than one: {e} vs {e1}"
    );

    // Frosted glass: the path tracer's rough interface (Walter et al.) against the GPU's
    // prefiltered map read along both refracted directions.
    scene.materials[0].roughness = 0.3;
    lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
    render(
        &glb,
        "reference",
        &["--spp", "256", "--max-depth", "32"],
        &reference,
    );
    render(
        &glb,
        "phong-shadow-maps",
        &["--ssaa", "2", "--sky-occlusion", "0"],
        &gpu,
    );
    let frosted = sphere_relmse(&scene, &gpu, &reference);
    eprintln!("frosted glass ball (roughness 0.3): relMSE {frosted:.4}");
    assert!(frosted <= 0.05, "frosted glass: relMSE {frosted}");
}

/// A thin-walled pane (glTF glass without KHR_materials_volume) in front of the environment,
/// seen obliquely: light crosses it unbent in both renderers, reflecting the sheet's 2F/(1+F).
#[test]
fn thin_glass_panes_transmit_straight_through() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let mut scene = ball(0.0, BrdfModel::Pbr);
    scene.meshes.clear();
    scene.instances.clear();
    let m = &mut scene.materials[0];
    m.metallic = 0.0;
    m.base_color = Vec4::ONE;
    m.specular_transmission = 1.0;
    m.double_sided = true;
    let h = 0.6;
    scene.add_mesh(
        lightlab_scene::builtin::geom::quad(
            "pane",
            [
                Vec3::new(-h, -h, 0.0),
                Vec3::new(h, -h, 0.0),
                Vec3::new(h, h, 0.0),
                Vec3::new(-h, h, 0.0),
            ],
            0,
        ),
        Mat4::from_rotation_y(0.6),
    );
    let inv = Mat4::from_rotation_y(-0.6);
    let on_pane = |o: Vec3, d: Vec3| {
        let (o, d) = (inv.transform_point3(o), inv.transform_vector3(d));
        let t = -o.z / d.z;
        let q = o + d * t;
        t > 0.0 && q.x.abs() < 0.97 * h && q.y.abs() < 0.97 * h
    };
    let glb = p("pane.glb");
    lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
    let (reference, gpu, none) = (p("ref.exr"), p("gpu.exr"), p("none.exr"));
    render(&glb, "reference", &["--spp", "256"], &reference);
    render(&glb, "phong-shadow-maps", &["--ssaa", "2"], &gpu);
    render(&glb, "phong-shadow-maps", &["--env-map", "none"], &none);
    let e = relmse_where(&scene, &gpu, &reference, on_pane);
    let without = relmse_where(&scene, &none, &reference, on_pane);
    eprintln!("thin pane: relMSE {e:.4} (none {without:.3})");
    assert!(e <= 0.005, "thin pane: relMSE {e}");
    assert!(without > 0.1, "the term changes nothing: {without}");
}

/// Heidrich's Fig 8.8: Fresnel-weighted mirror reflections of black dielectrics of index 1.5, 5
/// and 200 (F0 0.04, 0.44, 0.98; Schlick's approximation in both renderers), and a slightly
/// glossy one (roughness 0.1), against the path tracer.
#[test]
fn fresnel_weighted_reflections_follow_the_index_of_refraction() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let mut means = vec![];
    for (ior, roughness) in [(1.5f32, 0.0f32), (5.0, 0.0), (200.0, 0.0), (1.5, 0.1)] {
        let mut scene = ball(roughness, BrdfModel::Pbr);
        let m = &mut scene.materials[0];
        m.metallic = 0.0;
        m.base_color = Vec4::new(0.0, 0.0, 0.0, 1.0);
        m.ior = ior;
        let glb = p("fresnel.glb");
        lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
        let (reference, gpu) = (p("ref.exr"), p("gpu.exr"));
        render(&glb, "reference", &["--spp", "256"], &reference);
        render(&glb, "phong-shadow-maps", &["--ssaa", "2"], &gpu);
        let e = sphere_relmse(&scene, &gpu, &reference);
        let img = Image::read(&gpu).unwrap();
        means.push(img.data.iter().map(|c| c.x as f64).sum::<f64>() / img.data.len() as f64);
        eprintln!("Fresnel ior {ior}, roughness {roughness}: relMSE {e:.4}");
        // Heidrich's Fig 8.8 as images: LIGHTLAB_KEEP=DIR keeps each pair.
        if let Ok(keep) = std::env::var("LIGHTLAB_KEEP") {
            for (f, what) in [(&gpu, "gpu"), (&reference, "ref")] {
                let to = format!("fig8.8-ior{ior}-r{roughness}-{what}.exr");
                let _ = std::fs::copy(f, Path::new(&keep).join(to));
            }
        }
        assert!(e <= 0.01, "ior {ior} roughness {roughness}: relMSE {e}");
    }
    // More of the environment is reflected as the index grows.
    assert!(means[0] < means[1] && means[1] < means[2], "{means:?}");
}

/// `--dynamic-env`: a chrome ball over a grey floor, beside a red box, reflects them (rendered
/// into a cube at its centre) as the path tracer sees them. The neighbours stand 0.6 and 1.5
/// radii off its surface: a map projected from the centre misplaces what is nearer (parallax).
#[test]
fn dynamic_maps_reflect_the_neighbours() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let scene = ball_box_floor();
    let glb = p("dyn.glb");
    lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
    let reference = p("ref.exr");
    render(&glb, "reference", &["--spp", "256"], &reference);
    let (stat, dynamic) = (p("static.exr"), p("dynamic.exr"));
    let (es, ed) = static_and_dynamic(&scene, &glb, &reference, &stat, &dynamic);
    // Redness of the ball's pixels: the box is seen in it.
    let red_share = |f: &Path| {
        let img = Image::read(f).unwrap();
        let (r, g) = img.data.iter().fold((0.0f64, 0.0f64), |(r, g), c| {
            (r + c.x as f64, g + c.y as f64)
        });
        r / g
    };
    // The neighbours as the GPU draws them (what the dynamic map can at best reflect).
    let around = masked_relmse(&scene, &dynamic, &reference, false);
    eprintln!(
        "mirror ball beside a red box: relMSE static map {es:.4}, dynamic {ed:.4} (the GPU's \
         own image around the ball: {around:.4}); red/green static {:.3}, dynamic {:.3}, \
         reference {:.3}",
        red_share(&stat),
        red_share(&dynamic),
        red_share(&reference)
    );
    if let Ok(keep) = std::env::var("LIGHTLAB_KEEP") {
        for (f, to) in [
            (&reference, "dyn-ref.exr"),
            (&dynamic, "dyn-gpu.exr"),
            (&glb, "dyn.glb"),
        ] {
            let _ = std::fs::copy(f, Path::new(&keep).join(to));
        }
    }
    // The target: 0.05 over the mirror's pixels.
    assert!(ed < 0.1 * es, "the dynamic map does not help: {ed} vs {es}");
    assert!(ed <= 0.05, "dynamic map: relMSE {ed}");
}

/// Dynamic maps need no environment: under a sun alone, the chrome ball reflects the lit box
/// and floor (black without them).
#[test]
fn dynamic_maps_work_without_an_environment() {
    use lightlab_scene::{Light, LightKind};
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let mut scene = ball_box_floor();
    scene.environment = None;
    scene.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional {
            angular_diameter: 0.0,
        },
        color: Vec3::ONE,
        intensity: 3.0,
        position: Vec3::ZERO,
        direction: Vec3::new(-0.3, -1.0, -0.4).normalize(),
        range: None,
    });
    let glb = p("sun.glb");
    lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
    let reference = p("ref.exr");
    render(&glb, "reference", &["--spp", "128"], &reference);
    let (stat, dynamic) = (p("static.exr"), p("dynamic.exr"));
    let (es, ed) = static_and_dynamic(&scene, &glb, &reference, &stat, &dynamic);
    eprintln!("chrome ball under a sun, no environment: relMSE static {es:.4}, dynamic {ed:.4}");
    assert!(
        ed < 0.25 * es,
        "the dynamic map does not help: {ed} vs {es}"
    );
}

/// A chrome ball 0.6 radii over a grey floor, beside a red box 1.5 radii off its surface.
fn ball_box_floor() -> Scene {
    use lightlab_scene::builtin::geom;
    let mut scene = ball(0.0, BrdfModel::Pbr);
    scene.materials[0].base_color = Vec4::new(0.9, 0.9, 0.9, 1.0);
    let red = scene.add_material(Material::diffuse("red", Vec3::new(0.8, 0.05, 0.05)));
    let grey = scene.add_material(Material::diffuse("grey", Vec3::splat(0.5)));
    scene.add_mesh(
        geom::aabb_box(
            "box",
            Vec3::new(2.5, -1.6, -1.5),
            Vec3::new(3.7, 1.2, 0.5),
            red,
        ),
        Mat4::IDENTITY,
    );
    scene.add_mesh(
        geom::aabb_box(
            "floor",
            Vec3::new(-6.0, -1.8, -6.0),
            Vec3::new(6.0, -1.6, 6.0),
            grey,
        ),
        Mat4::IDENTITY,
    );
    scene
}

/// `phong-shadow-maps` of `glb` with the static maps (to `stat`) and with `--dynamic-env` (to
/// `dynamic`), and their relMSE over the ball against `reference`.
fn static_and_dynamic(
    scene: &Scene,
    glb: &Path,
    reference: &Path,
    stat: &Path,
    dynamic: &Path,
) -> (f64, f64) {
    render(glb, "phong-shadow-maps", &["--ssaa", "2"], stat);
    render(
        glb,
        "phong-shadow-maps",
        &["--ssaa", "2", "--dynamic-env"],
        dynamic,
    );
    (
        sphere_relmse(scene, stat, reference),
        sphere_relmse(scene, dynamic, reference),
    )
}

/// The environment's sun (`--env-sun on`, the default): the `spheres` sky's bright lobe becomes
/// a directional light with shadows for the diffuse term, so a diffuse ball casts its shadow on
/// the floor as in the path tracer, instead of the sun staying in the unshadowed SH ambient.
/// Measured with the sky unoccluded (`--sky-occlusion 0`) to see the sun alone, then with the
/// default occluded sky.
#[test]
fn the_environment_sun_casts_shadows() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let mut scene = ball_box_floor();
    let m = &mut scene.materials[0];
    m.metallic = 0.0;
    m.roughness = 1.0;
    m.base_color = Vec4::new(0.8, 0.8, 0.8, 1.0);
    let glb = p("sun.glb");
    lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
    let reference = p("ref.exr");
    render(&glb, "reference", &["--spp", "256"], &reference);
    let mut around = vec![];
    let mut on_ball = vec![];
    for (name, extra) in [
        ("off", &["--env-sun", "off", "--sky-occlusion", "0"][..]),
        ("sun", &["--sky-occlusion", "0"][..]),
        ("default", &[][..]),
    ] {
        let out = p(&format!("{name}.exr"));
        let mut args = vec!["--ssaa", "2"];
        args.extend_from_slice(extra);
        render(&glb, "phong-shadow-maps", &args, &out);
        around.push(masked_relmse(&scene, &out, &reference, false));
        on_ball.push(sphere_relmse(&scene, &out, &reference));
    }
    eprintln!(
        "diffuse ball on a floor under the spheres sky, relMSE around the ball / on it: sky \
         unshadowed with its sun {:.4} / {:.4}, the sun extracted {:.4} / {:.4}, and the sky \
         occluded {:.4} / {:.4}",
        around[0], on_ball[0], around[1], on_ball[1], around[2], on_ball[2]
    );
    assert!(
        around[1] < 0.7 * around[0],
        "the sun's shadow does not help: {around:?}"
    );
    assert!(
        on_ball[1] < 1.1 * on_ball[0],
        "the ball got worse: {on_ball:?}"
    );
    assert!(
        around[2] < 0.7 * around[1],
        "the occluded sky does not help: {around:?}"
    );
}
