//! Far-field photometry: goniometric light distributions read from IES LM-63 files
//! ([`ies`]) and EULUMDAT files ([`ldt`]) — what lighting designers bring as measured lamps.
//! Written here because no maintained Rust crate reads both formats with their symmetry and
//! tilt rules (issue 24 asks for our own parser, tested on files we make).
//!
//! **The light's frame.** A goniometric light shines along its glTF direction, local −Z.
//! - Type C (architectural; EULUMDAT is always C): the vertical angle γ runs from nadir (the
//!   light's direction, γ = 0) to zenith (180°); the horizontal angle C turns counterclockwise
//!   seen from above (from the zenith, +Z, looking down) from C0 = local +X to C90 = local +Y:
//!   d = (sin γ cos C, sin γ sin C, −cos γ).
//! - Type B (floodlights): the planes share the horizontal lateral axis (local +X); V turns the
//!   plane about it from the beam axis (−Z, V = 0) towards up (+Y, V = 90°), H leans within the
//!   plane towards +X: d = cos H·(0, sin V, −cos V) + sin H·(1, 0, 0).
//! - Type A (automotive): vertical planes around the up axis (+Y); V is the elevation (−90°
//!   down … 90° up) and H turns clockwise seen from above, from the beam axis (−Z) towards +X:
//!   d = (cos V sin H, sin V, −cos V cos H).
//!
//! **Symmetry** is kept as the file gives it and folded at evaluation: type C horizontal angles
//! {0} (rotational), 0–90 (quadrant), 0–180 (bilateral about the C0–C180 plane), 90–270
//! (bilateral about C90–C270), 0–360 (none; a last plane short of 360° wraps to the first);
//! types A and B 0–90 (symmetric about H = 0) or −90–90. Directions outside the measured
//! vertical range have no light. Intensities are bilinear in (horizontal, vertical) angle.

pub mod ies;
pub mod ldt;

use glam::Vec3;

/// Read a photometric file: EULUMDAT for `.ldt` (any case), IES LM-63 otherwise.
pub fn read(path: &std::path::Path) -> Result<Goniometric, PhotometryError> {
    if lightlab_core::image::extension(path) == "ldt" {
        ldt::read(path)
    } else {
        ies::read(path)
    }
}

/// Which photometric web the angles describe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotometryType {
    A,
    B,
    C,
}

/// A measured luminous intensity distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct Goniometric {
    pub kind: PhotometryType,
    /// Vertical angles in degrees, increasing.
    pub vertical: Vec<f32>,
    /// Horizontal angles in degrees, increasing.
    pub horizontal: Vec<f32>,
    /// Candela, `candela[h * vertical.len() + v]`, all factors applied.
    pub candela: Vec<f32>,
    /// IES `TILT=INCLUDE` data: (tilt angle in degrees, multiplier), increasing angles; empty
    /// for none. [`Goniometric::tilt_factor`] reads it.
    pub tilt: Vec<(f32, f32)>,
    /// Size of the luminous opening in metres (width, length, height; IES signs kept:
    /// negative for round shapes).
    pub opening: Vec3,
}

/// Why a photometric file was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{0}")]
pub struct PhotometryError(pub String);

pub(crate) fn bad(msg: impl Into<String>) -> PhotometryError {
    PhotometryError(msg.into())
}

