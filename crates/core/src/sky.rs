//! Daylight: the Preetham–Shirley–Smits analytic sky (SIGGRAPH 1999, "A Practical Analytic
//! Model for Daylight") and a sun, for scenes that bring no light of their own.
//!
//! Why Preetham and not Hosek–Wilkie (2012), its more accurate successor: Preetham's model is
//! a Perez distribution whose five parameters per channel are linear in the turbidity, about
//! thirty published constants in all, written here from the paper; Hosek–Wilkie needs its
//! fitted dataset (thousands of coefficients per wavelength band) shipped with the code. For a
//! default light that makes an unlit file visible and plausibly lit, Preetham's clear skies
//! are enough; a user with a measured or HDR sky passes `--env FILE`.
//!
//! Units: lightlab's daylight radiance is Preetham's luminance in units of 10 kcd/m², so
//! irradiance is in units of 10 klx: the default sun of 8 is ≈ 80 klx at normal incidence, and
//! the default sky (turbidity 3, sun at 45°) gives 2.9 (≈ 29 klx) on a horizontal surface, a
//! sun : sky ratio of 1.9 : 1. Preetham's clear skies are known to be bright next to measured
//! ones (3–5 : 1 at this elevation); the ratio is tested, not tuned. Below the horizon the
//! environment is a Lambertian ground of albedo [`Daylight::ground_albedo`] lit by sun and sky.

use crate::image::Image;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A clear-sky daylight: the sun's position and strength and the air's turbidity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Daylight {
    /// Sun elevation above the horizon [degrees], 0.5–90.
    pub elevation: f32,
    /// Sun azimuth [degrees], measured from +Z towards +X (0: the sun in the +Z direction).
    pub azimuth: f32,
    /// Irradiance of the sun at normal incidence [10 klx].
    pub sun_irradiance: f32,
    /// Turbidity, 2 (very clear) to 10 (hazy).
    pub turbidity: f32,
    pub ground_albedo: f32,
}

impl Default for Daylight {
    fn default() -> Self {
        Daylight {
            elevation: 45.0,
            azimuth: 135.0,
            sun_irradiance: 8.0,
            turbidity: 3.0,
            ground_albedo: 0.3,
        }
    }
}

/// The angular diameter of the sun [radians].
pub const SUN_DIAMETER: f32 = 0.0093;

/// Perez et al.'s five-parameter sky distribution.
fn perez(p: [f32; 5], cos_theta: f32, gamma: f32) -> f32 {
    let [a, b, c, d, e] = p;
    (1.0 + a * (b / cos_theta.max(0.01)).exp())
        * (1.0 + c * (d * gamma).exp() + e * gamma.cos().powi(2))
}

impl Daylight {
    /// The unit vector towards the sun.
    pub fn sun_direction(&self) -> Vec3 {
        let (e, a) = (self.elevation.to_radians(), self.azimuth.to_radians());
        Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
    }

    /// Check the parameters; the message names the one out of range.
    pub fn check(&self) -> Result<(), String> {
        let ok = |v: f32, lo: f32, hi: f32| v.is_finite() && (lo..=hi).contains(&v);
        if !ok(self.elevation, 0.5, 90.0) {
            return Err(format!(
                "sun elevation {} must be 0.5 to 90 degrees",
                self.elevation
            ));
        }
        if !self.azimuth.is_finite() {
            return Err("sun azimuth must be a finite number of degrees".into());
        }
        if !ok(self.sun_irradiance, 0.0, 1e6) {
            return Err(format!(
                "sun irradiance {} must be 0 to 1e6",
                self.sun_irradiance
            ));
        }
        if !ok(self.turbidity, 2.0, 10.0) {
            return Err(format!("turbidity {} must be 2 to 10", self.turbidity));
        }
        if !ok(self.ground_albedo, 0.0, 1.0) {
            return Err(format!(
                "ground albedo {} must be 0 to 1",
                self.ground_albedo
            ));
        }
        Ok(())
    }

    /// Sky radiance towards direction `d` (unit, y up), linear Rec.709, for `d.y ≥ 0`.
    pub fn sky(&self, d: Vec3) -> Vec3 {
        let t = self.turbidity;
        let s = self.sun_direction();
        let theta_s = s.y.clamp(-1.0, 1.0).acos();
        // Perez parameters of Y, x and y, linear in the turbidity (Preetham et al., App. A.2).
        let py = [
            0.1787 * t - 1.4630,
            -0.3554 * t + 0.4275,
            -0.0227 * t + 5.3251,
            0.1206 * t - 2.5771,
            -0.0670 * t + 0.3703,
        ];
        let px = [
            -0.0193 * t - 0.2592,
            -0.0665 * t + 0.0008,
            -0.0004 * t + 0.2125,
            -0.0641 * t - 0.8989,
            -0.0033 * t + 0.0452,
        ];
        let pyc = [
            -0.0167 * t - 0.2608,
            -0.0950 * t + 0.0092,
            -0.0079 * t + 0.2102,
            -0.0441 * t - 1.6537,
            -0.0109 * t + 0.0529,
        ];
        // Zenith luminance [kcd/m²] and chromaticity (App. A.2).
        let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * theta_s);
        let yz = ((4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192).max(0.0);
        let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
        let dot4 = |c: [f32; 4]| c.iter().zip(th).map(|(a, b)| a * b).sum::<f32>();
        let xz = t * t * dot4([0.00166, -0.00375, 0.00209, 0.0])
            + t * dot4([-0.02903, 0.06377, -0.03202, 0.00394])
            + dot4([0.11693, -0.21196, 0.06052, 0.25886]);
        let yzc = t * t * dot4([0.00275, -0.00610, 0.00317, 0.0])
            + t * dot4([-0.04214, 0.08970, -0.04153, 0.00516])
            + dot4([0.15346, -0.26756, 0.06670, 0.26688]);
        let cos_theta = d.y.max(0.0);
        let gamma = d.dot(s).clamp(-1.0, 1.0).acos();
        let rel = |p: [f32; 5]| perez(p, cos_theta, gamma) / perez(p, 1.0, theta_s);
        let lum = yz * rel(py) * 0.1; // kcd/m² → units of 10 kcd/m²
        let (x, y) = (xz * rel(px), yzc * rel(pyc));
        xyy_to_rgb(x, y, lum)
    }

