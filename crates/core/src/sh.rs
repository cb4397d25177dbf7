//! Real spherical harmonics: the one module that owns lightlab's SH basis.
//!
//! **Convention** (docs/ARCHITECTURE.md; Sloan's "Stupid SH Tricks", Ramamoorthi–Hanrahan 2001): real,
//! orthonormal over the unit sphere, index `i = l(l+1) + m`, functions of the direction
//! (x, y, z) with θ measured from +z and φ = atan2(y, x), **no Condon–Shortley phase**:
//! Y₀₀ = 0.282095; Y₁₋₁ = 0.488603·y, Y₁₀ = 0.488603·z, Y₁₁ = 0.488603·x;
//! Y₂₋₂ = 1.092548·xy, Y₂₋₁ = 1.092548·yz, Y₂₀ = 0.315392·(3z²−1), Y₂₁ = 1.092548·xz,
//! Y₂₂ = 0.546274·(x²−y²).
//!
//! Evaluation uses the Cartesian recurrence (no trigonometry): with
//! `P̃ₗᵐ = Pₗᵐ(z)/sinᵐθ` and `(x + iy)ᵐ = Cₘ + i·Sₘ`,
//! `Yₗᵐ = √2·Kₗᵐ·P̃ₗᵐ·Cₘ` (m > 0), `√2·Kₗ|ᵐ|·P̃ₗ|ᵐ|·S|ₘ|` (m < 0), `Kₗ⁰·P̃ₗ⁰` (m = 0),
//! `Kₗᵐ = √((2l+1)/4π · (l−m)!/(l+m)!)`. Any number of bands; f64 and f32 versions.
//!
//! Also here: projection (functions, lights, environment maps), rotation, zonal-harmonic
//! convolution (clamped cosine, Phong lobe), irradiance (general and Ramamoorthi–Hanrahan's
//! quadratic form), windowing against ringing, and the triple-product tensor.

use crate::quadrature::DirectionSet;
use glam::{DMat3, DVec3, Vec3};
use std::f64::consts::PI;

/// Number of coefficients of `bands` bands (bands = l_max + 1).
#[inline]
pub const fn num_coeffs(bands: usize) -> usize {
    bands * bands
}

/// Index of (l, m).
#[inline]
pub const fn index(l: usize, m: isize) -> usize {
    (l as isize * (l as isize + 1) + m) as usize
}

/// Normalisation constants Kₗᵐ·(√2 for m ≠ 0), for m ≥ 0, in (l, m) order.
fn norms(bands: usize) -> Vec<f64> {
    let mut k = Vec::with_capacity(bands * (bands + 1) / 2);
    for l in 0..bands {
        for m in 0..=l {
            // (l−m)!/(l+m)! as a product, stable for large l.
            let mut ratio = 1.0f64;
            for j in (l - m + 1)..=(l + m) {
                ratio /= j as f64;
            }
            let mut v = ((2 * l + 1) as f64 / (4.0 * PI) * ratio).sqrt();
            if m > 0 {
                v *= std::f64::consts::SQRT_2;
            }
            k.push(v);
        }
    }
    k
}

macro_rules! eval_impl {
    ($name:ident, $t:ty) => {
        /// Evaluate all `bands²` basis functions at the unit direction (x, y, z) into `out`.
        pub fn $name(bands: usize, x: $t, y: $t, z: $t, out: &mut [$t]) {
            assert!(out.len() >= bands * bands, "output holds {} < {} coefficients", out.len(), bands * bands);
            if bands == 0 {
                return;
            }
            thread_local! {
                static NORMS: std::cell::RefCell<(usize, Vec<f64>)> = const { std::cell::RefCell::new((0, Vec::new())) };
            }
            NORMS.with(|cell| {
                let mut c = cell.borrow_mut();
                if c.0 < bands {
                    *c = (bands, norms(bands));
                }
                let k = &c.1;
                let kidx = |l: usize, m: usize| l * (l + 1) / 2 + m;
                // (x + iy)^m, starting at m = 0.
                let (mut cm, mut sm): ($t, $t) = (1.0, 0.0);
                // P̃_m^m = (2m−1)!!
                let mut pmm: $t = 1.0;
                for m in 0..bands {
                    if m > 0 {
                        let (c2, s2) = (cm * x - sm * y, cm * y + sm * x);
                        cm = c2;
                        sm = s2;
                        pmm *= (2 * m - 1) as $t;
                    }
                    // l = m
                    let mut p_prev2: $t = 0.0;
                    let mut p_prev: $t = pmm;
                    for l in m..bands {
                        let p = if l == m {
                            pmm
                        } else if l == m + 1 {
                            z * (2 * m + 1) as $t * pmm
                        } else {
                            ((2 * l - 1) as $t * z * p_prev - (l + m - 1) as $t * p_prev2) / (l - m) as $t
                        };
                        if l > m {
                            p_prev2 = p_prev;
                            p_prev = p;
                        }
                        let kn = k[kidx(l, m)] as $t;
                        let base = l * (l + 1);
                        if m == 0 {
                            out[base] = kn * p;
                        } else {
                            out[base + m] = kn * p * cm;
                            out[base - m] = kn * p * sm;
                        }
                    }
                }
            });
        }
    };
}

