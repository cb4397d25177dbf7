//! glTF animations: a hand-written file (not lightlab's exporter's) read as the scene's rigid
//! animation, the built-in `prt-dynamic` round-tripped, broken files refused.
//! `python3 tests/animated/make.py` wrote the files.

use glam::{Quat, Vec3};
use lightlab_scene::{LoadOptions, gltf_io};
use std::path::Path;

fn load(name: &str) -> Result<lightlab_scene::Scene, lightlab_scene::SceneError> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/animated")
        .join(name);
    gltf_io::import(&p, LoadOptions::default())
}

#[test]
fn a_hand_written_animation_drives_its_nodes_and_their_children() {
    let s = load("animated.gltf").unwrap();
    let a = s.animation.as_ref().expect("the file's first animation");
    assert_eq!((a.fps, a.frames), (24.0, 48));
    // The arm (child of the turning rig) and the spinner move; the floor stays.
    let names: Vec<&str> = a
        .tracks
        .iter()
        .map(|t| s.instances[t.instance].name.as_str())
        .collect();
    assert_eq!(names, ["arm", "spinner"]);
    let warnings = s.warnings.join("\n");
    for w in ["2 animations", "cubic-spline", "scale channels"] {
        assert!(warnings.contains(w), "{w}: {warnings}");
    }
    // Frame 24 = 1 s: the rig has turned 90° about y, the arm has stepped to x = 2.
    let posed = s.posed(24);
    let arm = posed.instances[1].transform;
    assert!(
        arm.transform_point3(Vec3::ZERO)
            .abs_diff_eq(Vec3::new(0.0, 1.0, -2.0), 1e-4),
        "{arm}"
    );
    // Before the step (frame 6 = 0.25 s): x = 1, turned 22.5°.
    let early = s.posed(6).instances[1]
        .transform
        .transform_point3(Vec3::ZERO);
    let expect =
        Vec3::new(0.0, 1.0, 0.0) + Quat::from_rotation_y(std::f32::consts::PI / 8.0) * Vec3::X;
    assert!(early.abs_diff_eq(expect, 1e-4), "{early}");
    // The spinner, cubic keys read as values: 45° at 1 s, in place.
    let (_, r, t) = posed.instances[2].transform.to_scale_rotation_translation();
    assert!(t.abs_diff_eq(Vec3::new(0.0, 0.5, 2.0), 1e-5));
    assert!(r.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4)) < 1e-4);
    // The floor keeps its rest transform at every frame.
    assert_eq!(posed.instances[0].transform, s.instances[0].transform);
}

#[test]
fn broken_animations_are_refused_with_the_reason() {
    let e = load("animated_times_backwards.gltf")
        .unwrap_err()
        .to_string();
    assert!(e.contains("increasing"), "{e}");
    let e = load("animated_short_outputs.gltf").unwrap_err().to_string();
    assert!(e.contains("fewer translations than key times"), "{e}");
}

#[test]
fn prt_dynamic_round_trips_its_animation() {
    let s = lightlab_scene::builtin::builtin("prt-dynamic").unwrap();
    let dir = tempfile::tempdir().unwrap();
    for ext in ["glb", "gltf"] {
        let p = dir.path().join(format!("d.{ext}"));
        gltf_io::export(&s, &p).unwrap();
        let back = gltf_io::import(&p, LoadOptions::default()).unwrap();
        let a = back.animation.as_ref().expect("exported animation");
        assert_eq!((a.fps, a.frames), (24.0, 48));
        assert_eq!(a.tracks.len(), 3);
        for f in [0, 7, 12, 30, 47] {
            let (x, y) = (s.posed(f), back.posed(f));
            for (i, j) in x.instances.iter().zip(&y.instances) {
                assert!(
                    i.transform.abs_diff_eq(j.transform, 1e-4),
                    "frame {f}, {}: {} vs {}",
                    i.name,
                    i.transform,
                    j.transform
                );
            }
        }
    }
}

#[test]
fn the_node_hierarchy_is_kept_for_instances() {
    // The hand-written file: the arm sits under the rig.
    let s = load("animated.gltf").unwrap();
    assert_eq!(s.instances[1].name, "arm");
    assert_eq!(s.instances[1].nodes, ["rig"]);
    assert!(s.instances[0].nodes.is_empty());
    // prt-dynamic's tiles under ground / block_I_J survive an export as glTF group nodes.
    let d = lightlab_scene::builtin::builtin("prt-dynamic").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("d.glb");
    gltf_io::export(&d, &p).unwrap();
    let back = gltf_io::import(&p, LoadOptions::default()).unwrap();
    let names = |s: &lightlab_scene::Scene| -> Vec<(String, Vec<String>)> {
        s.instances
            .iter()
            .map(|i| (i.name.clone(), i.nodes.clone()))
            .collect()
    };
    assert_eq!(names(&back), names(&d));
    assert_eq!(back.instances[13].nodes, ["ground", "block_0_1"]);
    assert_eq!(back.instances[13].name, "tile_1_4");
}
