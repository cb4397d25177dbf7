//! The SH techniques `prt-vertex`, `prt-textured`, `shl`, `shl-compressed` (issue 6) for
//! `render`, `bench frame` and `demo`: their transfer data (read from `--baked`, or computed
//! now), the run-time light projection, and the GPU renderer.

use crate::bake_cmd::BakeArgs;
use anyhow::{Context, Result, bail};
use clap::Args;
use lightlab_bake::prt::{
    ShLightmaps, TransferKind, TransferSettings, VertexTransfer, bake_sh_lightmaps,
    read_sh_with_compressed, vertex_transfer,
};
use lightlab_bake::sh_compress::{CompressSettings, CompressedSh, compress};
use lightlab_bake::sh_light::{SamplePoints, ShLightSettings, ShLighting, ShProjector};
use lightlab_core::image::Image;
use lightlab_core::sh::Window;
use lightlab_gpu::GpuContext;
use lightlab_gpu::prt::{IndexPage, ShFilter, ShInput, ShTransfer};
use lightlab_gpu::raster::{Ambient, FrameTimes, Renderer, ShadowMethod};
use lightlab_scene::Scene;
use std::path::Path;

/// The SH techniques.
pub const SH_TECHNIQUES: [&str; 5] = [
    "prt-vertex",
    "prt-textured",
    "shl",
    "shl-compressed",
    "shl-normalmapped",
];

/// Run-time options of the SH techniques.
#[derive(Args, Clone, Debug)]
pub struct ShArgs {
    /// Incident-light sample points: `scene` (one at the scene's centre: distant light, the
    /// default of shl*) or `object` (six per instance at its box faces, blended by 1/distance:
    /// McKenzie §4.3, the default of prt-*).
    #[arg(long)]
    pub sh_points: Option<String>,
    /// Window on the light against ringing: none, hann or lanczos (default: hann for prt-*,
    /// none for shl*).
    #[arg(long)]
    pub sh_window: Option<String>,
    /// Window width W in bands (default: the band count, McKenzie's normalisation).
    #[arg(long)]
    pub sh_window_size: Option<f64>,
    /// Reads of `shl-compressed`: nearest, bilinear (of the relit representatives) or 4tap
    /// (Fuchs §5.8). Default bilinear.
    #[arg(long)]
    pub sh_filter: Option<String>,
    /// Representatives of `shl-compressed` (Fuchs §5.6; at most 65536).
    #[arg(long, default_value_t = 4096)]
    pub sh_representatives: usize,
}

impl Default for ShArgs {
    fn default() -> Self {
        ShArgs {
            sh_points: None,
            sh_window: None,
            sh_window_size: None,
            sh_filter: None,
            sh_representatives: 4096,
        }
    }
}

/// Transfer data of an SH technique.
pub enum ShData {
    Textured(ShLightmaps),
    Compressed(ShLightmaps, CompressedSh),
    Vertex(Scene, VertexTransfer),
}

/// The transfer settings of the bake options (`bake --method sh`, the SH techniques).
pub fn transfer_settings(args: &BakeArgs) -> Result<TransferSettings> {
    let kind = match args.transfer.as_str() {
        "unshadowed" => TransferKind::Unshadowed,
        "shadowed" => TransferKind::Shadowed,
        "interreflected" => TransferKind::Interreflected {
            bounces: args.bounces.unwrap_or(2),
        },
        "shooting" => TransferKind::Shooting(lightlab_bake::cashl::ShootSettings {
            block_size: args.block_size,
            stop: args.stop as f32,
            ..Default::default()
        }),
        t => {
            bail!("--transfer must be unshadowed, shadowed, interreflected or shooting, not '{t}'")
        }
    };
    if !(args.detail_cage > 0.0 && args.detail_cage.is_finite()) {
        bail!(
            "--detail-cage must be a positive fraction, not {}",
            args.detail_cage
        );
    }
    Ok(TransferSettings {
        bands: args.bands,
        samples: args.transfer_samples,
        kind,
        seed: args.bake_seed,
        detail: (!args.no_detail).then_some(lightlab_bake::detail::DetailSettings {
            cage: args.detail_cage,
        }),
        normal_mapped: args.normal_mapped,
    })
}

