//! The light-propagation-volume techniques `lpv` (Kaplanyan & Dachsbacher 2010) and
//! `lpv-faithful` (the WPI 2011 report's scheme): direct light with shadow maps, the
//! environment's SH ambient, and the volume's indirect light (`lpv`: multiple bounces through
//! the geometry volume by default; `lpv-faithful`: one), recomputed every
//! frame; and the layers of `--debug-view`.

use super::Request;
use crate::options::DebugView;
use crate::technique::Technique;
use anyhow::Result;
use glam::Vec3;
use lightlab_core::image::Image;
use lightlab_gpu::GpuContext;
use lightlab_gpu::lpv::LpvScheme;
use lightlab_gpu::raster::{RenderPath, Renderer};

/// A renderer of an LPV technique: shadow-mapped direct light plus the volume.
pub fn renderer(ctx: &GpuContext, req: &Request) -> Result<Renderer> {
    let (a, lpv) = (&req.args.raster, &req.args.lpv);
    let shadows = req.technique.shadows(a.shadow_variant)?;
    let mut settings = a.settings(shadows, req.width, req.height, req.camera)?;
    if lpv.debug_view.gbuffer() {
        // Only the deferred path writes the G-buffer.
        settings.path = RenderPath::Deferred;
    }
    let scheme = match req.technique {
        Technique::LpvFaithful => LpvScheme::Wpi,
        _ => LpvScheme::Kaplanyan,
    };
    if scheme == LpvScheme::Wpi && a.normal_filter.is_none() {
        // The report's own filter (§5.5).
        settings.normal_filter = lightlab_gpu::raster::NormalFilter::Rook;
    }
    let s = lpv.settings(scheme)?;
    Ok(Renderer::with_lpv(
        ctx,
        req.scene,
        settings,
        &s,
        lpv.debug_view == DebugView::Indirect,
    )?)
}

fn v3(c: &[f32; 4]) -> Vec3 {
    Vec3::new(c[0], c[1], c[2])
}

/// A `w`×`h` image of texels mapped by `f`.
fn layer(w: u32, h: u32, texels: &[[f32; 4]], f: &dyn Fn(&[f32; 4]) -> Vec3) -> Image {
    let mut img = Image::new(w, h);
    for (px, t) in img.data.iter_mut().zip(texels) {
        *px = f(t);
    }
    img
}

/// The layer a debug view shows, or None for the frame itself.
pub fn debug_image(
    ctx: &GpuContext,
    r: &Renderer,
    view: DebugView,
    ssaa: u32,
) -> Result<Option<Image>> {
    if view.gbuffer() {
        return Ok(Some(gbuffer_image(ctx, r, view)?.downsample(ssaa)));
    }
    let lpv = r.lpv().expect("an LPV renderer");
    let size = lpv.settings.rsm_size;
    let scene_grid = *lpv.grids.last().expect("a volume");
    let rsm = || lpv.read_rsm(ctx);
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
        DebugView::LpvSlices => Some(slices(&lpv.read_volume(ctx, lpv.grids.len() - 1)?)),
        _ => None,
    })
}

/// A G-buffer layer at the renderer's (supersampled) size.
fn gbuffer_image(ctx: &GpuContext, r: &Renderer, view: DebugView) -> Result<Image> {
    let g = r.read_gbuffer(ctx)?;
    let (w, h) = (r.settings.width, r.settings.height);
    Ok(match view {
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
                img.data[px as usize] = Vec3::new(c[0][0], c[1][0], c[2][0]) * k;
            }
        }
    }
    img
}
