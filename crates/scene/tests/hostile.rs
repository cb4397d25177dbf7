//! Hostile glTF input: every file of `tests/corpus/` (written by `corpus/make.py`, one broken
//! thing each) is refused with a message naming the problem, or loads; and a seeded mutation
//! fuzzer over the corpus finds no panic.

use lightlab_core::fuzz::Fuzzer;
use lightlab_scene::gltf_io::import_slice;
use lightlab_scene::{LoadOptions, Scene, SceneError};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

fn corpus() -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(corpus_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    v.sort();
    v
}

/// A folder laid out like a user's: the glTF in `scene/`, a sky map beside it, and files
/// outside the folder that hostile URIs try to reach.
fn workspace() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene");
    std::fs::create_dir(&scene).unwrap();
    std::fs::write(dir.path().join("outside.bin"), vec![0u8; 140]).unwrap();
    let sky = lightlab_core::image::Image::from_fn(8, 4, |_, _| glam::Vec3::splat(2.0));
    sky.write(
        &scene.join("sky.hdr").with_extension("exr"),
        Default::default(),
    )
    .unwrap();
    std::fs::copy(scene.join("sky.exr"), dir.path().join("sky.exr")).unwrap();
    (dir, scene)
}

fn load(
    scene_dir: &Path,
    name: &str,
    bytes: &[u8],
) -> std::thread::Result<Result<Scene, SceneError>> {
    let path = scene_dir.join(name);
    catch_unwind(AssertUnwindSafe(|| {
        import_slice(&path, bytes, LoadOptions::default())
    }))
}

/// What each corpus file must give: loaded, or an error containing every listed fragment.
const EXPECTED: &[(&str, &[&str])] = &[
    ("bad_accessor_index.gltf", &["POSITION names accessor 99"]),
    (
        "byte_length_too_large.gltf",
        &["buffer 0 holds", "byteLength says 4096"],
    ),
    ("camera_zero_fov.gltf", &["camera", "field of view"]),
    ("deep_chain.gltf", &["deeper than 1024"]),
    ("deep_json.gltf", &["invalid glTF"]),
    ("degenerate_triangle.gltf", &[]),
    (
        "environment_huge_intensity.gltf",
        &["environment", "intensity"],
    ),
    (
        "environment_outside.gltf",
        &["outside", "--allow-outside-paths"],
    ),
    ("glb_header_only.glb", &["truncated GLB header"]),
    ("glb_json_length_huge.glb", &["truncated GLB"]),
    (
        "glb_total_length_wrong.glb",
        &["the GLB header says 7 bytes"],
    ),
    ("glb_truncated.glb", &["invalid glTF"]),
    ("huge_scale.gltf", &["1e15"]),
    ("image_huge_dimensions.gltf", &["image 0", "data: URI"]),
    (
        "image_not_png.gltf",
        &["image 0", "Gif images are not supported"],
    ),
    ("image_truncated.gltf", &["image 0"]),
    ("image_uri_parent.gltf", &["image 0", "outside"]),
    ("index_out_of_range.gltf", &["index 9 out of range"]),
    (
        "indices_past_view.gltf",
        &["accessor 3", "run past bufferView 3"],
    ),
    (
        "missing_buffer.gltf",
        &["buffer 0", "missing.bin", "cannot read"],
    ),
    (
        "missing_image.gltf",
        &["image 0", "textures/missing.png", "cannot read"],
    ),
    ("nan_positions.gltf", &["NaN"]),
    ("negative_light.gltf", &["light", "negative"]),
    ("negative_range.gltf", &["range -1"]),
    ("negative_sun_diameter.gltf", &["angular diameter"]),
    ("node_cycle.gltf", &["reached twice"]),
    ("node_self_cycle.gltf", &["reached twice"]),
    ("node_two_parents.gltf", &["reached twice"]),
    ("not_json.gltf", &["invalid glTF"]),
    ("points_beside_triangles.gltf", &[]),
    ("points_mode.gltf", &["no triangle meshes"]),
    (
        "positions_past_view.gltf",
        &["accessor 0", "run past bufferView 0"],
    ),
    ("singular_scale.gltf", &["singular"]),
    ("sparse_past_view.gltf", &["accessor 0", "sparse"]),
    ("spot_cone_inverted.gltf", &["spot cone"]),
    ("stride_not_multiple_of_4.gltf", &["byteStride 14"]),
    (
        "stride_smaller_than_element.gltf",
        &["byteStride 4", "smaller than its 12-byte"],
    ),
    ("texcoord_set_missing.gltf", &["TEXCOORD_3"]),
    ("triangle_fan.gltf", &[]),
    ("triangle_strip.gltf", &[]),
    ("unknown_required_extension.gltf", &["EXT_made_up"]),
    ("unsupported_features.gltf", &[]),
    (
        "uri_absolute.gltf",
        &["buffer 0", "outside", "--allow-outside-paths"],
    ),
    ("uri_bad_percent.gltf", &["buffer 0", "percent"]),
    ("uri_file_scheme.gltf", &["buffer 0", "outside"]),
    ("uri_http.gltf", &["buffer 0", "'http:'"]),
    ("uri_parent.gltf", &["buffer 0", "outside"]),
    ("valid.glb", &[]),
    ("valid.gltf", &[]),
    (
        "view_past_buffer.gltf",
        &["bufferView 3", "run past buffer 0"],
    ),
    ("zero_normals.gltf", &[]),
];

