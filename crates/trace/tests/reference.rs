//! Acceptance tests of the reference path tracer against analytic values.

use glam::{Mat4, Vec2, Vec3};
use lightlab_core::image::Image;
use lightlab_core::sampling::Rng;
use lightlab_scene::builtin::geom;
use lightlab_scene::*;
use lightlab_trace::{Accel, PathTracer, RenderError, RenderSettings};
use std::f32::consts::PI;

fn camera_at(eye: Vec3, target: Vec3) -> Camera {
    Camera::look_at(
        "cam",
        eye,
        target,
        if (target - eye).normalize().y.abs() > 0.99 {
            Vec3::Z
        } else {
            Vec3::Y
        },
        1.0,
    )
}

/// Mean radiance over `n` samples along one ray.
fn mean_radiance(pt: &PathTracer, o: Vec3, d: Vec3, s: &RenderSettings, n: u32) -> Vec3 {
    let mut rng = Rng::new(s.seed, 0);
    let mut sum = glam::DVec3::ZERO;
    for _ in 0..n {
        sum += pt.radiance(o, d, s, &mut rng).as_dvec3();
    }
    (sum / n as f64).as_vec3()
}

/// Each triangle with its own vertices and its face normal.
fn flat_shaded(m: Mesh) -> Mesh {
    let mut f = Mesh {
        name: m.name.clone(),
        material: m.material,
        ..Default::default()
    };
    for t in m.indices.chunks_exact(3) {
        let p = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        for (k, q) in p.iter().enumerate() {
            f.positions.push(*q);
            f.normals.push(n);
            f.uv0.push(m.uv0[t[k] as usize]);
            f.indices.push(f.indices.len() as u32);
        }
    }
    f
}

/// White furnace: inside a closed enclosure whose surface emits Le and reflects ρ, radiance is
/// Le/(1−ρ) everywhere. Enclosures: a box and a (flat-shaded) sphere. With smooth shading normals
/// on a tessellated sphere, samples between the shading and geometric hemispheres are dropped
/// (≈0.8 % at ρ = 0.8): a property of shading normals, not of the integrator, so the sphere is
/// flat-shaded here.
#[test]
fn white_furnace_converges_to_le_over_one_minus_rho() {
    for enclosure in ["box", "sphere"] {
        for (rho, le) in [(0.5f32, 1.0f32), (0.8, 0.5)] {
            let mut s = Scene::default();
            let m = s.add_material(Material {
                emissive: Vec3::ONE,
                emissive_strength: le,
                double_sided: true,
                ..Material::diffuse("furnace", Vec3::splat(rho))
            });
            let mesh = if enclosure == "box" {
                geom::aabb_box(
                    "shell",
                    Vec3::new(-1.0, -0.7, -1.3),
                    Vec3::new(1.2, 0.9, 1.0),
                    m,
                )
            } else {
                flat_shaded(geom::sphere("shell", 1.0, 48, 24, m))
            };
            s.add_mesh(mesh, Mat4::IDENTITY);
            s.cameras.push(camera_at(
                Vec3::new(0.1, -0.1, 0.05),
                Vec3::new(0.3, 0.2, -1.0),
            ));
            let accel = Accel::new(&s);
            let pt = PathTracer::new(&s, &accel);
            // 1M paths: Russian roulette makes the path count geometric (variance ≈ 20 at
            // ρ = 0.8), so the standard error is ≈ 0.09 % and the 0.5 % bound sits at > 5σ.
            let settings = RenderSettings {
                width: 16,
                height: 16,
                spp: 4096,
                max_depth: 1000,
                seed: 3,
                ..Default::default()
            };
            let mean = pt.render(&settings, &|_, _| true).unwrap().mean();
            let expect = le / (1.0 - rho);
            let err = (mean.x - expect).abs() / expect;
            eprintln!(
                "furnace {enclosure} ρ={rho} Le={le}: {} vs Le/(1−ρ) = {expect} ({:+.3} %)",
                mean.x,
                (mean.x / expect - 1.0) * 100.0
            );
            assert!(
                err < 0.005,
                "{enclosure} ρ={rho}: {} vs {expect} ({:.3} %)",
                mean.x,
                err * 100.0
            );
        }
    }
}

