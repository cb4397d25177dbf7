//! The bake-folder readers on mutated folders: manifests changed field by field (their
//! integrity records kept), pages changed byte by byte and sealed again with a correct
//! checksum (so that the decoders and size checks run, as for a forged folder), and manifests
//! changed byte by byte. No input may panic (see `lightlab_core::fuzz`).

use lightlab_bake::folder::{FileSum, checksum};
use lightlab_bake::layout::LayoutSettings;
use lightlab_bake::prt::{TransferKind, TransferSettings, bake_sh_lightmaps, vertex_transfer};
use lightlab_bake::sh_compress::{CompressSettings, compress};
use lightlab_bake::sh_folder::{read_sh_with_compressed, read_vertex_transfer, write_sh};
use lightlab_bake::{BakeSettings, bake_lightmaps, no_progress, output};
use lightlab_core::fuzz::Fuzzer;
use lightlab_scene::Scene;
use std::path::{Path, PathBuf};

fn scene() -> Scene {
    lightlab_scene::builtin::builtin("cornell").unwrap()
}

/// Three small bake folders of cornell: light-maps, SH light-maps with their compressed copy,
/// per-vertex transfer.
fn folders(root: &Path, scene: &Scene) -> Vec<(&'static str, PathBuf)> {
    let layout = LayoutSettings {
        texels_per_metre: 6.0,
        ..Default::default()
    };
    let mut s = BakeSettings {
        layout,
        ..Default::default()
    };
    s.gather.samples = 2;
    let lm = bake_lightmaps(scene, &s, &no_progress).unwrap();
    let lm_dir = root.join("lightmaps");
    output::write(&lm, &lm_dir, "cornell", output::Outputs::default()).unwrap();
    let t = TransferSettings {
        bands: 2,
        samples: 4,
        kind: TransferKind::Unshadowed,
        ..Default::default()
    };
    let sl = bake_sh_lightmaps(scene, &layout, &t, &no_progress).unwrap();
    let c = compress(
        &sl,
        &CompressSettings {
            representatives: 4,
            ..Default::default()
        },
    )
    .unwrap();
    let sh_dir = root.join("sh");
    write_sh(&sl, Some(&c), &sh_dir, "cornell", 0.0).unwrap();
    let accel = lightlab_trace::Accel::new(scene);
    let (vt, _) = vertex_transfer(scene, &accel, &t).unwrap();
    let vt_dir = root.join("vertex");
    lightlab_bake::sh_folder::write_vertex_transfer(&vt, scene, &t, &vt_dir, "cornell", 0.0)
        .unwrap();
    vec![("lightmaps", lm_dir), ("sh", sh_dir), ("vertex", vt_dir)]
}

fn read(kind: &str, dir: &Path, scene: &Scene) -> bool {
    match kind {
        "lightmaps" => output::read(dir, scene).is_ok(),
        "sh" => read_sh_with_compressed(dir, scene).is_ok(),
        _ => read_vertex_transfer(dir, scene).is_ok(),
    }
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    v.sort();
    v
}

/// Write `files` as folder `dir` (replacing it), with `changed` replacing one file; when
/// `seal`, the manifest's integrity record is updated to the changed file's checksum.
fn lay_out(dir: &Path, files: &[(String, Vec<u8>)], changed: (&str, &[u8]), seal: bool) {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    for (name, bytes) in files {
        let b = if name == changed.0 { changed.1 } else { bytes };
        std::fs::write(dir.join(name), b).unwrap();
    }
    if seal {
        let sum: FileSum = checksum(&dir.join(changed.0)).unwrap();
        let m = dir.join("manifest.json");
        let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(&m).unwrap()).unwrap();
        for f in v["integrity"]["files"].as_array_mut().unwrap() {
            if f["name"] == changed.0 {
                *f = serde_json::to_value(&sum).unwrap();
            }
        }
        std::fs::write(&m, serde_json::to_vec(&v).unwrap()).unwrap();
    }
}

#[test]
fn mutated_bake_folders_never_panic() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene();
    let folders = folders(tmp.path(), &scene);
    for (kind, dir) in &folders {
        assert!(
            read(kind, dir, &scene),
            "{kind}: the intact folder does not read"
        );
    }
    let work = tmp.path().join("work");
    let mut fuzz = Fuzzer::from_env(1000, 0x666f_6c64_6572);
    for round in 0..fuzz.rounds {
        for (kind, dir) in &folders {
            let files = files(dir);
            let manifest = &files.iter().find(|(n, _)| n == "manifest.json").unwrap().1;
            // A field of the manifest.
            if let Some(m) = fuzz.mutated_json(manifest) {
                lay_out(&work, &files, ("manifest.json", &m), false);
                fuzz.run(&format!("round {round}, {kind} manifest field"), &m, || {
                    read(kind, &work, &scene)
                });
            }
            // A page, sealed again.
            let pages: Vec<_> = files.iter().filter(|(n, _)| n != "manifest.json").collect();
            let (name, bytes) = pages[fuzz.rng.below(pages.len())];
            let page = fuzz.mutated_bytes(bytes);
            lay_out(&work, &files, (name, &page), true);
            fuzz.run(&format!("round {round}, {kind} {name}"), &page, || {
                read(kind, &work, &scene)
            });
            // The manifest's bytes.
            let m = fuzz.mutated_bytes(manifest);
            lay_out(&work, &files, ("manifest.json", &m), false);
            fuzz.run(&format!("round {round}, {kind} manifest bytes"), &m, || {
                read(kind, &work, &scene)
            });
        }
    }
    let min = 8 * fuzz.rounds as usize;
    fuzz.finish("bake folder", min);
}
