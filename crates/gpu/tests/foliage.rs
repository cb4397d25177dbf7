//! Thin translucent foliage (issue 7): light arriving on the back of a leaf leaves through the
//! front, scaled by the translucency map, the same on the GPU as in the path tracer.

use glam::{Mat4, Vec2, Vec3, Vec4};
use lightlab_core::image::Image;
use lightlab_gpu::raster::{Ambient, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::test_context;
use lightlab_scene::builtin::geom::quad;
use lightlab_scene::{
    AlphaMode, BrdfModel, Camera, Light, LightKind, Material, Scene, Texture, TextureRef,
};
use lightlab_trace::Accel;

mod common;
use common::{shadow_mapped_sky, traced_direct};

const N: u32 = 64;

/// A leaf-like square facing +z, lit from behind by a directional light, seen from the front;
/// its translucency map lets all light through on the left half and a quarter on the right.
fn backlit_leaf(with_map: bool) -> Scene {
    let mut s = Scene::default();
    let tex = Texture {
        name: "translucency".into(),
        width: 16,
        height: 16,
        texels: lightlab_scene::Texels::Rgba32F(
            (0..256)
                .map(|i| Vec4::new(1.0, 1.0, 1.0, if i % 16 < 8 { 1.0 } else { 0.25 }))
                .collect(),
        ),
        srgb: false,
    };
    s.textures.push(tex);
    let m = s.add_material(Material {
        name: "leaf".into(),
        base_color: Vec4::new(0.5, 0.8, 0.3, 1.0),
        roughness: 1.0,
        specular: 0.0,
        alpha_mode: AlphaMode::Opaque,
        double_sided: true,
        transmission: 0.8,
        transmission_texture: with_map.then_some(TextureRef::new(0, 0)),
        brdf: BrdfModel::Lambert,
        ..Default::default()
    });
    let q = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let mut mesh = quad("leaf", q, m);
    // uv = (x, y) mapped to [0, 1]².
    mesh.uv0 = q
        .iter()
        .map(|p| Vec2::new(0.5 * (p.x + 1.0), 0.5 * (1.0 - p.y)))
        .collect();
    s.add_mesh(mesh, Mat4::IDENTITY);
    s.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional {
            angular_diameter: 0.0,
        },
        color: Vec3::ONE,
        intensity: 3.0,
        position: Vec3::ZERO,
        // Travelling towards +z: it reaches the back (−z side) of the leaf.
        direction: Vec3::new(0.3, -0.2, 1.0).normalize(),
        range: None,
    });
    s.cameras.push(Camera::look_at(
        "front",
        Vec3::new(0.0, 0.0, 2.2),
        Vec3::ZERO,
        Vec3::Y,
        40f32.to_radians(),
    ));
    s
}

fn half_means(img: &Image) -> (f32, f32) {
    let (mut l, mut r) = (0.0, 0.0);
    for y in N / 4..3 * N / 4 {
        for x in N / 8..3 * N / 8 {
            l += img.get(x, y).y;
        }
        for x in 5 * N / 8..7 * N / 8 {
            r += img.get(x, y).y;
        }
    }
    (l, r)
}

