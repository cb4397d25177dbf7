//! Outputs that appear whole or not at all.
//!
//! Every file lightlab writes goes to a temporary sibling (`.NAME.PID.tmp`) that is renamed
//! into place once complete ([`write_atomic`]); bake folders are staged as a whole in a sibling
//! folder by `lightlab-bake`. While a temporary exists it is listed in a process-wide registry,
//! so that a signal handler can remove what is in flight before the process exits
//! ([`remove_in_flight`]; the CLI installs one for SIGINT, SIGTERM and SIGHUP). A process killed
//! outright (SIGKILL, power loss) leaves its temporaries behind; the next write beside them
//! removes those whose process is gone ([`remove_stale`]).
//!
//! Written here rather than taken from `tempfile`: the names must be predictable per output so
//! that leftovers of a dead process can be recognised and removed later, and the registry must
//! be reachable from a signal handler's thread.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// A temporary file or folder listed as in flight for as long as this value lives; dropping it
/// removes the path from the list (not from the disk).
pub struct InFlight(PathBuf);

impl InFlight {
    pub fn new(path: PathBuf) -> Self {
        if let Ok(mut v) = IN_FLIGHT.lock() {
            v.push(path.clone());
        }
        InFlight(path)
    }
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for InFlight {
    fn drop(&mut self) {
        if let Ok(mut v) = IN_FLIGHT.lock()
            && let Some(i) = v.iter().rposition(|p| *p == self.0)
        {
            v.swap_remove(i);
        }
    }
}

/// Set when the process is stopping (a signal): outputs written after it fail instead of
/// creating files in folders being removed.
static STOPPING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// An output may not start: the process is stopping.
fn refuse_if_stopping(path: &Path) -> Result<(), crate::image::ImageError> {
    if STOPPING.load(std::sync::atomic::Ordering::SeqCst) {
        return Err(crate::image::ImageError::Io {
            path: path.into(),
            source: std::io::Error::new(std::io::ErrorKind::Interrupted, "stopping"),
        });
    }
    Ok(())
}

/// Remove every temporary file and staging folder in flight (for a signal handler, just
/// before the process exits), after which no new output starts. Returns how many paths were
/// removed.
pub fn remove_in_flight() -> usize {
    STOPPING.store(true, std::sync::atomic::Ordering::SeqCst);
    remove_listed(|_| true)
}

fn remove_listed(which: impl Fn(&Path) -> bool) -> usize {
    let paths: Vec<PathBuf> = match IN_FLIGHT.lock() {
        Ok(v) => v.clone(),
        Err(p) => p.into_inner().clone(),
    };
    let mut n = 0;
    for p in paths.into_iter().filter(|p| which(p)) {
        let removed = if p.is_dir() {
            remove_dir_while_written(&p)
        } else {
            std::fs::remove_file(&p)
        };
        n += removed.is_ok() as usize;
    }
    n
}

/// Remove folder `p` although other threads of the process may still be writing into it (a
/// signal arrives mid-bake; the reliability test's SIGINT once left a staging folder behind):
/// a file created between `remove_dir_all`'s listing and its last `rmdir` makes it fail with
/// "directory not empty", so it tries again, up to 50 times over about 50 ms. New outputs
/// are refused once the process is stopping, so only the writes already under way can race.
fn remove_dir_while_written(p: &Path) -> std::io::Result<()> {
    let mut last = Ok(());
    for _ in 0..50 {
        match std::fs::remove_dir_all(p) {
            Ok(()) => return Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => last = Err(e),
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    last
}

/// Whether process `pid` may still be running. On systems without `/proc` every process is
/// taken as alive, so nothing of another process is ever removed there.
pub fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc = Path::new("/proc");
    !proc.is_dir() || proc.join(pid.to_string()).exists()
}

/// The temporary name of `path`'s output: `.NAME.PID.tmp` beside it.
pub fn temporary_name(path: &Path) -> PathBuf {
    let name = file_name(path);
    parent(path).join(format!(".{name}.{}.tmp", std::process::id()))
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into())
}

/// The folder `path` lies in (`.` for a bare name).
pub fn parent(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Remove the leftovers of dead processes beside `path`: siblings named `.NAME.PID<rest>`
/// (temporary files `.NAME.PID.tmp`, staging folders `.NAME.PID-K.staging`) whose PID is
/// not running. Returns how many were removed; errors are ignored (a leftover is harmless).
pub fn remove_stale(path: &Path) -> usize {
    let prefix = format!(".{}.", file_name(path));
    let Ok(entries) = std::fs::read_dir(parent(path)) else {
        return 0;
    };
    let mut n = 0;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = name.strip_prefix(&prefix) else {
            continue;
        };
        let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        let tail = &rest[digits.len()..];
        let ours = tail == ".tmp" || (tail.starts_with('-') && tail.ends_with(".staging"));
        let Ok(pid) = digits.parse::<u32>() else {
            continue;
        };
        if !ours || process_alive(pid) {
            continue;
        }
        let p = e.path();
        let removed = if p.is_dir() {
            std::fs::remove_dir_all(&p)
        } else {
            std::fs::remove_file(&p)
        };
        n += removed.is_ok() as usize;
    }
    n
}

/// Write `path` atomically: `write` fills a temporary sibling, which is renamed over `path`
/// when it succeeds and removed when it fails. Leftovers of dead processes beside `path` are
/// removed first.
pub fn write_atomic<E: From<crate::image::ImageError>>(
    path: &Path,
    write: impl FnOnce(File) -> Result<(), E>,
) -> Result<(), E> {
    refuse_if_stopping(path)?;
    remove_stale(path);
    let tmp = InFlight::new(temporary_name(path));
    let io = |e: std::io::Error, p: &Path| crate::image::ImageError::Io {
        path: p.into(),
        source: e,
    };
    let file = File::create(tmp.path()).map_err(|e| E::from(io(e, path)))?;
    let result = match write(file) {
        Ok(()) => std::fs::rename(tmp.path(), path).map_err(|e| E::from(io(e, path))),
        Err(e) => Err(e),
    };
    if result.is_err() {
        let _ = std::fs::remove_file(tmp.path());
    }
    result
}

/// Write several files as one output (a `.gltf` with its `.bin` and environment map): every
/// file is first written to its temporary, and only when all are complete are they renamed
/// into place, in the order given (the file that names the others last). A failure before
/// that leaves nothing behind, neither new files nor temporaries.
pub fn write_all_atomic(files: &[(PathBuf, Vec<u8>)]) -> Result<(), crate::image::ImageError> {
    let io = |e: std::io::Error, p: &Path| crate::image::ImageError::Io {
        path: p.into(),
        source: e,
    };
    // A destination that is a folder would fail its rename after the others succeeded.
    if let Some((path, _)) = files.iter().find(|(p, _)| p.is_dir()) {
        return Err(io(std::io::Error::other("is a folder"), path));
    }
    let mut temps = vec![];
    for (path, bytes) in files {
        refuse_if_stopping(path)?;
        remove_stale(path);
        let tmp = InFlight::new(temporary_name(path));
        let written = std::fs::write(tmp.path(), bytes).map_err(|e| io(e, path));
        temps.push(tmp);
        if let Err(e) = written {
            for t in &temps {
                let _ = std::fs::remove_file(t.path());
            }
            return Err(e);
        }
    }
    for (k, ((path, _), tmp)) in files.iter().zip(&temps).enumerate() {
        if let Err(e) = std::fs::rename(tmp.path(), path) {
            for t in &temps[k..] {
                let _ = std::fs::remove_file(t.path());
            }
            return Err(io(e, path));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// A signal handler removes a staging folder that worker threads are still filling (the
    /// reliability test's SIGINT mid-bake once left one behind): `remove_dir_all` alone fails
    /// when a file appears during it.
    #[test]
    fn a_folder_being_written_is_removed_whole() {
        for round in 0..10 {
            let tmp = tempfile::tempdir().unwrap();
            let dir = tmp.path().join(format!(".lm.{round}.staging"));
            std::fs::create_dir(&dir).unwrap();
            let writers: Vec<_> = (0..2)
                .map(|w| {
                    let dir = dir.clone();
                    std::thread::spawn(move || {
                        // Pages as a bake writes them: a few hundred per second per thread.
                        for i in 0..2000 {
                            let page = dir.join(format!("{w}-{i}"));
                            if std::fs::write(page, b"page").is_err() {
                                break;
                            }
                            std::thread::sleep(std::time::Duration::from_micros(200));
                        }
                    })
                })
                .collect();
            std::thread::sleep(std::time::Duration::from_millis(5));
            remove_dir_while_written(&dir).unwrap();
            for w in writers {
                w.join().unwrap();
            }
            assert!(!dir.exists(), "round {round}");
        }
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed_and_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.png");
        // Linux PIDs are at most 4194304 (2^22), so these processes cannot exist.
        let dead = [".out.png.4194305.tmp", ".out.png.4194306-3.staging"];
        for d in dead {
            std::fs::write(dir.path().join(d), b"x").unwrap();
        }
        let mine = format!(".out.png.{}.tmp", std::process::id());
        let other = [
            ".out.png.x.tmp",
            ".other.png.4194305.tmp",
            "out.png.4194305.tmp",
        ];
        for d in other.iter().copied().chain([mine.as_str()]) {
            std::fs::write(dir.path().join(d), b"x").unwrap();
        }
        let removed = remove_stale(&out);
        let left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        if Path::new("/proc").is_dir() {
            assert_eq!(removed, 2, "left: {left:?}");
            for d in dead {
                assert!(!left.iter().any(|l| l == d), "{d} was kept");
            }
        }
        assert!(
            left.contains(&mine),
            "the live process's temporary was removed"
        );
        for d in other {
            assert!(
                left.iter().any(|l| l == d),
                "{d} is not ours and was removed"
            );
        }
    }

    #[test]
    fn a_failed_write_leaves_nothing_and_in_flight_temporaries_can_be_removed() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.bin");
        let r: Result<(), crate::image::ImageError> = write_atomic(&out, |mut f| {
            f.write_all(b"half").unwrap();
            Err(crate::image::ImageError::Io {
                path: out.clone(),
                source: std::io::Error::other("disk full"),
            })
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        // A temporary in flight is removed as the signal handler removes it (only this test's,
        // so that other tests' writes in this process are not disturbed).
        let tmp = dir.path().join("staging");
        std::fs::create_dir(&tmp).unwrap();
        std::fs::write(tmp.join("page.exr"), b"x").unwrap();
        let mine = |p: &Path| p.starts_with(dir.path());
        let guard = InFlight::new(tmp.clone());
        assert_eq!(remove_listed(mine), 1);
        assert!(!tmp.exists());
        drop(guard);
        // Once dropped it is no longer listed: a new folder at that path survives.
        std::fs::create_dir(&tmp).unwrap();
        assert_eq!(remove_listed(mine), 0);
        assert!(tmp.exists());
    }
}
