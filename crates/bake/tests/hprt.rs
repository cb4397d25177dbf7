//! Hierarchical PRT (McKenzie Chapter ch. 5): filters, occluder sets, caching, combining, and
//! the animated bake's occlusion groups. `cargo test -p lightlab-bake --test hprt`.

use glam::{DVec3, Mat4, Quat, Vec3};
use lightlab_bake::hprt::{Combine, FilterMode, Hierarchy, HprtSettings, Occlusion, Scope, Tree};
use lightlab_bake::sh_light::{SamplePoints, ShLightSettings, ShLighting};
use lightlab_core::sh::{self, Window};
use lightlab_scene::builtin::geom::{quad, sphere};
use lightlab_scene::{Animation, Material, Scene, Track};
use std::f64::consts::PI;

/// Spheres of radius `r` at `centres`, named `names`.
fn spheres(items: &[(&str, Vec3, f32)]) -> Scene {
    let mut s = Scene::default();
    let m = s.add_material(Material::diffuse("grey", Vec3::splat(0.5)));
    for (name, c, r) in items {
        s.add_mesh(sphere(name, *r, 32, 16, m), Mat4::from_translation(*c));
    }
    s
}

fn settings() -> HprtSettings {
    HprtSettings {
        bands: 4,
        samples: 4096,
        window: Window::Hann { size: 4.0 },
        bounce: false,
        ..Default::default()
    }
}

/// The filter's value in direction `d` (1 where unblocked, for an ideal mask).
fn value(f: &[f64], d: Vec3) -> f64 {
    sh::evaluate(f, d.as_dvec3())
}

#[test]
fn an_occluder_between_receiver_and_light_darkens_that_direction_only() {
    // The receiver at the origin, an occluder of radius 0.5 at 1.5 m along +x.
    let s = spheres(&[
        ("receiver", Vec3::ZERO, 0.2),
        ("occluder", Vec3::new(1.5, 0.0, 0.0), 0.5),
    ]);
    let mut h = Hierarchy::new(&s, Tree::flat(2), settings());
    h.update(&s);
    let f = &h.filters_of(0).unwrap()[0].coeffs;
    // The occluder's cone as seen from each point (the box's face centres, 1 % in) is
    // removed from the DC.
    let points = lightlab_bake::sh_light::box_face_centres(Vec3::splat(-0.2), Vec3::splat(0.2));
    for (pf, p) in h.filters_of(0).unwrap().iter().zip(points) {
        let d = (Vec3::new(1.5, 0.0, 0.0) - 0.99 * p).length() as f64;
        let share = (1.0 - (1.0 - (0.5 / d).powi(2)).sqrt()) / 2.0;
        let dc = (4.0 * PI).sqrt() * (1.0 - share);
        assert!((pf.coeffs[0] - dc).abs() < 0.02, "{} vs {dc}", pf.coeffs[0]);
    }
    // Band-limited (4 bands): a dip towards the occluder, the rest untouched.
    let (towards, away) = (value(f, Vec3::X), value(f, -Vec3::X));
    assert!(
        towards < 0.8 && away > 0.95,
        "towards {towards}, away {away}"
    );
    // Moving the occluder away restores the unit filter exactly.
    let mut far = s.clone();
    far.instances[1].transform =
        Mat4::from_translation(Vec3::new(1.5, 0.0, 40.0)) * Mat4::from_scale(Vec3::splat(0.01));
    h.update(&far);
    for pf in h.filters_of(0).unwrap() {
        assert_eq!(pf.coeffs[0], (4.0 * PI).sqrt());
        assert!(pf.coeffs[1..].iter().all(|c| *c == 0.0));
    }
}

#[test]
fn the_occluder_set_counts_a_direction_once_and_descent_twice() {
    // R under composite C with sibling S1; C's sibling S2 behind S1 covers S1's cone.
    let s = spheres(&[
        ("C/R", Vec3::ZERO, 0.1),
        ("C/S1", Vec3::new(0.0, 0.0, -1.5), 0.5),
        ("S2", Vec3::new(0.0, 0.0, -3.0), 1.5),
    ]);
    let tree = Tree::from_names(s.instances.iter().map(|i| i.name.as_str()));
    let dc = |mode| {
        let hs = HprtSettings {
            filters: mode,
            scope: Scope::Node,
            ..settings()
        };
        let mut h = Hierarchy::new(&s, tree.clone(), hs);
        h.update(&s);
        h.filters_of(0).unwrap()[0].coeffs[0]
    };
    let unit = (4.0 * PI).sqrt();
    let cone = |sin_a: f64| (1.0 - (1.0 - sin_a * sin_a).sqrt()) / 2.0;
    // Mask: the union, S2's 30° cone.
    let mask = dc(FilterMode::Mask);
    assert!((mask - unit * (1.0 - cone(0.5))).abs() < 0.03, "{mask}");
    // Descent subtracts S1's cone a second time (from R) over S2's (from C's centre).
    let descent = dc(FilterMode::Descent);
    assert!(
        descent < mask - 0.5 * unit * cone(0.5 / 1.5),
        "descent {descent}, mask {mask}"
    );
}

