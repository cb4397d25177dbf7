//! Vector-quantised SH light-maps (Fuchs 2005 §5.6, suggested to him by J. Kautz): every texel's
//! transfer vector is replaced by the index of its nearest *representative*; the representatives
//! are chosen by Lloyd's "iterated closest points" (k-means).
//!
//! Faithful to the thesis and its source: initial representatives are evenly strided vectors
//! `O[k·⌊|O|/|R|⌋]`; every vector (all atlas texels, dilated borders included) is assigned by
//! exhaustive squared-Euclidean search; an empty cluster keeps its old representative; the
//! iteration stops when the largest per-vector distance to its representative has not improved on
//! the best so far three times in a row (the rule that replaced "until no assignment changes",
//! which can cycle). |R| ≤ 2¹⁶ so indices fit 16 bits.
//!
//! Deviation: the search uses partial-distance early exit (exact, just faster), and runs in
//! parallel with a result independent of the thread count. Representatives are kept as f32
//! (Fuchs: 8-bit range-compressed); indices as 16-bit.
//!
//! Written here rather than taken from a crate: the stopping rule and initialisation are the
//! thesis's, and the k-means crates (linfa-clustering, kmeans) bring ndarray/BLAS stacks or
//! k-means++ initialisation that the method does not use.

use crate::prt::ShLightmaps;
use lightlab_core::sh;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Settings of the quantisation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CompressSettings {
    /// |R|, at most 65 536 (clamped to the number of vectors).
    pub representatives: usize,
    /// Consecutive iterations without improvement of the largest distance before stopping (3).
    pub patience: usize,
    /// Hard cap on iterations.
    pub max_iterations: usize,
}

impl Default for CompressSettings {
    fn default() -> Self {
        CompressSettings {
            representatives: 4096,
            patience: 3,
            max_iterations: 100,
        }
    }
}

/// Figures of one compression.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CompressStats {
    pub vectors: usize,
    pub representatives: usize,
    pub iterations: usize,
    /// Representatives no vector chose at the end.
    pub unused: usize,
    /// Largest and root-mean-square distance of a vector to its representative.
    pub max_distance: f64,
    pub rms_distance: f64,
    /// Raw f32 transfer, and indices (16 bit) + representatives (f32).
    pub raw_bytes: usize,
    pub compressed_bytes: usize,
    pub ratio: f64,
    pub seconds: f64,
}

/// One page's index map.
#[derive(Clone, Debug, PartialEq)]
pub struct IndexMap {
    pub width: u32,
    pub height: u32,
    pub indices: Vec<u32>,
}

/// Compressed SH light-maps: per page an index map, and the representatives.
#[derive(Clone, Debug)]
pub struct CompressedSh {
    pub bands: usize,
    /// `representatives × bands²`, row-major.
    pub representatives: Vec<f32>,
    pub pages: Vec<IndexMap>,
    pub stats: CompressStats,
}

/// Every texel's transfer vector (page-major, row-major), empty texels included.
pub fn texel_vectors(sl: &ShLightmaps) -> Vec<f32> {
    let nc = sh::num_coeffs(sl.bands);
    let mut out = vec![];
    for imgs in &sl.pages {
        let (w, h) = (imgs[0].width, imgs[0].height);
        for y in 0..h {
            for x in 0..w {
                for c in 0..nc {
                    out.push(imgs[c / 3].get(x, y)[c % 3]);
                }
            }
        }
    }
    out
}

/// Nearest representative of `v` (squared distance, exhaustive with partial-distance exit).
fn nearest(v: &[f32], reps: &[f32], nc: usize, hint: usize) -> (u32, f32) {
    let dist = |r: &[f32], bound: f32| {
        let mut d = 0.0f32;
        for (a, b) in v.iter().zip(r) {
            d += (a - b) * (a - b);
            if d >= bound {
                break;
            }
        }
        d
    };
    // Start from the previous assignment: a tight bound early makes the exits effective.
    let mut best = hint;
    let mut bd = dist(&reps[hint * nc..(hint + 1) * nc], f32::INFINITY);
    for (k, r) in reps.chunks_exact(nc).enumerate() {
        if k == hint {
            continue;
        }
        let d = dist(r, bd);
        if d < bd {
            bd = d;
            best = k;
        }
    }
    (best as u32, bd)
}

