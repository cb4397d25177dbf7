//! `lightlab demo`: the main job. Renders every built-in scene with every technique built so far
//! and writes `DIR/report.html` with the images, errors against the reference, timings and
//! settings. Each later technique adds its rows here.

use crate::render::render_reference;
use anyhow::{Context, Result};
use clap::ValueEnum;
use lightlab_core::image::{LdrSettings, write_atomic};
use lightlab_trace::RenderSettings;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

#[derive(Clone, Copy, ValueEnum, Debug, PartialEq)]
pub enum Quality {
    /// Tiny images in seconds: a smoke run of the whole pipeline.
    Preview,
    /// The default: about five minutes on two cores.
    Low,
    /// Larger, cleaner images.
    High,
}

/// Image size and samples per scene at each quality. `low` is sized for about five minutes on
/// a 2-core machine in total.
fn settings_for(scene: &str, q: Quality) -> RenderSettings {
    let (w, h, spp) = match (scene, q) {
        (_, Quality::Preview) => (48, 48, 4),
        ("cornell", Quality::Low) => (256, 256, 256),
        ("cornell", Quality::High) => (512, 512, 2048),
        ("room", Quality::Low) => (320, 240, 192),
        ("spheres", Quality::Low) => (320, 240, 192),
        (_, Quality::Low) => (320, 240, 128),
        (_, Quality::High) => (640, 480, 1024),
    };
    RenderSettings {
        width: w,
        height: h,
        spp,
        max_depth: 16,
        seed: 1,
        ..Default::default()
    }
}

struct Row {
    scene: String,
    technique: String,
    file: String,
    settings: RenderSettings,
    seconds: f64,
    triangles: usize,
    /// Error against the scene's `reference` image (None for the reference itself).
    error: Option<lightlab_core::metrics::Comparison>,
    /// GPU techniques: the frame time (GPU timestamps, else wall clock) and what it was on.
    frame: Option<(f64, String)>,
}

