//! `lightlab demo`: the main job. Renders every built-in scene with every technique built so far
//! and writes `DIR/report.html` with the images, errors against the reference, timings and
//! settings. Each later technique adds its rows here.

use crate::options::{BakeArgs, RasterArgs, TechniqueArgs};
use crate::render::render_reference;
use crate::technique::{Family, Technique};
use crate::techniques::{Bakes, Request};
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
    /// The default: about twenty minutes on two cores (lavapipe for the GPU techniques).
    Low,
    /// Larger, cleaner images.
    High,
}

/// Image size and samples per scene at each quality. `low` takes about twenty minutes on a
/// 2-core machine in total (20.6 min on 2026-12-03, of which the `luminaire` reference, traced
/// through its lamps' windows, is 4 min).
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
    technique: Technique,
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
    let gpu = match crate::gpu_context() {
        Ok(c) => Some(c),
        Err(e) => {
            eprintln!("GPU techniques skipped: {e:#}");
            None
        }
    };
    for name in names {
        let scene = lightlab_scene::builtin::builtin(name).expect("built-in");
        let mut reference: Option<lightlab_core::image::Image> = None;
        for technique in [Technique::Reference, Technique::Direct] {
            let mut settings = settings_for(name, quality);
            if technique == Technique::Direct {
                settings.spp = (settings.spp / 2).max(8);
            }
            let t = Instant::now();
            let img = render_reference(&scene, technique, &settings, &[])?;
            let seconds = t.elapsed().as_secs_f64();
            let file = format!("{name}-{technique}");
            let error = save_and_compare(out, &file, &img, reference.as_ref())?;
            eprintln!(
                "{name:<8} {technique:<10} {:>4}×{:<4} {:>5} spp {seconds:>7.1} s",
                settings.width, settings.height, settings.spp
            );
            if technique == Technique::Reference {
                reference = Some(img);
            }
            rows.push(Row {
                scene: name.into(),
                technique,
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
            let mut bakes = Bakes::default();
            for technique in demo_techniques(name) {
                let args = demo_args(name, technique.family(), quality);
                let req = Request {
                    scene: &scene,
                    technique,
                    args: &args,
                    width: settings.width,
                    height: settings.height,
                    camera: 0,
                };
                let t = Instant::now();
                let (img, times) = crate::techniques::build(ctx, &req, &mut bakes)?.image(ctx)?;
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
                    technique,
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
            eprintln!(
                "{name}: {} bake(s) made, shared by its techniques",
                bakes.len()
            );
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

/// The GPU techniques the demo shows on a scene: the Phong family everywhere, light-maps on
/// the scenes baked light is for, the SH techniques on `prt`, the volumes on the scenes of the
/// LPV work (the leafy bush, cornell, the room).
fn demo_techniques(scene: &str) -> Vec<Technique> {
    let mut families = vec![Family::Phong];
    if lightmap_density(scene).is_some() {
        families.push(Family::Lightmap);
    }
    if matches!(scene, "prt" | "prt-dynamic") {
        families.push(Family::Sh);
    }
    if matches!(scene, "bush" | "cornell" | "room" | "atrium" | "luminaire") {
        families.push(Family::Lpv);
    }
    families
        .into_iter()
        .flat_map(Technique::of)
        // Only `luminaire` has a lamp to can, only `glass` and `spheres` solid glass, only
        // `spheres` glossy metal.
        .filter(|t| *t != Technique::CannedLight || scene == "luminaire")
        .filter(|t| *t != Technique::LightfieldRefraction || matches!(scene, "glass" | "spheres"))
        .filter(|t| *t != Technique::LightfieldGlossy || scene == "spheres")
        .collect()
}

/// Light-map texel density of the scenes light-maps are baked for.
fn lightmap_density(scene: &str) -> Option<f32> {
    match scene {
        "cornell" => Some(32.0),
        "room" => Some(10.0),
        "shadows" => Some(8.0),
        "atrium" => Some(4.0),
        "luminaire" => Some(8.0),
        _ => None,
    }
}

/// The demo's options of a family's techniques: the reference's light model (physical
/// fall-off), 2×2 supersampling, and bakes, shadow maps and volumes sized to the quality
/// (`preview`'s 48 × 48 images need no 2048² shadow maps: those, and the LPV's reflective
/// shadow maps, cost most of a preview's GPU time on lavapipe).
fn demo_args(scene: &str, family: Family, quality: Quality) -> TechniqueArgs {
    let preview = quality == Quality::Preview;
    let raster = RasterArgs {
        attenuation: lightlab_gpu::lights::Attenuation::InverseSquare,
        ssaa: 2,
        shadow_size: if preview { 256 } else { 2048 },
        ..Default::default()
    };
    let lpv = if preview {
        crate::options::LpvArgs {
            rsm_size: Some(64),
            ..Default::default()
        }
    } else {
        Default::default()
    };
    let bake = match family {
        Family::Lightmap => BakeArgs {
            texels_per_metre: Some(lightmap_density(scene).unwrap_or(16.0)),
            samples: match quality {
                Quality::Preview => 8,
                Quality::Low => 64,
                Quality::High => 512,
            },
            ..Default::default()
        },
        Family::Sh => BakeArgs {
            texels_per_metre: Some(if preview { 4.0 } else { 12.0 }),
            transfer_samples: match quality {
                Quality::Preview => 16,
                Quality::Low => 64,
                Quality::High => 512,
            },
            bounces: Some(1),
            ..Default::default()
        },
        // `canned-light`'s slab of the luminaire, `lightfield-glossy`'s radiance field.
        Family::Phong => BakeArgs {
            slab: crate::options::SlabArgs {
                slab_uv: if preview { [4, 4] } else { [8, 8] },
                slab_st: if preview { [32, 32] } else { [64, 64] },
                slab_samples: match quality {
                    Quality::Preview => 2,
                    Quality::Low => 8,
                    Quality::High => 32,
                },
                ..Default::default()
            },
            field: crate::options::FieldArgs {
                field_uv: preview.then_some(16),
                field_st: preview.then_some(8),
                field_spp: match quality {
                    Quality::Preview => 2,
                    Quality::Low => 16,
                    Quality::High => 64,
                },
                ..Default::default()
            },
            ..Default::default()
        },
        _ => BakeArgs::default(),
    };
    let sh = crate::options::ShArgs {
        sh_representatives: if preview { 256 } else { 4096 },
        ..Default::default()
    };
    TechniqueArgs {
        raster,
        bake,
        lpv,
        sh,
        ..Default::default()
    }
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

/// The error-against-cost plot of one scene's rows.
fn scene_plot(rows: &[Row], scene: &str) -> String {
    let points: Vec<crate::plot::Point> = rows
        .iter()
        .filter(|r| r.scene == scene)
        .filter_map(|r| {
            Some(crate::plot::Point {
                label: r.technique.to_string(),
                cost_ms: r.frame.as_ref().map_or(r.seconds * 1e3, |f| f.0),
                relmse: r.error.as_ref()?.relmse,
                gpu: r.frame.is_some(),
            })
        })
        .collect();
    format!("<p>{}</p>", crate::plot::error_cost_svg(&points))
}

fn report_html(rows: &[Row], quality: Quality, total: f64) -> String {
    let mut h = String::new();
    h.push_str("<!doctype html><html><head><meta charset=\"utf-8\"><title>lightlab demo</title><style>\
        body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse}\
        td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}th{background:#eee}\
        figure{display:inline-block;margin:0 1em 1em 0}figcaption{font-size:90%}</style></head><body>");
    h.push_str("<h1>lightlab demo report</h1>");
    h.push_str(&format!(
        "<p>lightlab {} · quality <b>{:?}</b> · {} threads · total {:.1} s. Every image is measured against the \
         scene's <code>reference</code>. The GPU techniques use the reference's light model (physical inverse-square \
         fall-off) and 2×2 supersampling; each bake is made once per scene and shared by the techniques that read it. \
         Images are linear EXR beside each PNG (filmic tone curve, exposure 1). Each scene's plot shows error against \
         cost, one point per technique.</p><ul>",
        env!("CARGO_PKG_VERSION"),
        quality,
        rayon::current_num_threads(),
        total
    ));
    for e in crate::technique::REGISTRY {
        h.push_str(&format!(
            "<li><code>{}</code>: {} (sky light: {})</li>",
            e.name,
            e.about,
            e.family.sky_term()
        ));
    }
    h.push_str("</ul>");
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
            h.push_str(&scene_plot(rows, scene));
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
            d = if r.technique == Technique::Direct { 1 } else { r.settings.max_depth },
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