/// Quantise SH light-maps.
pub fn compress(sl: &ShLightmaps, s: &CompressSettings) -> Result<CompressedSh, crate::BakeError> {
    let t0 = std::time::Instant::now();
    if s.representatives == 0 || s.representatives > 65536 {
        return Err(crate::BakeError::Settings(format!(
            "representatives must be 1 to 65536, not {}",
            s.representatives
        )));
    }
    let nc = sh::num_coeffs(sl.bands);
    let data = texel_vectors(sl);
    let n = data.len() / nc;
    if n == 0 {
        return Err(crate::BakeError::Settings("no texels to compress".into()));
    }
    let r = s.representatives.min(n);
    let stride = n / r;
    let mut reps: Vec<f32> = (0..r)
        .flat_map(|k| data[k * stride * nc..(k * stride + 1) * nc].to_vec())
        .collect();
    let mut assign: Vec<u32> = (0..n)
        .map(|i| (i / stride.max(1)).min(r - 1) as u32)
        .collect();
    let mut best_max = f32::INFINITY;
    let mut failures = 0;
    let mut iterations = 0;
    let mut dists = vec![0.0f32; n];
    loop {
        iterations += 1;
        // Assign.
        let res: Vec<(u32, f32)> = data
            .par_chunks_exact(nc)
            .zip(assign.par_iter())
            .map(|(v, &h)| nearest(v, &reps, nc, h as usize))
            .collect();
        let mut max_d = 0.0f32;
        for (i, (a, d)) in res.into_iter().enumerate() {
            assign[i] = a;
            dists[i] = d;
            max_d = max_d.max(d);
        }
        if max_d < best_max {
            best_max = max_d;
            failures = 0;
        } else {
            failures += 1;
        }
        if failures >= s.patience || iterations >= s.max_iterations {
            break;
        }
        // Update: cluster means (f64 sums); empty clusters keep their representative.
        let mut sums = vec![0.0f64; r * nc];
        let mut counts = vec![0usize; r];
        for (v, &a) in data.chunks_exact(nc).zip(&assign) {
            let a = a as usize;
            counts[a] += 1;
            for (o, x) in sums[a * nc..(a + 1) * nc].iter_mut().zip(v) {
                *o += *x as f64;
            }
        }
        for k in 0..r {
            if counts[k] > 0 {
                for c in 0..nc {
                    reps[k * nc + c] = (sums[k * nc + c] / counts[k] as f64) as f32;
                }
            }
        }
    }
    let mut used = vec![false; r];
    for &a in &assign {
        used[a as usize] = true;
    }
    let mut pages = vec![];
    let mut o = 0;
    for imgs in &sl.pages {
        let (w, h) = (imgs[0].width, imgs[0].height);
        let m = (w * h) as usize;
        pages.push(IndexMap {
            width: w,
            height: h,
            indices: assign[o..o + m].to_vec(),
        });
        o += m;
    }
    let raw_bytes = n * nc * 4;
    let compressed_bytes = n * 2 + r * nc * 4;
    let rms = (dists.iter().map(|d| *d as f64).sum::<f64>() / n as f64).sqrt();
    Ok(CompressedSh {
        bands: sl.bands,
        representatives: reps,
        pages,
        stats: CompressStats {
            vectors: n,
            representatives: r,
            iterations,
            unused: used.iter().filter(|u| !**u).count(),
            max_distance: (dists.iter().fold(0.0f32, |a, b| a.max(*b)) as f64).sqrt(),
            rms_distance: rms,
            raw_bytes,
            compressed_bytes,
            ratio: raw_bytes as f64 / compressed_bytes as f64,
            seconds: t0.elapsed().as_secs_f64(),
        },
    })
}

/// How compressed transfer is read on the CPU (the GPU's `ShFilter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    /// Bilinear interpolation of the four neighbours' relit values.
    Bilinear,
    /// Fuchs's four nearest decompressions at ±¼ texel, averaged.
    FourTap,
}

