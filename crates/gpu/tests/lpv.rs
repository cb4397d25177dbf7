//! Light propagation volumes on the GPU against the CPU reference (`lightlab_core::lpv`) fed
//! with the GPU's own reflective shadow map (issue 7). Runs on lavapipe in CI.

use glam::Vec3;
use lightlab_core::image::Image;
use lightlab_core::lpv::{self, Occlusion, Surfel, Volume, Vpl};
use lightlab_gpu::lpv::{LpvScheme, LpvSettings, rsm_lights};
use lightlab_gpu::raster::{Ambient, RasterSettings, Renderer, ShadowMethod};
use lightlab_gpu::{GpuContext, test_context};
use lightlab_scene::Scene;

fn render_lpv(ctx: &GpuContext, scene: &Scene, s: &LpvSettings) -> Renderer {
    render_lpv_in(ctx, scene, s, Ambient::None)
}

/// The volume's indirect light at 64², with `ambient` (an environment turns on near occlusion
/// and the near field).
fn render_lpv_in(ctx: &GpuContext, scene: &Scene, s: &LpvSettings, ambient: Ambient) -> Renderer {
    let rs = RasterSettings {
        width: 64,
        height: 64,
        shadows: ShadowMethod::None,
        ambient,
        ..Default::default()
    };
    let mut r = Renderer::with_lpv(ctx, scene, rs, s, true).unwrap();
    r.render(ctx);
    r
}

/// The RSM texels (flux, normal, position) read back from the GPU.
fn read_rsm(ctx: &GpuContext, r: &Renderer) -> Vec<([f32; 4], [f32; 4], [f32; 4])> {
    let [f, n, p] = r.lpv().unwrap().read_rsm(ctx).unwrap();
    f.into_iter()
        .zip(n)
        .zip(p)
        .map(|((a, b), c)| (a, b, c))
        .collect()
}

/// The CPU pipeline on the GPU's RSM: VPLs (reflected and transmitted), blockers, propagation,
/// on cascade `cascade`'s grid.
fn cpu_volume(
    scene: &Scene,
    r: &Renderer,
    texels: &[([f32; 4], [f32; 4], [f32; 4])],
    cascade: usize,
) -> Volume {
    let l = r.lpv().unwrap();
    let grid = l.grids[cascade];
    let light = rsm_lights(
        scene,
        None,
        &[],
        l.grids.last().unwrap(),
        l.settings.rsm_size,
    )[0]
    .0;
    let eye = Vec3::from_array(light.eye);
    let mut vpls = Vec::new();
    let mut surfels = Vec::new();
    for (f, n, p) in texels {
        if p[3] <= 0.0 {
            continue;
        }
        let pos = Vec3::new(p[0], p[1], p[2]);
        let nrm = Vec3::new(n[0], n[1], n[2]).normalize();
        let flux = Vec3::new(f[0], f[1], f[2]);
        let tr = n[3].clamp(0.0, 1.0);
        vpls.push(Vpl {
            position: pos,
            normal: nrm,
            flux: flux * (1.0 - tr),
        });
        if tr > 0.0 {
            vpls.push(Vpl {
                position: pos,
                normal: -nrm,
                flux: flux * tr,
            });
        }
        let to_light = if light.kind == 0 {
            -Vec3::from_array(light.axis)
        } else {
            (eye - pos).normalize()
        };
        // The albedo as the injection recovers it: Φ / (colour × w × A).
        let lit = Vec3::from_array(light.color) * (f[3] * p[3]);
        let albedo = Vec3::select(
            lit.cmpgt(Vec3::ZERO),
            flux / lit.max(Vec3::splat(1e-30)),
            Vec3::ZERO,
        );
        surfels.push(Surfel {
            position: pos,
            normal: nrm,
            area: p[3] / nrm.dot(to_light).abs().max(0.25),
            albedo: albedo.min(Vec3::ONE),
        });
    }
    let seed = lpv::inject(grid, &vpls);
    let occ = l
        .settings
        .occlusion
        .then(|| Occlusion::inject(grid, &surfels));
    lpv::propagate(
        &seed,
        occ.as_ref(),
        l.settings.iterations(),
        l.settings.reemit,
        l.settings.reemit_lobe,
        l.settings.bounces,
    )
}

/// Relative L2 difference of two volumes (all coefficients).
fn rel_l2(a: &Volume, b: &Volume) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (x, y) in a.cells.iter().zip(&b.cells) {
        for ch in 0..3 {
            for k in 0..4 {
                num += ((x[ch][k] - y[ch][k]) as f64).powi(2);
                den += (y[ch][k] as f64).powi(2);
            }
        }
    }
    (num / den.max(1e-30)).sqrt()
}

#[test]
fn gpu_volume_matches_the_cpu_reference_on_cornell_and_room_cascades() {
    let Some(ctx) = test_context() else { return };
    // Cornell with and without the geometry volume; the room's sun with three cascades.
    for (name, occlusion, cascades) in [
        ("cornell", false, 1),
        ("cornell", true, 1),
        ("room", true, 3),
    ] {
        let scene = lightlab_scene::builtin::builtin(name).unwrap();
        let s = LpvSettings {
            grid: 16,
            rsm_size: 128,
            iterations: Some(8),
            occlusion,
            cascades,
            // The CPU reference here models the light's RSM only.
            camera_blockers: false,
            ..Default::default()
        };
        let r = render_lpv(&ctx, &scene, &s);
        let texels = read_rsm(&ctx, &r);
        let lit = texels.iter().filter(|t| t.2[3] > 0.0).count();
        assert!(lit > texels.len() / 16, "the RSM sees the scene: {lit}");
        for c in 0..cascades as usize {
            let cpu = cpu_volume(&scene, &r, &texels, c);
            let gpu = r.lpv().unwrap().read_volume(&ctx, c).unwrap();
            let e = rel_l2(&gpu, &cpu);
            let (fg, fc) = (gpu.total_flux(), cpu.total_flux());
            eprintln!(
                "{name}, occlusion {occlusion}, cascade {c}/{cascades}: relative L2 {e:.2e}, \
                 flux GPU {fg} CPU {fc}"
            );
            assert!(fc.x > 0.0, "cascade {c} holds light");
            assert!(e < 5e-3, "GPU vs CPU volume: {e}");
            assert!(((fg - fc) / fc).abs().max_element() < 2e-3);
        }
    }
}