pub fn run(out: &Path, quality: Quality, only: &[String]) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let names: Vec<&str> = if only.is_empty() {
        lightlab_scene::builtin::NAMES.to_vec()
    } else {
        for n in only {
            anyhow::ensure!(
                lightlab_scene::builtin::NAMES.contains(&n.as_str()),
                "unknown built-in scene '{n}' (see `lightlab scenes`)"
            );
        }
        only.iter().map(|s| s.as_str()).collect()
    };
    let start = Instant::now();
    let mut rows = vec![];
    // The GPU techniques need an adapter (lavapipe will do); without one they are left out of
    // the report with a note rather than failing the whole demo.
    let gpu = match crate::raster_cmd::context() {
        Ok(c) => Some(c),
        Err(e) => {
            eprintln!("GPU techniques skipped: {e:#}");
            None
        }
    };
    for name in names {
        let scene = lightlab_scene::builtin::builtin(name).expect("built-in");
        let mut reference: Option<lightlab_core::image::Image> = None;
        for technique in ["reference", "direct"] {
            let mut settings = settings_for(name, quality);
            if technique == "direct" {
                settings.spp = (settings.spp / 2).max(8);
            }
            let t = Instant::now();
            let img = render_reference(&scene, technique, &settings)?;
            let seconds = t.elapsed().as_secs_f64();
            let file = format!("{name}-{technique}");
            let error = save_and_compare(out, &file, &img, reference.as_ref())?;
            eprintln!(
                "{name:<8} {technique:<10} {:>4}×{:<4} {:>5} spp {seconds:>7.1} s",
                settings.width, settings.height, settings.spp
            );
            if technique == "reference" {
                reference = Some(img);
            }
            rows.push(Row {
                scene: name.into(),
                technique: technique.into(),
                file,
                settings,
                seconds,
                triangles: scene.triangle_count(),
                error,
                frame: None,
            });
        }
        if let Some(ctx) = &gpu {
            let settings = settings_for(name, quality);
            // Same light model as the reference (physical fall-off), 2×2 supersampled.
            let args = crate::raster_cmd::RasterArgs {
                attenuation: "inverse-square".into(),
                ssaa: 2,
                ..Default::default()
            };
            // Light-maps on the scenes baked light is for (texel density per scene).
            let density = match name {
                "cornell" => Some(32.0),
                "room" => Some(10.0),
                "shadows" => Some(8.0),
                _ => None,
            };
            let lightmap_techniques = density
                .map(|_| crate::bake_cmd::LIGHTMAP_TECHNIQUES.to_vec())
                .unwrap_or_default();
            // The SH techniques on the scene made for them: one SH light-map bake serves shl,
            // prt-textured and shl-compressed; shl-normalmapped bakes its own.
            let sh_techniques = if name == "prt" {
                crate::prt_cmd::SH_TECHNIQUES.to_vec()
            } else {
                vec![]
            };
            // Light propagation volumes on the scenes of the LPV issue: the leafy bush, cornell
            // and the room (default settings: 32³, 8 steps, RSM 256²).
            let lpv_techniques = if matches!(name, "bush" | "cornell" | "room") {
                crate::lpv_cmd::LPV_TECHNIQUES.to_vec()
            } else {
                vec![]
            };
            let lpv_args = crate::lpv_cmd::LpvArgs::default();
            let sh_bake = crate::bake_cmd::BakeArgs {
                texels_per_metre: 12.0,
                transfer_samples: match quality {
                    Quality::Preview => 32,
                    Quality::Low => 64,
                    Quality::High => 512,
                },
                bounces: Some(1),
                ..Default::default()
            };
            let sh_args = crate::prt_cmd::ShArgs::default();
            let mut sh_lightmaps = None;
            for technique in crate::raster_cmd::RASTER_TECHNIQUES
                .into_iter()
                .chain(lightmap_techniques)
                .chain(sh_techniques)
                .chain(lpv_techniques)
            {
                let t = Instant::now();
                let (img, times) = if crate::prt_cmd::SH_TECHNIQUES.contains(&technique) {
                    use crate::prt_cmd::{ShData, compressed, render_sh, sh_data_for};
                    let data = match technique {
                        // Per-vertex transfer, and the normal-mapped SH light-maps (their own
                        // bake, Fuchs §5.7).
                        "prt-vertex" | "shl-normalmapped" => {
                            sh_data_for(&scene, technique, None, &sh_bake, &sh_args)?
                        }
                        _ => {
                            if sh_lightmaps.is_none() {
                                match sh_data_for(&scene, "shl", None, &sh_bake, &sh_args)? {
                                    ShData::Textured(sl) => sh_lightmaps = Some(sl),
                                    _ => anyhow::bail!("the shl bake gave per-vertex data"),
                                }
                            }
                            let sl = sh_lightmaps.clone().expect("baked above");
                            if technique == "shl-compressed" {
                                compressed(sl, &sh_args)?
                            } else {
                                ShData::Textured(sl)
                            }
                        }
                    };
                    render_sh(
                        ctx,
                        &data,
                        technique,
                        &args,
                        &sh_args,
                        settings.width,
                        settings.height,
                        0,
                    )?
                } else if crate::lpv_cmd::LPV_TECHNIQUES.contains(&technique) {
                    crate::lpv_cmd::render_lpv(
                        ctx,
                        &scene,
                        technique,
                        &args,
                        &lpv_args,
                        settings.width,
                        settings.height,
                        0,
                    )?
                } else if let Some(tpm) = density.filter(|_| technique.starts_with("lightmap")) {
                    let bake = crate::bake_cmd::BakeArgs {
                        texels_per_metre: tpm,
                        samples: match quality {
                            Quality::Preview => 8,
                            Quality::Low => 64,
                            Quality::High => 512,
                        },
                        ..Default::default()
                    };
                    let lm = crate::bake_cmd::lightmaps_for(&scene, technique, None, &bake)?;
                    crate::bake_cmd::render_lightmap(
                        ctx,
                        &lm,
                        technique,
                        &args,
                        settings.width,
                        settings.height,
                        0,
                    )?
                } else {
                    crate::raster_cmd::render_raster(
                        ctx,
                        &scene,
                        technique,
                        &args,
                        settings.width,
                        settings.height,
                        0,
                    )?
                };
                let seconds = t.elapsed().as_secs_f64();
                let frame_ms = if times.gpu_ms.is_empty() {
                    times.wall_ms
                } else {
                    times.gpu_ms.values().sum()
                };
                let file = format!("{name}-{technique}");
                let error = save_and_compare(out, &file, &img, reference.as_ref())?;
                eprintln!(
                    "{name:<8} {technique:<20} {:>4}×{:<4} frame {frame_ms:>8.2} ms",
                    settings.width, settings.height
                );
                rows.push(Row {
                    scene: name.into(),
                    technique: technique.into(),
                    file,
                    settings: RenderSettings {
                        spp: 0,
                        ..settings.clone()
                    },
                    seconds,
                    triangles: scene.triangle_count(),
                    error,
                    frame: Some((
                        frame_ms,
                        format!("{} ({:?})", ctx.info.name, ctx.info.backend),
                    )),
                });
            }
        }
    }
    let total = start.elapsed().as_secs_f64();
    let report = out.join("report.html");
    let html = report_html(&rows, quality, total);
    write_atomic(&report, |mut f| -> Result<()> {
        Ok(f.write_all(html.as_bytes())?)
    })?;
    println!("report: {}", report.display());
    Ok(())
}

