//! Wind sway of foliage (the WPI report's §4.4 animated leaves): one displacement
//! function applied identically by every pass that rasterises the scene (camera G-buffer or
//! forward pass, shadow maps, reflective shadow maps; WGSL `sway` in common.wgsl) and by the
//! CPU when it builds the displaced scene the path tracer renders, so that the passes agree
//! (no self-shadowing shimmer) and the GPU can be tested against the CPU.
//!
//! A vertex at world position p with material weight w moves horizontally along the wind:
//! `p + d · a · w · h² · g`, where h = clamp((p.y − ground)/height, 0, 1) keeps roots and
//! trunks still and tips free, and g = sin φ + 0.3 sin(2.7 φ + 1.3 p.x + 0.7 p.z) is a gust
//! travelling along the wind (φ = 2π(f t − d·p/λ)) with a faster flutter on top.

use glam::{Vec3, Vec4};

/// Wind parameters. `amplitude` = 0 turns the sway off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    /// Horizontal unit direction the wind blows towards.
    pub direction: Vec3,
    /// Largest displacement [m] of a weight-1 vertex at full height.
    pub amplitude: f32,
    /// Gust frequency [Hz].
    pub frequency: f32,
    /// Gust wavelength along the wind [m].
    pub wavelength: f32,
    /// Time [s].
    pub time: f32,
    /// Height [m] below which nothing moves, and the height above it of full sway.
    pub ground: f32,
    pub height: f32,
}

impl Default for Wind {
    fn default() -> Self {
        Wind {
            direction: Vec3::X,
            amplitude: 0.0,
            frequency: 0.4,
            wavelength: 6.0,
            time: 0.0,
            ground: 0.0,
            height: 2.0,
        }
    }
}

/// Wind parameters that make no sense.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum WindError {
    #[error("wind parameters must be finite")]
    NotFinite,
    #[error("wind amplitude and frequency must not be negative")]
    Negative,
    #[error("wind wavelength and height must be positive")]
    NotPositive,
}

impl Wind {
    /// A breeze of `amplitude` metres towards `direction` (made horizontal) at time `time`.
    pub fn breeze(direction: Vec3, amplitude: f32, time: f32) -> Wind {
        Wind {
            direction: Vec3::new(direction.x, 0.0, direction.z).normalize_or(Vec3::X),
            amplitude,
            time,
            ..Default::default()
        }
    }

    /// Whether the parameters make sense (finite, non-negative sizes, a direction).
    pub fn validate(&self) -> Result<(), WindError> {
        let v = [
            self.amplitude,
            self.frequency,
            self.wavelength,
            self.time,
            self.ground,
            self.height,
        ];
        if !self.direction.is_finite() || v.iter().any(|x| !x.is_finite()) {
            return Err(WindError::NotFinite);
        }
        if self.amplitude < 0.0 || self.frequency < 0.0 {
            return Err(WindError::Negative);
        }
        if self.wavelength <= 0.0 || self.height <= 0.0 {
            return Err(WindError::NotPositive);
        }
        Ok(())
    }

    /// The displaced position of a vertex at `p` with material sway weight `weight`.
    pub fn sway(&self, p: Vec3, weight: f32) -> Vec3 {
        if self.amplitude == 0.0 || weight == 0.0 {
            return p;
        }
        let d = self.direction;
        let h = ((p.y - self.ground) / self.height).clamp(0.0, 1.0);
        let phi = std::f32::consts::TAU * (self.frequency * self.time - d.dot(p) / self.wavelength);
        let g = phi.sin() + 0.3 * (2.7 * phi + 1.3 * p.x + 0.7 * p.z).sin();
        p + d * (self.amplitude * weight * h * h * g)
    }

    /// The two vec4s of the WGSL `sway`: (direction·amplitude, frequency) and (wavelength,
    /// time, ground, height).
    pub fn uniform(&self) -> [[f32; 4]; 2] {
        [
            (self.direction * self.amplitude)
                .extend(self.frequency)
                .to_array(),
            Vec4::new(self.wavelength, self.time, self.ground, self.height).to_array(),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_stay_tips_move_along_the_wind_only() {
        let w = Wind::breeze(Vec3::new(1.0, 0.5, 1.0), 0.1, 0.7);
        assert!((w.direction.length() - 1.0).abs() < 1e-6 && w.direction.y == 0.0);
        let root = Vec3::new(0.3, 0.0, 0.2);
        assert_eq!(w.sway(root, 1.0), root);
        let tip = Vec3::new(0.3, 2.5, 0.2);
        let m = w.sway(tip, 1.0) - tip;
        assert!(m.length() > 0.0 && m.length() <= 0.13 + 1e-6, "{m}");
        assert!(m.normalize().dot(w.direction).abs() > 0.9999);
        // Weight scales the motion; no wind, no motion.
        let half = w.sway(tip, 0.5) - tip;
        assert!((half - 0.5 * m).length() < 1e-6);
        assert_eq!(Wind::default().sway(tip, 1.0), tip);
        // It changes over time.
        let later = Wind { time: 1.9, ..w };
        assert!((later.sway(tip, 1.0) - w.sway(tip, 1.0)).length() > 1e-3);
        assert!(w.validate().is_ok());
        assert!(
            Wind {
                wavelength: 0.0,
                ..w
            }
            .validate()
            .is_err()
        );
    }
}