#[test]
fn wpi_propagation_on_the_gpu_grows_like_the_report() {
    // The faithful scheme keeps the seed and adds ≈3.5 % per pass (extraction §5.5): the GPU
    // volume after 4 passes holds more light than after 1, by the CPU kernel's factor.
    let Some(ctx) = test_context() else { return };
    let scene = lightlab_scene::builtin::builtin("cornell").unwrap();
    let mut totals = vec![];
    for k in [0u32, 4] {
        let s = LpvSettings {
            scheme: LpvScheme::Wpi,
            grid: 16,
            rsm_size: 128,
            iterations: Some(k),
            ..Default::default()
        };
        let r = render_lpv(&ctx, &scene, &s);
        let v = r.lpv().unwrap().read_volume(&ctx, 0).unwrap();
        // The CPU kernel applied to the GPU's seed.
        if k == 0 {
            let mut cpu = v.clone();
            for _ in 0..4 {
                cpu = lpv::propagate_step_wpi(&cpu);
            }
            totals.push((v.total_flux(), Some(cpu)));
        } else {
            totals.push((v.total_flux(), None));
            let cpu = totals[0].1.as_ref().unwrap();
            let e = rel_l2(&v, cpu);
            eprintln!("WPI 4 passes: GPU vs CPU relative L2 {e:.2e}");
            assert!(e < 5e-3, "{e}");
        }
    }
    let growth = totals[1].0.x / totals[0].0.x;
    assert!(
        growth > 1.05,
        "the report's scheme is not conservative: ×{growth}"
    );
}

/// The reference's indirect light at 64×64: paths of 2 to `max_depth` segments (2: exactly
/// one bounce).
fn reference_indirect(scene: &Scene, max_depth: u32) -> lightlab_core::image::Image {
    let accel = lightlab_trace::Accel::new(scene);
    let pt = lightlab_trace::PathTracer::new(scene, &accel);
    let s = lightlab_trace::RenderSettings {
        width: 64,
        height: 64,
        spp: 512,
        min_depth: 2,
        max_depth,
        ..Default::default()
    };
    pt.render(&s, &|_, _| true).unwrap()
}

/// Per channel, the constant c minimising relMSE of c·A against R (weighted least squares with
/// relMSE's weights 1/(R² + 0.01)).
fn fit_constant(a: &lightlab_core::image::Image, r: &lightlab_core::image::Image) -> Vec3 {
    let mut c = [0.0f32; 3];
    for k in 0..3 {
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (x, y) in a.data.iter().zip(&r.data) {
            let (x, y) = (x[k] as f64, y[k] as f64);
            let w = 1.0 / (y * y + 0.01);
            num += w * x * y;
            den += w * x * x;
        }
        c[k] = (num / den.max(1e-30)) as f32;
    }
    Vec3::from_array(c)
}

/// relMSE of `img` against `reference`, both scaled so that the reference's mean luminance is
/// 1 (relMSE's ε = 0.01 assumes values near 1; the comparison is then independent of the
/// light's intensity).
fn relmse_scaled(img: &Image, reference: &Image) -> f64 {
    let k = 1.0 / lightlab_core::color::luminance(reference.mean()).max(1e-12);
    let scaled = |i: &Image| {
        let mut o = i.clone();
        for p in &mut o.data {
            *p *= k;
        }
        o
    };
    lightlab_core::metrics::relmse(&scaled(img), &scaled(reference)).unwrap()
}

/// The scene's diffuse albedo as the renderer sees it (a unit constant sky, unoccluded; no
/// lights, no emission), for the constant-ambient baseline.
fn albedo_image(ctx: &GpuContext, scene: &Scene) -> Image {
    let mut plain = scene.clone();
    plain.lights.clear();
    for m in &mut plain.materials {
        m.emissive = Vec3::ZERO;
    }
    let rs = RasterSettings {
        width: 64,
        height: 64,
        shadows: ShadowMethod::None,
        ambient: Ambient::Constant(Vec3::ONE),
        sky_occlusion: 0,
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, &plain, rs).unwrap();
    r.render(ctx);
    r.read_hdr(ctx).unwrap()
}

/// The best constant ambient term against `reference`: albedo × c, c fitted per channel to
/// the reference scaled as [`relmse_scaled`] scales it.
fn ambient_relmse(albedo: &Image, reference: &Image) -> f64 {
    let k = 1.0 / lightlab_core::color::luminance(reference.mean()).max(1e-12);
    let mut scaled = reference.clone();
    for p in &mut scaled.data {
        *p *= k;
    }
    let c = fit_constant(albedo, &scaled);
    let mut ambient = albedo.clone();
    for p in &mut ambient.data {
        *p *= c;
    }
    lightlab_core::metrics::relmse(&ambient, &scaled).unwrap()
}

#[test]
fn lpv_indirect_light_on_cornell_against_the_reference() {
    // Issue 7's measurement, at default settings (issue 22): the volume's indirect light only,
    // beside the best constant ambient term fitted to the same reference. `lpv`'s defaults
    // (16³, 48 steps, multiple bounces, side faces re-emitted as lobes of weight 0.85, two-sided
    // blockers) against all of the reference's indirect light; the one-bounce variants (and
    // lpv-faithful, a one-bounce scheme) against exactly one bounce, where issue 7's target was
    // first met on a grid that suits this closed box (8³, 4 steps, damping ½, side faces
    // re-emitted along their direction; Kaplanyan's face-normal re-emission does not reach it
    // at any setting, docs/lpv.md).
    let Some(ctx) = test_context() else { return };
    let scene = lightlab_scene::builtin::builtin("cornell").unwrap();
    let all = reference_indirect(&scene, 16);
    let one = reference_indirect(&scene, 2);
    let albedo = albedo_image(&ctx, &scene);
    let render = |s: &LpvSettings| {
        let mut r = render_lpv(&ctx, &scene, s);
        r.render(&ctx);
        r.read_hdr(&ctx).unwrap()
    };
    let d = LpvSettings::default();
    let lpv_img = render(&d);
    let lpv = relmse_scaled(&lpv_img, &all);
    if let Ok(dir) = std::env::var("LIGHTLAB_TEST_OUT") {
        let ldr = lightlab_core::image::LdrSettings::default();
        let _ = lpv_img.write(&std::path::Path::new(&dir).join("lpv_cornell.png"), ldr);
        let _ = all.write(&std::path::Path::new(&dir).join("lpv_cornell_ref.png"), ldr);
    }
    let (amb_all, amb_one) = (ambient_relmse(&albedo, &all), ambient_relmse(&albedo, &one));
    let undamped = relmse_scaled(
        &render(&LpvSettings {
            damping: 0.0,
            ..d.clone()
        }),
        &all,
    );
    let wpi = relmse_scaled(
        &render(&LpvSettings {
            scheme: LpvScheme::Wpi,
            grid: lightlab_gpu::lpv::FAITHFUL_GRID,
            ..d.clone()
        }),
        &one,
    );
    let box_grid = LpvSettings {
        grid: 8,
        iterations: Some(4),
        damping: 0.5,
        bounces: lightlab_core::lpv::Bounces::Single,
        ..d.clone()
    };
    let coarse = relmse_scaled(&render(&box_grid), &one);
    let coarse_face = relmse_scaled(
        &render(&LpvSettings {
            reemit: lightlab_core::lpv::Reemit::FaceNormal,
            ..box_grid.clone()
        }),
        &one,
    );
    eprintln!(
        "cornell indirect light, 64², relMSE: lpv defaults {lpv:.4} against all bounces \
         (fitted ambient {amb_all:.4}, no damping {undamped:.4}); one bounce: 8³, 4 steps, \
         damping ½ {coarse:.4} (face-normal re-emission {coarse_face:.4}), lpv-faithful \
         {wpi:.4}, fitted ambient {amb_one:.4}"
    );
    // Issue 7's target at default settings (issue 22): at most half the fitted ambient's
    // relMSE. Measured 0.166 against 0.381 with two-sided blockers and side faces re-emitted
    // as lobes of weight 0.85; one-sided blockers and cosine lobes scored 0.399 (docs/lpv.md).
    assert!(
        lpv <= 0.5 * amb_all,
        "defaults: {lpv} against half the ambient's {amb_all}"
    );
    assert!(lpv < 0.8 * undamped, "damping helps: {lpv} vs {undamped}");
    assert!(coarse < 0.5 * wpi, "lpv {coarse} vs lpv-faithful {wpi}");
    // Issue 7's target with one bounce (measured 0.174 against 0.5 × 0.408).
    assert!(
        coarse <= 0.5 * amb_one,
        "8³: {coarse} vs half the ambient's {amb_one}"
    );
    assert!(
        coarse < 0.9 * coarse_face,
        "central {coarse} vs face normal {coarse_face}"
    );
    assert!(
        amb_one < 0.5 && amb_all < 0.5,
        "the ambient baselines: {amb_one}, {amb_all}"
    );
}