fn plane_scene(albedo: f32) -> Scene {
    let mut s = Scene::default();
    let m = s.add_material(Material::diffuse("plane", Vec3::splat(albedo)));
    s.add_mesh(
        geom::quad(
            "plane",
            [
                Vec3::new(-50.0, 0.0, 50.0),
                Vec3::new(50.0, 0.0, 50.0),
                Vec3::new(50.0, 0.0, -50.0),
                Vec3::new(-50.0, 0.0, -50.0),
            ],
            m,
        ),
        Mat4::IDENTITY,
    );
    s.cameras
        .push(camera_at(Vec3::new(0.0, 5.0, 0.0), Vec3::ZERO));
    s
}

/// A diffuse plane under a point light: L = I·cosθ/r² · ρ/π.
#[test]
fn point_light_on_a_plane_matches_the_analytic_value() {
    let mut s = plane_scene(0.6);
    let light_pos = Vec3::new(0.5, 2.0, -0.3);
    s.lights.push(Light {
        name: "p".into(),
        kind: LightKind::Point,
        color: Vec3::new(1.0, 0.8, 0.5),
        intensity: 7.0,
        position: light_pos,
        direction: -Vec3::Y,
        range: None,
    });
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let settings = RenderSettings {
        max_depth: 1,
        ..Default::default()
    };
    let eye = Vec3::new(-1.0, 3.0, 2.0);
    for target in [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.7, 0.0, 0.4),
        Vec3::new(-2.0, 0.0, -3.0),
    ] {
        let to = light_pos - target;
        let cos = to.normalize().y;
        let expect = Vec3::new(1.0, 0.8, 0.5) * 7.0 * cos / to.length_squared() * 0.6 / PI;
        let got = mean_radiance(&pt, eye, (target - eye).normalize(), &settings, 4);
        eprintln!(
            "point light at {target}: {got} vs I·cosθ/r²·ρ/π = {expect} ({:+.4} %)",
            (got.x / expect.x - 1.0) * 100.0
        );
        assert!(
            (got - expect).abs().max_element() < 0.005 * expect.max_element(),
            "{got} vs {expect}"
        );
    }
}

/// A diffuse plane under a sun of angular diameter 0.5°..10°: L = ρ·E·cosθ/π (the cone is
/// sampled, so this checks the sun's radiance normalisation).
#[test]
fn sun_on_a_plane_matches_the_analytic_value() {
    for diameter in [0.0f32, 0.0093, 0.17] {
        let mut s = plane_scene(0.5);
        let dir = Vec3::new(0.3, -1.0, 0.2).normalize();
        s.lights.push(Light {
            name: "sun".into(),
            kind: LightKind::Directional {
                angular_diameter: diameter,
            },
            color: Vec3::ONE,
            intensity: 3.0,
            position: Vec3::ZERO,
            direction: dir,
            range: None,
        });
        let accel = Accel::new(&s);
        let pt = PathTracer::new(&s, &accel);
        let settings = RenderSettings {
            max_depth: 1,
            ..Default::default()
        };
        let got = mean_radiance(&pt, Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, &settings, 4000);
        // A uniform-radiance disc of angular radius α around axis a (wholly above the horizon)
        // gives ∫L·cos dω = L·π·sin²α·(a·n) = E·(a·n): the same as a delta sun.
        let expect = 0.5 * 3.0 * -dir.y / PI;
        eprintln!(
            "sun diameter {diameter}: {} vs ρ·E·cosθ/π = {expect} ({:+.3} %)",
            got.x,
            (got.x / expect - 1.0) * 100.0
        );
        assert!(
            (got.x - expect).abs() < 0.005 * expect,
            "diameter {diameter}: {} vs {expect}",
            got.x
        );
    }
}