/// The transfer of `technique`: SH light-maps from `baked` (a `bake --method sh` folder) or
/// baked now; per-vertex transfer computed now.
pub fn sh_data_for(
    scene: &Scene,
    technique: &str,
    baked: Option<&Path>,
    bake: &BakeArgs,
    sh: &ShArgs,
) -> Result<ShData> {
    let mut s = transfer_settings(bake)?;
    // Fuchs §5.7: only the bake changes; the renderer is shl's.
    s.normal_mapped |= technique == "shl-normalmapped";
    if technique == "prt-vertex" {
        if let Some(dir) = baked {
            let (vt, _) = lightlab_bake::prt::read_vertex_transfer(dir, scene)?;
            return Ok(ShData::Vertex(scene.clone(), vt));
        }
        eprintln!(
            "computing {} per-vertex transfer ({} bands, {:?}, {} directions)",
            scene.name, s.bands, s.kind, s.samples
        );
        let accel = lightlab_trace::Accel::new(scene);
        let (vt, _) = vertex_transfer(scene, &accel, &s)?;
        return Ok(ShData::Vertex(scene.clone(), vt));
    }
    let sl = match baked {
        Some(dir) => {
            let (sl, stored) = read_sh_with_compressed(dir, scene)?;
            if technique == "shl-compressed"
                && let Some(c) = stored
            {
                eprintln!(
                    "using the folder's compressed copy ({} representatives, {:.1}× smaller)",
                    c.stats.representatives, c.stats.ratio
                );
                return Ok(ShData::Compressed(sl, c));
            }
            if s.normal_mapped && !sl.settings.normal_mapped {
                bail!(
                    "{} was baked without normal maps; bake it with `lightlab bake --method sh \
                     --normal-mapped` for {technique}",
                    dir.display()
                );
            }
            sl
        }
        None => {
            eprintln!(
                "no --baked folder: baking {} SH light-maps now ({} bands, {:?}, {} directions, \
                 {} texels/m)",
                scene.name, s.bands, s.kind, s.samples, bake.texels_per_metre
            );
            let layout = lightlab_bake::layout::LayoutSettings {
                texels_per_metre: bake.texels_per_metre,
                ..Default::default()
            };
            bake_sh_lightmaps(scene, &layout, &s, &lightlab_bake::no_progress)?
        }
    };
    if technique == "shl-compressed" {
        return compressed(sl, sh);
    }
    Ok(ShData::Textured(sl))
}

/// Vector-quantise SH light-maps for `shl-compressed` (`--sh-representatives`).
pub fn compressed(sl: ShLightmaps, sh: &ShArgs) -> Result<ShData> {
    let c = compress(
        &sl,
        &CompressSettings {
            representatives: sh.sh_representatives,
            ..Default::default()
        },
    )?;
    let st = &c.stats;
    eprintln!(
        "compressed {} transfer vectors to {} representatives in {} iterations ({:.2} s): \
         {:.1}× smaller, rms distance {:.4}",
        st.vectors, st.representatives, st.iterations, st.seconds, st.ratio, st.rms_distance
    );
    Ok(ShData::Compressed(sl, c))
}

impl ShData {
    pub fn bands(&self) -> usize {
        match self {
            ShData::Textured(sl) | ShData::Compressed(sl, _) => sl.bands,
            ShData::Vertex(_, vt) => vt.bands,
        }
    }
    pub fn scene(&self) -> &Scene {
        match self {
            ShData::Textured(sl) | ShData::Compressed(sl, _) => &sl.scene,
            ShData::Vertex(s, _) => s,
        }
    }
}