#[test]
fn moving_the_camera_by_a_fraction_of_a_cell_does_not_flicker() {
    // Issue 7: the cascades follow the camera in whole cells, so a camera moved by a fraction
    // of the finest cell leaves the indirect light of a fixed view unchanged (< 1 %); unsnapped
    // cascades change it. Room (camera inside), 16³ × 3 cascades, the indirect light only.
    let Some(ctx) = test_context() else { return };
    let scene = lightlab_scene::builtin::builtin("room").unwrap();
    let cam = scene.default_camera().unwrap().clone();
    let forward = cam.transform.transform_vector3(-Vec3::Z);
    let base = LpvSettings {
        grid: 16,
        rsm_size: 128,
        iterations: Some(8),
        cascades: 3,
        ..Default::default()
    };
    // The cascades placed as for an eye whose finest cascade is centred on the pillars and the
    // lit floor the view looks at (the room camera itself sees little within its finest one).
    let finest = base.grid_for(&scene).cell / 4.0;
    let eye = Vec3::new(0.9, 0.6, 0.0) - forward * (0.25 * 16.0 * finest);
    // With the room's sky: near occlusion and the near field gathered from the sun's RSM are
    // on, and both move with the finest cascade.
    let render = |s: &LpvSettings| {
        let mut r = render_lpv_in(&ctx, &scene, s, Ambient::Environment);
        assert!(r.lpv().unwrap().near_occlusion_radius() > 0.0);
        r.render(&ctx);
        r.read_hdr(&ctx).unwrap()
    };
    let change = |a: &lightlab_core::image::Image, b: &lightlab_core::image::Image| {
        let (mut d, mut t) = (0.0f64, 0.0f64);
        for (x, y) in a.data.iter().zip(&b.data) {
            d += (*x - *y).abs().element_sum() as f64;
            t += x.element_sum() as f64;
        }
        d / t.max(1e-30)
    };
    let dir = Vec3::new(1.0, 0.3, -0.6).normalize();
    let mut worst = [0.0f64; 2];
    let mut crossed = false;
    for (k, snap) in [true, false].into_iter().enumerate() {
        let at = |f: f32| LpvSettings {
            snap,
            anchor: Some((eye + dir * f * finest, forward)),
            ..base.clone()
        };
        let still = render(&at(0.0));
        let grids0 = at(0.0).grids_for(&scene, eye, forward);
        for f in [0.3, 0.55, 0.8, 0.95] {
            let s = at(f);
            let c = change(&still, &render(&s));
            let moved = s.grids_for(&scene, eye, forward) != grids0;
            eprintln!(
                "snap {snap}: camera moved {f} of a cell (grids moved: {moved}): indirect \
                 image changes {c:.2e}"
            );
            crossed |= snap && moved;
            worst[k] = worst[k].max(c);
        }
    }
    // At least one move crossed a cell boundary, where the snapped grids shift by a whole cell.
    assert!(crossed);
    assert!(worst[0] < 0.01, "snapped cascades flicker: {}", worst[0]);
    assert!(
        worst[1] > 0.01,
        "unsnapped cascades should change: {}",
        worst[1]
    );
}

#[test]
fn a_point_light_in_a_closed_box_injects_all_its_reflected_flux() {
    // A point light of intensity I at the centre of a closed box of albedo ½: its six RSM faces
    // see every wall, so the injected flux is ½·4π·I (the seed, before propagation).
    let Some(ctx) = test_context() else { return };
    let mut scene = Scene::default();
    let m = scene.add_material(lightlab_scene::Material {
        brdf: lightlab_scene::BrdfModel::Lambert,
        double_sided: true,
        ..lightlab_scene::Material::diffuse("wall", Vec3::splat(0.5))
    });
    let mesh = lightlab_scene::builtin::geom::aabb_box("box", Vec3::ZERO, Vec3::splat(2.0), m);
    scene.add_mesh(mesh, glam::Mat4::IDENTITY);
    let intensity = 3.0;
    scene.lights.push(lightlab_scene::Light {
        name: "bulb".into(),
        kind: lightlab_scene::LightKind::Point,
        color: Vec3::ONE,
        intensity,
        position: Vec3::new(0.9, 1.1, 1.0),
        direction: -Vec3::Y,
        range: None,
    });
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "inside",
        Vec3::new(1.0, 1.0, 1.9),
        Vec3::splat(1.0),
        Vec3::Y,
        1.2,
    ));
    let s = LpvSettings {
        grid: 16,
        rsm_size: 128,
        iterations: Some(0),
        occlusion: false,
        ..Default::default()
    };
    let r = render_lpv(&ctx, &scene, &s);
    assert_eq!(r.lpv().unwrap().light_count(), 6);
    let flux = r.lpv().unwrap().read_volume(&ctx, 0).unwrap().total_flux();
    let want = 0.5 * 4.0 * std::f32::consts::PI * intensity;
    eprintln!("point light in a box: injected flux {flux} (exact {want})");
    assert!(
        ((flux - Vec3::splat(want)) / want).abs().max_element() < 0.01,
        "{flux} vs {want}"
    );
}

