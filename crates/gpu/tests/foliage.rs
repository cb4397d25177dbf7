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
use lightlab_trace::{Accel, PathTracer, RenderSettings};

const N: u32 = 64;

/// A leaf-like square facing +z, lit from behind by a directional light, seen from the front;
/// its translucency map lets all light through on the left half and a quarter on the right.
fn backlit_leaf(with_map: bool) -> Scene {
    let mut s = Scene::default();
    let tex = Texture {
        name: "translucency".into(),
        width: 16,
        height: 16,
        data: (0..256)
            .map(|i| Vec4::new(1.0, 1.0, 1.0, if i % 16 < 8 { 1.0 } else { 0.25 }))
            .collect(),
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
        transmission_texture: with_map.then_some(TextureRef {
            texture: 0,
            uv_set: 0,
        }),
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
    let accel = Accel::new(&scene);
    let settings = RenderSettings {
        width: N,
        height: N,
        spp: 16,
        max_depth: 1,
        min_depth: 0,
        seed: 5,
        camera: 0,
    };
    let reference = PathTracer::new(&scene, &accel)
        .render(&settings, &|_, _| true)
        .unwrap();
    let gpu = |scene: &Scene| {
        let mut r = Renderer::new(
            &ctx,
            scene,
            RasterSettings {
                width: N * 2,
                height: N * 2,
                shadows: ShadowMethod::None,
                ambient: Ambient::None,
                ..Default::default()
            },
        )
        .unwrap();
        r.render(&ctx);
        r.read_hdr(&ctx).unwrap().downsample(2)
    };
    let img = gpu(&scene);
    let e = lightlab_core::metrics::relmse(&img, &reference).unwrap();
    let (gl, gr) = half_means(&img);
    let (rl, rr) = half_means(&reference);
    eprintln!(
        "back-lit leaf: GPU vs path tracer relMSE {e:.5}; thin/veined halves GPU {:.3}, \
         reference {:.3} (map: 4)",
        gl / gr,
        rl / rr
    );
    assert!(gr > 0.0 && rr > 0.0, "light comes through");
    assert!((gl / gr - 4.0).abs() < 0.2, "GPU: {}", gl / gr);
    assert!((rl / rr - 4.0).abs() < 0.2, "reference: {}", rl / rr);
    assert!(e <= 0.01, "relMSE {e}");
    // Without the map the GPU image is uniform and far from the mapped reference.
    let plain = gpu(&backlit_leaf(false));
    let e_plain = lightlab_core::metrics::relmse(&plain, &reference).unwrap();
    assert!(e_plain > 10.0 * e.max(1e-4), "{e_plain} vs {e}");
}
