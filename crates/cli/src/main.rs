//! `lightlab`: the command line of the lightlab toolkit (its contract is the README's
//! "Commands" section).
//!
//! Exit codes: 0 success, 1 error (bad input, failed I/O), 2 not implemented yet.
//!
//! Modules: one per command (`bake_cmd`, `bench`, `demo`, `render`, `sh_cmd`, `view_cmd`);
//! `technique` (the registry of techniques), `techniques` (the one factory of GPU renderers,
//! by family), `options` (the option groups and their library settings), `progress`.

#[cfg(test)]
mod acceptance;
mod bake_cmd;
mod bench;
mod bench_canned;
mod bench_hprt;
mod bench_normals;
mod bench_refraction;
mod check;
mod demo;
mod options;
mod plot;
mod progress;
mod render;
mod sh_cmd;
mod technique;
mod techniques;
mod view_cmd;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use lightlab_core::color::ToneMap;
use lightlab_core::image::{Image, LdrSettings};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "lightlab",
    version,
    about = "Bake, render and measure real-time lighting methods against a path-traced reference."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The main job: render every technique on the built-in scenes and write DIR/report.html.
    Demo {
        /// Output folder (created if missing).
        #[arg(long, default_value = "demo-out")]
        out: PathBuf,
        /// `low` finishes in about twenty minutes on two cores; `high` renders larger,
        /// cleaner images.
        #[arg(long, value_enum, default_value_t = demo::Quality::Low)]
        quality: demo::Quality,
        /// Only these scenes (default: all built-in scenes).
        #[arg(long, value_delimiter = ',')]
        scenes: Vec<String>,
    },
    /// List the built-in scenes, one name per line.
    Scenes {
        /// Also print a description of each.
        #[arg(long, short)]
        verbose: bool,
    },
    /// Write a built-in scene as glTF 2.0 (.glb or .gltf).
    Export {
        #[arg(long)]
        scene: String,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Bake light transport (light-maps, SH/PRT, ...) for a scene.
    Bake {
        /// A built-in scene name or a .gltf/.glb path.
        #[arg(long)]
        scene: String,
        #[arg(long)]
        method: String,
        #[arg(long, default_value = "baked")]
        out: PathBuf,
        #[command(flatten)]
        options: options::BakeArgs,
        #[command(flatten)]
        load: options::LoadArgs,
        /// Print the bake's figures as one JSON object on the last line.
        #[arg(long)]
        json: bool,
        /// Bake only shard I of N (counted from 0) into a part folder for `lightlab merge`;
        /// `auto/N` reads I from JOB_COMPLETION_INDEX (Kubernetes) or SLURM_ARRAY_TASK_ID
        /// (Slurm). Path-gathered light-maps only (see docs/scale.md).
        #[arg(long, value_name = "I/N")]
        shard: Option<String>,
    },
    /// Assemble the part folders of a sharded bake (`bake --shard I/N`) into the bake one
    /// machine would have made; fails, writing nothing, when a part is missing, doubled or
    /// from another bake.
    Merge {
        /// The part folders, in any order.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        /// The scene, when it is not where the parts' manifests say (the bake's `--scene`).
        #[arg(long)]
        scene: Option<String>,
        #[command(flatten)]
        load: options::LoadArgs,
    },
    /// Render a scene with a technique (`reference`, `direct`, ...).
    Render(render::RenderArgs),
    /// Compare two images of equal size: RMSE, relMSE and FLIP (B is the reference).
    Compare {
        a: PathBuf,
        b: PathBuf,
        /// Print one JSON object as the last line.
        #[arg(long)]
        json: bool,
        /// Exposure applied to both images before FLIP's tone mapping.
        #[arg(long, default_value_t = 1.0)]
        exposure: f32,
    },
    /// Benchmarks that print figures: `trace` (ray casting), `bake`, `frame`.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Spherical harmonics of environment maps: coefficients and irradiance maps.
    #[command(subcommand)]
    Sh(sh_cmd::ShCommand),
    /// Interactive viewer: a window with the GPU techniques, an orbit camera and a panel.
    View(view_cmd::ViewArgs),
    /// Survey the glTF files of a folder: load time, peak memory, warnings, and the relMSE of
    /// phong-shadow-maps against direct and of lightmap against reference.
    Check(check::CheckArgs),
}

/// An error for features that later work will add: exit code 2.
#[derive(Debug)]
pub struct NotImplemented(pub String);

impl std::fmt::Display for NotImplemented {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "not implemented yet: {}", self.0)
    }
}

impl std::error::Error for NotImplemented {}

pub fn not_implemented(what: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(NotImplemented(what.into()))
}

