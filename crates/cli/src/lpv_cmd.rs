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

/// What `--debug-view` shows. Layers are written as linear values (the G-buffer's and the
/// RSM's at their own resolution); `--tonemap clamp` shows normals and albedo as stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DebugView {
    /// The full frame.
    Final,
    /// Only the volume's indirect light (diffuse albedo/π × its irradiance).
    Indirect,
    /// G-buffer: diffuse reflectance.
    Albedo,
    /// G-buffer: shading normal, n/2 + ½.
    Normal,
    /// G-buffer: specular F0 (r), roughness (g), diffuse transmission (b).
    Material,
    /// G-buffer: distance from the camera over the largest distance seen.
    Depth,
    /// RSM of the last light: reflected (and transmitted) flux per texel over the largest.
    RsmFlux,
    /// RSM: surface normal towards the light, n/2 + ½.
    RsmNormal,
    /// RSM: world position, mapped to the volume's box ([0, 1]³).
    RsmPosition,
    /// The scene's (coarsest) volume's z-slices side by side (row-major from z = 0): mean
    /// radiance of each cell, I₀/s² [W/(m²·sr)].
    LpvSlices,
}

impl DebugView {
    fn gbuffer(self) -> bool {
        matches!(
            self,
            DebugView::Albedo | DebugView::Normal | DebugView::Material | DebugView::Depth
        )
    }
}

/// `--lpv-reemit`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ReemitArg {
    Central,
    Face,
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
    /// Reflective-shadow-map side in texels (default: for `lpv` 32 per cell of the grid, 256 to
    /// 2048, see `lightlab_gpu::lpv::rsm_size_for_grid`; for `lpv-faithful` 256, the report's
    /// §5.3 setup).
    #[arg(long)]
    pub rsm_size: Option<u32>,
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
    /// `lpv`: how light crossing a cell's side faces is re-emitted: `central` along the
    /// direction it travelled (keeps it going; the default), `face` around the face's normal
    /// (Kaplanyan & Dachsbacher's original, more diffusive).
    #[arg(long, value_enum, default_value_t = ReemitArg::Central)]
    pub lpv_reemit: ReemitArg,
    /// What to show: the final frame or the volume's indirect light only.
    #[arg(long, value_enum, default_value_t = DebugView::Final)]
    pub debug_view: DebugView,
}

