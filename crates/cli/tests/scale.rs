//! Sharded bakes and renders (`--shard I/N`, `lightlab merge`): the merge equals the
//! one-machine result byte for byte, apart from the manifest's bake id and timings, and it
//! refuses parts that do not make one whole.

mod common;
use common::{lightlab, ok, stderr};
use std::path::{Path, PathBuf};

/// Small path-gathered light-map bakes.
const PATH: &[&str] = &[
    "--method",
    "path",
    "--texels-per-metre",
    "3",
    "--gather-samples",
    "6",
    "--gather-depth",
    "3",
];

/// Small SH light-map bakes (inter-reflected transfer, with its k-means compressed copy).
const SH: &[&str] = &[
    "--method",
    "sh",
    "--texels-per-metre",
    "3",
    "--transfer-samples",
    "16",
    "--compress",
    "8",
];

fn bake(scene: &str, out: &Path, extra: &[&str]) {
    let mut args = vec!["bake", "--scene", scene, "--out", out.to_str().unwrap()];
    if !extra.contains(&"sh") {
        args.extend_from_slice(PATH);
    }
    args.extend_from_slice(extra);
    ok(&lightlab(&args));
}

fn merge(parts: &[PathBuf], out: &Path) -> std::process::Output {
    let mut args = vec!["merge".to_string()];
    args.extend(parts.iter().map(|p| p.to_string_lossy().into_owned()));
    args.extend(["--out".into(), out.to_string_lossy().into_owned()]);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    lightlab(&a)
}