/// A diffuse plane under a uniform environment of radiance L reflects ρ·L.
#[test]
fn uniform_environment_on_a_plane() {
    let mut s = plane_scene(0.7);
    s.environment = Some(Environment {
        image: Image::from_fn(64, 32, |_, _| Vec3::splat(2.0)),
        intensity: 1.0,
    });
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let settings = RenderSettings {
        max_depth: 1,
        ..Default::default()
    };
    let got = mean_radiance(&pt, Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, &settings, 100_000);
    eprintln!(
        "uniform sky: {} vs ρ·L = 1.4 ({:+.3} %)",
        got.x,
        (got.x / 1.4 - 1.0) * 100.0
    );
    assert!((got.x - 1.4).abs() < 0.005 * 1.4, "{}", got.x);
    // Looking at the sky gives the sky.
    let sky = mean_radiance(&pt, Vec3::new(0.0, 2.0, 0.0), Vec3::Y, &settings, 1);
    assert_eq!(sky, Vec3::splat(2.0));
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    let s = builtin::builtin("cornell").unwrap();
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let settings = RenderSettings {
        width: 24,
        height: 24,
        spp: 4,
        seed: 9,
        ..Default::default()
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let a = one.install(|| pt.render(&settings, &|_, _| true).unwrap());
    let b = three.install(|| pt.render(&settings, &|_, _| true).unwrap());
    assert_eq!(a, b);
    let c = pt
        .render(
            &RenderSettings {
                seed: 10,
                ..settings.clone()
            },
            &|_, _| true,
        )
        .unwrap();
    assert_ne!(a, c, "a different seed must give different noise");
}

/// Two renders of `cornell` with different seeds: their relMSE falls as 1/spp once past the
/// first few samples (below ≈ 64 spp the noisy denominator b² + 0.01 inflates it). Plain MSE is
/// not asserted: at 32² it is dominated by the few anti-aliased pixels on the light's edge
/// (radiance 17 against 0), and its estimate swings by 2× between runs.
#[test]
fn noise_falls_as_one_over_spp() {
    let s = builtin::builtin("cornell").unwrap();
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let pair = |spp: u32| {
        let r = |seed| {
            pt.render(
                &RenderSettings {
                    width: 32,
                    height: 32,
                    spp,
                    seed,
                    ..Default::default()
                },
                &|_, _| true,
            )
            .unwrap()
        };
        let (a, b) = (r(1), r(2));
        ((), lightlab_core::metrics::relmse(&a, &b).unwrap())
    };
    let (b, c) = (pair(64), pair(256));
    let ratio = b.1 / c.1;
    eprintln!(
        "cornell 32²: relMSE between seeds 64 spp {}, 256 spp {} (ratio {ratio:.2})",
        b.1, c.1
    );
    assert!(
        (3.0..6.0).contains(&ratio),
        "relMSE 64 spp {} → 256 spp {}: ratio {ratio}, expected ≈ 4",
        b.1,
        c.1
    );
}

#[test]
fn cancel_and_bad_settings() {
    let s = builtin::builtin("cornell").unwrap();
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let r = pt.render(
        &RenderSettings {
            width: 64,
            height: 64,
            spp: 1,
            ..Default::default()
        },
        &|_, _| false,
    );
    assert_eq!(r.unwrap_err(), RenderError::Cancelled);
    for bad in [
        RenderSettings {
            width: 0,
            ..Default::default()
        },
        RenderSettings {
            spp: 0,
            ..Default::default()
        },
        RenderSettings {
            width: 100_000,
            height: 100_000,
            ..Default::default()
        },
        RenderSettings {
            max_depth: 0,
            ..Default::default()
        },
    ] {
        assert!(matches!(
            pt.render(&bad, &|_, _| true),
            Err(RenderError::InvalidSettings(_))
        ));
    }
    assert_eq!(
        pt.render(
            &RenderSettings {
                camera: 5,
                ..Default::default()
            },
            &|_, _| true
        )
        .unwrap_err(),
        RenderError::NoCamera(5)
    );
    let _ = Vec2::ZERO;
}

/// Form factor from a differential area to a parallel rectangle (a × b) whose corner lies
/// straight above it at height h.
fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}