impl Default for LpvArgs {
    fn default() -> Self {
        LpvArgs {
            lpv_grid: 32,
            lpv_iterations: None,
            rsm_size: None,
            no_lpv_occlusion: false,
            lpv_damping: 2.0,
            lpv_cascades: 1,
            no_lpv_snap: false,
            lpv_reemit: ReemitArg::Central,
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
            rsm_size: self.rsm_size.unwrap_or(if technique == "lpv-faithful" {
                256
            } else {
                lightlab_gpu::lpv::rsm_size_for_grid(self.lpv_grid)
            }),
            occlusion: !self.no_lpv_occlusion,
            damping: self.lpv_damping,
            cascades: self.lpv_cascades,
            snap: !self.no_lpv_snap,
            reemit: match self.lpv_reemit {
                ReemitArg::Central => lightlab_core::lpv::Reemit::Central,
                ReemitArg::Face => lightlab_core::lpv::Reemit::FaceNormal,
            },
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
    let mut settings =
        crate::raster_cmd::settings("phong-shadow-maps", raster, width, height, camera)?;
    if lpv.debug_view.gbuffer() {
        // Only the deferred path writes the G-buffer.
        settings.path = lightlab_gpu::raster::RenderPath::Deferred;
    }
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
    let (img, times) = crate::raster_cmd::timed_frame(ctx, &mut r, raster.ssaa)?;
    Ok((
        debug_image(ctx, &r, lpv.debug_view, raster.ssaa)?.unwrap_or(img),
        times,
    ))
}

/// The layer a debug view shows, or None for the frame itself.
fn debug_image(
    ctx: &GpuContext,
    r: &Renderer,
    view: DebugView,
    ssaa: u32,
) -> Result<Option<Image>> {
    use glam::Vec3;
    let v3 = |c: &[f32; 4]| Vec3::new(c[0], c[1], c[2]);
    let layer = |w: u32, h: u32, texels: &[[f32; 4]], f: &dyn Fn(&[f32; 4]) -> Vec3| {
        let mut img = Image::new(w, h);
        for (px, t) in img.data.iter_mut().zip(texels) {
            *px = f(t);
        }
        img
    };
    let lpv = r.lpv().expect("an LPV renderer");
    if view.gbuffer() {
        let g = r.read_gbuffer(ctx)?;
        let (w, h) = (r.settings.width, r.settings.height);
        let img = match view {
            DebugView::Albedo => layer(w, h, &g[0], &v3),
            DebugView::Normal => layer(w, h, &g[1], &|c| 0.5 * v3(c) + Vec3::splat(0.5)),
            DebugView::Material => {
                // F0 (r), roughness (the normal layer's w), transmission (fraction of w).
                let m: Vec<[f32; 4]> = g[2]
                    .iter()
                    .zip(&g[1])
                    .map(|(m, n)| [m[0], n[3], m[3].fract(), 0.0])
                    .collect();
                layer(w, h, &m, &v3)
            }
            _ => normalised(layer(w, h, &g[3], &|c| {
                Vec3::splat(if c[3] > 0.0 { v3(c).length() } else { 0.0 })
            })),
        };
        return Ok(Some(img.downsample(ssaa)));
    }
    let size = lpv.settings.rsm_size;
    let scene_grid = *lpv.grids.last().expect("a volume");
    let rsm = || lpv.read_rsm(ctx).map_err(|e| anyhow::anyhow!("{e}"));
    Ok(match view {
        DebugView::RsmFlux => Some(normalised(layer(size, size, &rsm()?[0], &v3))),
        DebugView::RsmNormal => Some(layer(size, size, &rsm()?[1], &|c| {
            if c == &[0.0; 4] {
                Vec3::ZERO
            } else {
                0.5 * v3(c) + Vec3::splat(0.5)
            }
        })),
        DebugView::RsmPosition => Some(layer(size, size, &rsm()?[2], &|c| {
            if c[3] > 0.0 {
                (v3(c) - scene_grid.origin) / (scene_grid.cell * scene_grid.n as f32)
            } else {
                Vec3::ZERO
            }
        })),
        DebugView::LpvSlices => {
            let vol = lpv
                .read_volume(ctx, lpv.grids.len() - 1)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            Some(slices(&vol))
        }
        _ => None,
    })
}

/// `img` over its largest component (unchanged if black).
fn normalised(mut img: Image) -> Image {
    let m = img
        .data
        .iter()
        .map(|p| p.max_element())
        .fold(0.0f32, f32::max);
    if m > 0.0 {
        for p in &mut img.data {
            *p /= m;
        }
    }
    img
}

/// A volume's z-slices side by side, ⌈√n⌉ per row, each cell its mean radiance I₀/s².
pub fn slices(vol: &lightlab_core::lpv::Volume) -> Image {
    let g = vol.grid;
    let n = g.n;
    let per_row = (n as f32).sqrt().ceil() as u32;
    let rows = n.div_ceil(per_row);
    let mut img = Image::new(per_row * n, rows * n);
    let k = lightlab_core::lpv::Y00 / (g.cell * g.cell);
    for z in 0..n {
        let (ox, oy) = ((z % per_row) * n, (z / per_row) * n);
        for y in 0..n {
            for x in 0..n {
                let c = vol.at(glam::IVec3::new(x as i32, y as i32, z as i32));
                // Image rows go down, the volume's y up.
                let px = (oy + n - 1 - y) * img.width + ox + x;
                img.data[px as usize] = glam::Vec3::new(c[0][0], c[1][0], c[2][0]) * k;
            }
        }
    }
    img
}