/// The run-time light settings of a technique and its options.
pub fn light_settings(technique: &str, bands: usize, a: &ShArgs) -> Result<ShLightSettings> {
    let prt = technique.starts_with("prt");
    let points = match a.sh_points.as_deref() {
        None => {
            if prt {
                SamplePoints::PerObject
            } else {
                SamplePoints::Scene
            }
        }
        Some("scene") => SamplePoints::Scene,
        Some("object") => SamplePoints::PerObject,
        Some(p) => bail!("--sh-points must be scene or object, not '{p}'"),
    };
    let size = a.sh_window_size.unwrap_or(bands as f64);
    anyhow::ensure!(
        size.is_finite() && size > 0.0,
        "--sh-window-size must be a positive number"
    );
    let window = match a.sh_window.as_deref() {
        None if prt => Window::Hann { size },
        None | Some("none") => Window::None,
        Some("hann") => Window::Hann { size },
        Some("lanczos") => Window::Lanczos { size },
        Some(w) => bail!("--sh-window must be none, hann or lanczos, not '{w}'"),
    };
    Ok(ShLightSettings {
        bands,
        points,
        window,
        environment: true,
        punctual: true,
    })
}

/// Upload this frame's SH light.
pub fn set_light(ctx: &GpuContext, r: &mut Renderer, light: &ShLighting) -> Result<()> {
    let (points, coeffs) = light.flattened();
    r.set_sh_light(ctx, &points, &coeffs)?;
    Ok(())
}

/// The GPU renderer of an SH technique (its first light set) and the light projector that
/// re-projects the scene's lights each frame.
#[allow(clippy::too_many_arguments)]
pub fn sh_renderer(
    ctx: &GpuContext,
    data: &ShData,
    technique: &str,
    a: &crate::raster_cmd::RasterArgs,
    sh: &ShArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<(Renderer, ShProjector)> {
    let bands = data.bands();
    let ls = light_settings(technique, bands, sh)?;
    let mut s = crate::raster_cmd::settings("phong", a, width, height, camera)?;
    s.shadows = ShadowMethod::None;
    s.ambient = Ambient::None;
    // The lights reach the surfaces through the transfer only.
    let mut scene = data.scene().clone();
    let projector = ShProjector::new(&scene, &ls);
    let light = projector.project(&scene, None);
    scene.lights.clear();
    let f = sh.sh_filter.as_deref().unwrap_or("bilinear");
    let filter = ShFilter::parse(f)
        .with_context(|| format!("--sh-filter must be nearest, bilinear or 4tap, not '{f}'"))?;
    let index_pages: Vec<IndexPage>;
    let (transfer, rects) = match data {
        ShData::Textured(sl) => (
            ShTransfer::Textured { pages: &sl.pages },
            crate::bake_cmd::layout_rects(&sl.layout),
        ),
        ShData::Compressed(sl, c) => {
            index_pages = c
                .pages
                .iter()
                .map(|p| IndexPage {
                    width: p.width,
                    height: p.height,
                    indices: &p.indices,
                })
                .collect();
            (
                ShTransfer::Compressed {
                    pages: &index_pages,
                    representatives: &c.representatives,
                    filter,
                },
                crate::bake_cmd::layout_rects(&sl.layout),
            )
        }
        ShData::Vertex(_, vt) => (
            ShTransfer::Vertex {
                instances: &vt.instances,
            },
            vec![],
        ),
    };
    let input = ShInput {
        bands,
        transfer,
        rects: &rects,
        per_object: ls.points == SamplePoints::PerObject,
        points: light.points[0].len(),
    };
    let mut r = Renderer::with_sh(ctx, &scene, s, &input)?;
    set_light(ctx, &mut r, &light)?;
    Ok((r, projector))
}

/// Render an SH technique on the GPU.
#[allow(clippy::too_many_arguments)]
pub fn render_sh(
    ctx: &GpuContext,
    data: &ShData,
    technique: &str,
    a: &crate::raster_cmd::RasterArgs,
    sh: &ShArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<(Image, FrameTimes)> {
    let (mut r, _) = sh_renderer(ctx, data, technique, a, sh, width, height, camera)?;
    crate::raster_cmd::timed_frame(ctx, &mut r, a.ssaa)
}
