//! The SH techniques on the GPU against the CPU views of the same data (issue 6): textured
//! transfer (SH light-maps / textured PRT), per-vertex transfer, one or six incident-light
//! sample points. Runs on lavapipe in CI.

mod common;

use glam::Vec3;
use lightlab_bake::layout::LayoutSettings;
use lightlab_bake::prt::{
    ShLightmaps, TransferKind, TransferSettings, bake_sh_lightmaps, render_sh_lightmaps,
    render_vertex_transfer, vertex_transfer,
};
use lightlab_bake::sh_compress::{CompressSettings, Filter, compress, render_compressed};
use lightlab_bake::sh_light::{SamplePoints, ShLightSettings, ShLighting};
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse;
use lightlab_gpu::prt::{IndexPage, ShFilter, ShInput, ShTransfer};
use lightlab_gpu::raster::{Ambient, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::{GpuContext, test_context};
use lightlab_scene::{Light, LightKind, Scene};

const N: u32 = 96;
const K: u32 = 3;

fn settings() -> RasterSettings {
    RasterSettings {
        width: N * K,
        height: N * K,
        shadows: ShadowMethod::None,
        ambient: Ambient::None,
        ..Default::default()
    }
}

/// Render an SH input under `light` and read it back at N×N.
fn gpu_render(ctx: &GpuContext, scene: &Scene, input: &ShInput, light: &ShLighting) -> Image {
    let mut unlit = scene.clone();
    unlit.lights.clear();
    let mut r = Renderer::with_sh(ctx, &unlit, settings(), input).unwrap();
    let (points, coeffs) = light.flattened();
    r.set_sh_light(ctx, &points, &coeffs).unwrap();
    r.render(ctx);
    r.read_hdr(ctx).unwrap().downsample(K)
}

/// The prt scene with a point light beside the knots (near light: the six sample points
/// matter) and its SH light-maps.
fn setup() -> (Scene, ShLightmaps, TransferSettings) {
    let mut scene = lightlab_scene::builtin::builtin("prt").unwrap();
    scene.lights.push(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        color: Vec3::new(1.0, 0.8, 0.6),
        intensity: 6.0,
        position: Vec3::new(0.0, 2.2, 1.5),
        direction: Vec3::NEG_Y,
        range: None,
    });
    let s = TransferSettings {
        bands: 4,
        samples: 64,
        kind: TransferKind::Shadowed,
        seed: 1,
        ..Default::default()
    };
    let layout = LayoutSettings {
        texels_per_metre: 12.0,
        ..Default::default()
    };
    let sl = bake_sh_lightmaps(&scene, &layout, &s, &lightlab_bake::no_progress).unwrap();
    (scene, sl, s)
}

fn lighting(scene: &Scene, bands: usize, points: SamplePoints) -> ShLighting {
    ShLighting::new(
        scene,
        &ShLightSettings {
            bands,
            points,
            ..Default::default()
        },
        None,
    )
}

/// The CPU views return the environment where rays escape, the GPU black: render both without.
fn no_background(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.environment = None;
    s
}

