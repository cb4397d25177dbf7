//! `lightlab bake --method radiosity|path` and the light-map techniques `lightmap` and
//! `lightmap+phong` of `render` and `demo`.

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use lightlab_bake::{BakeSettings, LightMode, Lightmaps, Method, bake_lightmaps, output};
use lightlab_core::image::Image;
use lightlab_gpu::GpuContext;
use lightlab_gpu::gpu_scene::UvRect;
use lightlab_gpu::raster::{FrameTimes, LightmapInput, Renderer, ShadowMethod};
use lightlab_scene::Scene;
use std::path::Path;
use std::sync::Mutex;

/// The light-map techniques.
pub const LIGHTMAP_TECHNIQUES: [&str; 2] = ["lightmap", "lightmap+phong"];

/// Options of the light-map bakers.
#[derive(Args, Clone, Debug)]
pub struct BakeArgs {
    /// Light-map texel density (texels per metre). Walls need two texels of thickness for
    /// bilinear sampling and four for bicubic, or light crosses them.
    #[arg(long, default_value_t = 16.0)]
    pub texels_per_metre: f32,
    /// Path-traced gathering: paths per texel.
    #[arg(id = "gather_samples", long = "gather-samples", default_value_t = 128)]
    pub samples: u32,
    /// Path-traced gathering: largest number of scattering events (1 = direct light only).
    #[arg(id = "gather_depth", long = "gather-depth", default_value_t = 16)]
    pub max_depth: u32,
    /// Path-traced gathering: also bake directional light-maps (three-direction basis, a
    /// third of the samples each: twice the bake time) so normal-mapped surfaces respond to
    /// baked light.
    #[arg(long)]
    pub directional: bool,
    /// Radiosity and SH shooting: shooter block size n (n×n patches, CaLight's BlockSize, 1..8).
    #[arg(long, default_value_t = 3)]
    pub block_size: u32,
    /// Radiosity and SH shooting: stop when no patch (block) holds more unshot radiosity
    /// (transfer) than this fraction of the largest initial one (CaLight's StopUE, relative).
    #[arg(long, default_value_t = 1e-4)]
    pub stop: f64,
    /// How punctual lights enter the bake: `all=MODE` or `NAME=MODE`, MODE one of baked,
    /// indirect-only, realtime (comma-separated; default: all baked).
    #[arg(long, value_delimiter = ',')]
    pub light_mode: Vec<String>,
    /// Also write tone-reproduced PNG pages (Ward Larson histogram adjustment, gamma 2).
    #[arg(long)]
    pub png: bool,
    /// Also write `scene.glb`: the scene with page-space TEXCOORD_1 per instance and the pages
    /// embedded (as PNG; node extras name the EXR), for other engines. Implies --png.
    #[arg(long)]
    pub gltf: bool,
    #[arg(long, default_value_t = 0)]
    pub bake_seed: u64,
    /// `--method sh`: SH bands (l_max + 1), 1..8; 4 as Fuchs, 5 as McKenzie Chapter.
    #[arg(long, default_value_t = 4)]
    pub bands: usize,
    /// `--method sh`: unshadowed, shadowed, interreflected (bounces gathered) or shooting
    /// (CaSHL: bounces shot between texels to `--stop`, grouped by `--block-size`) transfer.
    #[arg(long, default_value = "interreflected")]
    pub transfer: String,
    /// `--method sh`: bounces of inter-reflected transfer (default 2). With `--technique
    /// reference`: light that bounced at most this many times before reaching the surface seen
    /// (exactly this many with `--indirect-only`; default 1 then).
    #[arg(long)]
    pub bounces: Option<u32>,
    /// `--method sh`: directions per texel and vertex.
    #[arg(long, default_value_t = 256)]
    pub transfer_samples: u32,
    /// `--method sh`: texel normals from the materials' normal maps, averaged over each texel
    /// (Fuchs §5.7; the data of `shl-normalmapped`).
    #[arg(long)]
    pub normal_mapped: bool,
    /// `--method sh`: bake decimated meshes (glTF mesh extras.lightlab.detailSource) as they
    /// are, instead of taking position, normal and occlusion from their high-poly source.
    #[arg(long)]
    pub no_detail: bool,
    /// `--method sh`: how far (fraction of the source mesh's bounding-box diagonal) a decimated
    /// texel searches along its normal for the high-poly surface.
    #[arg(long, default_value_t = 0.05)]
    pub detail_cage: f32,
    /// `--method sh`: also write the k-means compressed copy with this many representatives
    /// (Fuchs §5.6; `indices-K.bin` + `representatives.bin`, read by `shl-compressed`).
    #[arg(long)]
    pub compress: Option<usize>,
}

