//! Colour: sRGB transfer functions, luminance and the tone operators used for PNG output.
//!
//! All radiometric values in lightlab are linear Rec.709 RGB. Tone mapping happens only when an
//! image is written as PNG (or compared perceptually with FLIP); EXR output stays linear.

use glam::Vec3;

/// Rec.709 / sRGB relative luminance of a linear RGB value.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// sRGB opto-electronic transfer function (linear → encoded), input clamped to [0, 1].
#[inline]
pub fn srgb_encode(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse of [`srgb_encode`] (encoded → linear).
#[inline]
pub fn srgb_decode(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Tone operator applied before sRGB encoding when writing LDR images.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum ToneMap {
    /// Clamp to [0, 1]: exact for values already in range (what comparisons use).
    #[default]
    Clamp,
    /// Reinhard's global operator on luminance, L/(1+L), hue preserving.
    Reinhard,
    /// A filmic curve (Narkowicz's fit of the ACES reference rendering transform).
    Filmic,
}

crate::named_enum!(ToneMap, "tone operator", {
    Clamp => "clamp",
    Reinhard => "reinhard",
    Filmic => "filmic",
});

impl ToneMap {
    /// Map a linear value (after exposure) to display-referred linear [0, 1].
    pub fn apply(self, c: Vec3) -> Vec3 {
        match self {
            ToneMap::Clamp => c.clamp(Vec3::ZERO, Vec3::ONE),
            ToneMap::Reinhard => {
                let l = luminance(c);
                if l <= 0.0 {
                    Vec3::ZERO
                } else {
                    (c * (1.0 / (1.0 + l))).clamp(Vec3::ZERO, Vec3::ONE)
                }
            }
            ToneMap::Filmic => {
                let f = |x: f32| {
                    let x = x.max(0.0);
                    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
                };
                Vec3::new(f(c.x), f(c.y), f(c.z))
            }
        }
    }
}

/// Linear RGB → 8-bit sRGB with exposure (a multiplier) and a tone operator.
pub fn to_srgb8(c: Vec3, exposure: f32, tone: ToneMap) -> [u8; 3] {
    let t = tone.apply(c * exposure);
    let q = |x: f32| (srgb_encode(x) * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8;
    [q(t.x), q(t.y), q(t.z)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip_and_known_points() {
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            assert!((srgb_decode(srgb_encode(x)) - x).abs() < 1e-5);
        }
        // Mid grey 0.5 encoded is 0.7354 (IEC 61966-2-1).
        assert!((srgb_encode(0.5) - 0.735_357).abs() < 1e-5);
        assert_eq!(to_srgb8(Vec3::ONE, 1.0, ToneMap::Clamp), [255, 255, 255]);
        assert_eq!(to_srgb8(Vec3::ZERO, 1.0, ToneMap::Filmic), [0, 0, 0]);
    }

    #[test]
    fn luminance_weights_sum_to_one() {
        assert!((luminance(Vec3::ONE) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn tone_operators_are_monotonic_and_bounded() {
        for op in [ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Filmic] {
            let mut last = -1.0;
            for i in 0..200 {
                let v = op.apply(Vec3::splat(i as f32 * 0.05)).x;
                assert!((0.0..=1.0).contains(&v));
                assert!(v >= last, "{op:?} not monotonic");
                last = v;
            }
        }
    }
}

/// Ward Larson, Rushmeier & Piatko's histogram-adjustment tone operator (1997), with the
/// constants of Fuchs's CaLight (§3.3.5; its `Ward97.cpp`): luminance = max(R, G, B),
/// histogram of ln L over [ln 1e-4, max] in 300 bins, display range [1, 80] cd/m², histogram
/// ceiling T·Δb/ln(Ld_max) re-applied until less than 2.5 % of the samples are trimmed (falling
/// back to linear scaling when the histogram empties), Ld = Ld_max^P(ln L) with the cumulative
/// histogram P interpolated within each bin. Each value is scaled by Ld/L
/// (hue-preserving), then everything by the global maximum component, so the output lies in
/// [0, 1]. Fuchs's final gamma 2.0 for 8-bit light-maps is left to the caller.
#[derive(Clone, Copy, Debug)]
pub struct WardLarson {
    pub bins: usize,
    pub ld_max: f64,
    pub tolerance: f64,
    pub floor: f64,
}

impl Default for WardLarson {
    fn default() -> Self {
        WardLarson {
            bins: 300,
            ld_max: 80.0,
            tolerance: 0.025,
            floor: 1e-4,
        }
    }
}

impl WardLarson {
    /// Tone-map a set of linear RGB values (pixels or light-map texels).
    pub fn apply(&self, values: &[Vec3]) -> Vec<Vec3> {
        let lum: Vec<f64> = values
            .iter()
            .map(|v| v.max_element().max(0.0) as f64)
            .collect();
        let b: Vec<f64> = lum.iter().map(|l| l.max(self.floor).ln()).collect();
        let bmin = self.floor.ln();
        let bmax = b.iter().cloned().fold(bmin, f64::max);
        let bins = self.bins.max(1);
        let width = (bmax - bmin) / bins as f64;
        let mapped: Vec<f64> = if width <= 0.0 {
            lum.clone()
        } else {
            let bin_of = |x: f64| (((x - bmin) / width) as usize).min(bins - 1);
            let mut hist = vec![0.0f64; bins];
            for &x in &b {
                hist[bin_of(x)] += 1.0;
            }
            let t0 = values.len() as f64;
            let mut linear = false;
            loop {
                let t: f64 = hist.iter().sum();
                if t < self.tolerance * t0 {
                    linear = true;
                    break;
                }
                let ceiling = t * width / self.ld_max.ln();
                let mut trimmed = 0.0;
                for h in &mut hist {
                    if *h > ceiling {
                        trimmed += *h - ceiling;
                        *h = ceiling;
                    }
                }
                if trimmed <= self.tolerance * t0 {
                    break;
                }
            }
            if linear {
                lum.clone()
            } else {
                let total: f64 = hist.iter().sum();
                let mut cum = vec![0.0; bins];
                let mut acc = 0.0;
                for (c, h) in cum.iter_mut().zip(&hist) {
                    *c = acc / total;
                    acc += h;
                }
                // Interpolated within the bin (as Ward Larson et al.; CaLight used the bin's
                // start, which is flat inside a bin and bands into 300 levels).
                b.iter()
                    .map(|&x| {
                        let k = bin_of(x);
                        let frac = ((x - bmin) / width - k as f64).clamp(0.0, 1.0);
                        self.ld_max.powf(cum[k] + frac * hist[k] / total)
                    })
                    .collect()
            }
        };
        let scaled: Vec<Vec3> = values
            .iter()
            .zip(lum.iter().zip(&mapped))
            .map(|(v, (l, m))| {
                if *l > 0.0 {
                    *v * (*m / *l) as f32
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        let peak = scaled
            .iter()
            .map(|v| v.max_element())
            .fold(0.0f32, f32::max);
        if peak > 0.0 {
            scaled
                .into_iter()
                .map(|v| (v / peak).clamp(Vec3::ZERO, Vec3::ONE))
                .collect()
        } else {
            scaled
        }
    }
}

#[cfg(test)]
mod ward_tests {
    use super::*;

    #[test]
    fn ward_larson_is_monotone_bounded_and_keeps_uniform_input_uniform() {
        // Grey values log-uniform over six decades.
        let input: Vec<Vec3> = (0..2000)
            .map(|i| Vec3::splat(10f32.powf(-3.0 + 6.0 * i as f32 / 1999.0)))
            .collect();
        let out = WardLarson::default().apply(&input);
        let mut last = -1.0;
        for v in &out {
            assert!((0.0..=1.0).contains(&v.x));
            assert!(v.x >= last, "not monotone");
            last = v.x;
        }
        // Six decades are compressed into the display's ≈ 80:1.
        let lo = out
            .iter()
            .map(|v| v.x)
            .filter(|x| *x > 0.0)
            .fold(1.0f32, f32::min);
        assert!(1.0 / lo <= 81.0, "contrast {}", 1.0 / lo);
        let uniform = WardLarson::default().apply(&vec![Vec3::new(0.3, 0.2, 0.1); 100]);
        assert!(uniform.iter().all(|v| (*v - uniform[0]).length() < 1e-7));
        // Hue is preserved.
        assert!((uniform[0].y / uniform[0].x - 2.0 / 3.0).abs() < 1e-5);
    }
}