#[test]
fn the_sky_enters_the_volume_as_directional_views() {
    // A closed box of albedo ½ under a uniform sky of radiance L (the constant ambient): each of
    // the sky's cells is a directional view of irradiance E⊥_k (Σ E⊥_k = 4πL) that sees the
    // box's projected area 4·(|x| + |y| + |z|) along its direction ω_k, so the injected flux is
    // ½ · Σ E⊥_k · 4·(|x_k| + |y_k| + |z_k|) (12πL for a continuous sky), at a quarter of the
    // RSM's side.
    let Some(ctx) = test_context() else { return };
    let mut scene = Scene::default();
    let m = scene.add_material(lightlab_scene::Material::diffuse("wall", Vec3::splat(0.5)));
    let mesh = lightlab_scene::builtin::geom::aabb_box("box", Vec3::ZERO, Vec3::splat(2.0), m);
    scene.add_mesh(mesh, glam::Mat4::IDENTITY);
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "outside",
        Vec3::new(5.0, 4.0, 6.0),
        Vec3::splat(1.0),
        Vec3::Y,
        0.8,
    ));
    let radiance = Vec3::new(0.6, 0.8, 1.0);
    let s = LpvSettings {
        grid: 16,
        rsm_size: 512,
        iterations: Some(0),
        occlusion: false,
        sky_lights: 16,
        ..Default::default()
    };
    let rs = RasterSettings {
        width: 64,
        height: 64,
        shadows: ShadowMethod::None,
        ambient: Ambient::Constant(radiance),
        ..Default::default()
    };
    let mut r = Renderer::with_lpv(&ctx, &scene, rs, &s, true).unwrap();
    r.render(&ctx);
    assert_eq!(r.lpv().unwrap().light_count(), 16);
    let flux = r.lpv().unwrap().read_volume(&ctx, 0).unwrap().total_flux();
    let uniform = lightlab_core::image::Image::from_fn(64, 32, |_, _| radiance);
    let cells = lightlab_gpu::raster::sky_lights(&uniform, 1.0, 16);
    let want: Vec3 = cells
        .iter()
        .map(|(d, e)| 0.5 * *e * 4.0 * (d.x.abs() + d.y.abs() + d.z.abs()))
        .sum();
    let continuous = 12.0 * std::f32::consts::PI * radiance;
    eprintln!("sky on a box: injected flux {flux}, expected {want} (continuous sky {continuous})");
    assert!(
        ((flux - want) / want).abs().max_element() < 0.01,
        "{flux} vs {want}"
    );
    assert!(((want - continuous) / continuous).abs().max_element() < 0.05);
    // Without sky lights the volume is dark.
    let none = LpvSettings { sky_lights: 0, ..s };
    let rs = RasterSettings {
        width: 64,
        height: 64,
        shadows: ShadowMethod::None,
        ambient: Ambient::Constant(radiance),
        ..Default::default()
    };
    let mut r = Renderer::with_lpv(&ctx, &scene, rs, &none, true).unwrap();
    r.render(&ctx);
    let dark = r.lpv().unwrap().read_volume(&ctx, 0).unwrap().total_flux();
    assert_eq!(dark, Vec3::ZERO);
}

#[test]
fn camera_blockers_stop_light_that_no_light_sees_the_blocker_of() {
    // Cornell's ceiling is behind its lamp: the lamp's RSM has no blocker there and light leaks
    // out of the box through it. The camera sees the ceiling: with its blockers the light above
    // the box drops.
    let Some(ctx) = test_context() else { return };
    let scene = lightlab_scene::builtin::builtin("cornell").unwrap();
    let top = scene.bounds().unwrap().1.y;
    let above = |camera_blockers| {
        let s = LpvSettings {
            grid: 16,
            rsm_size: 128,
            iterations: Some(8),
            camera_blockers,
            ..Default::default()
        };
        let r = render_lpv(&ctx, &scene, &s);
        assert_eq!(r.lpv().unwrap().light_count(), 1 + camera_blockers as usize);
        let v = r.lpv().unwrap().read_volume(&ctx, 0).unwrap();
        let mut out = 0.0;
        let mut inside = 0.0;
        for c in v.grid.cells() {
            let f = v.at(c)[0][0];
            if v.grid.centre(c).y > top + 0.5 * v.grid.cell {
                out += f;
            } else {
                inside += f;
            }
        }
        (out, inside)
    };
    let (leak, inside) = above(false);
    let (blocked, inside_b) = above(true);
    eprintln!(
        "light above cornell's ceiling: {:.3} % of the inside without camera blockers, {:.3} % \
         with",
        100.0 * leak / inside,
        100.0 * blocked / inside_b
    );
    assert!(blocked < 0.5 * leak, "{blocked} vs {leak}");
    // The light inside is not blocked more than a few percent by the extra blockers.
    assert!(inside_b > 0.8 * inside, "{inside_b} vs {inside}");
}

