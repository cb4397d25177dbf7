//! Path-traced gathering: the modern alternative to radiosity, with the same inputs (texels,
//! validity) and output (irradiance/π per texel).
//!
//! Each valid texel is a white Lambertian receiver at its sample point; `samples` paths leave
//! it through the reference path tracer (`lightlab_trace`): next-event estimation with MIS for
//! every light at every vertex, any number of bounces (Russian roulette after three). The mean
//! radiance leaving the white receiver is E/π, which is what a light-map stores: the rendered
//! radiance is albedo × light-map (+ emission). Because it is the reference's own estimator,
//! the baked light-map converges to the reference image's diffuse light.
//!
//! Determinism: texel i of the bake draws from `Rng::new(seed, i)`.
//!
//! **Directional light-maps** (`directional`): besides E/π about the texel's normal, each
//! texel gathers the irradiance about the three directions of Half-Life 2's "radiosity normal
//! mapping" basis (McTaggart 2004: tilted 54.7° from the normal, 120° apart, in the frame
//! `directional_frame(ns)`, which the GPU rebuilds from the interpolated vertex normal) with a
//! third of the samples each, and stores their luminances divided by their mean: ratios r_k
//! whose mean is 1. A normal-mapped fragment with tangent-space normal n then reads
//! E/π · Σ w_k r_k with w_k = max(n·b_k, 0)² / Σ max(n·b_j, 0)²: exactly the flat value for the
//! unperturbed normal (w_k = ⅓), brighter where the bump faces the light. Only the luminance
//! is directional (one RGBA page per page); colour comes from the E/π page.

use crate::texels::Texels;
use crate::{BakeError, Progress};
use glam::Vec3;
use lightlab_core::color::luminance;
use lightlab_core::sampling::Rng;
use lightlab_trace::{PathTracer, RenderSettings};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GatherSettings {
    /// Paths per texel.
    pub samples: u32,
    /// Largest number of scattering events, counting the texel's own (1 = direct light only).
    pub max_depth: u32,
    /// Also gather the three-direction basis of a directional light-map (see the module doc).
    #[serde(default)]
    pub directional: bool,
}

impl Default for GatherSettings {
    fn default() -> Self {
        GatherSettings {
            samples: 256,
            max_depth: 16,
            directional: false,
        }
    }
}

/// The tangent-space basis of directional light-maps (Half-Life 2's radiosity normal mapping),
/// in the frame `Frame::from_normal(n)`; the WGSL of the light-map technique uses the same.
pub const DIRECTIONAL_BASIS: [Vec3; 3] = [
    Vec3::new(-0.408_248_3, 0.707_106_77, 0.577_350_26),
    Vec3::new(-0.408_248_3, -0.707_106_77, 0.577_350_26),
    Vec3::new(0.816_496_6, 0.0, 0.577_350_26),
];

/// The tangent frame (t, b) of a directional light-map texel with normal `n` (Duff et al.'s
/// branch-free basis, with n.z = −0 counted as positive so that the GPU's rebuild from an
/// interpolated normal agrees with the bake).
pub fn directional_frame(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Weights of the three basis values for a tangent-space normal `n` (sum 1).
pub fn directional_weights(n: Vec3) -> Vec3 {
    let w = Vec3::from_array(DIRECTIONAL_BASIS.map(|b| {
        let c = n.dot(b).max(0.0);
        c * c
    }));
    let s = w.x + w.y + w.z;
    if s > 0.0 {
        w / s
    } else {
        Vec3::splat(1.0 / 3.0)
    }
}

/// Per-page texel values of a gather: E/π, and the directional ratios when asked for.
pub type Gathered = (Vec<Vec<Vec3>>, Option<Vec<Vec<Vec3>>>);

/// Gather every valid texel. Returns one value per texel and page (zero where invalid).
pub fn gather(
    tracer: &PathTracer,
    texels: &Texels,
    valid: &[Vec<bool>],
    settings: &GatherSettings,
    seed: u64,
    progress: Progress,
) -> Result<Gathered, BakeError> {
    if settings.samples == 0 || settings.max_depth == 0 {
        return Err(BakeError::Settings(
            "gathering needs at least one sample and one bounce".into(),
        ));
    }
    let rs = RenderSettings {
        max_depth: settings.max_depth,
        min_depth: 0,
        seed,
        ..Default::default()
    };
    let total: usize = texels.count();
    let done = AtomicUsize::new(0);
    let cancelled = AtomicBool::new(false);
    let mut base = 0u64;
    let mut out = Vec::with_capacity(texels.pages.len());
    let mut dir_out = Vec::with_capacity(texels.pages.len());
    let dir_samples = (settings.samples / 3).max(4);
    for (page, valid) in texels.pages.iter().zip(valid) {
        let start = base;
        base += page.samples.len() as u64;
        let zero = (Vec3::ZERO, Vec3::ONE);
        let values: Vec<(Vec3, Vec3)> = page
            .samples
            .par_iter()
            .zip(valid.par_iter())
            .enumerate()
            .map(|(i, (s, &ok))| {
                let Some(s) = s else { return zero };
                if cancelled.load(Ordering::Relaxed) {
                    return zero;
                }
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                if n.is_multiple_of(1024) && !progress("gather", n, total) {
                    cancelled.store(true, Ordering::Relaxed);
                }
                if !ok {
                    return zero;
                }
                let mut rng = Rng::new(seed, start + i as u64);
                let mut sum = glam::DVec3::ZERO;
                // Fully covered texels average over their square (a box-filtered light-map);
                // partly covered ones keep their point, which lies on the surface.
                let jitter = s.coverage >= 0.999;
                for _ in 0..settings.samples {
                    let p = if jitter {
                        let u = rng.next_vec2() - 0.5;
                        s.p + s.dpdx * u.x + s.dpdy * u.y
                    } else {
                        s.p
                    };
                    let v = tracer.surface_radiance(p, s.ng, s.ns, Vec3::ONE, &rs, &mut rng);
                    if v.is_finite() {
                        sum += v.as_dvec3();
                    }
                }
                let flat = (sum / settings.samples as f64).as_vec3();
                if !settings.directional {
                    return (flat, Vec3::ONE);
                }
                // The basis irradiances, as luminance ratios to their mean.
                let (t, bt) = directional_frame(s.ns);
                let mut lum = [0.0f64; 3];
                for (k, b) in DIRECTIONAL_BASIS.iter().enumerate() {
                    let nb = (t * b.x + bt * b.y + s.ns * b.z).normalize();
                    for _ in 0..dir_samples {
                        let v = tracer.surface_radiance(s.p, s.ng, nb, Vec3::ONE, &rs, &mut rng);
                        if v.is_finite() {
                            lum[k] += luminance(v) as f64;
                        }
                    }
                }
                let mean = (lum[0] + lum[1] + lum[2]) / 3.0;
                let r = if mean > 0.0 {
                    Vec3::new(
                        (lum[0] / mean) as f32,
                        (lum[1] / mean) as f32,
                        (lum[2] / mean) as f32,
                    )
                } else {
                    Vec3::ONE
                };
                (flat, r)
            })
            .collect();
        if cancelled.load(Ordering::Relaxed) {
            return Err(BakeError::Cancelled);
        }
        let (flat, dir): (Vec<Vec3>, Vec<Vec3>) = values.into_iter().unzip();
        out.push(flat);
        dir_out.push(dir);
    }
    progress("gather", total, total);
    Ok((out, settings.directional.then_some(dir_out)))
}
