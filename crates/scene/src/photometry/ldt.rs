//! EULUMDAT (`.ldt`) photometric files: one field per line — header lines 1–12, the
//! luminaire's dimensions (13–21, millimetres), downward flux fraction, light output ratio,
//! the intensity conversion factor, the tilt during measurement (22–25), `n` lamp sets (26:
//! each of 26a–f takes `n` lines: lamp count, type, total flux, colour temperature, colour
//! rendering, wattage), ten direct ratios (27), the `Mc` C-plane angles (28), the `Ng` γ
//! angles (29) and the intensities in cd per 1000 lm of lamp flux (30), for the C-planes the
//! symmetry indicator `Isym` keeps: 0 all, 1 one (rotational), 2 C0–C180, 3 C90–C270,
//! 4 C0–C90. Candela = value × total lamp flux / 1000 × conversion factor. Always type C.

use super::{Goniometric, PhotometryError, PhotometryType, bad};
use glam::Vec3;

/// Parse an EULUMDAT file's text.
pub fn parse(text: &str) -> Result<Goniometric, PhotometryError> {
    let lines: Vec<&str> = text
        .trim_start_matches('\u{feff}')
        .lines()
        .map(str::trim)
        .collect();
    let mut at = 0usize;
    let mut field = |what: &str| -> Result<&str, PhotometryError> {
        let l = lines
            .get(at)
            .copied()
            .ok_or_else(|| bad(format!("line {}: the file ends before the {what}", at + 1)))?;
        at += 1;
        Ok(l)
    };
    let num = |s: &str, what: &str| -> Result<f32, PhotometryError> {
        s.replace(',', ".")
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(format!("the {what} '{s}' is not a number")))
    };
    let _manufacturer = field("manufacturer")?;
    let _ityp = num(field("type indicator")?, "type indicator")?;
    let isym = num(field("symmetry indicator")?, "symmetry indicator")? as i64;
    let mc = whole(
        num(field("number of C-planes")?, "number of C-planes")?,
        "C-planes",
    )?;
    let _dc = field("C-plane distance")?;
    let ng = whole(
        num(field("number of γ angles")?, "number of γ angles")?,
        "γ angles",
    )?;
    let _dg = field("γ distance")?;
    for what in [
        "report number",
        "luminaire name",
        "luminaire number",
        "file name",
        "date",
    ] {
        field(what)?;
    }
    let mut dims = [0.0f32; 9];
    for (k, d) in dims.iter_mut().enumerate() {
        *d = num(
            field("luminaire dimension")?,
            &format!("dimension on line {}", 13 + k),
        )?;
    }
    let _dff = field("downward flux fraction")?;
    let _lor = field("light output ratio")?;
    let conversion = num(field("conversion factor")?, "conversion factor")?;
    let _tilt = field("tilt")?;
    let sets = whole(
        num(field("number of lamp sets")?, "number of lamp sets")?,
        "lamp sets",
    )?;
    let mut blocks: Vec<Vec<&str>> = vec![];
    for what in [
        "lamp counts",
        "lamp types",
        "lamp fluxes",
        "colour temperatures",
        "CRIs",
        "wattages",
    ] {
        blocks.push((0..sets).map(|_| field(what)).collect::<Result<_, _>>()?);
    }
    let flux: f32 = blocks[2]
        .iter()
        .map(|s| num(s, "lamp flux"))
        .sum::<Result<f32, _>>()?;
    for _ in 0..10 {
        field("direct ratios")?;
    }
    let c_angles = (0..mc)
        .map(|_| field("C angles").and_then(|s| num(s, "C angle")))
        .collect::<Result<Vec<_>, _>>()?;
    let gammas = (0..ng)
        .map(|_| field("γ angles").and_then(|s| num(s, "γ angle")))
        .collect::<Result<Vec<_>, _>>()?;
    let (first, last) = match isym {
        0 => (0, mc.saturating_sub(1)),
        1 => (0, 0),
        2 => (0, mc / 2),
        3 => (mc / 4, mc / 4 + mc / 2),
        4 => (0, mc / 4),
        s => return Err(bad(format!("symmetry indicator {s} is not 0 to 4"))),
    };
    let quarters = matches!(isym, 3 | 4) && mc % 4 != 0 || isym == 2 && mc % 2 != 0;
    if mc == 0 || last >= mc || quarters {
        return Err(bad(format!(
            "{mc} C-planes do not suit symmetry indicator {isym}"
        )));
    }
    let scale = flux / 1000.0 * conversion;
    let planes = last - first + 1;
    let candela = (0..planes * ng)
        .map(|_| field("intensities").and_then(|s| num(s, "intensity")))
        .map(|c| c.map(|c| c * scale))
        .collect::<Result<Vec<_>, _>>()?;
    if lines[at..].iter().any(|l| !l.is_empty()) {
        return Err(bad(format!(
            "line {}: more lines after the intensities",
            at + 1
        )));
    }
    if !(scale.is_finite() && scale > 0.0) {
        return Err(bad(format!(
            "lamp flux × conversion factor / 1000 is {scale}, not positive"
        )));
    }
    let horizontal = if isym == 1 {
        vec![0.0]
    } else {
        c_angles[first..=last].to_vec()
    };
    Goniometric {
        kind: PhotometryType::C,
        vertical: gammas,
        horizontal,
        candela,
        tilt: vec![],
        // Length, width, height in millimetres → width, length, height in metres.
        opening: Vec3::new(dims[1], dims[0], dims[2]) / 1000.0,
    }
    .check()
}

/// Read an EULUMDAT file.
pub fn read(path: &std::path::Path) -> Result<Goniometric, PhotometryError> {
    let bytes = std::fs::read(path).map_err(|e| bad(format!("{}: {e}", path.display())))?;
    // Older files are Latin-1: keep what is ASCII, numbers are.
    let text: String = bytes.iter().map(|&b| b as char).collect();
    parse(&text).map_err(|e| bad(format!("{}: {}", path.display(), e.0)))
}

fn whole(v: f32, what: &str) -> Result<usize, PhotometryError> {
    if v < 0.0 || v.fract() != 0.0 || v > 1e5 {
        return Err(bad(format!(
            "the number of {what} must be a whole number, not {v}"
        )));
    }
    Ok(v as usize)
}