#[test]
fn gpu_sh_techniques_match_the_cpu_views() {
    let Some(ctx) = test_context() else { return };
    let (scene, sl, s) = setup();
    let rects = common::layout_rects(&sl.layout);
    let view_scene = no_background(&sl.scene);
    for points in [SamplePoints::Scene, SamplePoints::PerObject] {
        let light = lighting(&sl.scene, s.bands, points);
        let input = ShInput {
            bands: s.bands,
            transfer: ShTransfer::Textured { pages: &sl.pages },
            rects: &rects,
            per_object: points == SamplePoints::PerObject,
            points: light.points[0].len(),
        };
        let gpu = gpu_render(&ctx, &view_scene, &input, &light);
        let cpu_sl = ShLightmaps {
            scene: view_scene.clone(),
            ..sl.clone()
        };
        let cpu = render_sh_lightmaps(&cpu_sl, &light, N, N, 0, 9).unwrap();
        let e = relmse(&gpu, &cpu).unwrap();
        println!(
            "textured, {points:?}: GPU vs CPU relMSE {e:.5}, means {:?} / {:?}",
            gpu.mean(),
            cpu.mean()
        );
        let ratio = gpu.mean() / cpu.mean();
        assert!(e < 0.008, "textured {points:?}: relMSE {e}");
        assert!((ratio - 1.0).abs().max_element() < 0.003, "{ratio:?}");
        assert!(gpu.mean().min_element() > 0.02, "lit: {:?}", gpu.mean());
    }

    // Compressed SH light-maps: nearest, bilinear of relit representatives, Fuchs's 4-tap.
    let c = compress(
        &sl,
        &CompressSettings {
            representatives: 256,
            ..Default::default()
        },
    )
    .unwrap();
    let index_pages: Vec<IndexPage> = c
        .pages
        .iter()
        .map(|p| IndexPage {
            width: p.width,
            height: p.height,
            indices: &p.indices,
        })
        .collect();
    let light = lighting(&sl.scene, s.bands, SamplePoints::PerObject);
    let cpu_sl = ShLightmaps {
        scene: no_background(&sl.scene),
        ..sl.clone()
    };
    for (gf, cf) in [
        (ShFilter::Nearest, Filter::Nearest),
        (ShFilter::Bilinear, Filter::Bilinear),
        (ShFilter::FourTap, Filter::FourTap),
    ] {
        let input = ShInput {
            bands: s.bands,
            transfer: ShTransfer::Compressed {
                pages: &index_pages,
                representatives: &c.representatives,
                filter: gf,
            },
            rects: &rects,
            per_object: true,
            points: 6,
        };
        let gpu = gpu_render(&ctx, &cpu_sl.scene, &input, &light);
        let cpu = render_compressed(&cpu_sl, &c, &light, cf, N, N, 0, 9).unwrap();
        let e = relmse(&gpu, &cpu).unwrap();
        let ratio = gpu.mean() / cpu.mean();
        println!("compressed, {gf:?}: GPU vs CPU relMSE {e:.5}, mean ratio {ratio:?}");
        assert!(e < 0.008, "compressed {gf:?}: relMSE {e}");
        assert!((ratio - 1.0).abs().max_element() < 0.003, "{ratio:?}");
    }

    // Per-vertex transfer on the original scene (no light-map unwrap needed).
    let accel = lightlab_trace::Accel::new(&scene);
    let (vt, _) = vertex_transfer(&scene, &accel, &s).unwrap();
    let view_scene = no_background(&scene);
    for points in [SamplePoints::Scene, SamplePoints::PerObject] {
        let light = lighting(&scene, s.bands, points);
        let input = ShInput {
            bands: s.bands,
            transfer: ShTransfer::Vertex {
                instances: &vt.instances,
            },
            rects: &[],
            per_object: points == SamplePoints::PerObject,
            points: light.points[0].len(),
        };
        let gpu = gpu_render(&ctx, &view_scene, &input, &light);
        let cpu = render_vertex_transfer(&view_scene, &vt, &light, N, N, 0, 9).unwrap();
        let e = relmse(&gpu, &cpu).unwrap();
        let ratio = gpu.mean() / cpu.mean();
        println!("per vertex, {points:?}: GPU vs CPU relMSE {e:.5}, mean ratio {ratio:?}");
        if let Ok(dir) = std::env::var("LIGHTLAB_TEST_OUT") {
            let ls = lightlab_core::image::LdrSettings::default();
            gpu.write(
                &std::path::Path::new(&dir).join(format!("vertex-{points:?}-gpu.png")),
                ls,
            )
            .unwrap();
            cpu.write(
                &std::path::Path::new(&dir).join(format!("vertex-{points:?}-cpu.png")),
                ls,
            )
            .unwrap();
        }
        // The knot's 86k thin ridges alias differently under the GPU's regular 3×3 samples
        // and the CPU's jittered ones; the means agree closely.
        assert!(e < 0.012, "per vertex {points:?}: relMSE {e}");
        assert!((ratio - 1.0).abs().max_element() < 0.005, "{ratio:?}");
    }

    // Malformed input is an error, not a panic.
    let bad = ShInput {
        bands: s.bands,
        transfer: ShTransfer::Vertex {
            instances: &vt.instances[..1],
        },
        rects: &[],
        per_object: false,
        points: 1,
    };
    assert!(Renderer::with_sh(&ctx, &scene, settings(), &bad).is_err());
}
