//! Clustered principal component analysis of SH light-maps (Sloan, Hall, Hart & Snyder 2003,
//! *Clustered Principal Components for Precomputed Radiance Transfer*): an alternative
//! compression beside Fuchs's vector quantisation ([`crate::sh_compress`]).
//!
//! Every texel's transfer vector x (bands² coefficients) is approximated in its cluster c by
//! the cluster mean plus N principal directions:
//!
//! ```text
//! x ≈ m_c + Σ_i w_i e_ci,    w_i = (x − m_c)·e_ci
//! ```
//!
//! so per texel only the cluster index (u16) and N weights (f16) are stored. At run time each cluster's
//! mean and directions are relit once (E/π = l·m_c, l·e_ci: (N + 1) dot products per cluster
//! and frame) and a texel's light is A_c + Σ w_i B_ci — linear in the weights, so bilinear
//! filtering of the reconstruction is exact as for the relit k-means representatives.
//!
//! Fitting (Sloan's iterative CPCA): clusters start from Fuchs's k-means, then alternate a PCA
//! per cluster (covariance in f64, eigenvectors by cyclic Jacobi rotations — the matrices are
//! at most 64 × 64, so a dependency on a linear-algebra crate buys nothing) and reassigning
//! every vector to the cluster that reconstructs it best. Vector quantisation is the N = 0
//! case; N = bands² is lossless.

use crate::prt::ShLightmaps;
use lightlab_core::sh;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CpcaSettings {
    /// Clusters (at most 65536: 16-bit indices).
    pub clusters: usize,
    /// Principal directions per cluster (0..=bands²).
    pub components: usize,
    /// PCA / reassignment rounds after the k-means start.
    pub iterations: usize,
}