#[test]
fn every_hostile_file_is_refused_with_its_problem_named_or_loads() {
    let (_dir, scene_dir) = workspace();
    let files = corpus();
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    let listed: Vec<&str> = EXPECTED.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names, listed,
        "the corpus and the table of expectations differ"
    );
    let mut wrong = vec![];
    for ((name, bytes), (_, fragments)) in files.iter().zip(EXPECTED) {
        match load(&scene_dir, name, bytes) {
            Err(_) => wrong.push(format!("{name}: PANIC")),
            Ok(Ok(scene)) if !fragments.is_empty() => {
                wrong.push(format!("{name}: loaded ({} meshes)", scene.meshes.len()))
            }
            Ok(Ok(scene)) => {
                // Loaded files are sound: unit normals everywhere, and every triangle (lists,
                // converted strips and fans) wound to face its normals.
                for m in &scene.meshes {
                    for n in &m.normals {
                        assert!((n.length() - 1.0).abs() < 1e-4, "{name}: normal {n}");
                    }
                    let kept = if name == "degenerate_triangle.gltf" {
                        3
                    } else {
                        6
                    };
                    assert_eq!(m.indices.len(), kept, "{name}: the quad's triangles");
                    for t in m.indices.chunks_exact(3) {
                        let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                        let facing = (b - a).cross(c - a).dot(m.normals[t[0] as usize]);
                        assert!(facing > 0.0, "{name}: triangle {t:?} is wound backwards");
                    }
                }
                let warned = !scene.warnings.is_empty();
                let expect = [
                    "degenerate_triangle.gltf",
                    "points_beside_triangles.gltf",
                    "unsupported_features.gltf",
                ];
                assert_eq!(
                    warned,
                    expect.contains(&name.as_str()),
                    "{name}: {:?}",
                    scene.warnings
                );
            }
            Ok(Err(e)) => {
                let msg = e.to_string();
                if fragments.is_empty() || !fragments.iter().all(|f| msg.contains(f)) {
                    wrong.push(format!("{name}: {msg}"));
                }
                assert!(
                    msg.contains(name.as_str()),
                    "{name}: the message does not name the file: {msg}"
                );
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "unexpected outcomes:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn outside_paths_load_when_allowed() {
    let (_dir, scene_dir) = workspace();
    let files = corpus();
    let bytes = &files
        .iter()
        .find(|(n, _)| n == "uri_parent.gltf")
        .unwrap()
        .1;
    let path = scene_dir.join("uri_parent.gltf");
    let allow = LoadOptions {
        allow_outside_paths: true,
        ..Default::default()
    };
    // `../outside.bin` exists (zeros): the file loads as far as its geometry, which is then
    // refused for what it is (all triangles degenerate), not for where it is.
    let e = import_slice(&path, bytes, allow).unwrap_err().to_string();
    assert!(!e.contains("outside"), "{e}");
}

/// The seeded fuzzer: about 52,000 inputs (structured JSON mutations of the .gltf files, byte
/// mutations of every file, one to three mutations each), each imported under
/// `catch_unwind`. Any panic fails the test and names the input, message and location.
#[test]
fn mutated_gltf_never_panics() {
    let (_dir, scene_dir) = workspace();
    let files = corpus();
    let mut fuzz = Fuzzer::from_env(600, 0x6c69_6768_746c_6162);
    for round in 0..fuzz.rounds {
        for (name, bytes) in &files {
            let mut inputs = vec![];
            if name.ends_with(".gltf") && bytes.len() < 100_000 {
                inputs.extend(fuzz.mutated_json(bytes));
            }
            inputs.push(fuzz.mutated_bytes(bytes));
            for input in inputs {
                let path = scene_dir.join(name);
                fuzz.run(&format!("round {round}, {name}"), &input, || {
                    import_slice(&path, &input, LoadOptions::default()).is_ok()
                });
            }
        }
    }
    let min = 80 * fuzz.rounds as usize;
    fuzz.finish("glTF import", min);
}

#[test]
fn a_failed_export_leaves_no_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = lightlab_scene::builtin::builtin("spheres").unwrap();
    if scene.environment.is_none() {
        scene.environment = Some(lightlab_scene::Environment {
            image: lightlab_core::image::Image::from_fn(8, 4, |_, _| glam::Vec3::ONE),
            intensity: 1.0,
        });
    }
    // The .gltf's name is taken by a folder: nothing may be written beside it (the .bin and
    // the .env.exr were left behind).
    let out = dir.path().join("out.gltf");
    std::fs::create_dir(&out).unwrap();
    assert!(lightlab_scene::gltf_io::export(&scene, &out).is_err());
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["out.gltf"], "left behind: {left:?}");
    // An environment that cannot be encoded (NaN) fails before anything is written.
    std::fs::remove_dir(&out).unwrap();
    scene.environment.as_mut().unwrap().image.data[0].x = f32::NAN;
    assert!(lightlab_scene::gltf_io::export(&scene, &out).is_err());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
