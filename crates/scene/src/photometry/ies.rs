//! IES LM-63 photometric files (1986, 1991, 1995, 2002): an optional format line, keyword
//! lines, `TILT=NONE|INCLUDE|<file>`, then numbers separated by blanks, commas or line ends:
//! lamps, lumens per lamp (−1: absolute photometry), candela multiplier, vertical and
//! horizontal angle counts, photometric type (1 C, 2 B, 3 A), units (1 feet, 2 metres),
//! width, length, height, ballast factor, a future-use (or ballast-lamp) factor, input watts,
//! the angles and the candela values, horizontal angle by horizontal angle. Candela are scaled
//! by the multiplier and the ballast factor (and the 1986/1991 ballast-lamp factor, where
//! later revisions write 1).

use super::{Goniometric, PhotometryError, PhotometryType, bad};
use glam::Vec3;

/// Reads the text of the tilt file a `TILT=<name>` line names.
pub type TiltReader<'a> = dyn Fn(&str) -> Result<String, PhotometryError> + 'a;

/// Parse an IES file's text. `tilt_file` reads the file a `TILT=<name>` line names (None:
/// such a file is refused).
pub fn parse(text: &str, tilt_file: Option<&TiltReader>) -> Result<Goniometric, PhotometryError> {
    let mut lines = text.lines();
    let tilt = loop {
        let Some(line) = lines.next() else {
            return Err(bad("no TILT= line: not an IES LM-63 file"));
        };
        let t = line.trim_start_matches('\u{feff}').trim();
        if let Some(rest) = t.strip_prefix("TILT=") {
            break rest.trim().to_string();
        }
    };
    let rest: Vec<&str> = lines.collect();
    let mut numbers = Numbers::new(&rest.join("\n"))?;
    let tilt = match tilt.as_str() {
        "NONE" => vec![],
        "INCLUDE" => read_tilt(&mut numbers)?,
        name => {
            let read = tilt_file.ok_or_else(|| {
                bad(format!(
                    "TILT={name}: the tilt data is in another file, which was not given"
                ))
            })?;
            read_tilt(&mut Numbers::new(&read(name)?)?)?
        }
    };
    let _lamps = numbers.next("number of lamps")?;
    let _lumens = numbers.next("lumens per lamp")?;
    let multiplier = numbers.next("candela multiplier")?;
    let nv = numbers.count("number of vertical angles")?;
    let nh = numbers.count("number of horizontal angles")?;
    let kind = match numbers.next("photometric type")? as i64 {
        1 => PhotometryType::C,
        2 => PhotometryType::B,
        3 => PhotometryType::A,
        t => {
            return Err(bad(format!(
                "photometric type {t} is not 1 (C), 2 (B) or 3 (A)"
            )));
        }
    };
    let to_metres = match numbers.next("units type")? as i64 {
        1 => 0.3048,
        2 => 1.0,
        u => return Err(bad(format!("units type {u} is not 1 (feet) or 2 (metres)"))),
    };
    let mut opening = Vec3::ZERO;
    for (k, what) in ["width", "length", "height"].iter().enumerate() {
        opening[k] = numbers.next(what)? * to_metres;
    }
    let ballast = numbers.next("ballast factor")?;
    let ballast_lamp = numbers.next("ballast-lamp photometric factor")?;
    let _watts = numbers.next("input watts")?;
    let vertical = numbers.take(nv, "vertical angles")?;
    let horizontal = numbers.take(nh, "horizontal angles")?;
    let scale = multiplier * ballast * ballast_lamp;
    let candela = numbers
        .take(nv * nh, "candela values")?
        .into_iter()
        .map(|c| c * scale)
        .collect();
    if numbers.remaining() > 0 {
        return Err(bad(format!(
            "{} numbers after the candela values",
            numbers.remaining()
        )));
    }
    if !(scale.is_finite() && scale > 0.0) {
        return Err(bad(format!(
            "the candela multiplier × ballast factors is {scale}, not positive"
        )));
    }
    Goniometric {
        kind,
        vertical,
        horizontal,
        candela,
        tilt,
        opening,
    }
    .check()
}

/// Read an IES file; a `TILT=<file>` is read from the same folder.
pub fn read(path: &std::path::Path) -> Result<Goniometric, PhotometryError> {
    let text =
        std::fs::read_to_string(path).map_err(|e| bad(format!("{}: {e}", path.display())))?;
    let folder = path.parent().unwrap_or(std::path::Path::new("."));
    let tilt = |name: &str| -> Result<String, PhotometryError> {
        let p = folder.join(name);
        if std::path::Path::new(name).components().count() != 1 {
            return Err(bad(format!(
                "TILT={name}: a tilt file must sit beside the IES file"
            )));
        }
        std::fs::read_to_string(&p).map_err(|e| bad(format!("TILT={name}: {e}")))
    };
    parse(&text, Some(&tilt)).map_err(|e| bad(format!("{}: {}", path.display(), e.0)))
}