impl Default for BakeArgs {
    fn default() -> Self {
        BakeArgs {
            texels_per_metre: 16.0,
            samples: 128,
            max_depth: 16,
            directional: false,
            block_size: 3,
            stop: 1e-4,
            light_mode: vec![],
            png: false,
            gltf: false,
            bake_seed: 0,
            bands: 4,
            transfer: "interreflected".into(),
            bounces: None,
            transfer_samples: 256,
            normal_mapped: false,
            no_detail: false,
            detail_cage: 0.05,
            compress: None,
        }
    }
}

impl BakeArgs {
    /// The library settings for `method` on `scene`.
    pub fn settings(&self, scene: &Scene, method: Method) -> Result<BakeSettings> {
        let mut s = BakeSettings {
            method,
            seed: self.bake_seed,
            ..Default::default()
        };
        s.layout.texels_per_metre = self.texels_per_metre;
        s.gather.samples = self.samples;
        s.gather.max_depth = self.max_depth;
        s.gather.directional = self.directional;
        s.radiosity.block_size = self.block_size;
        s.radiosity.stop = self.stop;
        let mut modes = vec![LightMode::Baked; scene.lights.len()];
        for item in &self.light_mode {
            let (name, mode) = item
                .split_once('=')
                .with_context(|| format!("--light-mode '{item}' is not NAME=MODE"))?;
            let mode = LightMode::parse(mode).with_context(|| {
                format!("unknown light mode '{mode}' (known: baked, indirect-only, realtime)")
            })?;
            if name == "all" {
                modes.iter_mut().for_each(|m| *m = mode);
            } else {
                let i = scene
                    .lights
                    .iter()
                    .position(|l| l.name == name)
                    .with_context(|| {
                        format!(
                            "the scene has no light '{name}' (lights: {})",
                            scene
                                .lights
                                .iter()
                                .map(|l| l.name.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        )
                    })?;
                modes[i] = mode;
            }
        }
        s.light_modes = modes;
        Ok(s)
    }
}

/// Run a bake with a progress bar on stderr: `bake` gets the library's progress callback.
fn with_progress_bar<T>(
    prefix: String,
    bake: impl FnOnce(lightlab_bake::Progress) -> Result<T, lightlab_bake::BakeError>,
) -> Result<T> {
    let bar = ProgressBar::new(1);
    bar.set_style(
        ProgressStyle::with_template("{prefix} {msg} [{bar:30}] {pos}/{len}, {elapsed}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_prefix(prefix);
    let last = Mutex::new(String::new());
    let out = bake(&|stage, done, total| {
        let mut l = last.lock().expect("progress lock");
        if *l != stage {
            *l = stage.to_string();
            bar.set_message(stage.to_string());
        }
        bar.set_length(total.max(done).max(1) as u64);
        bar.set_position(done as u64);
        true
    });
    bar.finish_and_clear();
    Ok(out?)
}

/// Bake light-maps with a progress bar on stderr.
pub fn bake_with_progress(scene: &Scene, settings: &BakeSettings) -> Result<Lightmaps> {
    with_progress_bar(
        format!("{} {}", scene.name, settings.method.name()),
        |progress| bake_lightmaps(scene, settings, progress),
    )
}

/// `lightlab bake --method radiosity|path`.
pub fn run(scene: &Scene, method: &str, out: &Path, args: &BakeArgs, json: bool) -> Result<()> {
    // Textured PRT's data are SH light-maps (transfer per light-map texel).
    if ["sh", "shl", "prt-textured"].contains(&method) {
        return bake_sh(scene, out, args, json);
    }
    if method == "prt" {
        return bake_vertex(scene, out, args, json);
    }
    if method == "prt-hierarchical" {
        return Err(crate::not_implemented(
            "bake method 'prt-hierarchical' (McKenzie Chapter ch. 5's scene-tree filters)",
        ));
    }
    let Some(m) = Method::parse(method) else {
        bail!(
            "unknown bake method '{method}' (known: {}; SH and PRT bakers are planned)",
            Method::NAMES.join(", ")
        );
    };
    let settings = args.settings(scene, m)?;
    let lm = bake_with_progress(scene, &settings)?;
    let manifest = output::write(
        &lm,
        out,
        &scene.name,
        output::Outputs {
            png: args.png,
            gltf: args.gltf,
        },
    )?;
    let st = &lm.stats;
    eprintln!(
        "baked {} with {}: {} pages, {} texels ({} valid), {:.2} s; wrote {}",
        scene.name,
        m.name(),
        st.pages,
        st.texels,
        st.valid_texels,
        st.seconds_total,
        out.display()
    );
    if let Some(r) = &st.radiosity {
        eprintln!(
            "radiosity: {} shots, unshot energy left {:.3} %{}",
            r.shots,
            r.unshot_fraction * 100.0,
            if r.hit_shot_limit {
                " (stopped by the shot limit)"
            } else {
                ""
            }
        );
    }
    if json {
        println!("{}", serde_json::to_string(&manifest.stats)?);
    }
    Ok(())
}

/// `lightlab bake --method prt`: per-vertex transfer (Sloan et al. 2002), one binary file per
/// instance and a manifest; `render --technique prt-vertex --baked DIR` reads it.
fn bake_vertex(scene: &Scene, out: &Path, args: &BakeArgs, json: bool) -> Result<()> {
    use lightlab_bake::prt::{vertex_transfer, write_vertex_transfer};
    let s = crate::prt_cmd::transfer_settings(args)?;
    eprintln!(
        "baking {} per-vertex transfer: {} bands, {:?}, {} directions per vertex",
        scene.name, s.bands, s.kind, s.samples
    );
    let t = std::time::Instant::now();
    let accel = lightlab_trace::Accel::new(scene);
    let (vt, _) = vertex_transfer(scene, &accel, &s)?;
    let seconds = t.elapsed().as_secs_f64();
    let m = write_vertex_transfer(&vt, scene, &s, out, &scene.name, seconds)?;
    let vertices: usize = m.instances.iter().map(|f| f.vertices).sum();
    eprintln!(
        "baked {} in {seconds:.2} s: {vertices} vertices of {} instances; wrote {}",
        scene.name,
        m.instances.len(),
        out.display()
    );
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "method": "prt", "bands": s.bands, "seconds": seconds,
                "vertices": vertices, "samples": s.samples, "transfer": args.transfer,
            })
        );
    }
    Ok(())
}

