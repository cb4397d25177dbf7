//! Directional light-maps (issue 5): on a normal-mapped floor lit from one side, the GPU's
//! `lightmap` technique with the directional pages is much closer to the path-traced reference
//! (which shades the normal map exactly) than the flat light-map, and equals it where the
//! normal map is flat.

mod common;

use glam::{Vec3, Vec4};
use lightlab_bake::{BakeSettings, Lightmaps, Method, bake_lightmaps, no_progress};
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse;
use lightlab_gpu::raster::{Ambient, LightmapInput, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::{GpuContext, test_context};
use lightlab_scene::builtin::geom::quad_facing;
use lightlab_scene::{
    BrdfModel, Camera, Instance, Light, LightKind, Material, Scene, Texture, TextureRef,
};
use lightlab_trace::{Accel, PathTracer, RenderSettings};

/// A 2 m floor whose normal map has ridges along z (slopes up to ±`tilt` radians, four per
/// metre), lit by a point light low on the −x side.
fn ridged_floor(tilt: f32) -> Scene {
    let mut floor = quad_facing(
        "floor",
        [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ],
        Vec3::Y * 5.0,
        0,
    );
    for uv in &mut floor.uv0 {
        *uv *= 8.0;
    }
    floor.compute_tangents();
    let size = 64u32;
    let data = (0..size * size)
        .map(|i| {
            let u = (i % size) as f32 / size as f32;
            let a = tilt * (std::f32::consts::TAU * u).sin();
            let n = Vec3::new(a.sin(), 0.0, a.cos());
            (n * 0.5 + Vec3::splat(0.5)).extend(1.0)
        })
        .collect::<Vec<Vec4>>();
    let mut m = Material::diffuse("white", Vec3::splat(0.8));
    m.brdf = BrdfModel::Lambert;
    m.normal_texture = Some(TextureRef::new(0, 0));
    Scene {
        name: "ridged-floor".into(),
        meshes: vec![floor],
        materials: vec![m],
        textures: vec![Texture {
            name: "ridges".into(),
            width: size,
            height: size,
            texels: lightlab_scene::Texels::Rgba32F(data),
            srgb: false,
        }],
        instances: vec![Instance {
            name: "floor".into(),
            mesh: 0,
            transform: glam::Mat4::IDENTITY,
            nodes: vec![],
            luminaire: None,
        }],
        lights: vec![Light {
            name: "low".into(),
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity: 3.0,
            position: Vec3::new(-1.6, 0.5, 0.0),
            direction: -Vec3::Y,
            range: None,
        }],
        cameras: vec![Camera::look_at(
            "top",
            Vec3::new(0.0, 1.6, 0.9),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::Y,
            0.9,
        )],
        environment: None,
        warnings: vec![],
        animation: None,
        luminaire_focus: Default::default(),
    }
}

fn gpu_render(ctx: &GpuContext, lm: &Lightmaps, directional: bool, n: u32, k: u32) -> Image {
    let rects = common::uv_rects(lm);
    let input = LightmapInput {
        pages: &lm.pages,
        rects: &rects,
        bicubic: false,
        directional: if directional {
            lm.directional.as_deref()
        } else {
            None
        },
    };
    let mut scene = lm.scene.clone();
    scene.lights.clear();
    let settings = RasterSettings {
        width: n * k,
        height: n * k,
        shadows: ShadowMethod::None,
        ambient: Ambient::None,
        ..Default::default()
    };
    let mut r = Renderer::with_lightmap(ctx, &scene, settings, Some(&input)).unwrap();
    r.render(ctx);
    r.read_hdr(ctx).unwrap().downsample(k)
}

#[test]
fn directional_lightmaps_follow_the_normal_map() {
    let Some(ctx) = test_context() else { return };
    let n = 96;
    let mut s = BakeSettings {
        method: Method::Path,
        ..Default::default()
    };
    s.layout.texels_per_metre = 8.0;
    s.gather.samples = 96;
    s.gather.max_depth = 1;
    s.gather.directional = true;
    let mut results = vec![];
    for tilt in [0.0f32, 0.6] {
        let scene = ridged_floor(tilt);
        let lm = bake_lightmaps(&scene, &s, &no_progress).unwrap();
        let dir = lm.directional.as_ref().expect("directional pages");
        // Ratios have mean 1 per texel.
        let inside = dir[0].data.iter().filter(|r| **r != Vec3::ONE);
        for r in inside {
            assert!(((r.x + r.y + r.z) / 3.0 - 1.0).abs() < 1e-3, "{r}");
        }
        let accel = Accel::new(&scene);
        let reference = PathTracer::new(&scene, &accel)
            .render(
                &RenderSettings {
                    width: n,
                    height: n,
                    spp: 64,
                    max_depth: 1,
                    ..Default::default()
                },
                &|_, _| true,
            )
            .unwrap();
        let flat = gpu_render(&ctx, &lm, false, n, 2);
        let directional = gpu_render(&ctx, &lm, true, n, 2);
        let ef = relmse(&flat, &reference).unwrap();
        let ed = relmse(&directional, &reference).unwrap();
        println!("tilt {tilt}: relMSE flat light-map {ef:.4}, directional {ed:.4}");
        results.push((tilt, ef, ed));
    }
    let (_, flat0, dir0) = results[0];
    // Without bumps the directional light-map is the flat one (ratios average to 1 and the
    // weights are equal), up to the noise of the ratios.
    assert!((dir0 - flat0).abs() < 0.2 * flat0 + 2e-3, "{results:?}");
    let (_, flat, dir) = results[1];
    // With bumps the flat light-map misses the ridges the reference shows; the directional one
    // reproduces most of them.
    assert!(dir < 0.5 * flat, "{results:?}");
}
