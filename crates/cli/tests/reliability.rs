//! Interrupted bakes on the real binary: a re-bake killed at any moment leaves the folder as
//! the complete old bake or the complete new one, never a mix, and leaves no temporaries after
//! SIGINT.

mod common;

use common::lightlab;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn bake(out: &Path, samples: u32) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lightlab"));
    c.args(["bake", "--scene", "cornell", "--method", "path"])
        .args(["--gather-samples", &samples.to_string()])
        .args(["--texels-per-metre", "100", "--png", "--gltf", "--out"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

/// The files of a bake folder as its manifest records them (name, size, CRC-32).
fn recorded_files(dir: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("manifest.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some(v["integrity"]["files"].clone())
}

/// Entries of `parent` other than the listed folders (temporaries, staging folders).
fn leftovers(parent: &Path, keep: &[&str]) -> Vec<String> {
    std::fs::read_dir(parent)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !keep.contains(&n.as_str()))
        .collect()
}

fn interrupt(child: &mut Child, hard: bool) {
    if hard {
        let _ = child.kill();
    } else {
        let _ = rustix::process::kill_process(
            rustix::process::Pid::from_child(child),
            rustix::process::Signal::INT,
        );
    }
}

#[test]
fn a_rebake_killed_at_20_moments_leaves_the_old_bake_or_the_new_one() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    // The two complete bakes the folder may hold, made undisturbed, and how long one takes.
    let (old_ref, new_ref) = (root.join("old"), root.join("new"));
    assert!(bake(&old_ref, 48).status().unwrap().success());
    let t0 = Instant::now();
    assert!(bake(&new_ref, 64).status().unwrap().success());
    let full = t0.elapsed().as_secs_f64();
    let (old_files, new_files) = (
        recorded_files(&old_ref).unwrap(),
        recorded_files(&new_ref).unwrap(),
    );
    assert_ne!(old_files, new_files);
    let scene = lightlab_scene::load("cornell", Default::default()).unwrap();
    let dir = root.join("lm");
    let keep = ["old", "new", "lm"];
    assert!(bake(&dir, 48).status().unwrap().success());
    let mut holds_new = false;
    let (mut old_seen, mut new_seen) = (0, 0);
    // Moments: ten spread over the whole bake, ten around its end, where the pages, the
    // manifest and the swap are written (SplitMix-style fixed sequence).
    let mut x: u64 = 0x5eed;
    let mut unit = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    for k in 0..20 {
        let at = if k < 10 {
            full * (0.05 + 0.95 * unit())
        } else {
            full * (0.85 + 0.3 * unit())
        };
        let hard = k % 2 == 1;
        let samples = if holds_new { 48 } else { 64 };
        let mut child = bake(&dir, samples).spawn().unwrap();
        std::thread::sleep(Duration::from_secs_f64(at));
        interrupt(&mut child, hard);
        let out = child.wait_with_output().unwrap();
        let files = recorded_files(&dir);
        let what = format!(
            "kill {k} ({}, at {at:.3} s of {full:.3} s, exit {:?}): {}",
            if hard { "SIGKILL" } else { "SIGINT" },
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        // The folder reads back whole (every checksum verified) ...
        let read = lightlab_bake::output::read(&dir, &scene);
        assert!(read.is_ok(), "{what}: {}", read.err().unwrap());
        // ... and is exactly one of the two bakes.
        let files = files.unwrap_or_else(|| panic!("{what}: no manifest"));
        if files == new_files {
            new_seen += 1;
            holds_new = true;
        } else if files == old_files {
            old_seen += 1;
            holds_new = false;
        } else {
            panic!("{what}: the folder is neither bake: {files}\nold {old_files}\nnew {new_files}");
        }
        if !hard {
            let left = leftovers(root, &keep);
            assert!(left.is_empty(), "{what}: SIGINT left {left:?}");
        }
    }
    eprintln!("20 kills: the folder held the old bake {old_seen} times, the new one {new_seen}");
    // A bake after the kills removes what SIGKILL left behind.
    assert!(bake(&dir, 64).status().unwrap().success());
    assert_eq!(recorded_files(&dir).unwrap(), new_files);
    let left = leftovers(root, &keep);
    assert!(left.is_empty(), "left after a complete bake: {left:?}");
}

#[test]
fn bake_folders_refuse_what_they_did_not_write() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lm");
    assert!(bake(&dir, 4).status().unwrap().success());
    let render = |baked: &Path, technique: &str| {
        Command::new(env!("CARGO_BIN_EXE_lightlab"))
            .args([
                "render",
                "--scene",
                "cornell",
                "--technique",
                technique,
                "--baked",
            ])
            .arg(baked)
            .args(["--width", "16", "-o"])
            .arg(tmp.path().join("x.png"))
            .output()
            .unwrap()
    };
    // A page from another bake of the same scene and size is refused by its checksum.
    let other = tmp.path().join("other");
    assert!(bake(&other, 8).status().unwrap().success());
    let page = PathBuf::from("lightmap-0.exr");
    std::fs::copy(other.join(&page), dir.join(&page)).unwrap();
    let o = render(&dir, "lightmap");
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("lightmap-0.exr") && e.contains("does not belong"),
        "{e}"
    );
    assert!(!tmp.path().join("x.png").exists());
    // A light-map folder given to an SH technique says what it is (it was a raw serde error).
    let o = render(&other, "shl");
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("is a light-map folder") && e.contains("--method sh"),
        "{e}"
    );
    // A folder of other files is never replaced by a bake.
    let mine = tmp.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), b"keep").unwrap();
    let o = bake(&mine, 4).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("neither empty nor a bake folder"));
    assert_eq!(std::fs::read(mine.join("notes.txt")).unwrap(), b"keep");
}