impl CompressedSh {
    /// E/π at page coordinates `uv` of `page` under incident radiance `light`, with `relit`
    /// the representatives relit under that light ([`CompressedSh::relight`]).
    pub fn shade(
        &self,
        page: u32,
        uv: glam::Vec2,
        relit: &[glam::Vec3],
        filter: Filter,
    ) -> glam::Vec3 {
        let p = &self.pages[page as usize];
        let at = |x: i64, y: i64| {
            let x = x.clamp(0, p.width as i64 - 1) as u32;
            let y = y.clamp(0, p.height as i64 - 1) as u32;
            relit[p.indices[(y * p.width + x) as usize] as usize]
        };
        let x = uv.x * p.width as f32;
        let y = uv.y * p.height as f32;
        match filter {
            Filter::Nearest => at(x.floor() as i64, y.floor() as i64),
            Filter::Bilinear => {
                let (fx, fy) = (x - 0.5, y - 0.5);
                let (ix, iy) = (fx.floor(), fy.floor());
                let (tx, ty) = (fx - ix, fy - iy);
                let (ix, iy) = (ix as i64, iy as i64);
                let top = at(ix, iy).lerp(at(ix + 1, iy), tx);
                let bottom = at(ix, iy + 1).lerp(at(ix + 1, iy + 1), tx);
                top.lerp(bottom, ty)
            }
            Filter::FourTap => {
                let mut e = glam::Vec3::ZERO;
                for (ox, oy) in [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
                    e += 0.25 * at((x + ox).floor() as i64, (y + oy).floor() as i64);
                }
                e
            }
        }
    }

    /// Every representative's E/π under incident radiance `light` (once per frame).
    pub fn relight(&self, light: &[glam::DVec3]) -> Vec<glam::Vec3> {
        let nc = sh::num_coeffs(self.bands);
        self.representatives
            .chunks_exact(nc)
            .map(|t| crate::prt::shade(t, light))
            .collect()
    }
}

/// Render compressed SH light-maps on the CPU (the reference view of `shl-compressed`) under the
/// light of `light`'s sample points (relit per group and point, blended at the hit).
#[allow(clippy::too_many_arguments)]
pub fn render_compressed(
    sl: &ShLightmaps,
    c: &CompressedSh,
    light: &crate::sh_light::ShLighting,
    filter: Filter,
    width: u32,
    height: u32,
    camera: usize,
    spp: u32,
) -> Option<lightlab_core::image::Image> {
    let scene = &sl.scene;
    let relit: Vec<Vec<Vec<glam::Vec3>>> = light
        .coeffs
        .iter()
        .map(|g| g.iter().map(|l| c.relight(l)).collect())
        .collect();
    crate::view::render_camera(scene, width, height, camera, spp, |accel, o, d| {
        let h = crate::view::layout_hit(scene, &sl.layout, accel, o, d)?;
        let g = light.group.get(h.instance).copied().unwrap_or(0);
        let pts = &light.points[g];
        let mut w = vec![0.0f32; pts.len()];
        crate::sh_light::point_weights(pts, h.p, &mut w);
        let e: glam::Vec3 = w
            .iter()
            .zip(&relit[g])
            .map(|(wk, r)| *wk * c.shade(h.page, h.uv, r, filter))
            .sum();
        Some(crate::texels::albedo(scene, h.material, h.tex_uv) * e.max(glam::Vec3::ZERO))
    })
}

/// Texture-space error of a compressed read against the uncompressed bilinear read, near texel
/// edges (⅞ and 1 texel from a centre's left edge) and near texel centres (½ and ⅝), as mean
/// squared error relative to the mean squared value: nearest reads jump at edges (blocks), a
/// good filter errs alike at both.
pub fn border_error(
    sl: &ShLightmaps,
    c: &CompressedSh,
    light: &[glam::DVec3],
    filter: Filter,
) -> (f64, f64) {
    let relit = c.relight(light);
    let nc = sh::num_coeffs(sl.bands);
    let mut t = vec![0.0f32; nc];
    let (mut edge, mut centre, mut norm) = (0.0f64, 0.0f64, 0.0f64);
    for (k, imgs) in sl.pages.iter().enumerate() {
        let (w, h) = (imgs[0].width, imgs[0].height);
        for y in 1..h.saturating_sub(2) {
            for x in 1..w.saturating_sub(2) {
                for (f, is_edge) in [(0.5, false), (0.625, false), (0.875, true), (1.0, true)] {
                    for dir in [0, 1] {
                        let (fx, fy) = if dir == 0 { (f, 0.5) } else { (0.5, f) };
                        let uv =
                            glam::Vec2::new((x as f32 + fx) / w as f32, (y as f32 + fy) / h as f32);
                        sl.sample(k as u32, uv, &mut t);
                        let want = crate::prt::shade(&t, light).as_dvec3();
                        let got = c.shade(k as u32, uv, &relit, filter).as_dvec3();
                        let e = (got - want).length_squared();
                        if is_edge {
                            edge += e;
                        } else {
                            centre += e;
                        }
                        norm += 0.5 * want.length_squared();
                    }
                }
            }
        }
    }
    if norm == 0.0 {
        return (0.0, 0.0);
    }
    (edge / norm, centre / norm)
}