fn main() -> ExitCode {
    // Rust ignores SIGPIPE, so `lightlab compare a b | head -1` panicked in println! once the
    // reader had gone; like other command-line tools, end quietly instead.
    // SAFETY: the first statement of `main`, before any other thread exists.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    quiet_device_select();
    remove_unfinished_outputs_on_signals();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            // clap exits 2 on a usage error; lightlab keeps 2 for "not implemented yet", so a
            // mistyped option is an ordinary error (1). Help and version exit 0.
            return ExitCode::from(if e.use_stderr() { 1 } else { 0 });
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if e.downcast_ref::<NotImplemented>().is_some() {
                eprintln!("lightlab: {e}");
                return ExitCode::from(2);
            }
            eprintln!("lightlab: error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::from(1)
        }
    }
}

/// Without a desktop session (no `XDG_RUNTIME_DIR`), Mesa's Vulkan device-select layer tries
/// to reach a Wayland compositor and prints "error: XDG_RUNTIME_DIR is invalid or not set"
/// twice on every headless run, although nothing failed. The layer only orders GPUs, which
/// wgpu does by power preference anyway, so it is turned off there (`NODEVICE_SELECT=1`,
/// unless the user set it).
fn quiet_device_select() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("NODEVICE_SELECT").is_none()
    {
        // SAFETY: the first statement of `main`, before any other thread exists.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

/// On SIGINT, SIGTERM or SIGHUP, remove every temporary file and staging folder in flight
/// (`lightlab_core::atomic`) and exit with 128 + the signal, as a shell reports it: an
/// interrupted `render` or `bake` leaves the previous output whole and no temporaries.
fn remove_unfinished_outputs_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            let n = lightlab_core::atomic::remove_in_flight();
            eprintln!("lightlab: interrupted (signal {sig}); removed {n} unfinished output(s)");
            std::process::exit(128 + sig);
        }
    });
}

/// A GPU context, with the adapter named on stderr.
pub fn gpu_context() -> Result<lightlab_gpu::GpuContext> {
    let ctx = lightlab_gpu::GpuContext::headless()?;
    eprintln!(
        "GPU: {} ({:?}, {})",
        ctx.info.name, ctx.info.backend, ctx.info.driver
    );
    Ok(ctx)
}

/// Load a scene, printing what loading dropped or changed as warnings.
pub fn load_scene(spec: &str, load: &options::LoadArgs) -> Result<lightlab_scene::Scene> {
    load.load(spec)
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Demo {
            out,
            quality,
            scenes,
        } => demo::run(&out, quality, &scenes),
        Command::Scenes { verbose } => {
            for name in lightlab_scene::builtin::NAMES {
                if verbose {
                    println!(
                        "{name}\t{}",
                        lightlab_scene::builtin::describe(name).unwrap_or("")
                    );
                } else {
                    println!("{name}");
                }
            }
            Ok(())
        }
        Command::Export { scene, output } => {
            let s = lightlab_scene::builtin::builtin(&scene).with_context(|| {
                format!("unknown built-in scene '{scene}' (see `lightlab scenes`)")
            })?;
            lightlab_scene::gltf_io::export(&s, &output)?;
            eprintln!(
                "wrote {} ({} triangles)",
                output.display(),
                s.triangle_count()
            );
            Ok(())
        }
        Command::Bake {
            scene,
            method,
            out,
            options,
            load,
            json,
            shard,
        } => {
            let spec = scene;
            let scene = load_scene(&spec, &load)?;
            match shard {
                Some(shard) => bake_cmd::run_shard(&scene, &spec, &method, &out, &options, &shard),
                None => bake_cmd::run(&scene, &method, &out, &options, json),
            }
        }
        Command::Merge {
            parts,
            out,
            scene,
            load,
        } => bake_cmd::merge(&parts, &out, scene.as_deref(), &load),
        Command::Render(args) => render::run(args),
        Command::Compare {
            a,
            b,
            json,
            exposure,
        } => {
            let ia = Image::read(&a)?;
            let ib = Image::read(&b)?;
            let ldr = LdrSettings {
                exposure,
                tone: ToneMap::Filmic,
            };
            let c = lightlab_core::metrics::compare(&ia, &ib, ldr)
                .with_context(|| format!("comparing {} with {}", a.display(), b.display()))?;
            if json {
                println!("{}", serde_json::to_string(&c)?);
            } else {
                println!("RMSE   {:.6}", c.rmse);
                println!("relMSE {:.6}", c.relmse);
                println!("FLIP   {:.6}", c.flip);
                let m = c.mean_ratio;
                println!("mean A/B {:.4} {:.4} {:.4}", m[0], m[1], m[2]);
            }
            Ok(())
        }
        Command::Bench(cmd) => bench::run(cmd),
        Command::Sh(cmd) => sh_cmd::run(cmd),
        Command::View(a) => view_cmd::view(&a),
        Command::Check(a) => check::run(&a),
    }
}