impl Default for CpcaSettings {
    fn default() -> Self {
        CpcaSettings {
            clusters: 64,
            components: 4,
            iterations: 4,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CpcaStats {
    pub vectors: usize,
    pub clusters: usize,
    pub components: usize,
    pub iterations: usize,
    /// RMS of |x − reconstruction| over all vectors.
    pub rms_error: f64,
    /// Raw f32 transfer.
    pub raw_bytes: usize,
    /// u16 cluster index + N f16 weights per texel, plus the clusters' f32 means and directions.
    pub compressed_bytes: usize,
    pub ratio: f64,
    pub seconds: f64,
}

/// One cluster: its mean and `components` orthonormal directions (row-major, bands² each).
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    pub mean: Vec<f32>,
    pub basis: Vec<f32>,
}

/// One page: per texel its cluster and weights.
#[derive(Clone, Debug, PartialEq)]
pub struct CpcaPage {
    pub width: u32,
    pub height: u32,
    pub cluster: Vec<u16>,
    /// Texel-major, `components` each (values representable in f16, as stored).
    pub weights: Vec<f32>,
}

#[derive(Clone, Debug)]
pub struct Cpca {
    pub bands: usize,
    pub components: usize,
    pub clusters: Vec<Cluster>,
    pub pages: Vec<CpcaPage>,
    pub stats: CpcaStats,
}

/// Eigen-decomposition of a symmetric `n`×`n` matrix (row-major) by cyclic Jacobi rotations:
/// eigenvalues and eigenvectors (as rows), sorted by decreasing eigenvalue.
pub fn symmetric_eigen(a: &[f64], n: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut a = a.to_vec();
    let mut v = vec![0.0f64; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    let scale: f64 = a
        .iter()
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt()
        .max(f64::MIN_POSITIVE);
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum::<f64>()
            .sqrt();
        if off <= 1e-13 * scale {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() <= 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                // A ← Jᵀ A J on rows/columns p and q.
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| a[j * n + j].total_cmp(&a[i * n + i]));
    let values = order.iter().map(|&i| a[i * n + i]).collect();
    let vectors = order
        .iter()
        .map(|&i| (0..n).map(|k| v[k * n + i]).collect())
        .collect();
    (values, vectors)
}

/// Mean and top-`k` principal directions of the vectors `members` of `data`.
fn pca(data: &[f32], nc: usize, members: &[usize], k: usize) -> Option<Cluster> {
    if members.is_empty() {
        return None;
    }
    let mut mean = vec![0.0f64; nc];
    for &i in members {
        for (m, x) in mean.iter_mut().zip(&data[i * nc..(i + 1) * nc]) {
            *m += *x as f64;
        }
    }
    mean.iter_mut().for_each(|m| *m /= members.len() as f64);
    let mut basis = vec![];
    if k > 0 {
        let mut cov = vec![0.0f64; nc * nc];
        let mut d = vec![0.0f64; nc];
        for &i in members {
            for (o, (x, m)) in d
                .iter_mut()
                .zip(data[i * nc..(i + 1) * nc].iter().zip(&mean))
            {
                *o = *x as f64 - m;
            }
            for r in 0..nc {
                for c in r..nc {
                    cov[r * nc + c] += d[r] * d[c];
                }
            }
        }
        for r in 0..nc {
            for c in 0..r {
                cov[r * nc + c] = cov[c * nc + r];
            }
        }
        let (_, vectors) = symmetric_eigen(&cov, nc);
        for e in vectors.iter().take(k) {
            basis.extend(e.iter().map(|v| *v as f32));
        }
    }
    Some(Cluster {
        mean: mean.iter().map(|m| *m as f32).collect(),
        basis,
    })
}

impl Cluster {
    /// Weights of `x` and the squared reconstruction error.
    fn project(&self, x: &[f32], k: usize, w: &mut [f32]) -> f32 {
        let nc = x.len();
        let mut r: Vec<f32> = x.iter().zip(&self.mean).map(|(a, m)| a - m).collect();
        for (i, wi) in w.iter_mut().enumerate().take(k) {
            let e = &self.basis[i * nc..(i + 1) * nc];
            *wi = r.iter().zip(e).map(|(a, b)| a * b).sum();
        }
        for (i, wi) in w.iter().enumerate().take(k) {
            let e = &self.basis[i * nc..(i + 1) * nc];
            for (a, b) in r.iter_mut().zip(e) {
                *a -= wi * b;
            }
        }
        r.iter().map(|a| a * a).sum()
    }
}

/// Fit CPCA to SH light-maps.
pub fn cpca(sl: &ShLightmaps, s: &CpcaSettings) -> Result<Cpca, crate::BakeError> {
    let t0 = std::time::Instant::now();
    let nc = sh::num_coeffs(sl.bands);
    if s.clusters == 0 || s.clusters > 65536 || s.components > nc {
        return Err(crate::BakeError::Settings(format!(
            "CPCA needs 1 to 65536 clusters and at most {nc} components, not {} and {}",
            s.clusters, s.components
        )));
    }
    // Start from Fuchs's k-means.
    let vq = crate::sh_compress::compress(
        sl,
        &crate::sh_compress::CompressSettings {
            representatives: s.clusters,
            ..Default::default()
        },
    )?;
    let data = crate::sh_compress::texel_vectors(sl);
    let n = data.len() / nc;
    let mut assign: Vec<usize> = vq
        .pages
        .iter()
        .flat_map(|p| p.indices.iter().map(|&i| i as usize))
        .collect();
    let c = vq.stats.representatives;
    let k = s.components;
    let fit = |assign: &[usize], previous: &[Cluster]| -> Vec<Cluster> {
        let mut members = vec![vec![]; c];
        for (i, &a) in assign.iter().enumerate() {
            members[a].push(i);
        }
        members
            .par_iter()
            .enumerate()
            .map(|(j, m)| {
                pca(&data, nc, m, k).unwrap_or_else(|| {
                    previous.get(j).cloned().unwrap_or(Cluster {
                        mean: vec![0.0; nc],
                        basis: vec![0.0; nc * k],
                    })
                })
            })
            .collect()
    };
    let mut clusters = fit(&assign, &[]);
    for _ in 0..s.iterations {
        assign = data
            .par_chunks_exact(nc)
            .map(|x| {
                let mut w = vec![0.0f32; k];
                let mut best = (f32::INFINITY, 0usize);
                for (j, cl) in clusters.iter().enumerate() {
                    let e = cl.project(x, k, &mut w);
                    if e < best.0 {
                        best = (e, j);
                    }
                }
                best.1
            })
            .collect();
        clusters = fit(&assign, &clusters);
    }
    // Weights, stored as f16, and the errors of what is stored.
    let res: Vec<(Vec<f32>, f32)> = data
        .par_chunks_exact(nc)
        .zip(assign.par_iter())
        .map(|(x, &a)| {
            let mut w = vec![0.0f32; k];
            clusters[a].project(x, k, &mut w);
            w.iter_mut()
                .for_each(|v| *v = half::f16::from_f32(*v).to_f32());
            let cl = &clusters[a];
            let mut r: Vec<f32> = x.iter().zip(&cl.mean).map(|(a, m)| a - m).collect();
            for (i, wi) in w.iter().enumerate() {
                for (d, e) in r.iter_mut().zip(&cl.basis[i * nc..(i + 1) * nc]) {
                    *d -= wi * e;
                }
            }
            (w, r.iter().map(|d| d * d).sum())
        })
        .collect();
    let mut pages = vec![];
    let mut o = 0;
    for imgs in &sl.pages {
        let (w, h) = (imgs[0].width, imgs[0].height);
        let m = (w * h) as usize;
        pages.push(CpcaPage {
            width: w,
            height: h,
            cluster: assign[o..o + m].iter().map(|&a| a as u16).collect(),
            weights: res[o..o + m].iter().flat_map(|r| r.0.clone()).collect(),
        });
        o += m;
    }
    let rms = (res.iter().map(|r| r.1 as f64).sum::<f64>() / n as f64).sqrt();
    let raw_bytes = n * nc * 4;
    let compressed_bytes = n * (2 + 2 * k) + c * (k + 1) * nc * 4;
    Ok(Cpca {
        bands: sl.bands,
        components: k,
        clusters,
        pages,
        stats: CpcaStats {
            vectors: n,
            clusters: c,
            components: k,
            iterations: s.iterations,
            rms_error: rms,
            raw_bytes,
            compressed_bytes,
            ratio: raw_bytes as f64 / compressed_bytes as f64,
            seconds: t0.elapsed().as_secs_f64(),
        },
    })
}

impl Cpca {
    /// The reconstructed transfer of texel `t` of page `p`.
    pub fn texel(&self, p: usize, t: usize, out: &mut [f32]) {
        let page = &self.pages[p];
        let cl = &self.clusters[page.cluster[t] as usize];
        let nc = out.len();
        out.copy_from_slice(&cl.mean);
        for i in 0..self.components {
            let w = page.weights[t * self.components + i];
            for (o, e) in out.iter_mut().zip(&cl.basis[i * nc..(i + 1) * nc]) {
                *o += w * e;
            }
        }
    }

    /// The SH light-maps this CPCA reconstructs (for the CPU view and error figures; bilinear
    /// reads of the reconstruction equal bilinear reads of per-texel relit values).
    pub fn reconstruct(&self, sl: &ShLightmaps) -> ShLightmaps {
        let nc = sh::num_coeffs(self.bands);
        let mut out = sl.clone();
        let mut v = vec![0.0f32; nc];
        for (p, imgs) in out.pages.iter_mut().enumerate() {
            let w = imgs[0].width as usize;
            for t in 0..self.pages[p].cluster.len() {
                self.texel(p, t, &mut v);
                let (x, y) = ((t % w) as u32, (t / w) as u32);
                for (j, img) in imgs.iter_mut().enumerate() {
                    let mut px = img.get(x, y);
                    for ch in 0..3 {
                        px[ch] = v.get(3 * j + ch).copied().unwrap_or(0.0);
                    }
                    img.set(x, y, px);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_diagonalises_a_symmetric_matrix() {
        let n = 6;
        let mut rng = lightlab_core::sampling::Rng::new(3, 0);
        let mut a = vec![0.0f64; n * n];
        for i in 0..n {
            for j in i..n {
                let v = rng.next_f32() as f64 - 0.5;
                a[i * n + j] = v;
                a[j * n + i] = v;
            }
        }
        let (values, vectors) = symmetric_eigen(&a, n);
        assert!(values.windows(2).all(|w| w[0] >= w[1]), "{values:?}");
        // A v = λ v, and the vectors are orthonormal.
        for (l, v) in values.iter().zip(&vectors) {
            for i in 0..n {
                let av: f64 = (0..n).map(|j| a[i * n + j] * v[j]).sum();
                assert!((av - l * v[i]).abs() < 1e-10, "{av} vs {}", l * v[i]);
            }
        }
        for (i, u) in vectors.iter().enumerate() {
            for (j, v) in vectors.iter().enumerate() {
                let d: f64 = u.iter().zip(v).map(|(a, b)| a * b).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-10);
            }
        }
    }
}