#[test]
fn caching_recomputes_what_a_move_can_change() {
    // Two trees: moving a1 dirties a1 and its sibling a2, never the other tree.
    let s = spheres(&[
        ("a1", Vec3::ZERO, 0.3),
        ("a2", Vec3::new(1.0, 0.0, 0.0), 0.3),
        ("b1", Vec3::new(10.0, 0.0, 0.0), 0.3),
        ("b2", Vec3::new(11.0, 0.0, 0.0), 0.3),
    ]);
    let mut tree = Tree::default();
    for (root, first) in [("A", 0), ("B", 2)] {
        let r = tree.add(root, None, None);
        tree.add("x", Some(r), Some(first));
        tree.add("y", Some(r), Some(first + 1));
    }
    let mut h = Hierarchy::new(&s, tree.clone(), settings());
    h.update(&s);
    assert_eq!(h.stats.nodes, 4);
    h.update(&s);
    assert_eq!(h.stats.nodes, 0, "nothing moved");
    let mut moved = s.clone();
    moved.instances[0].transform = Mat4::from_translation(Vec3::new(0.0, 0.2, 0.0));
    h.update(&moved);
    assert_eq!(h.stats.nodes, 2);
    // Without caching, everything every frame.
    let mut u = Hierarchy::new(
        &s,
        tree.clone(),
        HprtSettings {
            cache: false,
            ..settings()
        },
    );
    u.update(&s);
    u.update(&moved);
    assert_eq!(u.stats.nodes, 4);
    // A sphere spinning in place keeps its box: as a blob it dirties only itself.
    let mut spun = s.clone();
    spun.instances[0].transform = Mat4::from_quat(Quat::from_rotation_y(0.7));
    let blob = HprtSettings {
        occlusion: Occlusion::Blob,
        ..settings()
    };
    let mut b = Hierarchy::new(&s, tree, blob);
    b.update(&s);
    b.update(&spun);
    assert_eq!(b.stats.nodes, 1);
}

#[test]
fn an_unoccluded_object_gets_prt_textured_light_with_every_operator() {
    let mut s = spheres(&[("alone", Vec3::new(0.0, 1.0, 0.0), 0.5)]);
    s.lights.push(lightlab_scene::Light {
        name: "sun".into(),
        kind: lightlab_scene::LightKind::Directional {
            angular_diameter: 0.0,
        },
        color: Vec3::ONE,
        intensity: 3.0,
        position: Vec3::ZERO,
        direction: Vec3::new(-0.3, -1.0, -0.2).normalize(),
        range: None,
    });
    let ls = |window| ShLightSettings {
        bands: 4,
        points: SamplePoints::PerObject,
        window,
        environment: false,
        punctual: true,
    };
    let window = Window::Hann { size: 4.0 };
    let textured = ShLighting::new(&s, &ls(window), None);
    let world = ShLighting::new(&s, &ls(Window::None), None);
    for combine in [Combine::Masked, Combine::Product, Combine::Subtract] {
        let hs = HprtSettings {
            combine,
            bounce: true,
            ..settings()
        };
        let mut h = Hierarchy::new(&s, Tree::flat(1), hs);
        h.update(&s);
        let lit = h.relight(&world, None);
        for (a, b) in lit.coeffs[0].iter().zip(&textured.coeffs[0]) {
            for (x, y) in a.iter().zip(b) {
                assert!((*x - *y).length() < 1e-12, "{combine}: {x} vs {y}");
            }
        }
    }
}