eval_impl!(eval_f64, f64);
eval_impl!(eval_f32, f32);

/// All basis functions at unit direction `d` (f64).
pub fn eval(bands: usize, d: DVec3) -> Vec<f64> {
    let mut out = vec![0.0; num_coeffs(bands)];
    eval_f64(bands, d.x, d.y, d.z, &mut out);
    out
}

/// Value of the expansion `coeffs` at `d`.
pub fn evaluate(coeffs: &[f64], d: DVec3) -> f64 {
    let bands = bands_of(coeffs.len());
    eval(bands, d).iter().zip(coeffs).map(|(y, c)| y * c).sum()
}

/// RGB value of an RGB expansion at `d`.
pub fn evaluate_rgb(coeffs: &[DVec3], d: DVec3) -> DVec3 {
    let bands = bands_of(coeffs.len());
    eval(bands, d)
        .iter()
        .zip(coeffs)
        .map(|(y, c)| *c * *y)
        .sum()
}

/// Bands of a coefficient count (panics if not a square).
pub fn bands_of(n: usize) -> usize {
    let b = (n as f64).sqrt().round() as usize;
    assert_eq!(b * b, n, "{n} is not a square number of SH coefficients");
    b
}

// ---- projection ------------------------------------------------------------------------------

/// Project a scalar function with a direction set: cᵢ = Σ w·f(d)·Yᵢ(d).
pub fn project(bands: usize, set: &DirectionSet, f: impl Fn(DVec3) -> f64) -> Vec<f64> {
    let mut c = vec![0.0; num_coeffs(bands)];
    let mut y = vec![0.0; num_coeffs(bands)];
    for (d, w) in set.dirs.iter().zip(&set.weights) {
        let v = f(*d) * w;
        if v == 0.0 {
            continue;
        }
        eval_f64(bands, d.x, d.y, d.z, &mut y);
        for (ci, yi) in c.iter_mut().zip(&y) {
            *ci += v * yi;
        }
    }
    c
}

/// Project an RGB function with a direction set.
pub fn project_rgb(bands: usize, set: &DirectionSet, f: impl Fn(DVec3) -> DVec3) -> Vec<DVec3> {
    let mut c = vec![DVec3::ZERO; num_coeffs(bands)];
    let mut y = vec![0.0; num_coeffs(bands)];
    for (d, w) in set.dirs.iter().zip(&set.weights) {
        let v = f(*d) * *w;
        eval_f64(bands, d.x, d.y, d.z, &mut y);
        for (ci, yi) in c.iter_mut().zip(&y) {
            *ci += v * *yi;
        }
    }
    c
}

/// A delta light of radiance-integral `intensity` from direction `d` (towards the light):
/// cᵢ = intensity·Yᵢ(d). For a point light at distance r, pass I/r².
pub fn project_directional(bands: usize, d: DVec3, intensity: f64) -> Vec<f64> {
    eval(bands, d.normalize())
        .into_iter()
        .map(|y| y * intensity)
        .collect()
}

