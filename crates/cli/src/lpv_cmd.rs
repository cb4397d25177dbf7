//! The light-propagation-volume techniques `lpv` (Kaplanyan & Dachsbacher 2010) and
//! `lpv-faithful` (the WPI 2011 report's scheme) for `render`, `demo` and `bench frame`:
//! direct light with shadow maps, the environment's SH ambient, and one bounce of indirect
//! light from the volume, recomputed every frame.

use anyhow::Result;
use clap::{Args, ValueEnum};
use lightlab_core::image::Image;
use lightlab_gpu::GpuContext;
use lightlab_gpu::lpv::{LpvScheme, LpvSettings};
use lightlab_gpu::raster::{FrameTimes, Renderer};
use lightlab_scene::Scene;

pub const LPV_TECHNIQUES: [&str; 2] = ["lpv", "lpv-faithful"];

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DebugView {
    /// The full frame.
    Final,
    /// Only the volume's indirect light (diffuse albedo/π × its irradiance).
    Indirect,
}

/// Options of the LPV techniques.
#[derive(Args, Clone, Debug)]
pub struct LpvArgs {
    /// Cells per axis of the light propagation volume.
    #[arg(long, default_value_t = 32)]
    pub lpv_grid: u32,
    /// Propagation steps (default: 8 for `lpv`, 2 for `lpv-faithful`).
    #[arg(long)]
    pub lpv_iterations: Option<u32>,
    /// Reflective-shadow-map side in texels.
    #[arg(long, default_value_t = 256)]
    pub rsm_size: u32,
    /// `lpv`: propagate without the geometry volume (light leaks through walls).
    #[arg(long)]
    pub no_lpv_occlusion: bool,
    /// `lpv`: damping against self-illumination, in cells (the lookup keeps the smaller of the
    /// irradiance at the surface and this far out along the normal); 0 turns it off.
    #[arg(long, default_value_t = 2.0)]
    pub lpv_damping: f32,
    /// `lpv`: nested volumes; the coarsest fits the scene, each finer one halves the cell and
    /// follows the camera in whole cells.
    #[arg(long, default_value_t = 1)]
    pub lpv_cascades: u32,
    /// `lpv`: let the cascades follow the camera continuously instead of in whole cells
    /// (shows the flicker that snapping prevents).
    #[arg(long)]
    pub no_lpv_snap: bool,
    /// What to show: the final frame or the volume's indirect light only.
    #[arg(long, value_enum, default_value_t = DebugView::Final)]
    pub debug_view: DebugView,
}

impl Default for LpvArgs {
    fn default() -> Self {
        LpvArgs {
            lpv_grid: 32,
            lpv_iterations: None,
            rsm_size: 256,
            no_lpv_occlusion: false,
            lpv_damping: 2.0,
            lpv_cascades: 1,
            no_lpv_snap: false,
            debug_view: DebugView::Final,
        }
    }
}

impl LpvArgs {
    pub fn settings(&self, technique: &str) -> Result<LpvSettings> {
        let s = LpvSettings {
            scheme: if technique == "lpv-faithful" {
                LpvScheme::Wpi
            } else {
                LpvScheme::Kaplanyan
            },
            grid: self.lpv_grid,
            iterations: self.lpv_iterations,
            rsm_size: self.rsm_size,
            occlusion: !self.no_lpv_occlusion,
            damping: self.lpv_damping,
            cascades: self.lpv_cascades,
            snap: !self.no_lpv_snap,
            ..Default::default()
        };
        s.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(s)
    }
}

/// A renderer of an LPV technique: shadow-mapped direct light plus the volume.
#[allow(clippy::too_many_arguments)]
pub fn lpv_renderer(
    ctx: &GpuContext,
    scene: &Scene,
    technique: &str,
    raster: &crate::raster_cmd::RasterArgs,
    lpv: &LpvArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<Renderer> {
    let settings = crate::raster_cmd::settings("phong-shadow-maps", raster, width, height, camera)?;
    let s = lpv.settings(technique)?;
    Ok(Renderer::with_lpv(
        ctx,
        scene,
        settings,
        &s,
        lpv.debug_view == DebugView::Indirect,
    )?)
}

/// Render one image with an LPV technique.
#[allow(clippy::too_many_arguments)]
pub fn render_lpv(
    ctx: &GpuContext,
    scene: &Scene,
    technique: &str,
    raster: &crate::raster_cmd::RasterArgs,
    lpv: &LpvArgs,
    width: u32,
    height: u32,
    camera: usize,
) -> Result<(Image, FrameTimes)> {
    let mut r = lpv_renderer(ctx, scene, technique, raster, lpv, width, height, camera)?;
    crate::raster_cmd::timed_frame(ctx, &mut r, raster.ssaa)
}