/// `lpv-faithful` lit by one sun shades with the WPI report's composite (App. B) instead of
/// the light passes. A Lambert plane lit straight down, a slab floating above its centre: at
/// the shadow's centre the image must be a·E/π·illum with illum the report's screen blends of
/// its depth-difference shadow (every tap sees the slab: 1 − clamp(17·(Δz − bias))), GI and TI
/// evaluated from the volume read back; on the open plane the blend saturates at a·E/π.
#[test]
fn lpv_faithful_composites_as_the_report() {
    use lightlab_scene::builtin::geom::{aabb_box, quad};
    let Some(ctx) = test_context() else { return };
    let albedo = 0.6;
    let irradiance = 3.0;
    let mut scene = Scene::default();
    let m = scene.add_material(lightlab_scene::Material {
        brdf: lightlab_scene::BrdfModel::Lambert,
        ..lightlab_scene::Material::diffuse("ground", Vec3::splat(albedo))
    });
    let c = [(-3.0, 3.0), (3.0, 3.0), (3.0, -3.0), (-3.0, -3.0)].map(|(x, z)| Vec3::new(x, 0.0, z));
    scene.add_mesh(quad("ground", c, m), glam::Mat4::IDENTITY);
    let slab = (Vec3::new(-0.5, 0.35, -0.5), Vec3::new(0.5, 0.4, 0.5));
    scene.add_mesh(aabb_box("slab", slab.0, slab.1, m), glam::Mat4::IDENTITY);
    scene.lights.push(point_sun(-Vec3::Y, irradiance));
    // Camera 0 looks at the shadow's centre from low on the side (under the slab); camera 1
    // straight down at the open plane.
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "shadow",
        Vec3::new(3.0, 0.4, 0.0),
        Vec3::ZERO,
        Vec3::Y,
        0.3,
    ));
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "open",
        Vec3::new(-2.0, 3.0, 0.0),
        Vec3::new(-2.0, 0.0, 0.0),
        Vec3::Z,
        0.3,
    ));
    let s = LpvSettings {
        scheme: LpvScheme::Wpi,
        grid: 16,
        rsm_size: 256,
        iterations: Some(2),
        ..Default::default()
    };
    let centre = |camera: usize| {
        let rs = RasterSettings {
            width: 64,
            height: 64,
            shadows: ShadowMethod::Map,
            ambient: Ambient::None,
            camera,
            ..Default::default()
        };
        let mut r = Renderer::with_lpv(&ctx, &scene, rs, &s, false).unwrap();
        r.render(&ctx);
        let img = r.read_hdr(&ctx).unwrap();
        let px = (img.get(31, 31) + img.get(32, 31) + img.get(31, 32) + img.get(32, 32)) / 4.0;
        (r, px)
    };
    let lit = albedo * irradiance / std::f32::consts::PI;
    let (_, open) = centre(1);
    eprintln!("open plane: {open} (a·E/π = {lit})");
    assert!(
        (open - Vec3::splat(lit)).abs().max_element() < 0.01 * lit,
        "{open} vs {lit}"
    );

    let (r, shaded) = centre(0);
    let lpv = r.lpv().unwrap();
    let light = lpv.composite_light().expect("one sun: the composite");
    let vp = glam::Mat4::from_cols_array_2d(&light.view_proj);
    let depth = |p: Vec3| vp.project_point3(p).z;
    let gap = depth(Vec3::ZERO) - depth(Vec3::new(0.0, slab.1.y, 0.0)) - 2e-3;
    let shadow = 1.0 - (17.0 * gap.max(0.0)).clamp(0.0, 1.0);
    let vol = lpv.read_volume(&ctx, 0).unwrap();
    let cell = vol.sample(Vec3::ZERO);
    let toward = |ch: usize, d: Vec3| lightlab_core::lpv::eval(&cell[ch], d) / irradiance;
    let want = Vec3::from_array(std::array::from_fn(|ch| {
        let gi = toward(ch, -Vec3::Y).clamp(0.0, 1.0);
        let ti = 0.05 * toward(ch, -Vec3::Y).clamp(0.0, 1.0) * shadow;
        let illum = shadow + (1.0 - shadow) * gi;
        lit * (illum + (1.0 - illum) * ti)
    }));
    eprintln!("shadow's centre: {shaded} (the report's composite: {want}; shadow {shadow:.3})");
    assert!(shadow > 0.05 && shadow < 0.95, "a partial shadow: {shadow}");
    // Without GI and TI it would be lit·shadow, 0.0126 lower here.
    assert!(
        (shaded - want).abs().max_element() < 0.005 * lit,
        "{shaded} vs {want}"
    );
}

/// The first hit of the ray o + t·d (t > 0) with the box [lo, hi] (slab test).
fn hit_box(o: Vec3, d: Vec3, (lo, hi): (Vec3, Vec3)) -> Option<f32> {
    let inv = d.recip();
    let (a, b) = ((lo - o) * inv, (hi - o) * inv);
    let (near, far) = (a.min(b).max_element(), a.max(b).min_element());
    (far >= near.max(0.0)).then_some(near.max(0.0))
}

/// The cosine-weighted share of the upper hemisphere at p (normal +y) in which the first of
/// `boxes` lies further than `radius` (a 64 × 64 stratified grid of directions).
fn far_share(p: Vec3, boxes: &[(Vec3, Vec3)], radius: f32) -> f32 {
    far_share_around(p, 1.0, boxes, radius)
}

/// As [`far_share`], over the hemisphere around `up`·(0, 1, 0) (`up` = ±1).
fn far_share_around(p: Vec3, up: f32, boxes: &[(Vec3, Vec3)], radius: f32) -> f32 {
    let n = 64;
    let mut far = 0;
    for i in 0..n {
        for j in 0..n {
            // Malley: a disc point lifted to the hemisphere is cosine-distributed.
            let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
            let d = Vec3::new(r * phi.cos(), up * (1.0 - u).sqrt(), r * phi.sin());
            let first = boxes
                .iter()
                .filter_map(|&b| hit_box(p, d, b))
                .fold(f32::INFINITY, f32::min);
            far += (first.is_finite() && first > radius) as u32;
        }
    }
    far as f32 / (n * n) as f32
}

/// The volume's indirect light (debug view) of `scene` under a uniform sky, `size`², with near
/// occlusion and without, and its reach [m].
fn near_occlusion_on_and_off(ctx: &GpuContext, scene: &Scene, size: u32) -> (Image, Image, f32) {
    let render = |near_occlusion| {
        let s = LpvSettings {
            near_occlusion,
            ..Default::default()
        };
        let rs = RasterSettings {
            width: size,
            height: size,
            shadows: ShadowMethod::None,
            ambient: Ambient::Constant(Vec3::ONE),
            ..Default::default()
        };
        let mut r = Renderer::with_lpv(ctx, scene, rs, &s, true).unwrap();
        let radius = r.lpv().unwrap().near_occlusion_radius();
        r.render(ctx);
        (r.read_hdr(ctx).unwrap(), radius)
    };
    let (on, radius) = render(true);
    let (off, none) = render(false);
    assert_eq!(none, 0.0, "no reach without near occlusion");
    (on, off, radius)
}

