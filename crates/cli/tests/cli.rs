//! The command-line contract, exercised on the real binary.

mod common;

use common::{lightlab, stderr, stdout};
use std::path::Path;
use std::process::Command;

#[test]
fn scenes_lists_one_name_per_line() {
    let o = lightlab(&["scenes"]);
    assert!(o.status.success());
    let names: Vec<String> = stdout(&o).lines().map(String::from).collect();
    assert_eq!(
        names,
        [
            "cornell",
            "room",
            "shadows",
            "bush",
            "prt",
            "spheres",
            "atrium",
            "prt-dynamic",
            "luminaire",
            "mirror",
            "glass",
            "brdfs"
        ]
    );
}

#[test]
fn export_then_render_the_glb_then_compare() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("cornell.glb");
    let o = lightlab(&["export", "--scene", "cornell", "-o", glb.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a = dir.path().join("a.exr");
    let b = dir.path().join("b.exr");
    for (scene, out) in [(glb.to_str().unwrap(), &a), ("cornell", &b)] {
        let o = lightlab(&[
            "render",
            "--scene",
            scene,
            "--technique",
            "reference",
            "--width",
            "24",
            "--spp",
            "4",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        // The rate with and without the set-up (BVH, light tables) before tracing.
        let v: serde_json::Value =
            serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
        let (all, trace) = (&v["msamples_per_s"], &v["trace_msamples_per_s"]);
        assert!(v["setup_seconds"].as_f64().unwrap() >= 0.0, "{v}");
        assert!(trace.as_f64().unwrap() >= all.as_f64().unwrap() && all.as_f64().unwrap() > 0.0);
    }
    // The exported scene renders exactly like the built-in one (same seed, same geometry).
    let o = lightlab(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let last = stdout(&o).lines().last().unwrap().to_string();
    let v: serde_json::Value = serde_json::from_str(&last).unwrap();
    assert!(v["rmse"].as_f64().unwrap() < 1e-4, "{last}");
    assert!(v["relmse"].as_f64().is_some() && v["flip"].as_f64().is_some());
    // An environment map from a file lights the scene: a uniform white sky seen directly.
    let env = dir.path().join("sky.exr");
    lightlab_core::image::Image::from_fn(8, 4, |_, _| glam::Vec3::splat(0.25))
        .write(&env, Default::default())
        .unwrap();
    let lit = dir.path().join("lit.exr");
    let o = lightlab(&[
        "render",
        "--scene",
        "spheres",
        "--env",
        env.to_str().unwrap(),
        "--env-intensity",
        "2",
        "--width",
        "8",
        "--spp",
        "1",
        "-o",
        lit.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = lightlab_core::image::Image::read(&lit).unwrap();
    assert!(
        (img.get(0, 0) - glam::Vec3::splat(0.5)).abs().max_element() < 1e-6,
        "top-left pixel sees the sky: {}",
        img.get(0, 0)
    );
    // PNG output too.
    let png = dir.path().join("d.png");
    let o = lightlab(&[
        "render",
        "--scene",
        "spheres",
        "--technique",
        "direct",
        "--width",
        "16",
        "--height",
        "12",
        "--spp",
        "2",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(png.exists());
}

fn assert_fails_cleanly(args: &[&str], out: &Path, needle: &str) {
    let o = lightlab(args);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains(needle), "{args:?}: '{e}' lacks '{needle}'");
    assert!(!e.contains("panicked"), "{e}");
    assert!(!out.exists(), "{args:?} left {}", out.display());
}

#[test]
fn bad_render_requests_fail_with_clear_errors_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    let o = out.to_str().unwrap();
    assert_fails_cleanly(
        &["render", "--scene", "cornell", "--width", "0", "-o", o],
        &out,
        "at least 1×1",
    );
    assert_fails_cleanly(
        &["render", "--scene", "cornell", "--spp", "0", "-o", o],
        &out,
        "samples per pixel",
    );
    assert_fails_cleanly(
        &[
            "render", "--scene", "cornell", "--width", "100000", "--height", "100000", "-o", o,
        ],
        &out,
        "exceeds the limit",
    );
    assert_fails_cleanly(
        &["render", "--scene", "nowhere", "-o", o],
        &out,
        "unknown scene 'nowhere'",
    );
    assert_fails_cleanly(
        &[
            "render",
            "--scene",
            "cornell",
            "--technique",
            "magic",
            "-o",
            o,
        ],
        &out,
        "unknown technique",
    );
    assert_fails_cleanly(
        &["render", "--scene", "cornell", "--camera", "3", "-o", o],
        &out,
        "no camera 3",
    );
    // More sky directions than a depth texture array holds layers (once a wgpu panic).
    assert_fails_cleanly(
        &[
            "render",
            "--scene",
            "room",
            "--technique",
            "phong-shadow-maps",
            "--width",
            "16",
            "--height",
            "16",
            "--sky-occlusion",
            "512",
            "-o",
            o,
        ],
        &out,
        "sky occlusion directions 512 must be at most 256",
    );
    for bad in [
        "--exposure=NaN",
        "--exposure=inf",
        "--exposure=-1",
        "--exposure=0",
    ] {
        assert_fails_cleanly(
            &["render", "--scene", "cornell", bad, "-o", o],
            &out,
            "--exposure must be a positive number",
        );
    }
    assert_fails_cleanly(
        &[
            "render",
            "--scene",
            "brdfs",
            "--technique",
            "phong-shadow-maps",
            "--path",
            "deferred",
            "--brdf-eval",
            "tables",
            "-o",
            o,
        ],
        &out,
        "--brdf-eval tables needs --path forward",
    );
    assert_fails_cleanly(
        &[
            "render",
            "--scene",
            "spheres",
            "--technique",
            "phong",
            "--path",
            "deferred",
            "--normal-filter",
            "lit",
            "-o",
            o,
        ],
        &out,
        "--normal-filter lit needs --path forward",
    );
    let bmp = dir.path().join("x.bmp");
    assert_fails_cleanly(
        &["render", "--scene", "cornell", "-o", bmp.to_str().unwrap()],
        &bmp,
        ".exr or .png",
    );
    let missing = dir.path().join("missing.glb");
    assert_fails_cleanly(
        &["render", "--scene", missing.to_str().unwrap(), "-o", o],
        &out,
        "missing.glb",
    );
    let broken = dir.path().join("broken.gltf");
    std::fs::write(&broken, "{ not json").unwrap();
    assert_fails_cleanly(
        &["render", "--scene", broken.to_str().unwrap(), "-o", o],
        &out,
        "broken.gltf",
    );
}

#[test]
fn compare_rejects_different_sizes_and_unreadable_files() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.exr");
    let b = dir.path().join("b.exr");
    lightlab_core::image::Image::new(4, 4)
        .write(&a, Default::default())
        .unwrap();
    lightlab_core::image::Image::new(4, 5)
        .write(&b, Default::default())
        .unwrap();
    let o = lightlab(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("differ in size"), "{}", stderr(&o));
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"junk").unwrap();
    let o = lightlab(&["compare", a.to_str().unwrap(), junk.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("junk.png"), "{}", stderr(&o));
}

/// A refraction field baked once serves renders in another environment, and is refused for a
/// scene whose glass it was not baked for.
#[test]
fn refraction_field_bakes_once_and_renders_in_any_environment() {
    let dir = tempfile::tempdir().unwrap();
    let field = dir.path().join("field");
    let f = field.to_str().unwrap();
    let o = lightlab(&[
        "bake",
        "--scene",
        "glass",
        "--method",
        "refraction-field",
        "--field-uv",
        "8",
        "--field-st",
        "4",
        "--out",
        f,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(field.join("field.json").exists() && field.join("slab-5-throughput.exr").exists());
    // Another environment for the same field: a small render of cornell as the sky.
    let env = dir.path().join("cornell.exr");
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "reference",
        "--width",
        "16",
        "--height",
        "8",
        "--spp",
        "1",
        "-o",
        env.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    if lightlab_gpu::test_context().is_some() {
        let out = dir.path().join("glass.png");
        let o = lightlab(&[
            "render",
            "--scene",
            "glass",
            "--technique",
            "phong",
            "--refraction-field",
            f,
            "--env",
            env.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "24",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(!stderr(&o).contains("baking"), "no re-bake: {}", stderr(&o));
        assert!(out.exists());
    }
    // The field belongs to the torus: `spheres`'s glass ball has another box.
    let o = lightlab(&[
        "render",
        "--scene",
        "spheres",
        "--technique",
        "phong",
        "--refraction-field",
        f,
        "-o",
        dir.path().join("x.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("bake it again"), "{}", stderr(&o));
    // Only the Phong techniques read it.
    let o = lightlab(&[
        "render",
        "--scene",
        "glass",
        "--technique",
        "lpv",
        "--refraction-field",
        f,
        "-o",
        dir.path().join("y.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--refraction-field"), "{}", stderr(&o));
    // A folder that is not a field.
    let o = lightlab(&[
        "render",
        "--scene",
        "glass",
        "--technique",
        "phong",
        "--refraction-field",
        dir.path().to_str().unwrap(),
        "-o",
        dir.path().join("z.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("field.json"), "{}", stderr(&o));
}

/// Two light slabs baked by `bake --method light-field`, one per luminaire of `luminaire`
/// (the projector's (s,t) plane at its focus), then passed together to `direct` (the slabs as
/// emitters) and to `canned-light`; a folder that holds no slab is refused, writing nothing.
#[test]
fn light_slabs_bake_per_luminaire_and_light_the_scene_together() {
    let dir = tempfile::tempdir().unwrap();
    let small = [
        "--slab-uv",
        "2x2",
        "--slab-st",
        "8x8",
        "--slab-samples",
        "1",
    ];
    let mut slabs = vec![];
    for lamp in ["reflector", "projector"] {
        let out = dir.path().join(lamp);
        let mut a = vec!["bake", "--scene", "luminaire", "--method", "light-field"];
        a.extend([
            "--luminaire",
            lamp,
            "--json",
            "--out",
            out.to_str().unwrap(),
        ]);
        a.extend(small);
        let o = lightlab(&a);
        assert!(o.status.success(), "{lamp}: {}", stderr(&o));
        let last = stdout(&o).lines().last().unwrap().to_string();
        let v: serde_json::Value = serde_json::from_str(&last).unwrap();
        assert_eq!(v["luminaire"], lamp);
        // The projector is focused on its screen; the reflector's slab ends at infinity.
        assert_eq!(v["far"].is_number(), lamp == "projector", "{last}");
        slabs.push(out.to_str().unwrap().to_string());
    }
    for t in ["direct", "canned-light"] {
        let img = dir.path().join(format!("{t}.exr"));
        let mut a = vec!["render", "--scene", "luminaire", "--technique", t];
        a.extend(["--width", "32", "--height", "24", "--spp", "2"]);
        for s in &slabs {
            a.extend(["--light-field", s.as_str()]);
        }
        a.extend(["-o", img.to_str().unwrap()]);
        let o = lightlab(&a);
        assert!(o.status.success(), "{t}: {}", stderr(&o));
        assert!(img.exists());
    }
    let out = dir.path().join("none.exr");
    assert_fails_cleanly(
        &[
            "render",
            "--scene",
            "luminaire",
            "--technique",
            "canned-light",
            "--light-field",
            dir.path().to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        &out,
        "reading the light slab",
    );
}

#[test]
fn bake_methods_that_do_not_apply_say_what_to_do() {
    // A light slab needs a luminaire: the error says how to mark one.
    let o = lightlab(&["bake", "--scene", "cornell", "--method", "light-field"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("extras.lightlab.luminaire"),
        "{}",
        stderr(&o)
    );
    // A refraction field needs solid glass: the error says what makes glass solid.
    let o = lightlab(&["bake", "--scene", "cornell", "--method", "refraction-field"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("KHR_materials_volume"),
        "{}",
        stderr(&o)
    );
    // Hierarchical PRT is a technique, not a bake: the error says what to do instead.
    let o = lightlab(&["bake", "--scene", "cornell", "--method", "prt-hierarchical"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--method sh"), "{}", stderr(&o));
    // A mistyped option or a malformed value is an ordinary error (1), not "not implemented".
    for args in [
        vec!["render", "--scene", "cornell", "--no-such-option"],
        vec![
            "bake",
            "--scene",
            "prt",
            "--method",
            "sh",
            "--detail-cage",
            "-1",
        ],
    ] {
        let o = lightlab(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
    }
    assert_eq!(lightlab(&["--help"]).status.code(), Some(0));
}

#[test]
fn bench_bake_reports_both_bakers() {
    let o = lightlab(&[
        "bench",
        "bake",
        "--scene",
        "cornell",
        "--texels-per-metre",
        "8",
        "--gather-samples",
        "8",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
    for baker in ["radiosity", "path"] {
        let b = &v["bakers"][baker];
        let texels = b["valid_texels"].as_u64().unwrap();
        assert!(texels > 50, "{baker}: {b}");
        assert!(b["page_texels"].as_u64().unwrap() >= texels);
        // Every valid texel casts at least its validity probe (32 rays) and its light rays.
        assert!(b["rays"].as_u64().unwrap() > 32 * texels, "{baker}: {b}");
        assert!(b["seconds"].as_f64().unwrap() > 0.0 && b["mrays_per_s"].as_f64().unwrap() > 0.0);
        if cfg!(target_os = "linux") {
            assert!(b["peak_rss_mib"].as_f64().unwrap() > 1.0, "{b}");
        }
    }
    assert_eq!(v["bakers"]["path"]["samples_per_texel"], 8);
    assert!(v["bakers"]["radiosity"]["shots"].as_u64().unwrap() > 0);
}

#[test]
fn bench_trace_reports_json() {
    let o = lightlab(&[
        "bench", "trace", "--scene", "cornell", "--rays", "20000", "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
    for k in [
        "coherent_mrays_1t",
        "coherent_mrays_mt",
        "incoherent_mrays_1t",
        "incoherent_mrays_mt",
    ] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k}");
    }
    // Another BVH setting traces the same scene; a malformed one is refused with the keys.
    let with_bvh = |bvh| {
        lightlab(&[
            "bench", "trace", "--scene", "cornell", "--rays", "2000", "--bvh", bvh,
        ])
    };
    let o = with_bvh("fast:leaf=4");
    assert!(o.status.success(), "{}", stderr(&o));
    let o = with_bvh("slow:leaves=4");
    assert!(!o.status.success());
    assert!(stderr(&o).contains("expected key=value"), "{}", stderr(&o));
}

// The demo on every built-in scene, as two runs over half the scenes each: the harness runs
// them side by side (a demo run is mostly one thread: lavapipe compiles shaders on one).
#[test]
fn demo_preview_writes_a_report_for_the_first_scenes() {
    demo_preview(&["cornell", "shadows", "prt", "spheres", "glass", "brdfs"]);
}

#[test]
fn demo_preview_writes_a_report_for_the_other_scenes() {
    demo_preview(&[
        "room",
        "bush",
        "atrium",
        "prt-dynamic",
        "luminaire",
        "mirror",
    ]);
}

#[test]
fn the_demo_tests_cover_every_built_in_scene() {
    let o = lightlab(&["scenes"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let covered = [
        "cornell",
        "shadows",
        "prt",
        "spheres",
        "glass",
        "brdfs",
        "room",
        "bush",
        "atrium",
        "prt-dynamic",
        "luminaire",
        "mirror",
    ];
    for line in stdout(&o).lines() {
        let name = line.split_whitespace().next().unwrap_or_default();
        assert!(covered.contains(&name), "no demo test runs '{name}'");
    }
}

/// `demo --quality preview --scenes …`: a report with every scene's reference and, with a GPU,
/// its techniques' images and frame times.
fn demo_preview(scenes: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let o = lightlab(&[
        "demo",
        "--out",
        dir.path().to_str().unwrap(),
        "--quality",
        "preview",
        "--scenes",
        &scenes.join(","),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("report.html"));
    let html = std::fs::read_to_string(dir.path().join("report.html")).unwrap();
    for s in scenes {
        assert!(html.contains(&format!("{s}-reference.png")), "{s}");
        assert!(dir.path().join(format!("{s}-reference.exr")).exists());
    }
    // `direct` is measured against the reference: three figures per row.
    assert!(html.contains("relMSE") && html.contains("(ground truth)"));
    if lightlab_gpu::test_context().is_some() {
        for s in scenes {
            assert!(html.contains(&format!("{s}-phong.png")), "{s}-phong");
        }
        if scenes.contains(&"shadows") {
            for t in ["phong-shadow-volumes", "phong-shadow-maps"] {
                assert!(html.contains(&format!("shadows-{t}.png")), "{t}");
            }
        }
        for s in ["bush", "cornell", "room", "atrium"] {
            if scenes.contains(&s) {
                for t in ["lpv", "lpv-faithful"] {
                    assert!(html.contains(&format!("{s}-{t}.png")), "{s}-{t}");
                }
            }
        }
        assert!(html.contains("frame ms"));
    }
}

#[test]
fn sh_project_and_irradiance() {
    let dir = tempfile::tempdir().unwrap();
    let env = dir.path().join("sky.exr");
    // A constant lat-long sky of radiance 0.5: L00 = 2√π·0.5, irradiance π·0.5 everywhere.
    lightlab_core::image::Image::from_fn(64, 32, |_, _| glam::Vec3::splat(0.5))
        .write(&env, Default::default())
        .unwrap();
    let o = lightlab(&[
        "sh",
        "project",
        "--env",
        env.to_str().unwrap(),
        "--bands",
        "3",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
    let l00 = v["coefficients"][0][0].as_f64().unwrap();
    assert!((l00 - std::f64::consts::PI.sqrt()).abs() < 1e-6, "{l00}");
    assert_eq!(v["coefficients"].as_array().unwrap().len(), 9);
    let out = dir.path().join("irr.exr");
    let o = lightlab(&[
        "sh",
        "irradiance",
        "--env",
        env.to_str().unwrap(),
        "--width",
        "16",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let irr = lightlab_core::image::Image::read(&out).unwrap();
    assert_eq!((irr.width, irr.height), (16, 8));
    // Texel-centre sampling of a 64×32 map leaves L20 ≈ 1e-3·L00 (O(texel²)): 1e-3 relative.
    for p in &irr.data {
        assert!(
            (p.x as f64 / (std::f64::consts::PI * 0.5) - 1.0).abs() < 1e-3,
            "{p}"
        );
    }
    // Bad requests.
    let bad = lightlab(&[
        "sh",
        "project",
        "--env",
        env.to_str().unwrap(),
        "--bands",
        "0",
    ]);
    assert_eq!(bad.status.code(), Some(1));
    assert!(stderr(&bad).contains("--bands"));
    let odd = dir.path().join("odd.exr");
    lightlab_core::image::Image::new(30, 7)
        .write(&odd, Default::default())
        .unwrap();
    let bad = lightlab(&["sh", "project", "--env", odd.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(1));
    assert!(stderr(&bad).contains("--format"), "{}", stderr(&bad));
    // Maps that do not fit the layout asked for are refused, not indexed out of bounds
    // (a 30×7 cube strip panicked), and a 1×1 image is not taken as an angular map.
    for (args, needle) in [
        (vec!["--format", "cube-strip"], "not a cube strip"),
        (vec!["--format", "angular"], "not an angular map"),
    ] {
        let mut a = vec!["sh", "project", "--env", odd.to_str().unwrap()];
        a.extend(args);
        let bad = lightlab(&a);
        assert_eq!(bad.status.code(), Some(1), "{a:?}");
        assert!(stderr(&bad).contains(needle), "{}", stderr(&bad));
    }
    let tiny = dir.path().join("tiny.exr");
    lightlab_core::image::Image::new(1, 1)
        .write(&tiny, Default::default())
        .unwrap();
    let bad = lightlab(&["sh", "project", "--env", tiny.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(1));
    assert!(stderr(&bad).contains("--format"), "{}", stderr(&bad));
}

/// A headless GPU run without a desktop session prints nothing alarming: Mesa's device-select
/// layer used to print "error: XDG_RUNTIME_DIR is invalid or not set" twice on success.
#[test]
fn headless_gpu_runs_print_no_spurious_errors() {
    if lightlab_gpu::test_context().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let o = Command::new(env!("CARGO_BIN_EXE_lightlab"))
        .args([
            "render",
            "--scene",
            "cornell",
            "--technique",
            "phong",
            "--width",
            "16",
        ])
        .args(["-o", out.to_str().unwrap()])
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("error"), "{}", stderr(&o));
}

/// The GPU techniques through the command line (lavapipe in CI; skipped locally without an
/// adapter, like every GPU test).
#[test]
fn gpu_techniques_render_and_bench() {
    if lightlab_gpu::test_context().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (t, variant) in [
        ("phong", None),
        ("phong-shadow-volumes", Some("zpass")),
        ("phong-shadow-maps", Some("linear")),
        ("phong-shadow-maps", Some("planar")),
    ] {
        let out = dir.path().join(format!("{t}.png"));
        let mut args = vec![
            "render",
            "--scene",
            "shadows",
            "--technique",
            t,
            "--width",
            "64",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(v) = variant {
            args.extend(["--shadow-variant", v, "--path", "deferred"]);
        }
        let o = lightlab(&args);
        assert!(o.status.success(), "{t}: {}", stderr(&o));
        assert!(out.exists());
        let v: serde_json::Value =
            serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
        assert!(v["frame_wall_ms"].as_f64().unwrap() > 0.0);
    }
    let o = lightlab(&[
        "bench",
        "frame",
        "--scene",
        "shadows",
        "--technique",
        "phong-shadow-volumes",
        "--width",
        "64",
        "--height",
        "48",
        "--frames",
        "2",
        "--lights",
        "8",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
    assert_eq!(v["lights"].as_u64(), Some(8));
    assert!(v["wall_ms"].as_f64().unwrap() > 0.0);
    // A variant of another technique, and bad option values, are clear errors.
    let out = dir.path().join("bad.png");
    for (args, needle) in [
        (
            vec!["--technique", "phong", "--shadow-variant", "zfail"],
            "does not apply",
        ),
        (
            vec!["--technique", "phong", "--attenuation", "cubic"],
            "unknown attenuation 'cubic' (known: inverse-square",
        ),
        (
            vec!["--technique", "phong", "--brdf", "velvet"],
            "unknown BRDF model 'velvet'",
        ),
        (
            vec!["--technique", "phong", "--ambient", "1,2"],
            "--ambient",
        ),
    ] {
        let mut a = vec![
            "render",
            "--scene",
            "shadows",
            "--width",
            "32",
            "-o",
            out.to_str().unwrap(),
        ];
        a.extend(args);
        let o = lightlab(&a);
        assert_eq!(o.status.code(), Some(1), "{a:?}");
        assert!(stderr(&o).contains(needle), "{}", stderr(&o));
        assert!(!out.exists());
    }
}

#[test]
fn bake_then_render_the_lightmap_techniques() {
    let dir = tempfile::tempdir().unwrap();
    let baked = dir.path().join("baked");
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "radiosity",
        "--out",
        baked.to_str().unwrap(),
        "--texels-per-metre",
        "16",
        "--png",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["manifest.json", "lightmap-0.exr", "lightmap-0.png"] {
        assert!(baked.join(f).exists(), "{f}");
    }
    let v: serde_json::Value = serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
    assert!(v["valid_texels"].as_u64().unwrap() > 100);
    for (t, filter) in [("lightmap", "bilinear"), ("lightmap+phong", "bicubic")] {
        let out = dir.path().join(format!("{t}.exr"));
        let o = lightlab(&[
            "render",
            "--scene",
            "cornell",
            "--technique",
            t,
            "--baked",
            baked.to_str().unwrap(),
            "--lightmap-filter",
            filter,
            "--width",
            "48",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{t}: {}", stderr(&o));
        assert!(out.exists());
    }
    // Light-maps of another scene are refused with a clear message.
    let o = lightlab(&[
        "render",
        "--scene",
        "room",
        "--technique",
        "lightmap",
        "--baked",
        baked.to_str().unwrap(),
        "-o",
        dir.path().join("x.exr").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("different scene"), "{}", stderr(&o));
    // Bad options are errors naming the option.
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "path",
        "--light-mode",
        "lamp=baked",
        "--out",
        baked.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no light 'lamp'"), "{}", stderr(&o));
    // Directional bake with the glTF export; the GPU reads the directional pages back.
    let dirbake = dir.path().join("directional");
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "path",
        "--gather-samples",
        "8",
        "--directional",
        "--gltf",
        "--out",
        dirbake.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["directional-0.exr", "scene.glb", "lightmap-0.png"] {
        assert!(dirbake.join(f).exists(), "{f}");
    }
    let out = dir.path().join("directional.exr");
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "lightmap",
        "--baked",
        dirbake.to_str().unwrap(),
        "--width",
        "48",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The exported glTF loads as a scene of its own.
    let o = lightlab(&[
        "render",
        "--scene",
        dirbake.join("scene.glb").to_str().unwrap(),
        "--technique",
        "direct",
        "--width",
        "16",
        "--spp",
        "1",
        "-o",
        dir.path().join("g.exr").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Radiosity cannot bake directional light-maps: a clear error.
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "radiosity",
        "--directional",
        "--out",
        dir.path().join("r").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("path method"), "{}", stderr(&o));
}

/// The GPU techniques of the registry, as `render` lists them (all but the path tracer's).
fn gpu_techniques() -> Vec<String> {
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "?",
        "-o",
        "x.png",
    ]);
    let e = stderr(&o);
    let known = e.split("(known: ").nth(1).expect("the known techniques");
    known
        .split(')')
        .next()
        .unwrap()
        .split(", ")
        .filter(|t| !["reference", "direct"].contains(t))
        .map(String::from)
        .collect()
}

/// The viewer opens a real window (Xvfb in CI), presents frames and shows the same image as
/// `lightlab render` writes (the screenshot is the displayed 3D view without the panel), for
/// every GPU technique of the registry: baked techniques read a small bake made once.
#[test]
fn viewer_window_shows_what_render_writes() {
    let display =
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some();
    if !display {
        assert_ne!(
            std::env::var("CI").as_deref(),
            Ok("true"),
            "CI=true but no DISPLAY: .ci/run starts Xvfb for the viewer test"
        );
        eprintln!("skipping the viewer test: no DISPLAY or WAYLAND_DISPLAY");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let lm = dir.path().join("lm");
    let sh = dir.path().join("sh");
    let path = |p: &std::path::Path| p.to_str().unwrap().to_string();
    for (scene, method, extra) in [
        (
            "cornell",
            "path",
            vec!["--texels-per-metre", "8", "--gather-samples", "4"],
        ),
        (
            "shadows",
            "sh",
            vec![
                "--texels-per-metre",
                "4",
                "--transfer-samples",
                "8",
                "--bands",
                "3",
            ],
        ),
    ] {
        let out = if method == "path" {
            path(&lm)
        } else {
            path(&sh)
        };
        let mut a = vec!["bake", "--scene", scene, "--method", method, "--out", &out];
        a.extend(extra);
        a.push("--normal-mapped");
        if method == "path" {
            a.pop();
        }
        let o = lightlab(&a);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let shot = dir.path().join("view.png");
    let rendered = dir.path().join("render.png");
    let techniques = gpu_techniques();
    assert!(techniques.len() >= 12, "{techniques:?}");
    for t in &techniques {
        let (scene, mut options) = match t.as_str() {
            t if t.starts_with("lightmap") => ("cornell", vec!["--baked".to_string(), path(&lm)]),
            "prt-vertex" => (
                "shadows",
                vec![
                    "--transfer-samples".into(),
                    "8".into(),
                    "--bands".into(),
                    "3".into(),
                ],
            ),
            // Its own bake (each object's transfer its own), small, made at load.
            "prt-hierarchical" => (
                "shadows",
                [
                    "--transfer-samples",
                    "8",
                    "--bands",
                    "3",
                    "--texels-per-metre",
                    "4",
                ]
                .into_iter()
                .chain(["--hprt-samples", "64"])
                .map(String::from)
                .collect(),
            ),
            t if t.starts_with("prt") || t.starts_with("shl") => {
                ("shadows", vec!["--baked".to_string(), path(&sh)])
            }
            t if t.starts_with("lpv") => ("cornell", vec!["--lpv-grid".into(), "8".into()]),
            // A small slab of the luminaire's lamp, baked alike (same seed) by both commands.
            "canned-light" => (
                "luminaire",
                [
                    "--slab-uv",
                    "2x2",
                    "--slab-st",
                    "16x16",
                    "--slab-samples",
                    "1",
                ]
                .map(String::from)
                .to_vec(),
            ),
            // A small refraction field of the glass torus.
            "lightfield-refraction" => (
                "glass",
                ["--field-uv", "8", "--field-st", "4"]
                    .map(String::from)
                    .to_vec(),
            ),
            // A small radiance field of the silver ball.
            "lightfield-glossy" => (
                "spheres",
                ["--field-uv", "4", "--field-st", "4", "--field-spp", "1"]
                    .map(String::from)
                    .to_vec(),
            ),
            _ => ("shadows", vec![]),
        };
        if t == "shl-compressed" {
            options.extend(["--sh-representatives".into(), "64".into()]);
        }
        let size = ["--width", "96", "--height", "72"];
        let mut a = vec!["view", "--scene", scene, "--technique", t, "--frames", "3"];
        a.extend(size);
        a.extend(["--screenshot", shot.to_str().unwrap()]);
        a.extend(options.iter().map(|s| s.as_str()));
        let o = lightlab(&a);
        assert!(o.status.success(), "{t}: {}", stderr(&o));
        assert!(stderr(&o).contains("viewer: 3 frames"), "{}", stderr(&o));
        let mut a = vec!["render", "--scene", scene, "--technique", t];
        a.extend(size);
        a.extend(["-o", rendered.to_str().unwrap()]);
        a.extend(options.iter().map(|s| s.as_str()));
        let o = lightlab(&a);
        assert!(o.status.success(), "{t}: {}", stderr(&o));
        let o = lightlab(&[
            "compare",
            shot.to_str().unwrap(),
            rendered.to_str().unwrap(),
            "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let last = stdout(&o).lines().last().unwrap().to_string();
        let v: serde_json::Value = serde_json::from_str(&last).unwrap();
        // 8-bit rounding and the orbit camera's float round trip only; a different camera,
        // technique or tone curve is orders of magnitude further.
        assert!(v["relmse"].as_f64().unwrap() < 1e-3, "{t}: {last}");
        let mean = v["mean_ratio"][0].as_f64().unwrap();
        assert!((mean - 1.0).abs() < 0.02, "{t}: {last}");
    }
    // A technique the viewer does not show is refused before a window opens.
    let o = lightlab(&["view", "--scene", "shadows", "--technique", "reference"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("GPU techniques"), "{}", stderr(&o));
}

#[test]
fn bake_sh_lightmaps_writes_coefficient_pages() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sh");
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "sh",
        "--bands",
        "3",
        "--texels-per-metre",
        "8",
        "--transfer-samples",
        "16",
        "--bounces",
        "1",
        "--compress",
        "32",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
    assert_eq!(v["bands"], 3);
    // The compressed copy (Fuchs §5.6) beside the pages.
    assert!(out.join("representatives.bin").exists() && out.join("indices-0.bin").exists());
    // 9 coefficients: three RGB images per page.
    for f in ["manifest.json", "sh-0-0.exr", "sh-0-1.exr", "sh-0-2.exr"] {
        assert!(out.join(f).exists(), "{f}");
    }
    assert!(!out.join("sh-0-3.exr").exists());
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "sh",
        "--transfer",
        "glossy",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--transfer"), "{}", stderr(&o));

    // The SH techniques render from the folder (a 3-band bake serves them all) on the GPU.
    let baked = out.to_str().unwrap();
    for (technique, extra) in [
        ("shl", vec![]),
        ("prt-textured", vec!["--sh-window", "lanczos"]),
        (
            "shl-compressed",
            vec!["--sh-representatives", "64", "--sh-filter", "4tap"],
        ),
    ] {
        let png = dir.path().join(format!("{technique}.png"));
        let mut args = vec![
            "render",
            "--scene",
            "cornell",
            "--technique",
            technique,
            "--baked",
            baked,
            "--width",
            "48",
            "-o",
            png.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = lightlab(&args);
        assert!(o.status.success(), "{technique}: {}", stderr(&o));
        assert!(png.exists(), "{technique}");
    }
    // Bad run-time options are clear errors.
    for (flag, value) in [
        ("--sh-filter", "trilinear"),
        ("--sh-points", "everywhere"),
        ("--sh-window", "gauss"),
    ] {
        let o = lightlab(&[
            "render",
            "--scene",
            "cornell",
            "--technique",
            "shl",
            "--baked",
            baked,
            "--width",
            "16",
            flag,
            value,
            "-o",
            dir.path().join("x.png").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{flag}");
        assert!(stderr(&o).contains(flag), "{flag}: {}", stderr(&o));
    }
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "prt-vertex",
        "--baked",
        baked,
        "-o",
        dir.path().join("v.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("per-vertex transfer"), "{}", stderr(&o));
    // shl-normalmapped needs a normal-mapped bake: this folder is refused with the fix named.
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "shl-normalmapped",
        "--baked",
        baked,
        "-o",
        dir.path().join("n.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--normal-mapped"), "{}", stderr(&o));
    assert!(!dir.path().join("n.png").exists());
}

#[test]
fn shl_normalmapped_bakes_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("n.png");
    let o = lightlab(&[
        "render",
        "--scene",
        "prt",
        "--technique",
        "shl-normalmapped",
        "--texels-per-metre",
        "2",
        "--transfer",
        "shadowed",
        "--transfer-samples",
        "8",
        "--width",
        "32",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(png.exists());
    let o = lightlab(&[
        "bake",
        "--scene",
        "prt",
        "--method",
        "sh",
        "--detail-cage",
        "0",
        "--out",
        dir.path().join("b").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--detail-cage"), "{}", stderr(&o));
    // CaSHL's shooting variant bakes SH light-maps and records what it did.
    let out = dir.path().join("shot");
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "sh",
        "--transfer",
        "shooting",
        "--texels-per-metre",
        "6",
        "--transfer-samples",
        "16",
        "--stop",
        "0.01",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert!(m["shooting"]["shots"].as_u64().unwrap() > 0, "{m}");
    // Per-vertex transfer cannot shoot: a clear error.
    let o = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "prt",
        "--transfer",
        "shooting",
        "--out",
        dir.path().join("v").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("interreflected"), "{}", stderr(&o));
}

#[test]
fn prt_vertex_renders_without_a_bake() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("v.png");
    let o = lightlab(&[
        "render",
        "--scene",
        "shadows",
        "--technique",
        "prt-vertex",
        "--transfer-samples",
        "16",
        "--bounces",
        "1",
        "--width",
        "48",
        "--json",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).lines().last().unwrap()).unwrap();
    assert_eq!(v["technique"], "prt-vertex");
    // No emitters in `shadows`: its point and spot lights reach the surfaces through the
    // transfer and the projected SH light.
    let img = lightlab_core::image::Image::read(&png).unwrap();
    assert!(img.mean().max_element() > 0.02, "lit: {:?}", img.mean());
    // `bake --method prt` writes the same transfer to disk; rendering from it gives the same
    // image (same seed and settings), and another scene's folder is refused.
    let baked = dir.path().join("vt");
    let o = lightlab(&[
        "bake",
        "--scene",
        "shadows",
        "--method",
        "prt",
        "--transfer-samples",
        "16",
        "--bounces",
        "1",
        "--out",
        baked.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(baked.join("manifest.json").exists() && baked.join("transfer-0.bin").exists());
    let png2 = dir.path().join("v2.png");
    let o = lightlab(&[
        "render",
        "--scene",
        "shadows",
        "--technique",
        "prt-vertex",
        "--baked",
        baked.to_str().unwrap(),
        "--width",
        "48",
        "-o",
        png2.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img2 = lightlab_core::image::Image::read(&png2).unwrap();
    assert_eq!(img.data, img2.data);
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "prt-vertex",
        "--baked",
        baked.to_str().unwrap(),
        "-o",
        dir.path().join("x.png").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("different scene"), "{}", stderr(&o));
}

#[test]
fn lpv_techniques_render_and_reject_bad_options() {
    let dir = tempfile::tempdir().unwrap();
    let mut means = vec![];
    for (t, view) in [
        ("lpv", "final"),
        ("lpv", "indirect"),
        ("lpv-faithful", "indirect"),
    ] {
        let exr = dir.path().join(format!("{t}-{view}.exr"));
        let o = lightlab(&[
            "render",
            "--scene",
            "cornell",
            "--technique",
            t,
            "--debug-view",
            view,
            "--lpv-grid",
            "16",
            "--rsm-size",
            "64",
            "--width",
            "32",
            "--json",
            "-o",
            exr.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{t}: {}", stderr(&o));
        let img = lightlab_core::image::Image::read(&exr).unwrap();
        means.push(img.mean().max_element());
    }
    // The indirect view holds light (the area light's bounce) and less than the full frame
    // (which adds the emitter).
    assert!(means[1] > 0.0 && means[1] < means[0], "{means:?}");
    assert!(means[2] > 0.0);
    // Debug layers: the G-buffer at the frame's size, the RSM at its own, the scene volume's
    // 16 slices as 4 × 4 tiles of 16² cells; each holds something.
    for (view, size) in [
        ("albedo", 32),
        ("normal", 32),
        ("material", 32),
        ("depth", 32),
        ("rsm-flux", 64),
        ("rsm-normal", 64),
        ("rsm-position", 64),
        ("lpv-slices", 64),
    ] {
        let exr = dir.path().join(format!("{view}.exr"));
        let o = lightlab(&[
            "render",
            "--scene",
            "cornell",
            "--technique",
            "lpv",
            "--debug-view",
            view,
            "--lpv-grid",
            "16",
            "--lpv-cascades",
            "2",
            "--rsm-size",
            "64",
            "--width",
            "32",
            "-o",
            exr.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{view}: {}", stderr(&o));
        let img = lightlab_core::image::Image::read(&exr).unwrap();
        assert_eq!((img.width, img.height), (size, size), "{view}");
        assert!(img.mean().max_element() > 0.0, "{view} is black");
    }
    let out = dir.path().join("x.png");
    // Wind: sways with shadow maps (lpv), refused with shadow volumes (built on the CPU).
    let windy = |t: &str| {
        lightlab(&[
            "render",
            "--scene",
            "bush",
            "--technique",
            t,
            "--wind",
            "0.1",
            "--lpv-grid",
            "8",
            "--rsm-size",
            "32",
            "--width",
            "16",
            "-o",
            out.to_str().unwrap(),
        ])
    };
    let o = windy("lpv");
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::remove_file(&out).unwrap();
    // Options of other techniques are refused, not ignored.
    let refused: [&[&str]; 6] = [
        &["phong", "--debug-view", "indirect"],
        &["lpv", "--indirect-only"],
        &["phong-shadow-maps", "--bounces", "2"],
        &["lightmap", "--no-area-lights"],
        &["lpv-faithful", "--lpv-reemit", "face"],
        &["lpv-faithful", "--lpv-reemit-lobe", "0.7"],
    ];
    for args in refused {
        let mut v = vec!["render", "--scene", "cornell", "--technique"];
        v.extend(args);
        v.extend(["--width", "16", "-o", out.to_str().unwrap()]);
        let o = lightlab(&v);
        assert!(!o.status.success(), "{args:?} was accepted");
        assert!(stderr(&o).contains("applies to"), "{}", stderr(&o));
        assert!(!out.exists());
    }
    let o = windy("phong-shadow-volumes");
    assert!(
        !o.status.success() && stderr(&o).contains("shadow maps"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    for bad in [
        ["--lpv-grid", "2"],
        ["--rsm-size", "8"],
        ["--lpv-cascades", "5"],
        ["--lpv-damping", "9"],
        ["--lpv-reemit-lobe", "1.5"],
    ] {
        let o = lightlab(&[
            "render",
            "--scene",
            "cornell",
            "--technique",
            "lpv",
            bad[0],
            bad[1],
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success());
        assert!(
            stderr(&o).contains(&bad[0][2..6]) || stderr(&o).contains("must be"),
            "{}",
            stderr(&o)
        );
        assert!(!out.exists(), "no output on error");
    }
}

#[test]
fn reference_renders_exactly_one_indirect_bounce() {
    let dir = tempfile::tempdir().unwrap();
    let render = |extra: &[&str], name: &str| {
        let exr = dir.path().join(name);
        let mut args = vec![
            "render", "--scene", "cornell", "--spp", "16", "--width", "24", "-o",
        ];
        args.push(exr.to_str().unwrap());
        args.extend_from_slice(extra);
        let o = lightlab(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        lightlab_core::image::Image::read(&exr)
            .unwrap()
            .mean()
            .max_element()
    };
    let all = render(&[], "all.exr");
    let one = render(&["--indirect-only"], "one.exr");
    let two = render(&["--indirect-only", "--bounces", "2"], "two.exr");
    assert!(one > 0.0 && one < all && two < one, "{all} {one} {two}");
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "direct",
        "--indirect-only",
        "-o",
        dir.path().join("d.exr").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
}