/// Where a compressed SH light-map set lives in an SH folder (`manifest.json`'s `compressed`):
/// `representatives.bin` (little-endian f32, representatives × bands², row-major) and per page
/// `indices-K.bin` (little-endian u16, row-major: the representative of each texel; upload as an
/// R16Uint texture).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CompressedManifest {
    pub representatives: usize,
    pub file: String,
    pub index_pages: Vec<String>,
    pub stats: CompressStats,
}

fn io_err(path: &std::path::Path, e: impl std::fmt::Display) -> crate::BakeError {
    crate::BakeError::Io(format!("{}: {e}", path.display()))
}

/// Write the compressed data into `dir` (the SH folder's manifest then names them).
pub fn write_compressed(
    c: &CompressedSh,
    dir: &std::path::Path,
) -> Result<CompressedManifest, crate::BakeError> {
    let file = "representatives.bin".to_string();
    let bytes: Vec<u8> = c
        .representatives
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    crate::output::write_bytes(&dir.join(&file), &bytes)?;
    let mut index_pages = vec![];
    for (k, p) in c.pages.iter().enumerate() {
        let name = format!("indices-{k}.bin");
        let bytes: Vec<u8> = p
            .indices
            .iter()
            .flat_map(|&i| (i as u16).to_le_bytes())
            .collect();
        crate::output::write_bytes(&dir.join(&name), &bytes)?;
        index_pages.push(name);
    }
    Ok(CompressedManifest {
        representatives: c.stats.representatives,
        file,
        index_pages,
        stats: c.stats.clone(),
    })
}

/// Read compressed data named by an SH folder's manifest, for SH light-maps `sl` read from it
/// (page sizes and band count are checked).
pub fn read_compressed(
    m: &CompressedManifest,
    folder: &crate::folder::Checked,
    sl: &ShLightmaps,
) -> Result<CompressedSh, crate::BakeError> {
    let nc = sh::num_coeffs(sl.bands);
    let p = folder.file(&m.file)?;
    let bytes = std::fs::read(&p).map_err(|e| io_err(&p, e))?;
    if bytes.len() != m.representatives * nc * 4 || m.representatives == 0 {
        return Err(io_err(
            &p,
            format!(
                "{} bytes, expected {} representatives × {nc} coefficients × 4",
                bytes.len(),
                m.representatives
            ),
        ));
    }
    let representatives: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if representatives.iter().any(|v| !v.is_finite()) {
        return Err(io_err(&p, "holds NaN or infinite coefficients"));
    }
    if m.index_pages.len() != sl.layout.pages.len() {
        return Err(io_err(&p, "index pages do not match the layout's pages"));
    }
    let mut pages = vec![];
    for (name, &[w, h]) in m.index_pages.iter().zip(&sl.layout.pages) {
        let p = folder.file(name)?;
        let bytes = std::fs::read(&p).map_err(|e| io_err(&p, e))?;
        if bytes.len() != (w * h * 2) as usize {
            return Err(io_err(&p, format!("does not hold a {w}×{h} u16 index map")));
        }
        let indices: Vec<u32> = bytes
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]) as u32)
            .collect();
        if indices.iter().any(|&i| i as usize >= m.representatives) {
            return Err(io_err(
                &p,
                "an index names a representative that does not exist",
            ));
        }
        pages.push(IndexMap {
            width: w,
            height: h,
            indices,
        });
    }
    Ok(CompressedSh {
        bands: sl.bands,
        representatives,
        pages,
        stats: m.stats.clone(),
    })
}
