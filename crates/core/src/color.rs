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