#[test]
fn a_leafs_light_through_its_back_keeps_its_back_hemispheres_share() {
    // A 2 m double-sided leaf that lets all light through (diffuse transmission 1), 2.5 m over
    // a 10 m ground under a uniform sky, seen from above. Its indirect light is the volume's
    // light arriving on its back, around −n, where the ground lies beyond the lookup's reach:
    // near occlusion keeps the share of the back hemisphere whose first surface lies beyond it
    // (about 0.9: all but the directions past the ground's edge). The front sees only sky, so
    // the front's share (what the back's light was kept by before) is 0.
    let Some(ctx) = test_context() else { return };
    let mut scene = Scene::default();
    let grey = scene.add_material(lightlab_scene::Material::diffuse("grey", Vec3::splat(0.5)));
    let leaf = scene.add_material(lightlab_scene::Material {
        double_sided: true,
        transmission: 1.0,
        ..lightlab_scene::Material::diffuse("leaf", Vec3::new(0.3, 0.6, 0.2))
    });
    let quad = |name: &str, y: f32, h: f32, m| {
        lightlab_scene::builtin::geom::quad_facing(
            name,
            [
                Vec3::new(-h, y, -h),
                Vec3::new(h, y, -h),
                Vec3::new(h, y, h),
                Vec3::new(-h, y, h),
            ],
            Vec3::Y,
            m,
        )
    };
    scene.add_mesh(quad("ground", 0.0, 5.0, grey), glam::Mat4::IDENTITY);
    scene.add_mesh(quad("leaf", 2.5, 1.0, leaf), glam::Mat4::IDENTITY);
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "above",
        Vec3::new(0.0, 6.0, 0.01),
        Vec3::new(0.0, 2.5, 0.0),
        Vec3::Y,
        0.5,
    ));
    let (on, off, radius) = near_occlusion_on_and_off(&ctx, &scene, 48);
    let cam = scene.default_camera().unwrap();
    let ground = (Vec3::new(-5.0, -0.01, -5.0), Vec3::new(5.0, 0.0, 5.0));
    let lum = lightlab_core::color::luminance;
    let (mut kept, mut expected, mut pixels) = (0.0f32, 0.0f32, 0);
    for y in 0..48 {
        for x in 0..48 {
            let ndc = glam::Vec2::new((x as f32 + 0.5) / 24.0 - 1.0, 1.0 - (y as f32 + 0.5) / 24.0);
            let (o, d) = (cam.position(), cam.ray_direction(ndc, 1.0));
            let p = o + d * ((2.5 - o.y) / d.y);
            // Leaf pixels away from its edge.
            if p.x.abs() > 0.9 || p.z.abs() > 0.9 {
                continue;
            }
            let b = lum(off.get(x, y));
            assert!(
                b > 1e-6,
                "({x}, {y}): no light through the back without near occlusion"
            );
            kept += lum(on.get(x, y)) / b;
            expected += far_share_around(p, -1.0, &[ground], radius);
            pixels += 1;
        }
    }
    assert!(pixels > 300, "{pixels}");
    let (kept, expected) = (kept / pixels as f32, expected / pixels as f32);
    eprintln!(
        "radius {radius:.2} m: the leaf's back keeps {kept:.3}, expected {expected:.3} ({pixels} pixels)"
    );
    assert!(expected > 0.8, "{expected}");
    assert!(
        (kept - expected).abs() < 0.08,
        "kept {kept}, expected {expected}"
    );
}

#[test]
fn the_volumes_light_comes_only_from_surfaces_beyond_the_lookup() {
    // A 10 m ground under a uniform sky with a slab 0.8 m above it and a 3 m wall beside it.
    // The volume (16³, cells of about 0.7 m) cannot resolve the slab's gap, and the ground
    // under the open sky gets the sky's light, no bounce: each ground point keeps the share of
    // its hemisphere (cosine-weighted) whose first surface lies beyond the lookup's reach
    // (2.5 cells, about 1.8 m), computed here by casting rays at the two boxes.
    let Some(ctx) = test_context() else { return };
    let mut scene = Scene::default();
    let m = scene.add_material(lightlab_scene::Material::diffuse("grey", Vec3::splat(0.5)));
    let ground = lightlab_scene::builtin::geom::quad_facing(
        "ground",
        [
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(-5.0, 0.0, 5.0),
        ],
        Vec3::Y,
        m,
    );
    scene.add_mesh(ground, glam::Mat4::IDENTITY);
    let slab = (Vec3::new(-2.5, 0.8, -1.5), Vec3::new(0.0, 1.0, 1.5));
    let wall = (Vec3::new(2.8, 0.0, -5.0), Vec3::new(3.0, 3.0, 5.0));
    for (name, (lo, hi)) in [("slab", slab), ("wall", wall)] {
        let mesh = lightlab_scene::builtin::geom::aabb_box(name, lo, hi, m);
        scene.add_mesh(mesh, glam::Mat4::IDENTITY);
    }
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "low",
        Vec3::new(0.0, 0.4, 4.8),
        Vec3::new(0.0, 0.1, 0.0),
        Vec3::Y,
        1.0,
    ));
    let (on, off, radius) = near_occlusion_on_and_off(&ctx, &scene, 64);
    assert!((1.4..2.0).contains(&radius), "{radius}");
    // Each pixel's ground point: its camera ray meets y = 0 before either box.
    let cam = scene.default_camera().unwrap();
    let ground_at = |x: u32, y: u32| -> Option<Vec3> {
        let ndc = glam::Vec2::new((x as f32 + 0.5) / 32.0 - 1.0, 1.0 - (y as f32 + 0.5) / 32.0);
        let (o, d) = (cam.position(), cam.ray_direction(ndc, 1.0));
        let t = -o.y / d.y;
        let blocked = [slab, wall]
            .iter()
            .any(|&b| hit_box(o, d, b).is_some_and(|h| h < t));
        (d.y < 0.0 && !blocked).then(|| o + d * t)
    };
    let lum = lightlab_core::color::luminance;
    // (kept, expected, pixels) over all ground pixels, and under the slab's middle.
    let (mut all, mut under) = ((0.0f32, 0.0f32, 0), (0.0f32, 0.0f32, 0));
    let mut worst = 0.0f32;
    for y in 0..64 {
        for x in 0..64 {
            let (a, b) = (lum(on.get(x, y)), lum(off.get(x, y)));
            assert!(a <= b * 1.001 + 1e-6, "({x}, {y}): {a} vs {b}");
            let Some(p) = ground_at(x, y) else { continue };
            if b <= 1e-6 || p.x.abs() > 4.5 || p.z.abs() > 4.5 {
                continue;
            }
            let (kept, expected) = (a / b, far_share(p, &[slab, wall], radius));
            worst = worst.max((kept - expected).abs());
            all = (all.0 + (kept - expected).abs(), all.1 + expected, all.2 + 1);
            if (-2.0..-0.5).contains(&p.x) && p.z.abs() < 1.0 {
                under = (under.0 + kept, under.1 + expected, under.2 + 1);
            }
        }
    }
    let n = all.2.max(1) as f32;
    eprintln!(
        "radius {radius:.2} m: {} ground pixels, mean |kept − expected| {:.4} (mean expected \
         {:.4}, worst {worst:.3}); under the slab kept {:.4}, expected {:.4} ({} pixels)",
        all.2,
        all.0 / n,
        all.1 / n,
        under.0 / under.2.max(1) as f32,
        under.1 / under.2.max(1) as f32,
        under.2
    );
    assert!(all.2 >= 500 && under.2 >= 10, "{all:?} {under:?}");
    assert!(all.0 / n < 0.05, "mean |kept − expected| {}", all.0 / n);
    // Under the slab the volume keeps only the wall's share, low along the ground (without
    // near occlusion about 0.9: all but the open sky). The directions are 64 cells of about
    // 0.2 sr each, and those by the slab's edge fall to the slab or to the wall by a few
    // centimetres: measured 0.148 against 0.096.
    let (kept, expected) = (under.0 / under.2 as f32, under.1 / under.2 as f32);
    assert!(
        expected < 0.15 && (kept - expected).abs() < 0.07,
        "{under:?}"
    );
}