#[test]
fn translucency_maps_scale_light_through_the_back_of_a_leaf() {
    let Some(ctx) = test_context() else { return };
    let scene = backlit_leaf(true);
    let reference = traced_direct(&scene, N, N, 16, 5);
    let gpu = |scene: &Scene, shadows: ShadowMethod| {
        let mut r = Renderer::new(
            &ctx,
            scene,
            RasterSettings {
                width: N * 2,
                height: N * 2,
                shadows,
                ambient: Ambient::None,
                ..Default::default()
            },
        )
        .unwrap();
        r.render(&ctx);
        r.read_hdr(&ctx).unwrap().downsample(2)
    };
    // Shadowed too: a shadow map's lookup moves off the leaf towards the light, not towards the
    // viewer behind it, where the leaf would shadow itself (it did, with either map: relMSE
    // 0.475); a shadow volume's own leaf must not count.
    for shadows in [
        ShadowMethod::None,
        ShadowMethod::Map,
        ShadowMethod::MapLinear,
        ShadowMethod::VolumesZFail,
    ] {
        let img = gpu(&scene, shadows);
        let e = lightlab_core::metrics::relmse(&img, &reference).unwrap();
        let (gl, gr) = half_means(&img);
        let (rl, rr) = half_means(&reference);
        eprintln!(
            "back-lit leaf, {shadows:?}: GPU vs path tracer relMSE {e:.5}; thin/veined halves \
             GPU {:.3}, reference {:.3} (map: 4)",
            gl / gr,
            rl / rr
        );
        assert!(gr > 0.0 && rr > 0.0, "light comes through");
        assert!((gl / gr - 4.0).abs() < 0.2, "GPU: {}", gl / gr);
        assert!((rl / rr - 4.0).abs() < 0.2, "reference: {}", rl / rr);
        assert!(e <= 0.01, "{shadows:?}: relMSE {e}");
    }
    // Without the map the GPU image is uniform and far from the mapped reference.
    let e = lightlab_core::metrics::relmse(&gpu(&scene, ShadowMethod::None), &reference).unwrap();
    let plain = gpu(&backlit_leaf(false), ShadowMethod::None);
    let e_plain = lightlab_core::metrics::relmse(&plain, &reference).unwrap();
    assert!(e_plain > 10.0 * e.max(1e-4), "{e_plain} vs {e}");
}

/// The fraction of `points` (world positions, None where the GPU drew nothing) that lie on the
/// CPU scene's triangles: along `dir(p)`, some triangle crosses the segment p ± 1 cm within
/// 2 mm of p. (`accel` ignores alpha: the GPU's mip-mapped alpha test and the CPU's full-resolution
/// one disagree at leaf edges, which is not what this measures.)
fn on_surface(accel: &Accel, points: &[Option<Vec3>], dir: &dyn Fn(Vec3) -> Vec3) -> f64 {
    let (mut good, mut total) = (0usize, 0usize);
    for p in points.iter().flatten() {
        total += 1;
        let d = dir(*p);
        let o = *p - d * 0.01;
        // Step through every crossing (transparent parts of other leaves may come first).
        let mut t0 = 0.0;
        while let Some(h) = accel.intersect(o + d * t0, d, 0.02 - t0) {
            let t = t0 + h.t;
            if (o + d * t - *p).length() < 2e-3 {
                good += 1;
                break;
            }
            if t > 0.012 {
                break;
            }
            t0 = t + 1e-5;
        }
    }
    good as f64 / total.max(1) as f64
}

