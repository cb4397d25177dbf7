//! `lightlab`: the command line of the lightlab toolkit (see the README and DESIGN.md's
//! command-line contract).
//!
//! Exit codes: 0 success, 1 error (bad input, failed I/O), 2 not implemented yet.

mod bake_cmd;
mod bench;
mod demo;
mod lpv_cmd;
mod prt_cmd;
mod raster_cmd;
mod render;
mod sh_cmd;
mod view_cmd;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
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
        /// `low` finishes in about five minutes on two cores; `high` renders larger, cleaner
        /// images.
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
        options: bake_cmd::BakeArgs,
        /// Print the bake's figures as one JSON object on the last line.
        #[arg(long)]
        json: bool,
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
    Bench {
        #[arg(value_enum)]
        what: bench::BenchKind,
        #[arg(long)]
        scene: String,
        #[arg(long)]
        json: bool,
        /// Technique, for `bench frame`.
        #[arg(long)]
        technique: Option<String>,
        /// Rays per measurement, for `bench trace`.
        #[arg(long, default_value_t = 1_000_000)]
        rays: usize,
        /// Also write the triangles and rays of `bench trace` to this folder (for peers).
        #[arg(long)]
        dump: Option<PathBuf>,
        /// `bench trace`: ignore alpha (treat alpha-tested triangles as opaque).
        #[arg(long)]
        opaque: bool,
        #[command(flatten)]
        frame: raster_cmd::FrameBenchArgs,
        #[command(flatten)]
        raster: raster_cmd::RasterArgs,
        #[command(flatten)]
        bake: bake_cmd::BakeArgs,
        /// `bench frame` of a light-map technique: read the light-maps from this folder
        /// (written by `lightlab bake`) instead of baking them first.
        #[arg(long)]
        baked: Option<PathBuf>,
        #[command(flatten)]
        sh: prt_cmd::ShArgs,
        #[command(flatten)]
        lpv: lpv_cmd::LpvArgs,
    },
    /// Spherical harmonics of environment maps: coefficients and irradiance maps.
    #[command(subcommand)]
    Sh(sh_cmd::ShCommand),
    /// Interactive viewer: a window with the GPU techniques, an orbit camera and a panel.
    View(view_cmd::ViewArgs),
}

/// Tone operator choice on the command line.
#[derive(Clone, Copy, ValueEnum, Debug)]
pub enum ToneArg {
    Clamp,
    Reinhard,
    Filmic,
}

impl From<ToneArg> for ToneMap {
    fn from(t: ToneArg) -> Self {
        match t {
            ToneArg::Clamp => ToneMap::Clamp,
            ToneArg::Reinhard => ToneMap::Reinhard,
            ToneArg::Filmic => ToneMap::Filmic,
        }
    }
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

pub fn load_scene(spec: &str, drop_degenerate: bool) -> Result<lightlab_scene::Scene> {
    Ok(lightlab_scene::load(
        spec,
        lightlab_scene::LoadOptions { drop_degenerate },
    )?)
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
            json,
        } => {
            let scene = load_scene(&scene, false)?;
            bake_cmd::run(&scene, &method, &out, &options, json)
        }
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
        Command::Bench {
            what,
            scene,
            json,
            technique,
            rays,
            dump,
            opaque,
            frame,
            raster,
            bake,
            baked,
            sh,
            lpv,
        } => {
            if matches!(what, bench::BenchKind::Bake) {
                return bench::bench_bake(&scene, &bake, json);
            }
            if matches!(what, bench::BenchKind::Frame) {
                let t = technique.context("bench frame needs --technique")?;
                let mut s = load_scene(&scene, false)?;
                return raster_cmd::bench_frame(
                    &mut s,
                    &t,
                    &raster,
                    &frame,
                    &bake,
                    baked.as_deref(),
                    &sh,
                    &lpv,
                    json,
                );
            }
            bench::run(what, &scene, json, rays, dump, opaque)
        }
        Command::Sh(cmd) => sh_cmd::run(cmd),
        Command::View(a) => view_cmd::view(&a),
    }
}
