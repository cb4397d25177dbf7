//! Random numbers, low-discrepancy sequences and the samplers of the path tracer.
//!
//! Determinism: every stochastic computation in lightlab draws from an [`Rng`] created from
//! `(seed, stream)`, where the stream is a property of the work item (a pixel and sample index, a
//! texel), never of the thread that happens to run it. The same inputs and seed therefore give the
//! same output whatever the thread count.
//!
//! The generator is PCG32 (O'Neill 2014, XSH-RR output) seeded through SplitMix64, which
//! decorrelates neighbouring streams. It is ten lines, so it is written here rather than pulling a
//! crate whose stream layout could change between versions and break reproducibility.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// SplitMix64 finaliser: a strong 64-bit mixing function.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// PCG32 random number generator with a per-work-item stream.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    /// A generator for work item `stream` of a computation seeded with `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let inc = (mix64(seed ^ 0x5851_f42d_4c95_7f2d) << 1) | 1;
        let mut r = Rng {
            state: 0,
            inc: inc ^ (mix64(stream) << 1),
        };
        r.inc |= 1;
        r.state = mix64(seed.wrapping_add(mix64(stream)));
        r.next_u32();
        r
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1), with 24 bits of precision (never returns 1.0).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [0, 1) as f64, 53 bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    #[inline]
    pub fn next_vec2(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// Radical inverse of `i` in base `base` (van der Corput / Halton component).
pub fn radical_inverse(base: u32, mut i: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let mut f = inv;
    let mut r = 0.0;
    while i > 0 {
        r += f * (i % base as u64) as f64;
        i /= base as u64;
        f *= inv;
    }
    r
}

/// Point `i` of the `n`-point Hammersley set in [0,1)².
pub fn hammersley(i: u32, n: u32) -> Vec2 {
    Vec2::new(
        (i as f32 + 0.5) / n as f32,
        radical_inverse(2, i as u64) as f32,
    )
}

/// Point `i` of the R2 sequence (Roberts 2018), a rank-1 lattice with low discrepancy, shifted
/// by `offset` (Cranley–Patterson rotation, used to decorrelate pixels).
pub fn r2(i: u32, offset: Vec2) -> Vec2 {
    const G: f64 = 1.324_717_957_244_746; // plastic number
    let a1 = 1.0 / G;
    let a2 = 1.0 / (G * G);
    let x = (0.5 + a1 * i as f64 + offset.x as f64).fract() as f32;
    let y = (0.5 + a2 * i as f64 + offset.y as f64).fract() as f32;
    Vec2::new(x, y)
}

/// An orthonormal basis (t, b) around unit `n` (Duff et al. 2017, branchless).
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A local shading frame: `to_world(v)` maps z-up local directions around `n`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

impl Frame {
    pub fn from_normal(n: Vec3) -> Self {
        let (t, b) = orthonormal_basis(n);
        Frame { t, b, n }
    }
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
}

/// (cos φ, sin φ) for |φ| ≤ π/4, by their Taylor series to φ⁸ and φ⁹ (truncation errors below
/// 3e-8 and 4e-9 there, under f32's rounding): the concentric map's angles, without a call into
/// libm's `sincosf`, which cost 3 % of a path-traced Cornell box. The coefficients are written
/// as products with constant reciprocals: `x / 362_880.0` stays a division in the machine code
/// (the reciprocal is not exact, so the compiler may not substitute it).
#[inline]
fn cos_sin_quarter(phi: f32) -> (f32, f32) {
    const S3: f32 = -1.0 / 6.0;
    const S5: f32 = 1.0 / 120.0;
    const S7: f32 = -1.0 / 5040.0;
    const S9: f32 = 1.0 / 362_880.0;
    const C4: f32 = 1.0 / 24.0;
    const C6: f32 = -1.0 / 720.0;
    const C8: f32 = 1.0 / 40_320.0;
    let x2 = phi * phi;
    let s = phi * (1.0 + x2 * (S3 + x2 * (S5 + x2 * (S7 + x2 * S9))));
    let c = 1.0 + x2 * (-0.5 + x2 * (C4 + x2 * (C6 + x2 * C8)));
    (c, s)
}

/// Concentric map of the unit square onto the unit disc (Shirley–Chiu), area preserving.
///
/// Written with selects rather than a branch on which of |x| and |y| is larger (a coin toss
/// for random samples). The values are the branching form's; on the 2-core AMD host the
/// path-traced Cornell box's time did not move measurably either way.
#[inline]
pub fn concentric_disc(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    // θ = π/4 · y/x where |x| > |y|, else π/2 − π/4 · x/y (whose cosine and sine are the sine
    // and cosine of π/4 · x/y): both reduce to an angle of at most π/4.
    let x_major = o.x.abs() > o.y.abs();
    let (r, other) = if x_major { (o.x, o.y) } else { (o.y, o.x) };
    if r == 0.0 {
        return Vec2::ZERO;
    }
    let (c, s) = cos_sin_quarter((PI / 4.0) * (other / r));
    let (a, b) = if x_major { (c, s) } else { (s, c) };
    Vec2::new(r * a, r * b)
}

/// Cosine-weighted direction on the z-up hemisphere; pdf = cosθ/π.
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disc(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Uniform direction on the unit sphere; pdf = 1/(4π).
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction on the z-up hemisphere; pdf = 1/(2π).
pub fn uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone of half-angle acos(`cos_max`) around +z;
/// pdf = 1/(2π(1−cos_max)).
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    uniform_cone_1mc(u, 1.0 - cos_max)
}

/// [`uniform_cone`] from `1 − cos_max` given directly. For tiny cones (the sun: 1 − cos ≈ 1e-5)
/// `1 − cos` computed in f32 loses half its digits; pass `2·sin²(α/2)` instead.
pub fn uniform_cone_1mc(u: Vec2, one_minus_cos_max: f32) -> Vec3 {
    let one_minus_z = u.x * one_minus_cos_max;
    let z = 1.0 - one_minus_z;
    let r = (one_minus_z * (2.0 - one_minus_z)).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform point on a triangle as barycentrics (b1, b2) of v1 and v2 (Heitz 2019, low
/// distortion).
pub fn uniform_triangle(u: Vec2) -> Vec2 {
    // Halve the smaller coordinate and subtract it from the larger; selects rather than
    // branches, since the order of two random numbers is a coin toss.
    let x_smaller = u.x < u.y;
    let half = 0.5 * if x_smaller { u.x } else { u.y };
    let rest = if x_smaller { u.y } else { u.x } - half;
    let (b0, b1) = if x_smaller {
        (half, rest)
    } else {
        (rest, half)
    };
    let b0 = if b0.is_finite() { b0 } else { 0.0 };
    let b1 = if b1.is_finite() { b1 } else { 0.0 };
    Vec2::new(b1, 1.0 - b0 - b1)
}

/// Power heuristic (β = 2) for multiple importance sampling.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    if a + b == 0.0 { 0.0 } else { a / (a + b) }
}

/// A piecewise-constant 1-D distribution over `n` bins of [0, 1), sampled in constant time
/// through Walker's alias table (Vose's construction): u·n picks a bin, whose fraction either
/// keeps it (below the bin's threshold) or moves to its alias, and what is left of the fraction
/// places the sample inside the chosen bin. A binary search of the CDF cost the path tracer 7 %
/// of its time on an environment-lit scene (two searches per environment sample).
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// Per bin, the continuous density (the weight over the integral), kept rather than
    /// divided out at every sample: an f64 division in the environment's sampling and MIS
    /// pdfs at every path vertex.
    density: Vec<f32>,
    cdf: Vec<f64>,
    integral: f64,
    /// Per bin: the share of its slot it keeps, and the bin that takes the rest.
    alias: Vec<(f32, u32)>,
}

impl Distribution1D {
    /// From non-negative weights. All-zero weights fall back to uniform.
    pub fn new(weights: &[f32]) -> Self {
        let n = weights.len().max(1);
        let mut func: Vec<f32> = weights
            .iter()
            .map(|w| if w.is_finite() { w.max(0.0) } else { 0.0 })
            .collect();
        if func.is_empty() {
            func.push(1.0);
        }
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        let mut acc = 0.0f64;
        for &f in &func {
            acc += f as f64 / n as f64;
            cdf.push(acc);
        }
        let integral = acc;
        if integral <= 0.0 {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f64 / n as f64;
            }
            func.iter_mut().for_each(|f| *f = 1.0);
        } else {
            cdf.iter_mut().for_each(|c| *c /= integral);
        }
        let integral = if integral <= 0.0 { 1.0 } else { integral };
        let alias = alias_table(&cdf);
        let density = func.iter().map(|&f| (f as f64 / integral) as f32).collect();
        Distribution1D {
            density,
            cdf,
            integral,
            alias,
        }
    }

    pub fn len(&self) -> usize {
        self.density.len()
    }

    pub fn is_empty(&self) -> bool {
        self.density.is_empty()
    }

    /// Integral of the piecewise-constant function over [0, 1).
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// Sample a bin: (index, probability of that bin).
    #[inline]
    pub fn sample_discrete(&self, u: f32) -> (usize, f32) {
        // `pick`'s bin without the position inside it (which costs a division).
        let (slot, f) = self.slot(u);
        let (keep, other) = self.alias[slot];
        let i = if f < keep as f64 {
            slot
        } else {
            other as usize
        };
        (i, self.discrete_pdf(i))
    }

    /// The alias table's slot for u ∈ [0, 1), and where in the slot u falls ([0, 1]).
    #[inline]
    fn slot(&self, u: f32) -> (usize, f64) {
        let n = self.alias.len();
        let x = (u as f64).clamp(0.0, 1.0) * n as f64;
        let slot = (x as usize).min(n - 1);
        (slot, (x - slot as f64).clamp(0.0, 1.0))
    }

    /// The alias table's bin for u ∈ [0, 1), and where in that bin the sample falls ([0, 1)).
    fn pick(&self, u: f32) -> (usize, f64) {
        let (slot, f) = self.slot(u);
        let (keep, other) = self.alias[slot];
        let keep = keep as f64;
        if f < keep {
            (slot, f / keep)
        } else {
            let rest = 1.0 - keep;
            let t = if rest > 0.0 { (f - keep) / rest } else { 0.5 };
            (other as usize, t.min(1.0))
        }
    }

    /// Probability of choosing bin `i` with [`Self::sample_discrete`].
    pub fn discrete_pdf(&self, i: usize) -> f32 {
        (self.cdf[i + 1] - self.cdf[i]) as f32
    }

    /// Sample a continuous position in [0, 1): (x, density at x, bin).
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let (i, du) = self.pick(u);
        let x = ((i as f64 + du) / self.density.len() as f64).min(1.0 - 1e-7) as f32;
        (x, self.density(i), i)
    }

    /// Continuous density on bin `i`.
    pub fn density(&self, i: usize) -> f32 {
        self.density[i]
    }
}