#[test]
fn wind_sways_the_camera_view_the_shadow_map_and_the_reflective_shadow_map_alike() {
    // Issue 7: the sway is applied the same way in every pass. The G-buffer's positions (camera
    // pass) and the RSM's (light pass) of the bush in a breeze lie on the CPU's swayed scene,
    // and not on the rest pose; the shadow map's mask agrees with shadow rays through the swayed
    // leaves, clearly better than through the rest pose (the rest is alpha-test and PCF
    // differences at leaf edges).
    let Some(ctx) = test_context() else { return };
    let scene = lightlab_scene::builtin::builtin("bush").unwrap();
    let wind = lightlab_core::wind::Wind::breeze(Vec3::new(1.0, 0.0, 0.4), 0.12, 1.3);
    let swayed = Accel::with_alpha_test(&scene.swayed(&wind), false);
    let rest = Accel::with_alpha_test(&scene, false);
    let n = 128u32;
    let settings = RasterSettings {
        width: n,
        height: n,
        path: lightlab_gpu::raster::RenderPath::Deferred,
        shadows: ShadowMethod::Map,
        wind,
        ..Default::default()
    };
    let lpv = lightlab_gpu::lpv::LpvSettings {
        grid: 16,
        rsm_size: 128,
        ..Default::default()
    };
    let mut r = Renderer::with_lpv(&ctx, &scene, settings, &lpv, false).unwrap();
    r.render(&ctx);
    let cam = scene.default_camera().unwrap().clone();
    let eye = cam.position();
    let g = r.read_gbuffer(&ctx).unwrap();
    let seen: Vec<Option<Vec3>> = g[3]
        .iter()
        .map(|c| (c[3] > 0.0).then(|| Vec3::new(c[0], c[1], c[2]) + eye))
        .map(|p| p.filter(|p| p.y > 0.05))
        .collect();
    let from_eye = |p: Vec3| (p - eye).normalize();
    let cam_swayed = on_surface(&swayed, &seen, &from_eye);
    let cam_rest = on_surface(&rest, &seen, &from_eye);
    let [_, _, rsm] = r.lpv().unwrap().read_rsm(&ctx).unwrap();
    let lit: Vec<Option<Vec3>> = rsm
        .iter()
        .map(|c| (c[3] > 0.0).then(|| Vec3::new(c[0], c[1], c[2])))
        .map(|p| p.filter(|p| p.y > 0.05))
        .collect();
    let sun = scene.lights[0].direction.normalize();
    let from_sun = |_: Vec3| sun;
    let rsm_swayed = on_surface(&swayed, &lit, &from_sun);
    let rsm_rest = on_surface(&rest, &lit, &from_sun);
    // The shadow-map pass: the GPU's shadow mask against CPU shadow rays from the same points
    // through the swayed and the rest-pose leaves (alpha-tested).
    let masks = r.shadow_masks(&ctx).unwrap();
    let occ_swayed = Accel::new(&scene.swayed(&wind));
    let occ_rest = Accel::new(&scene);
    let agree = |accel: &Accel| {
        let (mut same, mut total) = (0usize, 0usize);
        for (p, m) in seen.iter().zip(&masks[0]) {
            let Some(p) = p else { continue };
            let n = (eye - *p).normalize();
            let lit = !accel.occluded(*p + n * 2e-3 - sun * 2e-3, -sun, 50.0);
            total += 1;
            same += usize::from(lit == (*m > 127));
        }
        same as f64 / total.max(1) as f64
    };
    let (sm_swayed, sm_rest) = (agree(&occ_swayed), agree(&occ_rest));
    eprintln!("shadow map vs CPU shadow rays on foliage: swayed {sm_swayed:.4}, rest {sm_rest:.4}");
    eprintln!(
        "bush in a 12 cm breeze: on the swayed scene: G-buffer {cam_swayed:.4}, RSM \
         {rsm_swayed:.4}; on the rest pose: {cam_rest:.4}, {rsm_rest:.4}"
    );
    assert!(sm_swayed > 0.88, "shadow-map pass: {sm_swayed}");
    assert!(
        sm_rest < sm_swayed - 0.1,
        "shadows follow the leaves: {sm_rest}"
    );
    assert!(cam_swayed > 0.97, "camera pass: {cam_swayed}");
    assert!(rsm_swayed > 0.97, "RSM pass: {rsm_swayed}");
    assert!(
        cam_rest < cam_swayed - 0.1,
        "the breeze moves leaves: {cam_rest}"
    );
    assert!(
        rsm_rest < rsm_swayed - 0.1,
        "the breeze moves leaves: {rsm_rest}"
    );
}