fn corpus(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scene/tests/corpus")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

#[test]
fn inputs_that_gave_nan_images_render_or_are_refused_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o.exr");
    let o = out.to_str().unwrap();
    // Zero-length normals: repaired at load; the GPU image is finite (it was NaN, and
    // lightlab refused to read its own EXR).
    let file = corpus("zero_normals.gltf");
    for technique in ["phong", "direct"] {
        let r = lightlab(&[
            "render",
            "--scene",
            &file,
            "--technique",
            technique,
            "--width",
            "24",
            "--spp",
            "2",
            "-o",
            o,
        ]);
        assert!(
            r.status.success(),
            "{technique}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let img = lightlab_core::image::Image::read(&out).unwrap();
        assert!(img.data.iter().all(|v| v.is_finite()) && img.mean().length() > 0.0);
        std::fs::remove_file(&out).unwrap();
    }
    // An environment intensity that overflows f32 once multiplied: refused, nothing written.
    let sky = tmp.path().join("sky.exr");
    lightlab_core::image::Image::from_fn(8, 4, |_, _| glam::Vec3::splat(10.0))
        .write(&sky, Default::default())
        .unwrap();
    let r = lightlab(&[
        "render",
        "--scene",
        "spheres",
        "--technique",
        "direct",
        "--env",
        sky.to_str().unwrap(),
        "--env-intensity",
        "3e38",
        "--width",
        "8",
        "-o",
        o,
    ]);
    let e = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{e}");
    assert!(e.contains("intensity") && e.contains("sky.exr"), "{e}");
    assert!(!out.exists());
    // An output folder that does not exist is refused before the render starts.
    let t0 = Instant::now();
    let missing = tmp.path().join("no/such/folder/o.png");
    let r = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "reference",
        "--width",
        "512",
        "--spp",
        "4096",
        "-o",
        missing.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{e}");
    assert!(e.contains("does not exist"), "{e}");
    assert!(
        t0.elapsed() < Duration::from_secs(20),
        "the render ran before the check"
    );
    // An SH folder given to a light-map technique says what it is (a raw serde error before).
    let sh = tmp.path().join("sh");
    let b = lightlab(&[
        "bake",
        "--scene",
        "cornell",
        "--method",
        "sh",
        "--bands",
        "2",
        "--transfer-samples",
        "4",
        "--texels-per-metre",
        "4",
        "--out",
        sh.to_str().unwrap(),
    ]);
    assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
    let r = lightlab(&[
        "render",
        "--scene",
        "cornell",
        "--technique",
        "lightmap",
        "--baked",
        sh.to_str().unwrap(),
        "--width",
        "8",
        "-o",
        o,
    ]);
    let e = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{e}");
    assert!(
        e.contains("is an SH light-map folder") && e.contains("radiosity|path"),
        "{e}"
    );
}

#[test]
fn a_closed_output_pipe_ends_the_command_quietly() {
    // `lightlab scenes | head -0`: the reader is gone before anything is printed. Rust's
    // println! panicked (exit 101) on the broken pipe; now the process ends by SIGPIPE.
    let mut child = Command::new(env!("CARGO_BIN_EXE_lightlab"))
        .args(["scenes", "-v"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(!e.contains("panicked"), "{e}");
    assert_ne!(out.status.code(), Some(101), "{e}");
}