/// A manifest without its bake id and timing fields.
fn manifest_sans_timings(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("manifest.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["integrity"]
        .as_object_mut()
        .unwrap()
        .remove("bake_id")
        .unwrap();
    // Light-map bakes keep their timings in `stats`, SH bakes in `seconds` (and the
    // compressed copy's in its stats).
    if let Some(stats) = v.get_mut("stats").and_then(|s| s.as_object_mut()) {
        for k in ["seconds_layout", "seconds_solve", "seconds_total"] {
            stats.remove(k).unwrap();
        }
    } else {
        v.as_object_mut().unwrap().remove("seconds").unwrap();
        if let Some(c) = v.get_mut("compressed").and_then(|c| c.get_mut("stats")) {
            c.as_object_mut().unwrap().remove("seconds").unwrap();
        }
    }
    v
}

/// Every file of `a` equals `b`'s byte for byte, the manifests apart from their timings.
fn assert_same_bake(a: &Path, b: &Path) {
    let names = |d: &Path| {
        let mut n: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        n.sort();
        n
    };
    assert_eq!(names(a), names(b));
    for n in names(a).iter().filter(|n| *n != "manifest.json") {
        let (x, y) = (
            std::fs::read(a.join(n)).unwrap(),
            std::fs::read(b.join(n)).unwrap(),
        );
        assert!(
            x == y,
            "{n} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
    assert_eq!(manifest_sans_timings(a), manifest_sans_timings(b));
}

fn shards(scene: &str, dir: &Path, n: u32, extra: &[&str]) -> Vec<PathBuf> {
    (0..n)
        .map(|i| {
            let p = dir.join(format!("{scene}-{n}-{}-part-{i}", extra.len()));
            let spec = format!("{i}/{n}");
            let mut e = vec!["--shard", spec.as_str()];
            e.extend_from_slice(extra);
            bake(scene, &p, &e);
            p
        })
        .collect()
}

#[test]
fn sharded_bakes_and_renders_merge_to_the_one_machine_result() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let cases = [
        ("cornell", &["--png", "--gltf"][..]),
        ("room", &[][..]),
        ("cornell", SH),
        ("room", SH),
    ];
    for (scene, extra) in cases {
        let whole = t.join(format!("{scene}-{}-whole", extra.len()));
        bake(scene, &whole, extra);
        for n in [1, 3, 7] {
            let parts = shards(scene, t, n, extra);
            let merged = t.join(format!("{scene}-{}-merged-{n}", extra.len()));
            // Any order of the parts.
            let mut order = parts.clone();
            order.reverse();
            ok(&merge(&order, &merged));
            assert_same_bake(&whole, &merged);
        }
    }
    // A reference render, as rows of three shards.
    let render = |extra: &[&str], out: &Path| {
        let mut args = vec![
            "render", "--scene", "cornell", "--width", "40", "--height", "30", "--spp", "4", "-o",
        ];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        ok(&lightlab(&args));
    };
    let whole = t.join("whole.exr");
    render(&[], &whole);
    let parts: Vec<PathBuf> = (0..3)
        .map(|i| {
            let p = t.join(format!("render-part-{i}"));
            render(&["--shard", &format!("{i}/3")], &p);
            p
        })
        .collect();
    let merged = t.join("merged.exr");
    ok(&merge(&parts, &merged));
    assert!(std::fs::read(&whole).unwrap() == std::fs::read(&merged).unwrap());
    // A part rendered through another lens belongs to another render.
    let lens = t.join("render-part-lens");
    render(&["--shard", "2/3", "--camera-model", "lens:doublet"], &lens);
    let o = merge(
        &[parts[0].clone(), parts[1].clone(), lens],
        &t.join("mixed.exr"),
    );
    assert!(!o.status.success(), "a part through another lens merged");
    assert!(
        stderr(&o).contains("render settings differs"),
        "{}",
        stderr(&o)
    );
    assert!(!t.join("mixed.exr").exists());
}

#[test]
fn merges_refuse_missing_doubled_and_foreign_parts_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let parts = shards("cornell", t, 3, &[]);
    let other = shards("room", t, 3, &[]);
    let out = t.join("merged");
    let fails = |parts: &[PathBuf], needle: &str| {
        let o = merge(parts, &out);
        let e = stderr(&o);
        assert!(!o.status.success() && e.contains(needle), "{needle}: {e}");
        assert!(!out.exists(), "a failed merge left {}", out.display());
    };
    fails(&parts[..2], "part 2/3 missing");
    fails(&[parts[1].clone()], "parts 0/3, 2/3 missing");
    fails(
        &[parts[0].clone(), parts[1].clone(), parts[0].clone()],
        "part 0/3 is given twice",
    );
    let foreign = [parts[0].clone(), parts[1].clone(), other[2].clone()];
    fails(
        &foreign,
        &format!("{} belongs to another bake", other[2].display()),
    );
    // A part of another shard count, and a damaged part.
    let four = shards("cornell", t, 4, &[]);
    fails(
        &[parts[0].clone(), parts[1].clone(), four[2].clone()],
        "shard count differs",
    );
    let values = parts[2].join("values.bin");
    let mut bytes = std::fs::read(&values).unwrap();
    bytes[0] ^= 1;
    std::fs::write(&values, bytes).unwrap();
    fails(&parts, "values.bin");
    // Radiosity and SH shooting (CaSHL) are one global iteration: refused with the reason.
    let refused = |method: &[&str], needle: &str| {
        let out = t.join("refused");
        let mut args = vec!["bake", "--scene", "cornell", "--shard", "0/2"];
        args.extend_from_slice(method);
        args.extend(["--out", out.to_str().unwrap()]);
        let o = lightlab(&args);
        assert!(
            !o.status.success() && stderr(&o).contains(needle),
            "{}",
            stderr(&o)
        );
        assert!(!out.exists());
    };
    refused(&["--method", "radiosity"], "radiosity cannot be sharded");
    refused(
        &["--method", "sh", "--transfer", "shooting"],
        "shooting (CaSHL) cannot be sharded",
    );
    // An SH part does not join a light-map bake.
    let sh = shards("cornell", t, 3, SH);
    fails(
        &[parts[0].clone(), parts[1].clone(), sh[2].clone()],
        "kind of bake differs",
    );
}

/// The Slurm scripts of `deploy/`, run as plain processes with the variables Slurm sets: four
/// array tasks, then the merge, equal the one-machine bake (`bench/slurm_shards.sh` runs the
/// same scripts under a real Slurm).
#[test]
fn the_slurm_scripts_bake_and_merge_as_one_machine_does() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let script = |name: &str, task: Option<u32>| {
        let mut c = std::process::Command::new("sh");
        c.arg(root.join("deploy/slurm").join(name))
            .env("LIGHTLAB", env!("CARGO_BIN_EXE_lightlab"))
            .env("SCENE", "room")
            .env("WORK", t)
            .env("SHARDS", "4")
            .env("BAKE_ARGS", PATH.join(" "))
            .env_remove("JOB_COMPLETION_INDEX");
        if let Some(i) = task {
            c.env("SLURM_ARRAY_TASK_ID", i.to_string());
        }
        ok(&c.output().expect("sh runs"));
    };
    for i in 0..4 {
        script("bake.sbatch", Some(i));
    }
    script("merge.sbatch", None);
    let whole = t.join("whole");
    bake("room", &whole, &[]);
    assert_same_bake(&whole, &t.join("baked"));
}
