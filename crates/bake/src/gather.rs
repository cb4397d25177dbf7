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

use crate::texels::Texels;
use crate::{BakeError, Progress};
use glam::Vec3;
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
}

impl Default for GatherSettings {
    fn default() -> Self {
        GatherSettings {
            samples: 256,
            max_depth: 16,
        }
    }
}

/// Gather every valid texel. Returns one value per texel and page (zero where invalid).
pub fn gather(
    tracer: &PathTracer,
    texels: &Texels,
    valid: &[Vec<bool>],
    settings: &GatherSettings,
    seed: u64,
    progress: Progress,
) -> Result<Vec<Vec<Vec3>>, BakeError> {
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
    for (page, valid) in texels.pages.iter().zip(valid) {
        let start = base;
        base += page.samples.len() as u64;
        let values: Vec<Vec3> = page
            .samples
            .par_iter()
            .zip(valid.par_iter())
            .enumerate()
            .map(|(i, (s, &ok))| {
                let Some(s) = s else { return Vec3::ZERO };
                if cancelled.load(Ordering::Relaxed) {
                    return Vec3::ZERO;
                }
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                if n.is_multiple_of(1024) && !progress("gather", n, total) {
                    cancelled.store(true, Ordering::Relaxed);
                }
                if !ok {
                    return Vec3::ZERO;
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
                (sum / settings.samples as f64).as_vec3()
            })
            .collect();
        if cancelled.load(Ordering::Relaxed) {
            return Err(BakeError::Cancelled);
        }
        out.push(values);
    }
    progress("gather", total, total);
    Ok(out)
}