#[test]
fn a_blocked_ray_sees_the_occluders_light_when_occluders_reflect() {
    // A ball 0.7 m above a lit white floor: its bottom point's light from below is the
    // floor's radiance ρE/π (E = π under unit sky radiance from above), none when black.
    let mut s = spheres(&[("ball", Vec3::new(0.0, 1.0, 0.0), 0.3)]);
    let white = s.add_material(Material::diffuse("white", Vec3::ONE));
    s.add_mesh(
        quad(
            "floor",
            [
                Vec3::new(-50.0, 0.0, 50.0),
                Vec3::new(50.0, 0.0, 50.0),
                Vec3::new(50.0, 0.0, -50.0),
                Vec3::new(-50.0, 0.0, -50.0),
            ],
            white,
        ),
        Mat4::IDENTITY,
    );
    let bands = 4;
    let nc = sh::num_coeffs(bands);
    // Unit radiance from the upper hemisphere, as each point's world light.
    let sky = sh::project_uniform_sky(bands, DVec3::Y, 1.0);
    let mut world = ShLighting::new(
        &s,
        &ShLightSettings {
            bands,
            points: SamplePoints::PerObject,
            window: Window::None,
            environment: false,
            punctual: false,
        },
        None,
    );
    for g in &mut world.coeffs {
        for p in g.iter_mut() {
            *p = sky.iter().map(|c| DVec3::splat(*c)).collect();
        }
    }
    let below = |bounce| {
        let hs = HprtSettings {
            bounce,
            window: Window::None,
            combine: Combine::Product,
            ..settings()
        };
        let mut h = Hierarchy::new(&s, Tree::flat(2), hs);
        h.update(&s);
        let lit = h.relight(&world, None);
        // The ball's bottom sample point (−y face), radiance straight down.
        let c: Vec<f64> = lit.coeffs[0][2].iter().map(|v| v.x).collect();
        assert_eq!(c.len(), nc);
        sh::evaluate(&c, -DVec3::Y)
    };
    let lit = below(true);
    let black = below(false);
    // The floor's radiance ρE/π = 1 from below (a sky of radiance 1), band-limited at 4 bands;
    // black, only the ringing of the band-limited product remains.
    assert!((lit - 1.0).abs() < 0.15, "reflecting {lit}, black {black}");
    assert!(lit - black > 0.6, "reflecting {lit}, black {black}");
}

#[test]
fn moving_objects_bake_their_own_transfer_only() {
    // A ground quad and a box-like sphere above it: still, the ground under the sphere is
    // shadowed; animated, the sphere is its own occlusion group and the ground is not.
    let mut s = spheres(&[("ball", Vec3::new(0.0, 0.5, 0.0), 0.4)]);
    let m = s.materials.len() - 1;
    s.add_mesh(
        quad(
            "ground",
            [
                Vec3::new(-1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(-1.0, 0.0, -1.0),
            ],
            m,
        ),
        Mat4::IDENTITY,
    );
    let ts = lightlab_bake::prt::TransferSettings {
        bands: 2,
        kind: lightlab_bake::prt::TransferKind::Shadowed,
        samples: 128,
        ..Default::default()
    };
    let layout = lightlab_bake::layout::LayoutSettings {
        texels_per_metre: 8.0,
        ..Default::default()
    };
    let dc_under = |scene: &Scene| {
        let sl =
            lightlab_bake::prt::bake_sh_lightmaps(scene, &layout, &ts, &lightlab_bake::no_progress)
                .unwrap();
        // The ground's texel under the ball, reached from below.
        let accel = lightlab_trace::Accel::new(&sl.scene);
        let o = Vec3::new(0.05, -1.0, 0.05);
        let h = lightlab_bake::view::layout_hit(&sl.scene, &sl.layout, &accel, o, Vec3::Y)
            .expect("the ground");
        assert_eq!(h.instance, 1);
        let mut c = vec![0.0f32; 4];
        sl.sample(h.page, h.uv, &mut c);
        c[0]
    };
    let still = dc_under(&s);
    let mut animated = s.clone();
    animated.animation = Some(Animation {
        fps: 24.0,
        frames: 24,
        tracks: vec![Track {
            instance: 0,
            times: vec![0.0],
            translations: vec![Vec3::ZERO],
            rotations: vec![Quat::IDENTITY],
        }],
    });
    let moving = dc_under(&animated);
    let y0 = 0.5 / std::f32::consts::PI.sqrt();
    assert!(
        (moving - y0).abs() < 0.01,
        "the ground sees the whole sky: {moving}"
    );
    assert!(still < 0.7 * y0, "the ball shadows the ground: {still}");
}
