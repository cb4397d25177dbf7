//! Bake folders that are never half old and half new, and readers that verify what they load.
//!
//! A bake is written whole into a staging folder beside its destination
//! (`.NAME.PID-K.staging`), its `manifest.json` last, carrying a bake id and the size and CRC-32
//! of every other file. The staging folder then replaces the destination in one step: on Linux
//! by exchanging the two names (`renameat2(RENAME_EXCHANGE)`), after which the old bake is
//! removed; where the file system cannot exchange, by two renames (a crash between them leaves
//! the old bake under its staging name, and no folder at the destination). A crash or kill at
//! any other moment leaves the destination as it was: the old complete bake, or none.
//!
//! Readers ([`read_manifest`]) check the format and version before anything else, then that
//! every file the manifest lists is present with its size and checksum, so a page swapped in
//! from another bake, truncated or edited is refused with its name.
//!
//! A destination that exists must be empty or a bake folder (it has a `manifest.json`): a bake
//! replaces its folder as a whole, so it refuses to write over a folder of other files.

use crate::BakeError;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::{Path, PathBuf};

pub const MANIFEST: &str = "manifest.json";

/// Size and checksum of one file of a bake.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileSum {
    pub name: String,
    pub bytes: u64,
    pub crc32: u32,
}

/// What every manifest carries besides its own fields (the `integrity` object).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Integrity {
    /// Unique per bake: the time and process that wrote it.
    pub bake_id: String,
    /// Every file of the folder but the manifest, by name.
    pub files: Vec<FileSum>,
}

fn io(path: &Path, e: impl std::fmt::Display) -> BakeError {
    BakeError::Io(format!("{}: {e}", path.display()))
}

/// Size and CRC-32 of a file.
pub fn checksum(path: &Path) -> Result<FileSum, BakeError> {
    let bytes = std::fs::read(path).map_err(|e| io(path, e))?;
    let mut h = crc32fast::Hasher::new();
    h.update(&bytes);
    Ok(FileSum {
        name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        bytes: bytes.len() as u64,
        crc32: h.finalize(),
    })
}

/// Check `dir` before any work: it may be missing, empty, or a bake folder, nothing else.
pub fn check_destination(dir: &Path) -> Result<(), BakeError> {
    if !dir.exists() {
        return Ok(());
    }
    if !dir.is_dir() {
        return Err(io(dir, "exists and is not a folder"));
    }
    let mut entries = std::fs::read_dir(dir).map_err(|e| io(dir, e))?;
    if entries.next().is_none() || dir.join(MANIFEST).is_file() {
        return Ok(());
    }
    Err(io(
        dir,
        "is neither empty nor a bake folder (it has no manifest.json); a bake replaces its \
         folder as a whole, so choose a new or empty folder",
    ))
}

/// Write a bake folder at `dir`: `fill` writes every file into the staging folder it is given
/// and returns the manifest; the manifest is written last with the [`Integrity`] of the files,
/// and the staging folder replaces `dir` (see the module documentation). On any error nothing
/// at `dir` changes and the staging folder is removed.
pub fn write<M: Serialize>(
    dir: &Path,
    fill: impl FnOnce(&Path) -> Result<M, BakeError>,
) -> Result<M, BakeError> {
    check_destination(dir)?;
    let parent = lightlab_core::atomic::parent(dir);
    std::fs::create_dir_all(&parent).map_err(|e| io(&parent, e))?;
    lightlab_core::atomic::remove_stale(dir);
    let staging = lightlab_core::atomic::InFlight::new(staging_name(dir));
    let stage = staging.path().to_path_buf();
    std::fs::create_dir(&stage).map_err(|e| io(&stage, e))?;
    let result = fill(&stage).and_then(|m| {
        write_manifest(&stage, &m)?;
        commit(&stage, dir)?;
        Ok(m)
    });
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&stage);
    }
    result
}

fn staging_name(dir: &Path) -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "bake".into());
    let k = COUNT.fetch_add(1, Ordering::Relaxed);
    lightlab_core::atomic::parent(dir).join(format!(".{name}.{}-{k}.staging", std::process::id()))
}

fn bake_id() -> String {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    format!(
        "{}.{:09}-{}",
        t.as_secs(),
        t.subsec_nanos(),
        std::process::id()
    )
}