impl Goniometric {
    /// Check the angle lists and values (called by both parsers).
    pub(crate) fn check(self) -> Result<Goniometric, PhotometryError> {
        let (nv, nh) = (self.vertical.len(), self.horizontal.len());
        if nv == 0 || nh == 0 {
            return Err(bad("no vertical or no horizontal angles"));
        }
        if self.candela.len() != nv * nh {
            return Err(bad(format!(
                "{} candela values for {nh} horizontal × {nv} vertical angles",
                self.candela.len()
            )));
        }
        for (what, a) in [
            ("vertical", &self.vertical),
            ("horizontal", &self.horizontal),
        ] {
            if a.iter().any(|x| !x.is_finite()) || a.windows(2).any(|w| w[1] <= w[0]) {
                return Err(bad(format!("{what} angles must be finite and increasing")));
            }
        }
        let (v0, v1) = (self.vertical[0], self.vertical[nv - 1]);
        let (h0, h1) = (self.horizontal[0], self.horizontal[nh - 1]);
        let ok = match self.kind {
            PhotometryType::C => v0 >= 0.0 && v1 <= 180.0 && h0 >= 0.0 && h1 <= 360.0,
            _ => v0 >= -90.0 && v1 <= 90.0 && h0 >= -90.0 && h1 <= 90.0,
        };
        if !ok {
            return Err(bad(format!(
                "angles out of range for type {:?} photometry: vertical {v0}…{v1}, horizontal \
                 {h0}…{h1}",
                self.kind
            )));
        }
        if self.kind == PhotometryType::C && h0 > 0.0 && !(h0 == 90.0 && h1 == 270.0) {
            return Err(bad(format!(
                "type C horizontal angles start at 0 (or run 90…270), not {h0}"
            )));
        }
        if self.candela.iter().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(bad("candela values must be finite and not negative"));
        }
        Ok(self)
    }

    /// The (horizontal, vertical) angles in degrees of local direction `d` (any length).
    pub fn angles(&self, d: Vec3) -> (f32, f32) {
        let d = d.normalize_or(Vec3::NEG_Z);
        match self.kind {
            PhotometryType::C => {
                let gamma = (-d.z).clamp(-1.0, 1.0).acos().to_degrees();
                let c = d.y.atan2(d.x).to_degrees().rem_euclid(360.0);
                (c, gamma)
            }
            PhotometryType::B => {
                let h = d.x.clamp(-1.0, 1.0).asin().to_degrees();
                let v = d.y.atan2(-d.z).to_degrees();
                (h, v)
            }
            PhotometryType::A => {
                let v = d.y.clamp(-1.0, 1.0).asin().to_degrees();
                let h = d.x.atan2(-d.z).to_degrees();
                (h, v)
            }
        }
    }

    /// The local direction of angles (horizontal, vertical) in degrees.
    pub fn direction(&self, h: f32, v: f32) -> Vec3 {
        let (h, v) = (h.to_radians(), v.to_radians());
        match self.kind {
            PhotometryType::C => Vec3::new(v.sin() * h.cos(), v.sin() * h.sin(), -v.cos()),
            PhotometryType::B => h.cos() * Vec3::new(0.0, v.sin(), -v.cos()) + h.sin() * Vec3::X,
            PhotometryType::A => Vec3::new(v.cos() * h.sin(), v.sin(), -v.cos() * h.cos()),
        }
    }

    /// The horizontal angle folded into the measured range by the file's symmetry; None
    /// where a type A or B web has no data.
    fn fold_horizontal(&self, h: f32) -> Option<f32> {
        let (h0, h1) = (
            self.horizontal[0],
            *self.horizontal.last().expect("checked"),
        );
        Some(match self.kind {
            PhotometryType::C => {
                let h = h.rem_euclid(360.0);
                if self.horizontal.len() == 1 {
                    h0
                } else if h0 == 90.0 {
                    // Bilateral about the C90–C270 plane.
                    match h {
                        h if h < 90.0 => 180.0 - h,
                        h if h > 270.0 => 540.0 - h,
                        h => h,
                    }
                } else if h1 <= 90.0 {
                    let h = if h > 180.0 { 360.0 - h } else { h };
                    if h > 90.0 { 180.0 - h } else { h }
                } else if h1 <= 180.0 {
                    if h > 180.0 { 360.0 - h } else { h }
                } else {
                    h
                }
            }
            _ => {
                let h = if h0 >= 0.0 { h.abs() } else { h };
                if h < h0 || h > h1 {
                    return None;
                }
                h
            }
        })
    }

    /// Candela towards local direction `d` (bilinear in the angles; 0 outside the web).
    pub fn intensity(&self, d: Vec3) -> f32 {
        let (h, v) = self.angles(d);
        let Some(h) = self.fold_horizontal(h) else {
            return 0.0;
        };
        let nv = self.vertical.len();
        let Some((v0, v1, fv)) = bracket(&self.vertical, v) else {
            return 0.0;
        };
        // A full type C web short of 360° wraps from its last plane to its first.
        let (h0, h1, fh) = match bracket(&self.horizontal, h) {
            Some(b) => b,
            None => {
                let last = self.horizontal.len() - 1;
                let span = self.horizontal[0] + 360.0 - self.horizontal[last];
                let t = (h - self.horizontal[last]).rem_euclid(360.0);
                (last, 0, (t / span).clamp(0.0, 1.0))
            }
        };
        let at = |hh: usize, vv: usize| self.candela[hh * nv + vv];
        let a = at(h0, v0) * (1.0 - fv) + at(h0, v1) * fv;
        let b = at(h1, v0) * (1.0 - fv) + at(h1, v1) * fv;
        a * (1.0 - fh) + b * fh
    }

    /// The tilt multiplier at a lamp tilt of `angle` degrees (1 without tilt data; held at
    /// the ends of the table).
    pub fn tilt_factor(&self, angle: f32) -> f32 {
        if self.tilt.is_empty() {
            return 1.0;
        }
        // A linear scan: tables are short, and the path tracer calls this per light sample.
        let t = &self.tilt;
        if angle <= t[0].0 {
            return t[0].1;
        }
        for w in t.windows(2) {
            let ((a0, m0), (a1, m1)) = (w[0], w[1]);
            if angle <= a1 {
                let f = if a1 > a0 {
                    (angle - a0) / (a1 - a0)
                } else {
                    1.0
                };
                return m0 + (m1 - m0) * f;
            }
        }
        t[t.len() - 1].1
    }
}

/// The indices around `x` in increasing `xs` and the fraction between them; None outside
/// (a single value stands for every `x`).
fn bracket(xs: &[f32], x: f32) -> Option<(usize, usize, f32)> {
    let n = xs.len();
    if n == 1 {
        return Some((0, 0, 0.0));
    }
    if x < xs[0] - 1e-4 || x > xs[n - 1] + 1e-4 {
        return None;
    }
    let x = x.clamp(xs[0], xs[n - 1]);
    let j = xs.partition_point(|&a| a <= x).clamp(1, n - 1);
    let i = j - 1;
    Some((i, j, ((x - xs[i]) / (xs[j] - xs[i])).clamp(0.0, 1.0)))
}