/// A diffuse plane under a one-sided square area light facing down: the reflected radiance
/// straight below the light's centre is ρ/π · π·Le·F, with F the exact form factor. Checks
/// next-event estimation and its MIS weights with a small single-sided emitter, with and
/// without a second (grey, diffuse) bounce blocker out of the way.
#[test]
fn square_area_light_matches_the_form_factor() {
    let (side, h, le, rho) = (0.5f32, 1.0f32, 4.0f32, 0.6f32);
    let mut s = plane_scene(rho);
    let light = s.add_material(Material {
        emissive: Vec3::ONE,
        emissive_strength: le,
        ..Material::diffuse("light", Vec3::splat(0.5))
    });
    let c = side / 2.0;
    s.add_mesh(
        geom::quad_facing(
            "light",
            [
                Vec3::new(-c, h, -c),
                Vec3::new(c, h, -c),
                Vec3::new(c, h, c),
                Vec3::new(-c, h, c),
            ],
            Vec3::ZERO,
            light,
        ),
        Mat4::IDENTITY,
    );
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let f = 4.0 * corner_form_factor(c as f64, c as f64, h as f64);
    let expect = (rho as f64 / std::f64::consts::PI * std::f64::consts::PI * le as f64 * f) as f32;
    // Look at the point below the centre from the side (the light does not block the view).
    let eye = Vec3::new(2.0, 0.5, 0.0);
    let settings = RenderSettings {
        max_depth: 1,
        ..Default::default()
    };
    let got = mean_radiance(&pt, eye, (Vec3::ZERO - eye).normalize(), &settings, 200_000);
    eprintln!(
        "square light, below centre: {} vs form factor {expect} ({:+.3} %)",
        got.x,
        (got.x / expect - 1.0) * 100.0
    );
    assert!(
        (got.x - expect).abs() < 0.005 * expect,
        "direct: {} vs {expect}",
        got.x
    );
    // Away from the light, at oblique incidence (where a shadow ray aimed from the wrong origin
    // once hit the light itself): against a fine midpoint quadrature of Le·cosθ·cosθ'/r² over
    // the light (both cosines equal the height over the distance here).
    let target = Vec3::new(1.5, 0.0, 0.3);
    let n = 400;
    let mut e = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let q = Vec3::new(
                -c + side * (i as f32 + 0.5) / n as f32,
                h,
                -c + side * (j as f32 + 0.5) / n as f32,
            );
            let d = (q - target).as_dvec3();
            let r2 = d.length_squared();
            let cos = d.y / r2.sqrt();
            e += le as f64 * cos * cos / r2 * (side as f64).powi(2) / (n * n) as f64;
        }
    }
    let expect = (rho as f64 / std::f64::consts::PI * e) as f32;
    let eye = target + Vec3::new(0.3, 0.5, 0.2);
    let got = mean_radiance(&pt, eye, (target - eye).normalize(), &settings, 200_000);
    eprintln!(
        "square light, oblique: {} vs quadrature {expect} ({:+.3} %)",
        got.x,
        (got.x / expect - 1.0) * 100.0
    );
    assert!(
        (got.x - expect).abs() < 0.01 * expect,
        "oblique: {} vs {expect}",
        got.x
    );
}

