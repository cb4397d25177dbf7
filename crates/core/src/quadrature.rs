//! Direction sets on the sphere for integration.
//!
//! - [`DirectionSet::gauss`]: Gauss–Legendre nodes in z = cosθ times equally spaced φ. With
//!   `n_z` nodes and `n_phi` angles it integrates exactly every polynomial in (x, y, z) of degree
//!   ≤ min(2·n_z − 1, n_phi − 1): products of spherical harmonics are integrated to rounding
//!   error (orthonormality, rotation, triple products).
//! - [`DirectionSet::stratified`]: one jittered sample per cell of an equal-area grid over
//!   (z, φ), weight 4π/N: the unbiased Monte Carlo set that bakers use with visibility.
//!
//! The Gauss–Legendre nodes are found by Newton's method on the Legendre recurrence (written
//! here: a dozen lines, no crate offers just this without a linear-algebra stack).

use crate::sampling::Rng;
use glam::DVec3;
use std::f64::consts::PI;

/// Gauss–Legendre nodes and weights on [−1, 1] (n ≥ 1).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        // Initial guess (Tricomi), then Newton on P_n.
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 {
                1.0
            } else if n == 1 {
                z
            } else {
                p1
            };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pn1) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        x[i] = z;
        x[n - 1 - i] = -z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        w[n - 1 - i] = w[i];
    }
    (x, w)
}

/// Directions with integration weights (solid angle).
#[derive(Clone, Debug)]
pub struct DirectionSet {
    pub dirs: Vec<DVec3>,
    pub weights: Vec<f64>,
}

impl DirectionSet {
    /// Gauss–Legendre in z × `n_phi` equally spaced φ (exact for degree ≤ min(2n_z−1, n_phi−1)).
    pub fn gauss(n_z: usize, n_phi: usize) -> Self {
        let (zs, ws) = gauss_legendre(n_z);
        let mut dirs = Vec::with_capacity(n_z * n_phi);
        let mut weights = Vec::with_capacity(n_z * n_phi);
        for (z, wz) in zs.iter().zip(&ws) {
            let r = (1.0 - z * z).max(0.0).sqrt();
            for k in 0..n_phi {
                let phi = 2.0 * PI * (k as f64 + 0.5) / n_phi as f64;
                dirs.push(DVec3::new(r * phi.cos(), r * phi.sin(), *z));
                weights.push(wz * 2.0 * PI / n_phi as f64);
            }
        }
        DirectionSet { dirs, weights }
    }

    /// The smallest Gauss set that integrates polynomials of degree `degree` exactly.
    pub fn exact_for_degree(degree: usize) -> Self {
        Self::gauss(degree / 2 + 1, degree + 1)
    }

    /// About `n` stratified directions (an `nz × 2nz` grid in (z, φ), jittered), weight 4π/N.
    pub fn stratified(n: usize, seed: u64) -> Self {
        let nz = ((n as f64 / 2.0).sqrt().ceil() as usize).max(1);
        let nphi = 2 * nz;
        let total = nz * nphi;
        let mut rng = Rng::new(seed, 0x5354_5241);
        let mut dirs = Vec::with_capacity(total);
        for i in 0..nz {
            for j in 0..nphi {
                let z = 1.0 - 2.0 * (i as f64 + rng.next_f64()) / nz as f64;
                let phi = 2.0 * PI * (j as f64 + rng.next_f64()) / nphi as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                dirs.push(DVec3::new(r * phi.cos(), r * phi.sin(), z));
            }
        }
        DirectionSet {
            dirs,
            weights: vec![4.0 * PI / total as f64; total],
        }
    }

    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in 1..20 {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n={n}");
            for deg in 0..(2 * n) {
                let got: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let expect = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg + 1) as f64
                };
                assert!((got - expect).abs() < 1e-13, "n={n} deg={deg}: {got}");
            }
        }
    }

    #[test]
    fn direction_sets_cover_the_sphere() {
        let g = DirectionSet::gauss(8, 16);
        assert!((g.weights.iter().sum::<f64>() - 4.0 * PI).abs() < 1e-12);
        // ∫ z² dω = 4π/3
        let m: f64 = g
            .dirs
            .iter()
            .zip(&g.weights)
            .map(|(d, w)| d.z * d.z * w)
            .sum();
        assert!((m - 4.0 * PI / 3.0).abs() < 1e-12);
        let s = DirectionSet::stratified(10_000, 1);
        let m: f64 = s
            .dirs
            .iter()
            .zip(&s.weights)
            .map(|(d, w)| d.x * d.x * w)
            .sum();
        assert!((m - 4.0 * PI / 3.0).abs() < 1e-2);
        assert!(s.dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-12));
    }
}