    /// The irradiance the sky gives a horizontal surface (numerically, `n` × `n/2` samples).
    pub fn sky_horizontal_irradiance(&self, n: usize) -> Vec3 {
        let mut e = Vec3::ZERO;
        for i in 0..n {
            for j in 0..n / 2 {
                let phi = 2.0 * PI * (i as f32 + 0.5) / n as f32;
                let theta = 0.5 * PI * (j as f32 + 0.5) / (n / 2) as f32;
                let d = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                let dw = (2.0 * PI / n as f32) * (0.5 * PI / (n / 2) as f32) * theta.sin();
                e += self.sky(d) * d.y * dw;
            }
        }
        e
    }

    /// The sky as an equirectangular map `width` × `width/2` (lightlab's lat-long convention,
    /// v = 0 at +Y), with the lit ground below the horizon. The sun itself is not in the map:
    /// it is the directional light [`Daylight::sun_direction`].
    pub fn environment(&self, width: u32) -> Image {
        let height = (width / 2).max(1);
        let s = self.sun_direction();
        let e_ground = self.sky_horizontal_irradiance(64)
            + Vec3::splat(self.sun_irradiance * s.y.max(0.0)) * SUN_COLOR;
        let ground = e_ground * self.ground_albedo / PI;
        Image::from_fn(width, height, |x, y| {
            let uv = Vec2::new(
                (x as f32 + 0.5) / width as f32,
                (y as f32 + 0.5) / height as f32,
            );
            let d = crate::sh_env::latlong_uv_to_dir(uv);
            if d.y >= 0.0 { self.sky(d) } else { ground }
        })
    }
}

/// The sun's colour (a warm white of unit luminance, as a clear-day sun at mid elevation).
pub const SUN_COLOR: Vec3 = Vec3::new(1.06, 0.99, 0.89);

/// CIE xyY → linear Rec.709 RGB (D65).
fn xyy_to_rgb(x: f32, y: f32, lum: f32) -> Vec3 {
    if y <= 1e-6 {
        return Vec3::ZERO;
    }
    let (cx, cz) = (x * lum / y, (1.0 - x - y) * lum / y);
    Vec3::new(
        3.2406 * cx - 1.5372 * lum - 0.4986 * cz,
        -0.9689 * cx + 1.8758 * lum + 0.0415 * cz,
        0.0557 * cx - 0.2040 * lum + 1.0570 * cz,
    )
    .max(Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sky_is_brightest_near_the_sun_and_bluer_overhead_than_at_the_horizon() {
        let d = Daylight::default();
        let s = d.sun_direction();
        assert!((s.length() - 1.0).abs() < 1e-6 && (s.y - 45f32.to_radians().sin()).abs() < 1e-6);
        let near = d.sky((s + Vec3::new(0.0, 0.05, 0.0)).normalize());
        let away = d.sky(Vec3::new(-s.x, 0.5, -s.z).normalize());
        assert!(near.length() > 3.0 * away.length(), "{near} vs {away}");
        // Blue dominates away from the sun.
        assert!(away.z > away.x, "{away}");
        // Horizontal sky irradiance of a clear day, 4–8 times below the sun's.
        let e = d.sky_horizontal_irradiance(128);
        let sun_h = d.sun_irradiance * s.y;
        let ratio = sun_h / e.y;
        assert!((1.7..2.2).contains(&ratio), "sun/sky {ratio} (sky {e})");
        // Hazier air: a brighter, whiter sky.
        let hazy = Daylight {
            turbidity: 8.0,
            ..d
        };
        let eh = hazy.sky_horizontal_irradiance(128);
        assert!(eh.y > e.y, "{eh} vs {e}");
    }

    #[test]
    fn the_map_matches_the_model_and_its_ground_is_lit() {
        let d = Daylight::default();
        let img = d.environment(64);
        assert_eq!((img.width, img.height), (64, 32));
        assert!(
            img.data
                .iter()
                .all(|v| v.is_finite() && v.min_element() >= 0.0)
        );
        // Top row ≈ zenith radiance; bottom row = the ground.
        let zenith = d.sky(Vec3::Y);
        let top = img.data[5];
        assert!(
            (top - zenith).length() < 0.05 * zenith.length(),
            "{top} vs {zenith}"
        );
        let ground = img.data[img.data.len() - 1];
        assert!(ground.min_element() > 0.0 && ground.max_element() < zenith.max_element() * 10.0);
        assert!(d.check().is_ok());
        let bad = Daylight {
            elevation: -5.0,
            ..d
        };
        assert!(bad.check().unwrap_err().contains("elevation"));
    }
}