/// The manifest `m` with the integrity of every other file of `stage`, written last.
fn write_manifest<M: Serialize>(stage: &Path, m: &M) -> Result<(), BakeError> {
    let path = stage.join(MANIFEST);
    let mut names: Vec<PathBuf> = std::fs::read_dir(stage)
        .map_err(|e| io(stage, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.file_name().is_some_and(|n| n != MANIFEST))
        .collect();
    names.sort();
    let files = names
        .iter()
        .map(|p| checksum(p))
        .collect::<Result<_, _>>()?;
    let integrity = Integrity {
        bake_id: bake_id(),
        files,
    };
    let mut value = serde_json::to_value(m).map_err(|e| io(&path, e))?;
    let Value::Object(map) = &mut value else {
        return Err(io(&path, "a manifest must be a JSON object"));
    };
    map.insert(
        "integrity".into(),
        serde_json::to_value(&integrity).map_err(|e| io(&path, e))?,
    );
    let json = serde_json::to_string_pretty(&value).map_err(|e| io(&path, e))?;
    crate::output::write_bytes(&path, json.as_bytes())
}

/// Put the complete `stage` in the place of `dir`.
fn commit(stage: &Path, dir: &Path) -> Result<(), BakeError> {
    if !dir.exists() {
        return std::fs::rename(stage, dir).map_err(|e| io(dir, e));
    }
    if exchange(stage, dir) {
        // `stage` now holds the old bake.
        let _ = std::fs::remove_dir_all(stage);
        return Ok(());
    }
    let old = staging_name(dir);
    std::fs::rename(dir, &old).map_err(|e| io(dir, e))?;
    if let Err(e) = std::fs::rename(stage, dir) {
        let _ = std::fs::rename(&old, dir);
        return Err(io(dir, e));
    }
    let _ = std::fs::remove_dir_all(&old);
    Ok(())
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> bool {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).is_ok()
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> bool {
    false
}

/// A bake folder whose manifest was read and whose files were verified.
#[derive(Debug)]
pub struct Checked {
    pub dir: PathBuf,
    /// The manifest's path, for messages.
    pub manifest: PathBuf,
    files: Vec<String>,
}

impl Checked {
    /// The path of `name`, a verified file of the folder; any other name is an error naming
    /// the manifest (a manifest cannot make a reader open a file it did not checksum).
    pub fn file(&self, name: &str) -> Result<PathBuf, BakeError> {
        if self.files.iter().any(|f| f == name) {
            Ok(self.dir.join(name))
        } else {
            Err(io(
                &self.manifest,
                format!("names '{name}', which is not among the files of its integrity record"),
            ))
        }
    }

    /// Parse the manifest's JSON into its type; a field that does not parse is named.
    pub fn parse<M: serde::de::DeserializeOwned>(&self, value: Value) -> Result<M, BakeError> {
        serde_json::from_value(value).map_err(|e| io(&self.manifest, e))
    }
}

/// Read and check the manifest of a bake folder written by `lightlab bake --method METHOD`:
/// its format must be `format` and its version `version`, and every file it lists must be
/// present with its recorded size and checksum. Returns the checked folder and the JSON.
pub fn read_manifest(
    dir: &Path,
    format: &str,
    version: u32,
    method: &str,
) -> Result<(Checked, Value), BakeError> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        io(
            &path,
            format!("{e} (is this a folder written by `lightlab bake --method {method}`?)"),
        )
    })?;
    let value: Value = serde_json::from_str(&text).map_err(|e| io(&path, e))?;
    let found = value.get("format").and_then(Value::as_str);
    if found != Some(format) {
        return Err(io(
            &path,
            format!(
                "is {}; this needs {}",
                kind_of(found),
                kind_of(Some(format))
            ),
        ));
    }
    let v = value.get("version").and_then(Value::as_u64);
    if v != Some(version as u64) {
        return Err(io(
            &path,
            format!(
                "has version {}, this lightlab reads version {version}: bake it again",
                v.map_or("none".into(), |v| v.to_string())
            ),
        ));
    }
    let integrity: Integrity = value
        .get("integrity")
        .cloned()
        .ok_or_else(|| io(&path, "has no integrity record: bake it again"))
        .and_then(|i| serde_json::from_value(i).map_err(|e| io(&path, e)))?;
    verify(dir, &integrity)?;
    let checked = Checked {
        dir: dir.to_path_buf(),
        manifest: path,
        files: integrity.files.into_iter().map(|f| f.name).collect(),
    };
    Ok((checked, value))
}

/// What a folder of manifest format `format` is, and which bake writes it.
fn kind_of(format: Option<&str>) -> &'static str {
    match format {
        Some(crate::output::FORMAT) => "a light-map folder (`bake --method radiosity|path`)",
        Some(crate::sh_folder::SH_FORMAT) => {
            "an SH light-map folder (`bake --method sh|prt-textured`)"
        }
        Some(crate::sh_folder::VERTEX_FORMAT) => {
            "a per-vertex transfer folder (`bake --method prt`)"
        }
        Some(crate::shard::PART_FORMAT) => "a part of a sharded bake (`bake --shard I/N`)",
        Some(crate::shard::RENDER_PART_FORMAT) => {
            "a part of a sharded render (`render --shard I/N`)"
        }
        _ => "not a lightlab bake folder",
    }
}