/// A 2 m leaf (transmission 0.6) at 1 m, seen from below, under a sky of radiance 1 above the
/// horizon and 0.05 below; with `roof`, an opaque 1.2 m square 0.3 m above the leaf.
fn leaf_under_the_sky(roof: bool) -> Scene {
    let mut s = Scene::default();
    let leaf = s.add_material(Material {
        name: "leaf".into(),
        base_color: Vec4::new(0.4, 0.7, 0.3, 1.0),
        roughness: 1.0,
        specular: 0.0,
        double_sided: true,
        transmission: 0.6,
        brdf: BrdfModel::Lambert,
        ..Default::default()
    });
    let at = |y: f32, r: f32| {
        [
            Vec3::new(-r, y, r),
            Vec3::new(r, y, r),
            Vec3::new(r, y, -r),
            Vec3::new(-r, y, -r),
        ]
    };
    s.add_mesh(quad("leaf", at(1.0, 1.0), leaf), Mat4::IDENTITY);
    if roof {
        let grey = s.add_material(Material::diffuse("roof", Vec3::splat(0.5)));
        s.add_mesh(quad("roof", at(1.3, 0.6), grey), Mat4::IDENTITY);
    }
    let (w, h) = (64u32, 32u32);
    s.environment = Some(lightlab_scene::Environment {
        image: Image::from_fn(w, h, |_, y| Vec3::splat(if y < h / 2 { 1.0 } else { 0.05 })),
        intensity: 1.0,
    });
    s.cameras.push(Camera::look_at(
        "below",
        Vec3::new(0.0, 0.2, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::Z,
        0.8,
    ));
    s
}

/// The sky behind a thin translucent leaf lights it through its back (issue 22, foliage), and
/// what hides that sky hides its light: the occluded sky term against the path tracer's direct
/// light, with and without a roof over the leaf. (The sky term once lit leaves by their front
/// only, with the whole albedo: 0.08 of the traced light here.)
#[test]
fn the_sky_lights_a_leaf_through_its_back_where_nothing_hides_it() {
    let Some(ctx) = test_context() else { return };
    let mut means = vec![];
    for roof in [false, true] {
        let scene = leaf_under_the_sky(roof);
        let traced = traced_direct(&scene, 32, 32, 256, 7);
        let gpu = shadow_mapped_sky(&ctx, &scene, 32, 32);
        let mean = |i: &Image| i.data.iter().map(|p| p.y as f64).sum::<f64>() / i.data.len() as f64;
        let (g, t) = (mean(&gpu), mean(&traced));
        eprintln!(
            "leaf under the sky, roof {roof}: GPU {g:.4}, traced {t:.4}, ratio {:.3}",
            g / t
        );
        assert!(
            (g / t - 1.0).abs() < 0.08,
            "roof {roof}: GPU {g}, traced {t}"
        );
        means.push(t);
    }
    // The roof hides most of the sky behind the leaf.
    assert!(means[1] < 0.6 * means[0], "{means:?}");
}

/// Inside the bush's canopy, leaves a few centimetres apart hide the sky from each other: the
/// occluded sky on the canopy against the path tracer's direct sky light (the sun taken away).
/// Its shadow-mapped directions see past what lies within their bias of a point: with a bias
/// of a texel at 256² (and the leaves' whole albedo for the light on their front) the inner
/// canopy took 2.0 times the traced light; 1.21 now.
#[test]
fn the_occluded_sky_darkens_the_inside_of_a_canopy() {
    let Some(ctx) = test_context() else { return };
    let mut scene = lightlab_scene::builtin::builtin("bush").unwrap();
    scene.lights.clear();
    let (w, h) = (80u32, 60u32);
    let traced = traced_direct(&scene, w, h, 64, 3);
    let gpu = shadow_mapped_sky(&ctx, &scene, w, h);
    // The canopy's inner part: an ellipse around its centre in the default view.
    let (cx, cy, rx, ry) = (
        0.494 * w as f32,
        0.31 * h as f32,
        0.18 * w as f32,
        0.17 * h as f32,
    );
    let (mut g, mut t, mut n) = (0.0f64, 0.0f64, 0);
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = ((x as f32 + 0.5 - cx) / rx, (y as f32 + 0.5 - cy) / ry);
            if dx * dx + dy * dy < 1.0 {
                g += gpu.get(x, y).y as f64;
                t += traced.get(x, y).y as f64;
                n += 1;
            }
        }
    }
    eprintln!(
        "canopy's inside ({n} pixels): GPU / traced sky light {:.3}",
        g / t
    );
    assert!(n > 200, "{n}");
    assert!((g / t - 1.0).abs() < 0.3, "GPU {g}, traced {t}");
}