/// A chrome ball over a sunlit ground under `lpv`: the sky maps hide the sky below the ball's
/// horizon, and the glossy lobe's hidden directions reflect the volume's light instead (the
/// ground's bounce), not black (sky_occlusion.wgsl `spec`). Measured over the ball's lower
/// half against the path tracer (four bounces).
#[test]
fn a_glossy_ball_reflects_the_lit_ground_its_sky_maps_hide() {
    use lightlab_scene::builtin::geom::{quad, sphere};
    let Some(ctx) = test_context() else { return };
    let mut scene = Scene::default();
    let ground = scene.add_material(lightlab_scene::Material::diffuse(
        "ground",
        Vec3::splat(0.5),
    ));
    let chrome = scene.add_material(lightlab_scene::Material {
        metallic: 1.0,
        roughness: 0.2,
        ..lightlab_scene::Material::diffuse("chrome", Vec3::splat(0.9))
    });
    let c = [(-4.0, 4.0), (4.0, 4.0), (4.0, -4.0), (-4.0, -4.0)].map(|(x, z)| Vec3::new(x, 0.0, z));
    scene.add_mesh(quad("ground", c, ground), glam::Mat4::IDENTITY);
    let centre = Vec3::new(0.0, 0.6, 0.0);
    scene.add_mesh(
        sphere("ball", 0.5, 48, 24, chrome),
        glam::Mat4::from_translation(centre),
    );
    scene
        .lights
        .push(point_sun(Vec3::new(-0.4, -1.0, -0.3), 3.0));
    scene.environment = Some(lightlab_scene::Environment {
        image: Image::from_fn(16, 8, |_, y| {
            if y < 4 {
                Vec3::new(0.25, 0.3, 0.4)
            } else {
                Vec3::splat(0.05)
            }
        }),
        intensity: 1.0,
    });
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "ball",
        Vec3::new(2.4, 0.9, 0.4),
        centre,
        Vec3::Y,
        0.45,
    ));
    let (w, h, ssaa) = (48u32, 48u32, 2u32);
    let rs = RasterSettings {
        width: w * ssaa,
        height: h * ssaa,
        shadows: ShadowMethod::Map,
        ambient: Ambient::Environment,
        ..Default::default()
    };
    let mut r = Renderer::with_lpv(&ctx, &scene, rs, &LpvSettings::default(), false).unwrap();
    r.render(&ctx);
    let gpu = r.read_hdr(&ctx).unwrap().downsample(ssaa);
    let accel = lightlab_trace::Accel::new(&scene);
    let traced = lightlab_trace::PathTracer::new(&scene, &accel)
        .render(
            &lightlab_trace::RenderSettings {
                width: w,
                height: h,
                spp: 256,
                max_depth: 4,
                min_depth: 0,
                seed: 3,
                camera: 0,
                lens: Default::default(),
            },
            &|_, _| true,
        )
        .unwrap();
    // The ball's lower half: pixels whose camera ray hits the ball below its centre.
    let cam = &scene.cameras[0];
    let origin = cam.position();
    let (mut g, mut t, mut count) = (0.0f64, 0.0f64, 0);
    for y in 0..h {
        for x in 0..w {
            let ndc = glam::Vec2::new(
                (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
            );
            let dir = cam.ray_direction(ndc, 1.0);
            let Some(hit) = accel.intersect(origin, dir, f32::INFINITY) else {
                continue;
            };
            let p = origin + dir * hit.t;
            if (p - centre).length() < 0.52 && p.y < centre.y - 0.1 {
                let i = (y * w + x) as usize;
                g += gpu.data[i].element_sum() as f64;
                t += traced.data[i].element_sum() as f64;
                count += 1;
            }
        }
    }
    let ratio = g / t;
    eprintln!("chrome ball's lower half: {count} pixels, GPU / traced {ratio:.3}");
    assert!(count > 100, "{count} pixels");
    assert!((ratio - 1.0).abs() < 0.35, "GPU / traced {ratio}");
}

/// A white sun of no angular size travelling along `direction` with `irradiance` on a surface
/// facing it.
fn point_sun(direction: Vec3, irradiance: f32) -> lightlab_scene::Light {
    lightlab_scene::Light {
        name: "sun".into(),
        kind: lightlab_scene::LightKind::Directional {
            angular_diameter: 0.0,
        },
        color: Vec3::ONE,
        intensity: irradiance,
        position: Vec3::ZERO,
        direction: direction.normalize(),
        range: None,
    }
}

/// A grey (albedo ½) 10 m ground under a sun straight down (irradiance 2, so radiosity 1)
/// and a dim sky, seen from `eye` on +x towards (0, 0.6, 0); and its material.
fn sunlit_ground(eye: Vec3) -> (Scene, usize) {
    let mut scene = Scene::default();
    let m = scene.add_material(lightlab_scene::Material::diffuse("grey", Vec3::splat(0.5)));
    let c = [(-5.0, 5.0), (5.0, 5.0), (5.0, -5.0), (-5.0, -5.0)].map(|(x, z)| Vec3::new(x, 0.0, z));
    scene.add_mesh(
        lightlab_scene::builtin::geom::quad("ground", c, m),
        glam::Mat4::IDENTITY,
    );
    scene.lights.push(point_sun(Vec3::NEG_Y, 2.0));
    scene.environment = Some(lightlab_scene::Environment {
        image: Image::from_fn(16, 8, |_, _| Vec3::splat(0.02)),
        intensity: 1.0,
    });
    scene.cameras.push(lightlab_scene::Camera::look_at(
        "side",
        eye,
        Vec3::new(0.0, 0.6, 0.0),
        Vec3::Y,
        1.0,
    ));
    (scene, m)
}

/// `lpv`'s indirect light alone on `scene` at size², 2 × 2 supersampled, with the near field's
/// `near_field` texels; and the volume.
fn sunlit_indirect(
    ctx: &GpuContext,
    scene: &Scene,
    size: u32,
    near_field: u32,
) -> (Image, Renderer) {
    let s = LpvSettings {
        near_field,
        ..Default::default()
    };
    let rs = RasterSettings {
        width: size * 2,
        height: size * 2,
        shadows: ShadowMethod::Map,
        ambient: Ambient::Environment,
        ..Default::default()
    };
    let mut r = Renderer::with_lpv(ctx, scene, rs, &s, true).unwrap();
    r.render(ctx);
    (r.read_hdr(ctx).unwrap().downsample(2), r)
}

