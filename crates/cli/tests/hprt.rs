//! Hierarchical PRT on the GPU (issue 23): on the animated `prt-dynamic`, frames 0, 12 and
//! 24, `prt-hierarchical` against the path-traced reference of the same frame errs at most
//! half as much as `prt-textured`, which misses the shadows between the moving objects.
//! `cargo test -p lightlab --test hprt -- --nocapture` prints the figures.

mod common;

use common::{lightlab, ok, stderr, stdout};

fn relmse(a: &std::path::Path, b: &std::path::Path) -> f64 {
    let o = lightlab(&[
        "compare",
        "--json",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
    ]);
    ok(&o);
    let line = stdout(&o).lines().last().unwrap().to_string();
    let v: serde_json::Value = serde_json::from_str(&line).unwrap();
    v["relmse"].as_f64().unwrap()
}

#[test]
fn hierarchical_prt_halves_textured_prts_error_between_moving_objects() {
    let dir = tempfile::tempdir().unwrap();
    // Each object's transfer its own (prt-hierarchical's bake); on prt-dynamic, whose still
    // objects are coplanar tiles, prt-textured's own bake is the same.
    let baked = dir.path().join("sh");
    ok(&lightlab(&[
        "bake",
        "--scene",
        "prt-dynamic",
        "--method",
        "sh",
        "--occluders",
        "object",
        "--out",
        baked.to_str().unwrap(),
    ]));
    let size = ["--width", "96", "--height", "72"];
    for frame in ["0", "12", "24"] {
        let path = |t: &str| dir.path().join(format!("{t}-{frame}.exr"));
        let ref_path = path("reference");
        let mut reference = vec!["render", "--scene", "prt-dynamic", "--frame", frame];
        reference.extend(size);
        reference.extend(["--spp", "128", "-o", ref_path.to_str().unwrap()]);
        ok(&lightlab(&reference));
        let mut errors = vec![];
        for t in ["prt-textured", "prt-hierarchical"] {
            let out = path(t);
            let mut args = vec!["render", "--scene", "prt-dynamic", "--frame", frame];
            args.extend(size);
            args.extend(["--technique", t, "--baked", baked.to_str().unwrap()]);
            args.extend(["-o", out.to_str().unwrap()]);
            ok(&lightlab(&args));
            errors.push(relmse(&out, &ref_path));
        }
        eprintln!(
            "frame {frame}: prt-textured {:.4}, prt-hierarchical {:.4} ({:.2}×)",
            errors[0],
            errors[1],
            errors[1] / errors[0]
        );
        assert!(errors[1] <= 0.5 * errors[0], "frame {frame}: {errors:?}");
    }
}

#[test]
fn frames_pose_animated_scenes_only() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    for technique in ["reference", "phong"] {
        let o = lightlab(&[
            "render",
            "--scene",
            "cornell",
            "--frame",
            "3",
            "--technique",
            technique,
            "--width",
            "8",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1));
        assert!(stderr(&o).contains("has no animation"), "{}", stderr(&o));
        assert!(!out.exists());
    }
    // A bake where objects shadow each other would be shadowed twice.
    let baked = dir.path().join("sh");
    ok(&lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "sh",
        "--texels-per-metre",
        "2",
        "--transfer-samples",
        "16",
        "--bands",
        "2",
        "--out",
        baked.to_str().unwrap(),
    ]));
    let o = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "prt-hierarchical",
        "--baked",
        baked.to_str().unwrap(),
        "--width",
        "8",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--occluders object"), "{}", stderr(&o));
    // prt-hierarchical needs per-object sample points.
    let o = lightlab(&[
        "render",
        "--scene",
        "prt-dynamic",
        "--technique",
        "prt-hierarchical",
        "--sh-points",
        "scene",
        "--width",
        "8",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--sh-points object"), "{}", stderr(&o));
}

#[test]
fn the_viewer_poses_and_plays_the_animation() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let rendered = dir.path().join("rendered.png");
    let size = ["--width", "64", "--height", "48"];
    for technique in ["prt-hierarchical", "phong-shadow-maps"] {
        let mut a = vec!["view", "--scene", "prt-dynamic", "--technique", technique];
        a.extend([
            "--frame",
            "12",
            "--frames",
            "2",
            "--screenshot",
            shot.to_str().unwrap(),
        ]);
        a.extend(size);
        ok(&lightlab(&a));
        let mut a = vec!["render", "--scene", "prt-dynamic", "--technique", technique];
        a.extend(["--frame", "12", "-o", rendered.to_str().unwrap()]);
        a.extend(size);
        ok(&lightlab(&a));
        // The viewer's frame 12 is the render's (8-bit rounding apart).
        assert!(relmse(&shot, &rendered) < 1e-3, "{technique}");
        // Playing: the objects move from frame to frame.
        let mut a = vec!["view", "--scene", "prt-dynamic", "--technique", technique];
        a.extend([
            "--animate",
            "--frames",
            "4",
            "--screenshot",
            shot.to_str().unwrap(),
        ]);
        a.extend(size);
        let e = ok(&lightlab(&a));
        assert!(e.contains("viewer: 4 frames"), "{e}");
    }
}
