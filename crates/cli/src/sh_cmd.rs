//! `lightlab sh project` and `lightlab sh irradiance`: spherical-harmonic coefficients and
//! irradiance maps of environment maps (the user job of Ramamoorthi–Hanrahan's `prefilter`).

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand, ValueEnum};
use lightlab_core::image::{Image, LdrSettings};
use lightlab_core::sh_env::{self, EnvFormat};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Clone, Copy, ValueEnum, Debug)]
pub enum FormatArg {
    /// 2:1 images are lat-long, square ones angular, 6:1 cube strips.
    Auto,
    Latlong,
    Angular,
    /// Six square faces side by side: +X, −X, +Y, −Y, +Z, −Z.
    CubeStrip,
}

/// The environment map shared by the `sh` subcommands.
#[derive(Args)]
pub struct EnvArgs {
    /// Environment map (HDR/EXR/PNG).
    #[arg(long)]
    env: PathBuf,
    /// Number of bands (l_max + 1), 1..=16.
    #[arg(long, default_value_t = 3)]
    bands: usize,
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    format: FormatArg,
}

#[derive(Subcommand)]
pub enum ShCommand {
    /// Print the RGB SH coefficients of an environment map.
    Project {
        #[command(flatten)]
        map: EnvArgs,
        /// Print one JSON object as the last line.
        #[arg(long)]
        json: bool,
    },
    /// Write the irradiance map (lat-long, linear EXR) of an environment map.
    Irradiance {
        #[command(flatten)]
        map: EnvArgs,
        /// Width of the output (height = width/2).
        #[arg(long, default_value_t = 256)]
        width: u32,
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// Read the map and settle its layout (checking the band count first).
fn load(args: &EnvArgs) -> Result<(Image, EnvFormat)> {
    let (env, format, bands) = (&args.env, args.format, args.bands);
    if !(1..=16).contains(&bands) {
        bail!("--bands must be in 1..=16 (got {bands})");
    }
    let img = Image::read(env)?;
    let f = match format {
        FormatArg::Latlong => EnvFormat::LatLong,
        FormatArg::Angular => EnvFormat::Angular,
        FormatArg::CubeStrip => EnvFormat::CubeStrip,
        FormatArg::Auto => EnvFormat::guess(img.width, img.height).with_context(|| {
            format!(
                "{}: cannot tell the layout of a {}×{} image (2:1 is lat-long, 1:1 angular from 8×8, 6:1 a cube strip); pass --format",
                env.display(),
                img.width,
                img.height
            )
        })?,
    };
    f.check(img.width, img.height)
        .with_context(|| format!("{} as --format {:?}", env.display(), format))?;
    Ok((img, f))
}

pub fn run(cmd: ShCommand) -> Result<()> {
    match cmd {
        ShCommand::Project { map, json } => {
            let (img, f) = load(&map)?;
            let bands = map.bands;
            let t = Instant::now();
            let c = sh_env::project_env(&img, f, bands);
            let secs = t.elapsed().as_secs_f64();
            for l in 0..bands {
                for m in -(l as isize)..=(l as isize) {
                    let v = c[lightlab_core::sh::index(l, m)];
                    println!("L{l}{m:+} {:>12.6} {:>12.6} {:>12.6}", v.x, v.y, v.z);
                }
            }
            eprintln!(
                "{}×{} {:?} map, {bands} bands, projected in {secs:.4} s",
                img.width, img.height, f
            );
            if json {
                let coeffs: Vec<[f64; 3]> = c.iter().map(|v| v.to_array()).collect();
                println!(
                    "{}",
                    serde_json::json!({ "bands": bands, "format": format!("{f:?}"), "width": img.width,
                        "height": img.height, "seconds": secs, "coefficients": coeffs })
                );
            }
            Ok(())
        }
        ShCommand::Irradiance { map, width, output } => {
            let (img, f) = load(&map)?;
            let bands = map.bands;
            if !(2..=16_384).contains(&width) {
                bail!("--width must be in 2..=16384");
            }
            let ext = lightlab_core::image::extension(&output);
            if ext != "exr" && ext != "png" {
                bail!("{}: the output must be .exr or .png", output.display());
            }
            let c = sh_env::project_env(&img, f, bands);
            let e = sh_env::irradiance_map(&c, width);
            e.write(&output, LdrSettings::default())?;
            eprintln!(
                "wrote {} (irradiance, {}×{})",
                output.display(),
                e.width,
                e.height
            );
            Ok(())
        }
    }
}