/// Zonal coefficients zₗ (the m = 0 coefficients about +z) of a spherical cap of half-angle
/// `alpha` with unit radiance: zₗ = 2π·√((2l+1)/4π)·∫_{cos α}^1 Pₗ(t) dt.
pub fn cap_zonal(bands: usize, alpha: f64) -> Vec<f64> {
    let c = alpha.cos();
    // Legendre P_l(c) for l = 0..bands+1.
    let mut p = vec![1.0, c];
    for l in 2..=bands + 1 {
        let v = ((2 * l - 1) as f64 * c * p[l - 1] - (l - 1) as f64 * p[l - 2]) / l as f64;
        p.push(v);
    }
    (0..bands)
        .map(|l| {
            let integral = if l == 0 {
                1.0 - c
            } else {
                (p[l - 1] - p[l + 1]) / (2 * l + 1) as f64
            };
            2.0 * PI * ((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * integral
        })
        .collect()
}

/// Rotate zonal coefficients `zonal` (about +z) to axis `d`: cₗₘ = √(4π/(2l+1))·zₗ·Yₗₘ(d).
pub fn zonal_to_axis(zonal: &[f64], d: DVec3) -> Vec<f64> {
    let bands = zonal.len();
    let y = eval(bands, d.normalize());
    let mut c = vec![0.0; num_coeffs(bands)];
    for l in 0..bands {
        let s = (4.0 * PI / (2 * l + 1) as f64).sqrt() * zonal[l];
        for m in -(l as isize)..=(l as isize) {
            c[index(l, m)] = s * y[index(l, m)];
        }
    }
    c
}

/// A disc-shaped light (the sun) of angular radius `alpha` around direction `d` with uniform
/// `radiance`.
pub fn project_disc(bands: usize, d: DVec3, alpha: f64, radiance: f64) -> Vec<f64> {
    let z: Vec<f64> = cap_zonal(bands, alpha)
        .into_iter()
        .map(|v| v * radiance)
        .collect();
    zonal_to_axis(&z, d)
}

/// A uniform sky: radiance `radiance` over the hemisphere around `up`, zero below.
pub fn project_uniform_sky(bands: usize, up: DVec3, radiance: f64) -> Vec<f64> {
    project_disc(bands, up, PI / 2.0, radiance)
}

// ---- zonal convolution and irradiance ---------------------------------------------------------

/// Zonal coefficients of the clamped cosine max(cos θ, 0): 0.886227, 1.023327, 0.495416, 0,
/// −0.110778, … (computed by exact Gauss–Legendre integration of Yₗ₀·t over [0, 1]).
pub fn clamped_cosine_zonal(bands: usize) -> Vec<f64> {
    lobe_zonal(bands, |t| t.max(0.0), bands + 2)
}

/// Zonal coefficients of the normalised Phong lobe (n+1)/(2π)·max(cos θ, 0)ⁿ.
pub fn phong_zonal(bands: usize, exponent: f64) -> Vec<f64> {
    let n = exponent;
    lobe_zonal(
        bands,
        move |t| (n + 1.0) / (2.0 * PI) * t.max(0.0).powf(n),
        bands + 64,
    )
}

/// zₗ = 2π ∫₀¹ f(t)·Yₗ₀(t) dt for a lobe f that vanishes for t < 0, by Gauss–Legendre on [0, 1].
fn lobe_zonal(bands: usize, f: impl Fn(f64) -> f64, nodes: usize) -> Vec<f64> {
    let (x, w) = crate::quadrature::gauss_legendre(nodes.max(bands + 2));
    let mut z = vec![0.0; bands];
    let mut y = vec![0.0; num_coeffs(bands)];
    for (xi, wi) in x.iter().zip(&w) {
        let t = 0.5 * (xi + 1.0);
        let ft = f(t);
        if ft == 0.0 {
            continue;
        }
        let s = (1.0 - t * t).max(0.0).sqrt();
        eval_f64(bands, s, 0.0, t, &mut y);
        for (l, zl) in z.iter_mut().enumerate() {
            *zl += 2.0 * PI * 0.5 * wi * ft * y[index(l, 0)];
        }
    }
    z
}

/// Convolve `coeffs` with a zonal kernel given by its zonal coefficients:
/// cₗₘ ← √(4π/(2l+1))·kₗ·cₗₘ (Funk–Hecke).
pub fn convolve_zonal<T: Copy + std::ops::Mul<f64, Output = T>>(coeffs: &mut [T], kernel: &[f64]) {
    let bands = bands_of(coeffs.len());
    for l in 0..bands {
        let a = if l < kernel.len() {
            (4.0 * PI / (2 * l + 1) as f64).sqrt() * kernel[l]
        } else {
            0.0
        };
        for m in -(l as isize)..=(l as isize) {
            let i = index(l, m);
            coeffs[i] = coeffs[i] * a;
        }
    }
}

/// Irradiance coefficients from radiance coefficients (convolution with the clamped cosine:
/// Aₗ = π, 2π/3, π/4, 0, −π/24, …).
pub fn irradiance_from_radiance<T: Copy + std::ops::Mul<f64, Output = T>>(
    radiance: &[T],
) -> Vec<T> {
    let mut c = radiance.to_vec();
    convolve_zonal(&mut c, &clamped_cosine_zonal(bands_of(radiance.len())));
    c
}

/// Ramamoorthi–Hanrahan 2001, eq. 12: irradiance at normal `n` from 9 RGB radiance coefficients
/// in this module's order (L00, L1-1, L10, L11, L2-2, L2-1, L20, L21, L22).
pub fn irradiance_rh(l: &[DVec3; 9], n: DVec3) -> DVec3 {
    const C1: f64 = 0.429043;
    const C2: f64 = 0.511664;
    const C3: f64 = 0.743125;
    const C4: f64 = 0.886227;
    const C5: f64 = 0.247708;
    let (x, y, z) = (n.x, n.y, n.z);
    l[8] * (C1 * (x * x - y * y)) + l[6] * (C3 * z * z) + l[0] * C4 - l[6] * C5
        + (l[4] * (x * y) + l[7] * (x * z) + l[5] * (y * z)) * (2.0 * C1)
        + (l[3] * x + l[1] * y + l[2] * z) * (2.0 * C2)
}

// ---- windowing -------------------------------------------------------------------------------

/// Windows that taper high bands against ringing (Gibbs) in truncated expansions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Window {
    None,
    /// Hann: wₗ = (1 + cos(π·l/W))/2 for l < W, 0 beyond; W = `size`.
    Hann {
        size: f64,
    },
    /// Lanczos σ factors: wₗ = sinc(π·l/W) for l < W, 0 beyond.
    Lanczos {
        size: f64,
    },
}

impl Window {
    pub fn weight(self, l: usize) -> f64 {
        let l = l as f64;
        match self {
            Window::None => 1.0,
            Window::Hann { size } => {
                if l >= size {
                    0.0
                } else {
                    0.5 * (1.0 + (PI * l / size).cos())
                }
            }
            Window::Lanczos { size } => {
                if l == 0.0 {
                    1.0
                } else if l >= size {
                    0.0
                } else {
                    let a = PI * l / size;
                    a.sin() / a
                }
            }
        }
    }

    /// Multiply each band of `coeffs` by its weight.
    pub fn apply<T: Copy + std::ops::Mul<f64, Output = T>>(self, coeffs: &mut [T]) {
        let bands = bands_of(coeffs.len());
        for l in 0..bands {
            let w = self.weight(l);
            for c in &mut coeffs[l * l..(l + 1) * (l + 1)] {
                *c = *c * w;
            }
        }
    }
}

// ---- rotation --------------------------------------------------------------------------------

/// Block-diagonal SH rotation: `blocks[l]` is the (2l+1)² matrix (row-major, m = −l..l) that maps
/// the coefficients of f to those of f∘R⁻¹ (the function rotated by R).
///
/// Computed exactly by projecting the rotated basis with a Gauss direction set that integrates
/// band-l products without error (an exact alternative to Ivanic–Ruedenberg's recurrence:
/// the result equals the analytic matrices to rounding).
#[derive(Clone, Debug)]
pub struct Rotation {
    pub blocks: Vec<Vec<f64>>,
}

impl Rotation {
    pub fn new(bands: usize, r: DMat3) -> Rotation {
        let set = DirectionSet::exact_for_degree(2 * bands.saturating_sub(1));
        let n = num_coeffs(bands);
        let mut blocks: Vec<Vec<f64>> = (0..bands)
            .map(|l| vec![0.0; (2 * l + 1) * (2 * l + 1)])
            .collect();
        let mut y = vec![0.0; n];
        let mut yr = vec![0.0; n];
        let rinv = r.transpose();
        for (d, w) in set.dirs.iter().zip(&set.weights) {
            eval_f64(bands, d.x, d.y, d.z, &mut y);
            let dr = rinv * *d;
            eval_f64(bands, dr.x, dr.y, dr.z, &mut yr);
            for (l, block) in blocks.iter_mut().enumerate() {
                let s = 2 * l + 1;
                let o = l * l;
                for a in 0..s {
                    let ya = y[o + a] * w;
                    for b in 0..s {
                        block[a * s + b] += ya * yr[o + b];
                    }
                }
            }
        }
        Rotation { blocks }
    }

    /// Rotate coefficients (any element type that scales by f64 and adds).
    pub fn apply<T>(&self, coeffs: &[T]) -> Vec<T>
    where
        T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T> + Default,
    {
        let bands = bands_of(coeffs.len()).min(self.blocks.len());
        let mut out = vec![T::default(); coeffs.len()];
        for l in 0..bands {
            let s = 2 * l + 1;
            let o = l * l;
            for a in 0..s {
                let mut acc = T::default();
                for b in 0..s {
                    acc = acc + coeffs[o + b] * self.blocks[l][a * s + b];
                }
                out[o + a] = acc;
            }
        }
        out
    }
}

// ---- products --------------------------------------------------------------------------------

/// The SH triple-product (Clebsch–Gordan / Gaunt) tensor Γᵢⱼₖ = ∫ YᵢYⱼYₖ dω, stored sparsely.
/// Computed with a Gauss set exact for degree 3(L−1); selection rules skip the triples that
/// vanish (odd l-sum, triangle inequality) before integrating.
#[derive(Clone, Debug)]
pub struct TripleProduct {
    pub bands: usize,
    /// (i, j, k, Γ) with i ≤ j ≤ k (238 at 5 bands).
    pub entries: Vec<(u16, u16, u16, f64)>,
    /// Every ordered (i, j, k) with Γᵢⱼₖ ≠ 0: the permutations of `entries` (1 158 at 5
    /// bands, McKenzie §5.1.7's sparse table), what the products loop over.
    pub ordered: Vec<(u16, u16, u16, f64)>,
}

impl TripleProduct {
    pub fn new(bands: usize) -> TripleProduct {
        let n = num_coeffs(bands);
        let set = DirectionSet::exact_for_degree(3 * bands.saturating_sub(1));
        let ys: Vec<Vec<f64>> = set.dirs.iter().map(|d| eval(bands, *d)).collect();
        let band = |i: usize| (i as f64).sqrt() as usize;
        let mut entries = vec![];
        for i in 0..n {
            for j in i..n {
                for k in j..n {
                    let (li, lj, lk) = (band(i), band(j), band(k));
                    if (li + lj + lk) % 2 == 1 || lk > li + lj || lk + li < lj || lk + lj < li {
                        continue;
                    }
                    let g: f64 = ys
                        .iter()
                        .zip(&set.weights)
                        .map(|(y, w)| y[i] * y[j] * y[k] * w)
                        .sum();
                    if g.abs() > 1e-12 {
                        entries.push((i as u16, j as u16, k as u16, g));
                    }
                }
            }
        }
        let mut ordered = vec![];
        for &(i, j, k, g) in &entries {
            let mut perms = [
                (i, j, k),
                (i, k, j),
                (j, i, k),
                (j, k, i),
                (k, i, j),
                (k, j, i),
            ];
            perms.sort_unstable();
            for (p, q) in perms.iter().enumerate() {
                if p == 0 || perms[p - 1] != *q {
                    ordered.push((q.0, q.1, q.2, g));
                }
            }
        }
        TripleProduct {
            bands,
            entries,
            ordered,
        }
    }

    /// Coefficients of the projected product of `a` and `b` (both `bands²` long).
    pub fn product<T>(&self, a: &[f64], b: &[T]) -> Vec<T>
    where
        T: Copy + Default + std::ops::Mul<f64, Output = T> + std::ops::AddAssign,
    {
        let mut c = vec![T::default(); num_coeffs(self.bands)];
        for &(i, j, k, g) in &self.ordered {
            c[k as usize] += b[j as usize] * (g * a[i as usize]);
        }
        c
    }

    /// McKenzie's "SH product masking" (§5.1.7): the product of the Hann-windowed (or any
    /// `window`) operands, Cₖ = Σ Γᵢⱼₖ·w(lᵢ)aᵢ·w(lⱼ)bⱼ. Windowing both sides takes the power
    /// of sudden, negative occlusion data in the high bands over the low output bands. With
    /// the unit filter as `a` (DC √4π), the result is `b` windowed.
    pub fn masked_product<T>(&self, a: &[f64], b: &[T], window: Window) -> Vec<T>
    where
        T: Copy + Default + std::ops::Mul<f64, Output = T> + std::ops::AddAssign,
    {
        let mut aw = a.to_vec();
        let mut bw = b.to_vec();
        window.apply(&mut aw);
        window.apply(&mut bw);
        self.product(&aw, &bw)
    }

    /// The product matrix M(a) with M(a)·b = product(a, b) (row-major, bands² × bands²).
    pub fn matrix(&self, a: &[f64]) -> Vec<f64> {
        let n = num_coeffs(self.bands);
        let mut m = vec![0.0; n * n];
        for &(i, j, k, g) in &self.ordered {
            m[k as usize * n + j as usize] += g * a[i as usize];
        }
        m
    }
}

/// Convenience: f32 RGB coefficients from f64.
pub fn to_f32_rgb(c: &[DVec3]) -> Vec<Vec3> {
    c.iter().map(|v| v.as_vec3()).collect()
}
