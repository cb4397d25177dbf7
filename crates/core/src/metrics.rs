//! Image error metrics: RMSE, relMSE and FLIP.
//!
//! - RMSE: sqrt of the mean squared difference over pixels and channels.
//! - relMSE: mean over pixels and channels of (a−b)²/(b²+0.01), with `b` the reference (the
//!   second image); the 0.01 keeps dark pixels from dominating.
//! - FLIP (Andersson et al. 2020) through the `nv-flip` crate (NVIDIA's reference
//!   implementation). FLIP is defined on display-referred LDR images, so both images are first
//!   mapped through the same exposure and tone curve ([`LdrSettings`]); the mean of the FLIP
//!   error map is reported, at the default 67 pixels per degree (0.7 m from a 0.7 m wide 4K
//!   monitor).

use crate::image::{Image, LdrSettings};

#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    #[error("images differ in size: {a_w}×{a_h} vs {b_w}×{b_h}")]
    SizeMismatch {
        a_w: u32,
        a_h: u32,
        b_w: u32,
        b_h: u32,
    },
}

/// The figures of `lightlab compare`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Comparison {
    pub rmse: f64,
    pub relmse: f64,
    pub flip: f64,
    /// Mean of A over mean of B, per channel (a global brightness bias).
    pub mean_ratio: [f64; 3],
}

fn check(a: &Image, b: &Image) -> Result<(), MetricsError> {
    if a.width != b.width || a.height != b.height {
        return Err(MetricsError::SizeMismatch {
            a_w: a.width,
            a_h: a.height,
            b_w: b.width,
            b_h: b.height,
        });
    }
    Ok(())
}

/// Root-mean-square error over pixels and channels.
pub fn rmse(a: &Image, reference: &Image) -> Result<f64, MetricsError> {
    check(a, reference)?;
    let s: f64 = a
        .data
        .iter()
        .zip(&reference.data)
        .map(|(x, y)| (*x - *y).as_dvec3().length_squared())
        .sum();
    Ok((s / (3.0 * a.data.len() as f64)).sqrt())
}

/// Relative mean squared error: mean of (a−b)²/(b²+0.01), `reference` = b.
pub fn relmse(a: &Image, reference: &Image) -> Result<f64, MetricsError> {
    check(a, reference)?;
    let mut s = 0.0f64;
    for (x, y) in a.data.iter().zip(&reference.data) {
        for c in 0..3 {
            let (x, y) = (x[c] as f64, y[c] as f64);
            s += (x - y) * (x - y) / (y * y + 0.01);
        }
    }
    Ok(s / (3.0 * a.data.len() as f64))
}

/// [`relmse`] over the pixels where `mask` is true (row-major, one flag per pixel); 0 when
/// none is.
pub fn relmse_masked(a: &Image, reference: &Image, mask: &[bool]) -> Result<f64, MetricsError> {
    check(a, reference)?;
    let (mut s, mut n) = (0.0f64, 0usize);
    for ((x, y), _) in a
        .data
        .iter()
        .zip(&reference.data)
        .zip(mask)
        .filter(|(_, m)| **m)
    {
        for c in 0..3 {
            let (x, y) = (x[c] as f64, y[c] as f64);
            s += (x - y) * (x - y) / (y * y + 0.01);
        }
        n += 3;
    }
    Ok(if n == 0 { 0.0 } else { s / n as f64 })
}

/// Mean LDR-FLIP error after tone mapping both images with `ldr`.
pub fn flip(a: &Image, reference: &Image, ldr: LdrSettings) -> Result<f64, MetricsError> {
    check(a, reference)?;
    let ra = nv_flip::FlipImageRgb8::with_data(a.width, a.height, &a.to_srgb8(ldr));
    let rb = nv_flip::FlipImageRgb8::with_data(
        reference.width,
        reference.height,
        &reference.to_srgb8(ldr),
    );
    let err = nv_flip::flip(rb, ra, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    Ok(nv_flip::FlipPool::from_image(&err).mean() as f64)
}

/// All three metrics of `a` against `reference`.
pub fn compare(a: &Image, reference: &Image, ldr: LdrSettings) -> Result<Comparison, MetricsError> {
    Ok(Comparison {
        rmse: rmse(a, reference)?,
        relmse: relmse(a, reference)?,
        flip: flip(a, reference, ldr)?,
        mean_ratio: {
            let (ma, mb) = (a.mean().as_dvec3(), reference.mean().as_dvec3());
            [0, 1, 2].map(|k| if mb[k] > 0.0 { ma[k] / mb[k] } else { f64::NAN })
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn identical_images_have_zero_error() {
        let a = Image::from_fn(32, 32, |x, y| {
            Vec3::new(x as f32 / 32.0, y as f32 / 32.0, 0.5)
        });
        let c = compare(&a, &a, LdrSettings::default()).unwrap();
        assert_eq!(c.rmse, 0.0);
        assert_eq!(c.relmse, 0.0);
        assert!(c.flip < 1e-6, "{}", c.flip);
    }

    #[test]
    fn known_values() {
        let b = Image::from_fn(4, 4, |_, _| Vec3::splat(0.1));
        let a = Image::from_fn(4, 4, |_, _| Vec3::splat(0.2));
        assert!((rmse(&a, &b).unwrap() - 0.1).abs() < 1e-7);
        // (0.1)² / (0.01 + 0.01) = 0.5
        assert!((relmse(&a, &b).unwrap() - 0.5).abs() < 1e-6);
        let f = flip(&a, &b, LdrSettings::default()).unwrap();
        assert!(f > 0.01 && f < 1.0, "{f}");
    }

    #[test]
    fn flip_grows_with_the_difference() {
        let b = Image::from_fn(32, 32, |x, _| Vec3::splat(x as f32 / 32.0));
        let small = Image::from_fn(32, 32, |x, _| Vec3::splat(x as f32 / 32.0 + 0.02));
        let big = Image::from_fn(32, 32, |x, _| Vec3::splat(1.0 - x as f32 / 32.0));
        let fs = flip(&small, &b, LdrSettings::default()).unwrap();
        let fb = flip(&big, &b, LdrSettings::default()).unwrap();
        assert!(fs < fb, "{fs} {fb}");
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let a = Image::new(4, 4);
        let b = Image::new(4, 5);
        assert!(matches!(
            compare(&a, &b, LdrSettings::default()),
            Err(MetricsError::SizeMismatch { .. })
        ));
    }
}