/// `lightlab bake --method sh`: SH light-maps (per-texel diffuse transfer, Fuchs §5).
fn bake_sh(scene: &Scene, out: &Path, args: &BakeArgs, json: bool) -> Result<()> {
    use lightlab_bake::prt::{bake_sh_lightmaps, write_sh};
    let s = crate::prt_cmd::transfer_settings(args)?;
    let kind = s.kind;
    let layout = lightlab_bake::layout::LayoutSettings {
        texels_per_metre: args.texels_per_metre,
        ..Default::default()
    };
    eprintln!(
        "baking {} SH light-maps: {} bands, {:?}, {} directions per texel, {} texels/m",
        scene.name, s.bands, kind, s.samples, args.texels_per_metre
    );
    let t = std::time::Instant::now();
    let sl = with_progress_bar(format!("{} sh", scene.name), |progress| {
        bake_sh_lightmaps(scene, &layout, &s, progress)
    })?;
    let seconds = t.elapsed().as_secs_f64();
    if let Some(d) = &sl.detail {
        eprintln!(
            "detail from high-poly sources: {} texels projected (mean offset {:.4} m), {} missed \
             the cage (kept on the decimated surface)",
            d.texels - d.misses,
            d.mean_offset,
            d.misses
        );
    }
    if let Some(st) = &sl.shooting {
        eprintln!(
            "shooting: {} shots over {} texels, unshot transfer left {:.2e}{}",
            st.shots,
            st.patches,
            st.unshot_fraction,
            if st.hit_shot_limit {
                " (stopped at the shot limit)"
            } else {
                ""
            }
        );
    }
    let compressed = match args.compress {
        Some(n) => {
            let c = lightlab_bake::sh_compress::compress(
                &sl,
                &lightlab_bake::sh_compress::CompressSettings {
                    representatives: n,
                    ..Default::default()
                },
            )?;
            let st = &c.stats;
            eprintln!(
                "compressed {} transfer vectors to {} representatives in {} iterations: {:.1}× \
                 smaller, rms distance {:.4}",
                st.vectors, st.representatives, st.iterations, st.ratio, st.rms_distance
            );
            Some(c)
        }
        None => None,
    };
    let m = write_sh(&sl, compressed.as_ref(), out, &scene.name, seconds)?;
    eprintln!(
        "baked {} in {seconds:.2} s: {} pages × {} coefficient images; wrote {}",
        scene.name,
        m.pages.len(),
        m.pages.first().map_or(0, |p| p.len()),
        out.display()
    );
    if json {
        println!(
            "{}",
            serde_json::json!({
                "scene": scene.name, "method": "sh", "bands": s.bands, "seconds": seconds,
                "pages": m.pages.len(), "texels_per_metre": args.texels_per_metre,
                "samples": s.samples, "transfer": args.transfer,
                "normal_mapped": s.normal_mapped, "detail": sl.detail, "shooting": sl.shooting,
            })
        );
    }
    Ok(())
}

