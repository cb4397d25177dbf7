//! Lens prescriptions: the surfaces of a real lens, read from lightlab's small text format
//! (documented in `docs/lenses.md`), and the three lenses lightlab ships.
//!
//! ```text
//! # comment
//! name achromatic doublet
//! units mm                      # mm (the default) or m
//! #        radius  thickness  ior     aperture
//! stop             8.0                10.0
//! surface  22.39   5.0        1.5168  22.0
//! surface  -22.39  2.0        1.620   22.0
//! surface  -408.0  44.0       1       22.0
//! ```
//!
//! Surfaces run from the object side to the film. `radius` is the signed radius of curvature
//! (positive: the centre of curvature lies towards the film; `0` or `inf`: a plane),
//! `thickness` the axial distance to the next surface (the last one's is the nominal distance
//! to the film, which focusing replaces), `ior` the refractive index of the medium behind the
//! surface, towards the film (1 for air), `aperture` the clear diameter. A `stop` line is the
//! aperture stop: a plane in air with a diameter and the distance to the next surface.
//! No crate reads lens prescriptions (lens-design files such as Zemax's are proprietary and
//! much larger), so this format and its parser are our own.

/// One surface of a lens, in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    /// Signed radius of curvature; positive when the centre lies towards the film; 0: a plane.
    pub radius: f64,
    /// Axial distance to the next surface.
    pub thickness: f64,
    /// Refractive index behind the surface (towards the film).
    pub ior: f64,
    /// Clear aperture diameter.
    pub aperture: f64,
    /// The aperture stop (a plane that only blocks).
    pub stop: bool,
}

/// A lens: its name and surfaces from the object side to the film, in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct Prescription {
    pub name: String,
    pub elements: Vec<Element>,
}

/// A prescription that cannot be read or cannot form a lens.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PrescriptionError {
    #[error("line {line}: {message}")]
    Line { line: usize, message: String },
    #[error("the prescription has no refracting surface")]
    NoSurface,
    #[error("the prescription has more than one stop")]
    TwoStops,
}

/// The lenses lightlab ships: (name, prescription text).
pub const BUILTIN: [(&str, &str); 3] = [
    ("doublet", include_str!("../../lenses/doublet.lens")),
    ("biconvex", include_str!("../../lenses/biconvex.lens")),
    (
        "double-gauss",
        include_str!("../../lenses/double-gauss.lens"),
    ),
];

impl Prescription {
    /// A shipped lens by name (`doublet`, `biconvex`, `double-gauss`).
    pub fn builtin(name: &str) -> Option<Prescription> {
        BUILTIN
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, text)| Prescription::parse(text).expect("a shipped lens reads"))
    }

    /// Read a prescription from lightlab's lens format.
    pub fn parse(text: &str) -> Result<Prescription, PrescriptionError> {
        let mut name = String::from("lens");
        let mut scale = 1e-3;
        let mut elements = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let err = |message: String| PrescriptionError::Line { line, message };
            let content = raw.split('#').next().unwrap_or("").trim();
            let mut words = content.split_whitespace();
            let Some(key) = words.next() else { continue };
            let rest: Vec<&str> = words.collect();
            match key {
                "name" => name = rest.join(" "),
                "units" => {
                    scale = match rest.as_slice() {
                        ["mm"] => 1e-3,
                        ["m"] => 1.0,
                        _ => return Err(err(format!("units must be mm or m, not {rest:?}"))),
                    };
                    if !elements.is_empty() {
                        return Err(err("units must come before the surfaces".into()));
                    }
                }
                "surface" | "stop" => {
                    let stop = key == "stop";
                    let want = if stop { 2 } else { 4 };
                    if rest.len() != want {
                        let cols = if stop {
                            "thickness aperture"
                        } else {
                            "radius thickness ior aperture"
                        };
                        return Err(err(format!("'{key}' takes {want} numbers: {cols}")));
                    }
                    let nums = rest
                        .iter()
                        .map(|w| number(w).map_err(&err))
                        .collect::<Result<Vec<f64>, _>>()?;
                    let e = if stop {
                        Element {
                            radius: 0.0,
                            thickness: nums[0] * scale,
                            ior: 1.0,
                            aperture: nums[1] * scale,
                            stop,
                        }
                    } else {
                        Element {
                            radius: nums[0] * scale,
                            thickness: nums[1] * scale,
                            ior: nums[2],
                            aperture: nums[3] * scale,
                            stop,
                        }
                    };
                    check(&e).map_err(err)?;
                    elements.push(e);
                }
                _ => {
                    return Err(err(format!(
                        "unknown keyword '{key}' (name, units, surface, stop)"
                    )));
                }
            }
        }
        if !elements.iter().any(|e| !e.stop) {
            return Err(PrescriptionError::NoSurface);
        }
        if elements.iter().filter(|e| e.stop).count() > 1 {
            return Err(PrescriptionError::TwoStops);
        }
        Ok(Prescription { name, elements })
    }

    /// The same lens with every length multiplied by `k`.
    pub fn scaled(&self, k: f64) -> Prescription {
        let mut p = self.clone();
        for e in &mut p.elements {
            e.radius *= k;
            e.thickness *= k;
            e.aperture *= k;
        }
        p
    }
}