/// An environment of radiance 1 where `lit(direction)`, 0 elsewhere.
fn env_where(lit: impl Fn(Vec3) -> bool) -> Environment {
    let (w, h) = (128u32, 64u32);
    let data = (0..w * h)
        .map(|i| {
            let uv = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5)
                / Vec2::new(w as f32, h as f32);
            if lit(Environment::uv_to_dir(uv)) {
                Vec3::ONE
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    Environment {
        image: Image {
            width: w,
            height: h,
            data,
        },
        intensity: 1.0,
    }
}

fn glass() -> Material {
    Material {
        base_color: glam::Vec4::ONE,
        roughness: 0.0,
        specular_transmission: 1.0,
        ior: 1.5,
        // A solid (KHR_materials_volume); 0 would make it thin-walled.
        thickness: 1.0,
        ..Material::diffuse("glass", Vec3::ONE)
    }
}

/// Thin-walled glass (glTF's default without KHR_materials_volume): one double-sided quad is a
/// sheet that light crosses without bending, reflecting 2F/(1+F). Seen at 60° in a sky lit only
/// within 8° of the view direction, it transmits 1 − 2F/(1+F) of it (a solid interface would
/// bend the ray out of the lit cone).
#[test]
fn thin_walled_glass_transmits_straight_through() {
    let mut s = Scene::default();
    let mut m = glass();
    m.thickness = 0.0;
    m.double_sided = true;
    let m = s.add_material(m);
    s.add_mesh(
        geom::quad(
            "pane",
            [
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            m,
        ),
        Mat4::IDENTITY,
    );
    let d = Vec3::new(60f32.to_radians().sin(), 0.0, -60f32.to_radians().cos());
    s.environment = Some(env_where(move |e| e.dot(d) > 8f32.to_radians().cos()));
    s.cameras
        .push(camera_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO));
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let settings = RenderSettings {
        max_depth: 16,
        seed: 3,
        ..Default::default()
    };
    let l = mean_radiance(&pt, Vec3::ZERO - d * 2.0, d, &settings, 20_000).x;
    let f = lightlab_core::brdf::fresnel_dielectric(0.5, 1.5) as f32;
    let expect = 1.0 - 2.0 * f / (1.0 + f);
    eprintln!("thin-walled pane at 60°: {l} against 1 − 2F/(1+F) = {expect}");
    assert!(
        (l - expect).abs() < 0.01,
        "pane transmits {l}, expected {expect}"
    );
}

/// A clear glass slab in front of a white sky, seen at normal incidence: the light behind comes
/// through with T²/(1−R²) (both faces' Fresnel transmittance, every inner reflection pair
/// summed), R = ((n−1)/(n+1))². A closed glass sphere in a uniform sky neither gains nor loses
/// light (reflection, refraction and total internal reflection conserve it).
#[test]
fn smooth_glass_refracts_with_fresnel_and_conserves_energy() {
    let mut s = Scene::default();
    let m = s.add_material(glass());
    s.add_mesh(
        geom::aabb_box(
            "slab",
            Vec3::new(-1.0, -1.0, -0.05),
            Vec3::new(1.0, 1.0, 0.05),
            m,
        ),
        Mat4::IDENTITY,
    );
    s.environment = Some(env_where(|d| d.z < -0.5));
    s.cameras
        .push(camera_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO));
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let settings = RenderSettings {
        max_depth: 64,
        seed: 5,
        ..Default::default()
    };
    let l = mean_radiance(&pt, Vec3::new(0.01, 0.02, 3.0), -Vec3::Z, &settings, 20_000).x;
    let r = 0.04f32;
    let expect = (1.0 - r) * (1.0 - r) / (1.0 - r * r);
    eprintln!("glass slab: {l} against T²/(1−R²) = {expect}");
    assert!(
        (l - expect).abs() < 0.01,
        "slab transmits {l}, expected {expect}"
    );

    let mut s = Scene::default();
    let m = s.add_material(glass());
    s.add_mesh(
        flat_shaded(geom::sphere("ball", 1.0, 48, 24, m)),
        Mat4::IDENTITY,
    );
    s.environment = Some(env_where(|_| true));
    s.cameras
        .push(camera_at(Vec3::new(0.0, 0.3, 3.0), Vec3::ZERO));
    let accel = Accel::new(&s);
    let pt = PathTracer::new(&s, &accel);
    let settings = RenderSettings {
        width: 24,
        height: 24,
        spp: 256,
        max_depth: 256,
        seed: 7,
        ..Default::default()
    };
    let mean = pt.render(&settings, &|_, _| true).unwrap().mean();
    eprintln!("glass sphere in a white sky: mean {mean}");
    assert!((mean.x - 1.0).abs() < 0.01, "glass sphere furnace: {mean}");
}
