//! `lightlab check DIR`: how the glTF files of a folder fare, one line each: load time, peak
//! memory of the load, the warnings and notices loading gave, and at default settings the
//! relMSE of `phong-shadow-maps` against `direct` and of `lightmap` against `reference`.
//!
//! Each file is loaded in this process (time, peak RSS since a reset of the counter); the
//! renders run as child `lightlab render` processes, so a file that fails or crashes a
//! technique is reported as such and the survey goes on.

use crate::options::LoadArgs;
use anyhow::{Context, Result};
use lightlab_core::image::{Image, LdrSettings};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Options of `lightlab check`.
#[derive(clap::Args, Clone, Debug)]
pub struct CheckArgs {
    /// A folder searched recursively for .gltf and .glb files (or one file).
    pub dir: PathBuf,
    /// Image width of the comparisons (height from the camera's aspect: square).
    #[arg(long, default_value_t = 64)]
    pub width: u32,
    /// Samples per pixel of `direct` and `reference`.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Skip the light-map bake and its comparison (the slow part on large files).
    #[arg(long)]
    pub no_lightmap: bool,
    /// Print one JSON object per file.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub load: LoadArgs,
}

/// Every .gltf/.glb under `dir`, sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    if dir.is_file() {
        return vec![dir.to_path_buf()];
    }
    let mut out = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            let ext = lightlab_core::image::extension(&p);
            if p.is_dir() {
                stack.push(p);
            } else if ext == "gltf" || ext == "glb" {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// relMSE of technique `a` against `b` on `file`, rendered by child processes; Err says why
/// a render failed (its last line of stderr).
fn relmse(file: &Path, a: &[&str], b: &[&str], c: &CheckArgs, tmp: &Path) -> Result<f64, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut images = vec![];
    for (k, args) in [a, b].into_iter().enumerate() {
        let out = tmp.join(format!("{k}.exr"));
        let mut cmd = Command::new(&exe);
        cmd.args(["render", "--scene"]).arg(file).args(args);
        cmd.args([
            "--width",
            &c.width.to_string(),
            "--spp",
            &c.spp.to_string(),
            "-o",
        ]);
        cmd.arg(&out);
        if c.load.allow_outside_paths {
            cmd.arg("--allow-outside-paths");
        }
        let o = cmd.output().map_err(|e| e.to_string())?;
        if !o.status.success() {
            let e = String::from_utf8_lossy(&o.stderr);
            let last = e
                .lines()
                .rev()
                .find(|l| l.contains("error"))
                .unwrap_or("failed");
            return Err(format!("{}: {}", args[1], last.trim()));
        }
        images.push(Image::read(&out).map_err(|e| e.to_string())?);
    }
    lightlab_core::metrics::compare(&images[0], &images[1], LdrSettings::default())
        .map(|c| c.relmse)
        .map_err(|e| e.to_string())
}

/// `lightlab check`.
pub fn run(c: &CheckArgs) -> Result<()> {
    let list = files(&c.dir);
    anyhow::ensure!(
        !list.is_empty(),
        "{}: no .gltf or .glb files found",
        c.dir.display()
    );
    let tmp = tempfile_dir()?;
    if !c.json {
        println!(
            "{:<40} {:>8} {:>8} {:>9} {:>9}  warnings",
            "file", "load s", "peak MB", "phong-sm", "lightmap"
        );
    }
    for file in list {
        crate::bench::reset_peak_memory();
        let t0 = Instant::now();
        let loaded = c.load.load_quietly(&file.to_string_lossy());
        let seconds = t0.elapsed().as_secs_f64();
        let peak = crate::bench::memory_mib().map(|m| m.1);
        let name = file
            .strip_prefix(&c.dir)
            .unwrap_or(&file)
            .to_string_lossy()
            .into_owned();
        let (warnings, phong, lightmap) = match loaded {
            Err(e) => (
                vec![format!("refused: {e}").replace(&format!("{}: ", file.display()), "")],
                None,
                None,
            ),
            Ok((_, notes)) => {
                // Short forms for the table: the file is named in its row.
                let spec = file.to_string_lossy().into_owned();
                let notes = notes
                    .iter()
                    .map(|n| {
                        if n.starts_with("notice:") && n.contains("default daylight") {
                            "no lights: default daylight".to_string()
                        } else {
                            n.replace(&format!("{spec}: "), "")
                        }
                    })
                    .collect();
                let phong = relmse(
                    &file,
                    &["--technique", "phong-shadow-maps"],
                    &["--technique", "direct"],
                    c,
                    &tmp,
                );
                let lightmap = (!c.no_lightmap).then(|| {
                    relmse(
                        &file,
                        &["--technique", "lightmap"],
                        &["--technique", "reference"],
                        c,
                        &tmp,
                    )
                });
                (notes, Some(phong), lightmap)
            }
        };
        let fig = |r: &Option<Result<f64, String>>| match r {
            Some(Ok(v)) => format!("{v:.4}"),
            Some(Err(_)) => "failed".into(),
            None => "-".into(),
        };
        let mut notes = warnings.clone();
        for r in [&phong, &lightmap].into_iter().flatten() {
            if let Err(e) = r {
                notes.push(e.clone());
            }
        }
        if c.json {
            let val = |r: &Option<Result<f64, String>>| match r {
                Some(Ok(v)) => serde_json::json!(v),
                _ => serde_json::Value::Null,
            };
            println!(
                "{}",
                serde_json::json!({
                    "file": name, "load_s": seconds, "peak_mb": peak,
                    "phong_shadow_maps_relmse": val(&phong), "lightmap_relmse": val(&lightmap),
                    "warnings": notes,
                })
            );
        } else {
            println!(
                "{:<40} {:>8.2} {:>8} {:>9} {:>9}  {}",
                name,
                seconds,
                peak.map_or("-".into(), |p| format!("{:.0}", p * 1.048_576)),
                fig(&phong),
                fig(&lightmap),
                notes.join("; ")
            );
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
    Ok(())
}

fn tempfile_dir() -> Result<PathBuf> {
    let d = std::env::temp_dir().join(format!("lightlab-check-{}", std::process::id()));
    std::fs::create_dir_all(&d).with_context(|| format!("creating {}", d.display()))?;
    Ok(d)
}