/// A number of the format; `inf` is a plane's radius.
fn number(w: &str) -> Result<f64, String> {
    if w.eq_ignore_ascii_case("inf") {
        return Ok(0.0);
    }
    w.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("'{w}' is not a finite number"))
}

fn check(e: &Element) -> Result<(), String> {
    if e.aperture <= 0.0 {
        return Err(format!("the aperture must be > 0 (got {})", e.aperture));
    }
    if e.thickness < 0.0 {
        return Err(format!("the thickness must be ≥ 0 (got {})", e.thickness));
    }
    if !(1.0..=4.0).contains(&e.ior) {
        return Err(format!("the index must be in 1..=4 (got {})", e.ior));
    }
    if e.radius != 0.0 && e.radius.abs() < 0.5 * e.aperture {
        return Err(format!(
            "a sphere of radius {} cannot span an aperture of diameter {}",
            e.radius.abs(),
            e.aperture
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_lenses_read() {
        for (name, _) in BUILTIN {
            let p = Prescription::builtin(name).unwrap();
            assert!(p.elements.len() >= 3, "{name}");
        }
        let d = Prescription::builtin("doublet").unwrap();
        assert!(d.elements[0].stop);
        assert!((d.elements[1].radius - 0.02239).abs() < 1e-12);
        assert_eq!(d.elements[2].ior, 1.620);
    }

    #[test]
    fn bad_prescriptions_say_where() {
        let bad = |t: &str| Prescription::parse(t).unwrap_err();
        assert_eq!(
            bad("surface 10 2 1.5\n"),
            PrescriptionError::Line {
                line: 1,
                message: "'surface' takes 4 numbers: radius thickness ior aperture".into()
            }
        );
        assert!(matches!(
            bad("\n\nsurface 1 2 1.5 10\n"),
            PrescriptionError::Line { line: 3, .. }
        ));
        assert!(matches!(
            bad("surface 10 2 0.5 4\n"),
            PrescriptionError::Line { .. }
        ));
        assert!(matches!(
            bad("surface 10 x 1.5 4\n"),
            PrescriptionError::Line { .. }
        ));
        assert!(matches!(bad("lens 10\n"), PrescriptionError::Line { .. }));
        assert_eq!(bad("stop 1 5\n"), PrescriptionError::NoSurface);
        assert_eq!(
            bad("stop 1 5\nstop 1 5\nsurface inf 1 1.5 4\n"),
            PrescriptionError::TwoStops
        );
        let ok = Prescription::parse("units m\nsurface inf 0.01 1.5 0.02 # flat\n").unwrap();
        assert_eq!(ok.elements[0].radius, 0.0);
        assert_eq!(ok.elements[0].thickness, 0.01);
    }
}