/// Every file of `integrity` is in `dir` with its size and checksum.
pub fn verify(dir: &Path, integrity: &Integrity) -> Result<(), BakeError> {
    for f in &integrity.files {
        if f.name.contains(['/', '\\']) || f.name == ".." || f.name == "." {
            return Err(io(
                &dir.join(MANIFEST),
                format!("lists '{}', which is not a file of the folder", f.name),
            ));
        }
        let p = dir.join(&f.name);
        let sum = checksum(&p)?;
        if sum.bytes != f.bytes || sum.crc32 != f.crc32 {
            return Err(io(
                &p,
                format!(
                    "does not belong to this bake ({} bytes, CRC-32 {:08x}; the manifest of bake \
                     {} records {} bytes, {:08x}): the folder was changed after it was baked, \
                     bake it again",
                    sum.bytes, sum.crc32, integrity.bake_id, f.bytes, f.crc32
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize, serde::Deserialize, PartialEq, Debug)]
    struct M {
        format: String,
        version: u32,
        n: u32,
    }

    fn bake(dir: &Path, n: u32) -> Result<M, BakeError> {
        write(dir, |stage| {
            std::fs::write(stage.join("page-0.bin"), vec![n as u8; 100 + n as usize])
                .map_err(|e| io(stage, e))?;
            Ok(M {
                format: "test".into(),
                version: 1,
                n,
            })
        })
    }

    fn read(dir: &Path) -> Result<M, BakeError> {
        let (c, v) = read_manifest(dir, "test", 1, "test")?;
        c.file("page-0.bin")?;
        assert!(c.file("other.bin").is_err());
        c.parse(v)
    }

    #[test]
    fn a_rebake_replaces_the_folder_whole_and_a_failed_one_leaves_it() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out");
        bake(&dir, 1).unwrap();
        assert_eq!(read(&dir).unwrap().n, 1);
        bake(&dir, 2).unwrap();
        assert_eq!(read(&dir).unwrap().n, 2);
        // A failing bake changes nothing and leaves no staging folder.
        let r: Result<M, _> = write(&dir, |stage| {
            std::fs::write(stage.join("page-0.bin"), b"new").unwrap();
            Err(BakeError::Io("interrupted".into()))
        });
        assert!(r.is_err());
        assert_eq!(read(&dir).unwrap().n, 2);
        let names: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "a staging folder was left behind");
    }

    #[test]
    fn a_page_from_another_bake_or_a_changed_page_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
        bake(&a, 3).unwrap();
        bake(&b, 3).unwrap();
        // Same size, same content: accepted (it is the same bake's data).
        std::fs::copy(b.join("page-0.bin"), a.join("page-0.bin")).unwrap();
        read(&a).unwrap();
        // Same size, other content: refused, naming the file.
        std::fs::write(a.join("page-0.bin"), vec![9u8; 103]).unwrap();
        let e = read(&a).unwrap_err().to_string();
        assert!(
            e.contains("page-0.bin") && e.contains("does not belong"),
            "{e}"
        );
        std::fs::remove_file(a.join("page-0.bin")).unwrap();
        assert!(read(&a).unwrap_err().to_string().contains("page-0.bin"));
    }

    #[test]
    fn destinations_other_than_bake_folders_are_refused_before_any_work() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("mine");
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(dir.join("notes.txt"), b"keep me").unwrap();
        let mut ran = false;
        let r = write(&dir, |_| {
            ran = true;
            Ok(M {
                format: "test".into(),
                version: 1,
                n: 0,
            })
        });
        assert!(
            r.unwrap_err()
                .to_string()
                .contains("neither empty nor a bake folder")
        );
        assert!(!ran);
        assert_eq!(std::fs::read(dir.join("notes.txt")).unwrap(), b"keep me");
        let file = tmp.path().join("file");
        std::fs::write(&file, b"x").unwrap();
        assert!(check_destination(&file).is_err());
    }

    #[test]
    fn manifests_of_other_kinds_and_versions_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("sh");
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(
            dir.join(MANIFEST),
            r#"{"format": "lightlab-sh-lightmaps", "version": 2}"#,
        )
        .unwrap();
        let e = read_manifest(&dir, "lightlab-lightmaps", 2, "radiosity")
            .unwrap_err()
            .to_string();
        assert!(e.contains("SH light-map folder"), "{e}");
        std::fs::write(dir.join(MANIFEST), r#"{"format": "test", "version": 0}"#).unwrap();
        let e = read(&dir).unwrap_err().to_string();
        assert!(
            e.contains("version 0") && e.contains("bake it again"),
            "{e}"
        );
        std::fs::write(
            dir.join(MANIFEST),
            r#"{"format": "test", "version": 1, "integrity": {"bake_id": "x",
               "files": [{"name": "../escape", "bytes": 1, "crc32": 0}]}}"#,
        )
        .unwrap();
        assert!(
            read(&dir)
                .unwrap_err()
                .to_string()
                .contains("not a file of")
        );
    }
}
