//! The `lightmap` technique on the GPU against the CPU light-map view of the same bake (issue 5):
//! bilinear and bicubic sampling must read the pages as the CPU does. Runs on lavapipe and
//! llvmpipe in CI.

mod common;

use lightlab_bake::{BakeSettings, Method, bake_lightmaps, no_progress, view};
use lightlab_core::metrics::relmse;
use lightlab_gpu::raster::{Ambient, LightmapInput, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::test_context;

#[test]
fn gpu_lightmap_matches_the_cpu_view() {
    let Some(ctx) = test_context() else { return };
    let scene = lightlab_scene::builtin::builtin("cornell").unwrap();
    let mut s = BakeSettings {
        method: Method::Path,
        ..Default::default()
    };
    s.layout.texels_per_metre = 16.0;
    s.gather.samples = 16;
    let lm = bake_lightmaps(&scene, &s, &no_progress).unwrap();
    let rects = common::uv_rects(&lm);
    let (n, k) = (96u32, 4u32);
    let mut lit = lm.scene.clone();
    lit.lights.clear();
    for (bicubic, filter) in [
        (false, view::Filter::Bilinear),
        (true, view::Filter::Bicubic),
    ] {
        let input = LightmapInput {
            pages: &lm.pages,
            rects: &rects,
            bicubic,
            directional: None,
        };
        let settings = RasterSettings {
            width: n * k,
            height: n * k,
            shadows: ShadowMethod::None,
            ambient: Ambient::None,
            ..Default::default()
        };
        let mut r = Renderer::with_lightmap(&ctx, &lit, settings, Some(&input)).unwrap();
        r.render(&ctx);
        // Clamped at 1: the emitter (radiance 17, 1 % of the pixels) would otherwise weigh its
        // edge coverage more than all the light-mapped surfaces together.
        let clamp = |mut i: lightlab_core::image::Image| {
            i.data.iter_mut().for_each(|v| *v = v.min(glam::Vec3::ONE));
            i
        };
        let gpu = clamp(r.read_hdr(&ctx).unwrap().downsample(k));
        let cpu = clamp(view::render(&lm, n, n, 0, filter, 16).unwrap());
        let e = relmse(&gpu, &cpu).unwrap();
        // Means over the light-mapped pixels only. The whole-image means differ by about 1.5 %
        // because of the emitter's partly covered edge row: the GPU's regular 4×4 samples miss
        // a sliver that the CPU's jittered samples hit (× radiance 17), an aliasing difference
        // of the emitter, not of the light-map.
        let (mut sg, mut sc) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for (g, c) in gpu.data.iter().zip(&cpu.data) {
            if g.max_element() < 0.9 && c.max_element() < 0.9 {
                sg += g.as_dvec3();
                sc += c.as_dvec3();
            }
        }
        let ratio = sg / sc;
        let whole = gpu.mean() / cpu.mean();
        println!(
            "GPU vs CPU light-map view, {filter:?}: relMSE {e:.5}, mean ratio {ratio:?} \
             (light-mapped pixels), {whole:?} (whole image)"
        );
        assert!(e < 0.005, "{filter:?}: relMSE {e}");
        assert!(
            (ratio - 1.0).abs().max_element() < 0.005,
            "{filter:?}: {ratio:?}"
        );
    }
    // A light-map that does not fit the scene is an error, not a panic.
    let bad = LightmapInput {
        pages: &lm.pages,
        rects: &rects[..1],
        bicubic: false,
        directional: None,
    };
    assert!(Renderer::with_lightmap(&ctx, &lit, RasterSettings::default(), Some(&bad)).is_err());
}