/// Write `DIR/FILE.exr` and `.png`, and measure the image against the scene's reference (every
/// technique is measured against the same scene's reference image; None for the reference).
fn save_and_compare(
    out: &Path,
    file: &str,
    img: &lightlab_core::image::Image,
    reference: Option<&lightlab_core::image::Image>,
) -> Result<Option<lightlab_core::metrics::Comparison>> {
    img.write(&out.join(format!("{file}.exr")), LdrSettings::default())?;
    img.write(&out.join(format!("{file}.png")), LdrSettings::default())?;
    Ok(match reference {
        Some(r) => Some(lightlab_core::metrics::compare(
            img,
            r,
            LdrSettings::default(),
        )?),
        None => None,
    })
}

fn report_html(rows: &[Row], quality: Quality, total: f64) -> String {
    let mut h = String::new();
    h.push_str("<!doctype html><html><head><meta charset=\"utf-8\"><title>lightlab demo</title><style>\
        body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse}\
        td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}th{background:#eee}\
        figure{display:inline-block;margin:0 1em 1em 0}figcaption{font-size:90%}</style></head><body>");
    h.push_str("<h1>lightlab demo report</h1>");
    h.push_str(&format!(
        "<p>lightlab {} · quality <b>{:?}</b> · {} threads · total {:.1} s. Technique <code>reference</code> is the \
         path-traced ground truth (unidirectional, NEE + MIS, Russian roulette), <code>direct</code> its direct-light-only \
         variant. <code>phong</code>, <code>phong-shadow-volumes</code> and <code>phong-shadow-maps</code> are the GPU \
         rasterisers (Fuchs 2005 §4; forward path, 2×2 supersampling, physical inverse-square fall-off so that they \
         compare with the reference; the ambient term is the environment's unshadowed SH irradiance; no indirect light, \
         area lights only as emissive surfaces). Images are linear EXR beside each PNG (filmic tone curve, exposure 1).</p>",
        env!("CARGO_PKG_VERSION"),
        quality,
        rayon::current_num_threads(),
        total
    ));
    let mut scene = "";
    for r in rows {
        if r.scene != scene {
            scene = &r.scene;
            h.push_str(&format!(
                "<h2>{}</h2><p>{} · {} triangles</p>",
                r.scene,
                lightlab_scene::builtin::describe(&r.scene).unwrap_or(""),
                r.triangles
            ));
        }
        if let Some((ms, adapter)) = &r.frame {
            h.push_str(&format!(
                "<figure><img src=\"{f}.png\" width=\"{w}\"><figcaption><b>{t}</b> · {w}×{hh} · frame {ms:.2} ms on \
                 {adapter} · <a href=\"{f}.exr\">EXR</a></figcaption></figure>",
                f = r.file,
                w = r.settings.width,
                hh = r.settings.height,
                t = r.technique,
            ));
            continue;
        }
        h.push_str(&format!(
            "<figure><img src=\"{f}.png\" width=\"{w}\"><figcaption><b>{t}</b> · {w}×{hh} · {spp} spp · max depth {d} · \
             seed {seed} · {s:.1} s · <a href=\"{f}.exr\">EXR</a></figcaption></figure>",
            f = r.file,
            w = r.settings.width,
            hh = r.settings.height,
            t = r.technique,
            spp = r.settings.spp,
            d = if r.technique == "direct" { 1 } else { r.settings.max_depth },
            seed = r.settings.seed,
            s = r.seconds
        ));
    }
    h.push_str("<h2>Errors against the reference and timings</h2><table><tr><th>scene</th><th>technique</th><th>size</th><th>spp</th>\
        <th>RMSE</th><th>relMSE</th><th>FLIP</th><th>seconds</th><th>Msamples/s</th><th>frame ms</th></tr>");
    for r in rows {
        let samples = r.settings.width as f64 * r.settings.height as f64 * r.settings.spp as f64;
        h.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{}×{}</td><td>{}</td>{}<td>{:.2}</td><td>{}</td><td>{}</td></tr>",
            r.scene,
            r.technique,
            r.settings.width,
            r.settings.height,
            if r.frame.is_some() {
                "—".to_string()
            } else {
                r.settings.spp.to_string()
            },
            match &r.error {
                Some(e) => format!("<td>{:.5}</td><td>{:.5}</td><td>{:.4}</td>", e.rmse, e.relmse, e.flip),
                None => "<td colspan=\"3\">(ground truth)</td>".into(),
            },
            r.seconds,
            match &r.frame {
                Some(_) => "—".to_string(),
                None => format!("{:.2}", samples / r.seconds / 1e6),
            },
            match &r.frame {
                Some((ms, _)) => format!("{ms:.2}"),
                None => "—".to_string(),
            },
        ));
    }
    h.push_str("</table></body></html>\n");
    h
}