/// The light-maps a technique renders with: read from `baked`, or baked now (all lights baked
/// for `lightmap`; for `lightmap+phong` punctual lights bake only their indirect light, since
/// their direct light is drawn in real time).
pub fn lightmaps_for(
    scene: &Scene,
    technique: &str,
    baked: Option<&Path>,
    args: &BakeArgs,
) -> Result<Lightmaps> {
    if let Some(dir) = baked {
        return Ok(output::read(dir, scene)?);
    }
    let mut settings = args.settings(scene, Method::Path)?;
    if technique == "lightmap+phong" && args.light_mode.is_empty() {
        settings.light_modes = vec![LightMode::IndirectOnly; scene.lights.len()];
    }
    eprintln!(
        "no --baked folder: baking {} light-maps now (path, {} texels/m, {} samples)",
        scene.name, args.texels_per_metre, args.samples
    );
    bake_with_progress(scene, &settings)
}

/// Render a light-map technique on the GPU.
pub fn render_lightmap(
    ctx: &GpuContext,
    lm: &Lightmaps,
    technique: &str,
    a: &crate::raster_cmd::RasterArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<(Image, FrameTimes)> {
    let mut r = lightmap_renderer(ctx, lm, technique, a, width, height, camera)?;
    crate::raster_cmd::timed_frame(ctx, &mut r, a.ssaa)
}

/// The GPU renderer of a light-map technique (`lightmap`: the light-maps alone;
/// `lightmap+phong`: light-maps plus the real-time lights with shadow volumes).
pub fn lightmap_renderer(
    ctx: &GpuContext,
    lm: &Lightmaps,
    technique: &str,
    a: &crate::raster_cmd::RasterArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<Renderer> {
    if !["bilinear", "bicubic"].contains(&a.lightmap_filter.as_str()) {
        bail!(
            "--lightmap-filter must be bilinear or bicubic, not '{}'",
            a.lightmap_filter
        );
    }
    let base = if technique == "lightmap+phong" {
        "phong-shadow-volumes"
    } else {
        "phong"
    };
    let mut s = crate::raster_cmd::settings(base, a, width, height, camera)?;
    let mut scene = lm.scene.clone();
    if technique == "lightmap" {
        scene.lights.clear();
        s.shadows = ShadowMethod::None;
    }
    let rects = layout_rects(&lm.layout);
    let input = LightmapInput {
        pages: &lm.pages,
        rects: &rects,
        bicubic: a.lightmap_filter == "bicubic",
        directional: lm.directional.as_deref(),
    };
    Ok(Renderer::with_lightmap(ctx, &scene, s, Some(&input))?)
}

/// The GPU's per-instance page rectangles of a light-map layout (light-maps, SH light-maps).
pub fn layout_rects(layout: &lightlab_bake::layout::Layout) -> Vec<Option<UvRect>> {
    layout
        .instances
        .iter()
        .map(|r| {
            r.map(|r| UvRect {
                page: r.page,
                offset: r.offset,
                scale: r.scale,
            })
        })
        .collect()
}
