//! Hostile glTF input: every file of `tests/corpus/` (written by `corpus/make.py`, one broken
//! thing each) is refused with a message naming the problem, or loads; and a seeded mutation
//! fuzzer over the corpus finds no panic.

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
    ("degenerate_triangle.gltf", &["zero area"]),
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
    ("points_mode.gltf", &["mode Points"]),
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
    ("unknown_required_extension.gltf", &["EXT_made_up"]),
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
                // Loaded files are sound: unit normals everywhere.
                for m in &scene.meshes {
                    for n in &m.normals {
                        assert!((n.length() - 1.0).abs() < 1e-4, "{name}: normal {n}");
                    }
                }
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

/// A small deterministic generator (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that break arithmetic: zero, signs, powers of two around integer widths, huge floats.
const INTERESTING: &[f64] = &[
    0.0,
    -1.0,
    1.0,
    3.0,
    4.0,
    255.0,
    256.0,
    65535.0,
    65536.0,
    2147483647.0,
    4294967295.0,
    4294967296.0,
    1e19,
    -1e19,
    1e39,
    1e300,
    0.5,
    1e-45,
];

/// Change one number, key or array somewhere in a JSON document.
fn mutate_json(v: &mut serde_json::Value, rng: &mut Rng) {
    use serde_json::Value;
    let mut node = v;
    loop {
        let children = match node {
            Value::Object(m) => m.len(),
            Value::Array(a) => a.len(),
            _ => 0,
        };
        if children == 0 || rng.below(4) == 0 {
            break;
        }
        let k = rng.below(children);
        node = match node {
            Value::Object(m) => m.values_mut().nth(k).unwrap(),
            Value::Array(a) => &mut a[k],
            _ => unreachable!(),
        };
    }
    match (rng.below(6), &mut *node) {
        (0 | 1, n) => *n = serde_json::json!(INTERESTING[rng.below(INTERESTING.len())]),
        (2, Value::Object(m)) if !m.is_empty() => {
            let key = m.keys().nth(rng.below(m.len())).unwrap().clone();
            m.remove(&key);
        }
        (3, Value::Array(a)) if !a.is_empty() => {
            let x = a[rng.below(a.len())].clone();
            a.push(x);
        }
        (4, Value::String(s)) => {
            *s = ["../x.bin", "%FF", "data:,", "data:;base64,@@", "/", ""][rng.below(6)].into()
        }
        (_, n) => *n = serde_json::json!(rng.below(8) as i64 - 2),
    }
}

fn mutate_bytes(b: &mut Vec<u8>, rng: &mut Rng) {
    let n = b.len().max(1);
    match rng.below(5) {
        0 => {
            let i = rng.below(n);
            if let Some(x) = b.get_mut(i) {
                *x ^= 1 << rng.below(8);
            }
        }
        1 => {
            let i = rng.below(n);
            if let Some(x) = b.get_mut(i) {
                *x = [0, 0xff, 0x7f, 0x80, b'"', b'[', b'9'][rng.below(7)];
            }
        }
        2 => b.truncate(rng.below(n)),
        3 => {
            let (i, j) = (rng.below(n), rng.below(n));
            let len = b.len();
            b.drain(i.min(j).min(len)..i.max(j).min(len));
        }
        _ => {
            let i = rng.below(n).min(b.len());
            let chunk: Vec<u8> = b[i..(i + 16).min(b.len())].to_vec();
            b.splice(i..i, chunk);
        }
    }
}

/// The seeded fuzzer: about 52,000 inputs (structured JSON mutations of the .gltf files, byte
/// mutations of every file, one to three mutations each), each imported under
/// `catch_unwind`. Any panic fails the test and names the seed and input.
#[test]
fn mutated_gltf_never_panics() {
    let (_dir, scene_dir) = workspace();
    let files = corpus();
    // Fixed by default; LIGHTLAB_FUZZ_SEED and LIGHTLAB_FUZZ_ROUNDS explore further by hand.
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let rounds = env("LIGHTLAB_FUZZ_ROUNDS").unwrap_or(600);
    let mut rng = Rng(env("LIGHTLAB_FUZZ_SEED").unwrap_or(0x6c69_6768_746c_6162));
    let mut panics = vec![];
    let (mut inputs, mut loaded) = (0usize, 0usize);
    let start = std::time::Instant::now();
    // Silence the message of each caught panic on this test's thread (counted below instead);
    // other threads' panics are reported as usual.
    static WHERE: std::sync::Mutex<String> = std::sync::Mutex::new(String::new());
    static FUZZING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(true);
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let fuzzing = FUZZING.load(std::sync::atomic::Ordering::Relaxed);
        if !fuzzing || std::thread::current().name() != Some("mutated_gltf_never_panics") {
            hook(info)
        } else if let Some(l) = info.location() {
            *WHERE.lock().unwrap() = format!("{}:{}", l.file(), l.line());
        }
    }));
    for round in 0..rounds {
        for (name, bytes) in &files {
            let structured = name.ends_with(".gltf") && bytes.len() < 100_000;
            let mut tries = vec![];
            if structured && let Ok(mut v) = serde_json::from_slice::<serde_json::Value>(bytes) {
                for _ in 0..=rng.below(3) {
                    mutate_json(&mut v, &mut rng);
                }
                tries.push(serde_json::to_vec(&v).unwrap());
            }
            let mut b = bytes.clone();
            for _ in 0..=rng.below(3) {
                mutate_bytes(&mut b, &mut rng);
            }
            tries.push(b);
            for input in tries {
                inputs += 1;
                match load(&scene_dir, name, &input) {
                    Err(p) => {
                        let msg = p
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                            .unwrap_or_default();
                        let at = WHERE.lock().unwrap().clone();
                        panics.push(format!("round {round}, {name}: {msg} at {at}"))
                    }
                    Ok(Ok(_)) => loaded += 1,
                    Ok(Err(_)) => {}
                }
                if panics.len() == 1 && panics[0].starts_with(&format!("round {round}, {name}")) {
                    std::fs::write(
                        std::env::temp_dir().join("lightlab-fuzz-panic.gltf"),
                        &input,
                    )
                    .ok();
                }
            }
        }
    }
    FUZZING.store(false, std::sync::atomic::Ordering::Relaxed);
    eprintln!(
        "glTF fuzz: {inputs} inputs, {loaded} loaded, {} panics, {:.1} s",
        panics.len(),
        start.elapsed().as_secs_f64()
    );
    assert!(inputs as u64 >= rounds * 80, "only {inputs} inputs ran");
    assert!(
        panics.is_empty(),
        "{} of {inputs} inputs panicked (first written to {}): {:?}",
        panics.len(),
        std::env::temp_dir()
            .join("lightlab-fuzz-panic.gltf")
            .display(),
        &panics[..panics.len().min(10)]
    );
}