/// `TILT=INCLUDE` data: lamp-to-luminaire geometry, the count, the angles, the factors.
fn read_tilt(n: &mut Numbers) -> Result<Vec<(f32, f32)>, PhotometryError> {
    let geometry = n.next("lamp-to-luminaire geometry")? as i64;
    if !(1..=3).contains(&geometry) {
        return Err(bad(format!(
            "lamp-to-luminaire geometry {geometry} is not 1, 2 or 3"
        )));
    }
    let count = n.count("number of tilt angles")?;
    let angles = n.take(count, "tilt angles")?;
    let factors = n.take(count, "tilt multiplying factors")?;
    if count == 0 || angles.windows(2).any(|w| w[1] <= w[0]) {
        return Err(bad("tilt angles must be increasing (and at least one)"));
    }
    if factors.iter().any(|f| !f.is_finite() || *f < 0.0) {
        return Err(bad("tilt factors must be finite and not negative"));
    }
    Ok(angles.into_iter().zip(factors).collect())
}

/// The numbers of a file, in order.
struct Numbers {
    values: Vec<f32>,
    at: usize,
}

impl Numbers {
    fn new(text: &str) -> Result<Numbers, PhotometryError> {
        let values = text
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
            .map(|t| {
                t.parse::<f32>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(format!("'{t}' is not a number")))
            })
            .collect::<Result<_, _>>()?;
        Ok(Numbers { values, at: 0 })
    }

    fn next(&mut self, what: &str) -> Result<f32, PhotometryError> {
        let v = self
            .values
            .get(self.at)
            .copied()
            .ok_or_else(|| bad(format!("the file ends before the {what}")))?;
        self.at += 1;
        Ok(v)
    }

    /// A count: a whole number, at most 100 000.
    fn count(&mut self, what: &str) -> Result<usize, PhotometryError> {
        let v = self.next(what)?;
        if v < 0.0 || v.fract() != 0.0 || v > 1e5 {
            return Err(bad(format!(
                "the {what} must be a whole number up to 100000, not {v}"
            )));
        }
        Ok(v as usize)
    }

    fn take(&mut self, n: usize, what: &str) -> Result<Vec<f32>, PhotometryError> {
        if self.remaining() < n {
            return Err(bad(format!(
                "{n} {what} expected, {} numbers left",
                self.remaining()
            )));
        }
        let v = self.values[self.at..self.at + n].to_vec();
        self.at += n;
        Ok(v)
    }

    fn remaining(&self) -> usize {
        self.values.len() - self.at
    }
}

/// Write `g` as an LM-63-2002 file (absolute photometry, metres, multiplier 1, tilt data
/// included): [`parse`] reads it back to the same distribution. The exporter writes a
/// goniometric light's profile this way beside the glTF.
pub fn write(g: &Goniometric, label: &str) -> String {
    use std::fmt::Write;
    let mut s = String::from("IESNA:LM-63-2002\n");
    let _ = writeln!(s, "[TEST] written by lightlab");
    let _ = writeln!(s, "[LUMINAIRE] {}", label.replace(['\n', '\r'], " "));
    if g.tilt.is_empty() {
        s.push_str("TILT=NONE\n");
    } else {
        s.push_str("TILT=INCLUDE\n1\n");
        let _ = writeln!(s, "{}", g.tilt.len());
        let _ = writeln!(s, "{}", join(g.tilt.iter().map(|t| t.0)));
        let _ = writeln!(s, "{}", join(g.tilt.iter().map(|t| t.1)));
    }
    let kind = match g.kind {
        PhotometryType::C => 1,
        PhotometryType::B => 2,
        PhotometryType::A => 3,
    };
    let o = g.opening;
    let _ = writeln!(
        s,
        "1 -1 1 {} {} {kind} 2 {} {} {}",
        g.vertical.len(),
        g.horizontal.len(),
        o.x,
        o.y,
        o.z
    );
    s.push_str("1 1 0\n");
    let _ = writeln!(s, "{}", join(g.vertical.iter().copied()));
    let _ = writeln!(s, "{}", join(g.horizontal.iter().copied()));
    for row in g.candela.chunks(g.vertical.len()) {
        let _ = writeln!(s, "{}", join(row.iter().copied()));
    }
    s
}

/// Numbers separated by blanks, each printed exactly (Rust's shortest round-trip form).
fn join(values: impl Iterator<Item = f32>) -> String {
    values.map(|v| v.to_string()).collect::<Vec<_>>().join(" ")
}