/// The pixels (x, y) of a size² view of `scene`'s camera that see the plane x = `plane` from
/// +x at heights `heights` within `half` of z = 0, and the point seen.
fn plane_pixels(
    scene: &Scene,
    size: u32,
    plane: f32,
    heights: std::ops::Range<f32>,
    half: f32,
) -> Vec<(u32, u32, Vec3)> {
    let cam = scene.default_camera().unwrap();
    let mut out = vec![];
    for y in 0..size {
        for x in 0..size {
            let ndc = glam::Vec2::new(
                (x as f32 + 0.5) / size as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / size as f32 * 2.0,
            );
            let (o, d) = (cam.position(), cam.ray_direction(ndc, 1.0));
            let p = o + d * ((plane - o.x) / d.x);
            if d.x < 0.0 && heights.contains(&p.y) && p.z.abs() <= half {
                out.push((x, y, p));
            }
        }
    }
    out
}

#[test]
fn a_leaf_gets_the_suns_bounce_once_from_the_near_field_in_place_of_the_volume() {
    // A thin translucent sheet (diffuse transmission 0.45) standing on the sunlit ground: the
    // sun's share of the volume's light is 0.97. Both its sides see the lit ground, so its
    // indirect light is the single bounce from the ground within the reach (the near field,
    // in place of that share of the volume's light) and 0.03 of the volume's. The volume's
    // light and the near field added together gave 1.38 of the bounce; the volume's alone
    // (session 39) 0.50. Measured 0.89.
    let Some(ctx) = test_context() else { return };
    let (mut scene, _) = sunlit_ground(Vec3::new(2.5, 0.7, 0.0));
    let leaf = scene.add_material(lightlab_scene::Material {
        transmission: 0.45,
        double_sided: true,
        ..lightlab_scene::Material::diffuse("leaf", Vec3::splat(0.5))
    });
    let sheet =
        [(0.0, 1.5), (1.2, 1.5), (1.2, -1.5), (0.0, -1.5)].map(|(y, z)| Vec3::new(0.0, y, z));
    scene.add_mesh(
        lightlab_scene::builtin::geom::quad("sheet", sheet, leaf),
        glam::Mat4::IDENTITY,
    );
    let size = 64u32;
    let (img, r) = sunlit_indirect(&ctx, &scene, size, lightlab_gpu::lpv::DEFAULT_NEAR_FIELD);
    let lpv = r.lpv().unwrap();
    let (radius, share) = (lpv.near_occlusion_radius(), lpv.near_field_share());
    assert!(radius > 0.5 && share > 0.9, "reach {radius}, share {share}");
    let pixels = plane_pixels(&scene, size, 0.0, 0.15..1.0, 1.2);
    let gpu: f64 = pixels
        .iter()
        .map(|&(x, y, _)| lightlab_core::color::luminance(img.get(x, y)) as f64)
        .sum();
    let cpu = bounce_radiance_sum(&pixels, 0.0, radius);
    let (ratio, count) = (gpu / cpu, pixels.len());
    eprintln!(
        "reach {radius:.2} m, share {share:.3}: {count} sheet pixels, indirect light {:.4} \
         against the near single bounce {:.4} ({ratio:.3})",
        gpu / count as f64,
        cpu / count as f64
    );
    assert!(count > 300, "{count}");
    assert!(
        (0.7..1.25).contains(&ratio),
        "indirect / single bounce {ratio}"
    );
}

/// The irradiance at p, on a surface facing +x, from the ground (y = 0) at x > x0 within
/// `radius` of p, a Lambertian emitter of radiosity 1: ∫ 1/π · cos_ground · cos / d² dA on a
/// 2 cm grid.
fn ground_bounce(p: Vec3, x0: f32, radius: f32) -> f32 {
    let (step, mut e) = (0.02f32, 0.0f32);
    let n = (radius / step).ceil() as i32;
    for i in 0..n {
        for k in -n..=n {
            let g = Vec3::new(x0 + (i as f32 + 0.5) * step, 0.0, p.z + k as f32 * step);
            let d = g - p;
            let d2 = d.length_squared();
            if d2 > radius * radius {
                continue;
            }
            let (cos_g, cos_w) = (p.y / d2.sqrt(), d.x / d2.sqrt());
            e += 1.0 / std::f32::consts::PI * cos_g * cos_w / d2 * step * step;
        }
    }
    e
}

/// The radiance of a grey (albedo ½) surface facing +x at each pixel's point lit by
/// [`ground_bounce`], summed over the pixels.
fn bounce_radiance_sum(pixels: &[(u32, u32, Vec3)], x0: f32, radius: f32) -> f64 {
    pixels
        .iter()
        .map(|&(_, _, p)| (0.5 / std::f32::consts::PI * ground_bounce(p, x0, radius)) as f64)
        .sum()
}

#[test]
fn the_near_field_lights_a_wall_from_the_sunlit_ground_beside_it() {
    // A 3 m wall on the sunlit ground. The wall's side gets no sun; the ground by it lights
    // it. Near occlusion takes the ground within the lookup's reach out of the volume's light,
    // and the near field gathers it back from the sun's RSM: the difference it makes on the
    // wall's side is the single bounce from the lit ground within the reach.
    let Some(ctx) = test_context() else { return };
    let (mut scene, m) = sunlit_ground(Vec3::new(2.5, 0.8, 0.0));
    let wall = (Vec3::new(-0.1, 0.0, -3.0), Vec3::new(0.1, 3.0, 3.0));
    scene.add_mesh(
        lightlab_scene::builtin::geom::aabb_box("wall", wall.0, wall.1, m),
        glam::Mat4::IDENTITY,
    );
    let size = 64u32;
    let (on, r) = sunlit_indirect(&ctx, &scene, size, lightlab_gpu::lpv::DEFAULT_NEAR_FIELD);
    let radius = r.lpv().unwrap().near_occlusion_radius();
    let (off, _) = sunlit_indirect(&ctx, &scene, size, 0);
    assert!(radius > 0.5, "{radius}");
    let lum = lightlab_core::color::luminance;
    let pixels = plane_pixels(&scene, size, 0.1, 0.15..1.5, 1.5);
    // Indirect radiance = albedo/π · E: what the near field adds, against the single bounce
    // from the lit ground (x > 0.1) within the reach onto the wall's side.
    let gpu: f64 = pixels
        .iter()
        .map(|&(x, y, _)| (lum(on.get(x, y)) - lum(off.get(x, y))) as f64)
        .sum();
    let cpu = bounce_radiance_sum(&pixels, 0.1, radius);
    let (ratio, count) = (gpu / cpu, pixels.len());
    eprintln!(
        "reach {radius:.2} m: {count} wall pixels, near field {:.4} against the single bounce {:.4} \
         ({ratio:.3})",
        gpu / count as f64,
        cpu / count as f64
    );
    assert!(count > 300, "{count}");
    // Measured 0.85 (0.90 unoccluded: the 32 texels of the disc miss some of the ground by the
    // wall; the rest is the geometry volume's nodes between); 0.53 when the nodes nearest the
    // ends counted.
    assert!(
        (0.7..1.1).contains(&ratio),
        "near field / single bounce {ratio}"
    );
}