/// Vose's alias table for the bins' probabilities (the CDF's steps): each of the n slots holds
/// 1/n of probability, its own bin's share of it and one other bin's. Slots whose bin has no
/// probability keep none of it.
fn alias_table(cdf: &[f64]) -> Vec<(f32, u32)> {
    let n = cdf.len() - 1;
    let mut scaled: Vec<f64> = cdf.windows(2).map(|w| (w[1] - w[0]) * n as f64).collect();
    let mut table = vec![(1.0f32, 0u32); n];
    for (i, t) in table.iter_mut().enumerate() {
        t.1 = i as u32;
    }
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        table[s] = (scaled[s] as f32, l as u32);
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left holds 1 up to rounding.
    for i in small.into_iter().chain(large) {
        table[i] = (1.0, i as u32);
    }
    table
}

/// A piecewise-constant 2-D distribution on [0,1)², rows along v (marginal) and columns along u.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// From a `width × height` row-major weight grid.
    pub fn new(weights: &[f32], width: usize, height: usize) -> Self {
        let conditional: Vec<Distribution1D> = (0..height)
            .map(|y| Distribution1D::new(&weights[y * width..(y + 1) * width]))
            .collect();
        let row_integrals: Vec<f32> = conditional.iter().map(|d| d.integral() as f32).collect();
        Distribution2D {
            conditional,
            marginal: Distribution1D::new(&row_integrals),
        }
    }

    /// Sample a point: (uv, density with respect to area on [0,1)²).
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample_continuous(u.y);
        let (x, pdf_u, _) = self.conditional[row].sample_continuous(u.x);
        (Vec2::new(x, v), pdf_u * pdf_v)
    }

    /// Density at `uv` with respect to area on [0,1)².
    pub fn pdf(&self, uv: Vec2) -> f32 {
        let h = self.conditional.len();
        let row = ((uv.y * h as f32) as usize).min(h - 1);
        let w = self.conditional[row].len();
        let col = ((uv.x * w as f32) as usize).min(w - 1);
        self.marginal.density(row) * self.conditional[row].density(col)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_concentric_map_matches_its_trigonometric_form() {
        let mut worst = 0.0f64;
        for i in 0..=2000 {
            let phi = (i as f64 / 1000.0 - 1.0) * std::f64::consts::FRAC_PI_4;
            let (c, s) = cos_sin_quarter(phi as f32);
            worst = worst.max(
                (c as f64 - phi.cos())
                    .abs()
                    .max((s as f64 - phi.sin()).abs()),
            );
        }
        assert!(worst < 2e-7, "{worst:e}");
        let mut rng = Rng::new(5, 0);
        for _ in 0..10_000 {
            let u = rng.next_vec2();
            let o = 2.0 * u.as_dvec2() - glam::DVec2::ONE;
            let (r, theta) = if o.x.abs() > o.y.abs() {
                (o.x, std::f64::consts::FRAC_PI_4 * (o.y / o.x))
            } else {
                (
                    o.y,
                    std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (o.x / o.y),
                )
            };
            let want = glam::DVec2::new(r * theta.cos(), r * theta.sin());
            let got = concentric_disc(u).as_dvec2();
            assert!((got - want).length() < 1e-6, "{u} {got} {want}");
        }
    }

    #[test]
    fn rng_is_deterministic_and_streams_differ() {
        let a: Vec<u32> = {
            let mut r = Rng::new(7, 3);
            (0..8).map(|_| r.next_u32()).collect()
        };
        let b: Vec<u32> = {
            let mut r = Rng::new(7, 3);
            (0..8).map(|_| r.next_u32()).collect()
        };
        let c: Vec<u32> = {
            let mut r = Rng::new(7, 4);
            (0..8).map(|_| r.next_u32()).collect()
        };
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn rng_uniform_mean_and_variance() {
        let mut r = Rng::new(1, 0);
        let n = 200_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let x = r.next_f32() as f64;
            assert!((0.0..1.0).contains(&x));
            s += x;
            s2 += x * x;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.002, "{var}");
    }

    #[test]
    fn basis_is_orthonormal() {
        let mut r = Rng::new(2, 0);
        for _ in 0..1000 {
            let n = uniform_sphere(r.next_vec2());
            let f = Frame::from_normal(n);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!((f.b.length() - 1.0).abs() < 1e-5);
            assert!(f.t.dot(f.b).abs() < 1e-5);
            assert!(f.t.dot(n).abs() < 1e-5);
            assert!((f.t.cross(f.b) - n).length() < 1e-4, "right-handed");
            let v = uniform_sphere(r.next_vec2());
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    /// Monte Carlo estimate of E[cosθ] under cosine sampling is 2/3; under uniform hemisphere 1/2.
    #[test]
    fn hemisphere_samplers_have_the_right_moments() {
        let mut r = Rng::new(3, 0);
        let n = 100_000;
        let mut c = 0.0;
        let mut u = 0.0;
        for _ in 0..n {
            let d = cosine_hemisphere(r.next_vec2());
            assert!((d.length() - 1.0).abs() < 1e-4 && d.z >= 0.0);
            c += d.z as f64;
            u += uniform_hemisphere(r.next_vec2()).z as f64;
        }
        assert!((c / n as f64 - 2.0 / 3.0).abs() < 0.005);
        assert!((u / n as f64 - 0.5).abs() < 0.005);
    }

    #[test]
    fn cone_sampler_stays_in_cone() {
        let mut r = Rng::new(4, 0);
        for _ in 0..1000 {
            let d = uniform_cone(r.next_vec2(), 0.9);
            assert!(d.z >= 0.9 - 1e-6);
        }
    }

    #[test]
    fn triangle_sampler_is_uniform() {
        let mut r = Rng::new(5, 0);
        // Mean barycentric of a uniform point is (1/3, 1/3).
        let n = 100_000;
        let mut m = Vec2::ZERO;
        for _ in 0..n {
            let b = uniform_triangle(r.next_vec2());
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            m += b;
        }
        m /= n as f32;
        assert!((m - Vec2::splat(1.0 / 3.0)).length() < 0.005, "{m}");
    }

    #[test]
    fn distribution_1d_matches_weights() {
        let d = Distribution1D::new(&[1.0, 3.0, 0.0, 4.0]);
        assert!((d.discrete_pdf(0) - 0.125).abs() < 1e-6);
        assert!((d.discrete_pdf(1) - 0.375).abs() < 1e-6);
        assert_eq!(d.discrete_pdf(2), 0.0);
        let mut r = Rng::new(6, 0);
        let mut counts = [0usize; 4];
        for _ in 0..80_000 {
            counts[d.sample_discrete(r.next_f32()).0] += 1;
        }
        assert_eq!(counts[2], 0, "zero-weight bin must never be chosen");
        assert!((counts[3] as f64 / 80_000.0 - 0.5).abs() < 0.01);
        let (x, pdf, i) = d.sample_continuous(0.99);
        assert!(
            (i as f32 / 4.0..(i + 1) as f32 / 4.0).contains(&x),
            "{x} in bin {i}"
        );
        assert!((pdf - d.density(i)).abs() < 1e-6);
        // Continuous samples: the bins' shares, spread evenly inside each (halves of bins).
        let mut halves = [0usize; 8];
        for _ in 0..80_000 {
            let (x, _, i) = d.sample_continuous(r.next_f32());
            assert!(
                (i as f32 / 4.0..(i + 1) as f32 / 4.0).contains(&x),
                "{x} in bin {i}"
            );
            halves[(x * 8.0) as usize] += 1;
        }
        for (h, &c) in halves.iter().enumerate() {
            let want = d.discrete_pdf(h / 2) as f64 / 2.0;
            assert!((c as f64 / 80_000.0 - want).abs() < 0.01, "half {h}: {c}");
        }
        // Many bins of uneven weight, zeros among them: every bin's share.
        let w: Vec<f32> = (0..257).map(|i| ((i * 37) % 11) as f32).collect();
        let d = Distribution1D::new(&w);
        let mut counts = vec![0usize; w.len()];
        let n = 400_000;
        for k in 0..n {
            counts[d.sample_discrete((k as f32 + 0.5) / n as f32).0] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            let want = d.discrete_pdf(i) as f64;
            assert!(
                (c as f64 / n as f64 - want).abs() < 2e-4,
                "bin {i}: {c} vs {want}"
            );
        }
    }

    #[test]
    fn distribution_2d_pdf_integrates_to_one() {
        let (w, h) = (8, 4);
        let weights: Vec<f32> = (0..w * h).map(|i| (i % 5) as f32).collect();
        let d = Distribution2D::new(&weights, w, h);
        let mut integral = 0.0;
        for y in 0..h {
            for x in 0..w {
                let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                integral += d.pdf(uv) / (w * h) as f32;
            }
        }
        assert!((integral - 1.0).abs() < 1e-4);
        let mut r = Rng::new(8, 0);
        for _ in 0..1000 {
            let (uv, pdf) = d.sample(r.next_vec2());
            assert!(pdf > 0.0);
            assert!((d.pdf(uv) - pdf).abs() < 1e-3 * pdf.max(1.0));
        }
    }

    #[test]
    fn low_discrepancy_points() {
        assert_eq!(radical_inverse(2, 1), 0.5);
        assert_eq!(radical_inverse(2, 3), 0.75);
        assert!((radical_inverse(3, 1) - 1.0 / 3.0).abs() < 1e-12);
        let p = hammersley(0, 4);
        assert_eq!(p, Vec2::new(0.125, 0.0));
        let q = r2(10, Vec2::ZERO);
        assert!(q.x >= 0.0 && q.x < 1.0 && q.y >= 0.0 && q.y < 1.0);
    }
}
