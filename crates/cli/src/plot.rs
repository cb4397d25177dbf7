//! The demo report's error-against-cost plot, drawn as inline SVG: one point per technique,
//! relMSE against the reference (up) over its cost (right), both on log axes.

/// One technique's point: its name, its cost in milliseconds (a GPU frame, or a CPU render)
/// and its relMSE against the reference.
pub struct Point {
    pub label: String,
    pub cost_ms: f64,
    pub relmse: f64,
    pub gpu: bool,
}

const W: f64 = 560.0;
const H: f64 = 300.0;
const LEFT: f64 = 60.0;
const RIGHT: f64 = 150.0;
const TOP: f64 = 14.0;
const BOTTOM: f64 = 40.0;

/// The decades [10^lo, 10^hi] that hold every value (at least one decade).
fn decades(values: impl Iterator<Item = f64>) -> (i32, i32) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| *v > 0.0 && v.is_finite()) {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    if !lo.is_finite() {
        return (0, 1);
    }
    let (lo, hi) = (lo.floor() as i32, hi.ceil() as i32);
    (lo, hi.max(lo + 1))
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The plot, or an empty string when no point has both figures.
pub fn error_cost_svg(points: &[Point]) -> String {
    let pts: Vec<&Point> = points
        .iter()
        .filter(|p| p.cost_ms > 0.0 && p.relmse > 0.0 && p.relmse.is_finite())
        .collect();
    if pts.is_empty() {
        return String::new();
    }
    let (x0, x1) = decades(pts.iter().map(|p| p.cost_ms));
    let (y0, y1) = decades(pts.iter().map(|p| p.relmse));
    let pw = W - LEFT - RIGHT;
    let ph = H - TOP - BOTTOM;
    let x = |v: f64| LEFT + (v.log10() - x0 as f64) / (x1 - x0) as f64 * pw;
    let y = |v: f64| TOP + (1.0 - (v.log10() - y0 as f64) / (y1 - y0) as f64) * ph;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\" font-family=\"sans-serif\" \
         font-size=\"11\"><rect x=\"{LEFT}\" y=\"{TOP}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#888\"/>"
    );
    for d in x0..=x1 {
        let px = x(10f64.powi(d));
        s += &format!(
            "<line x1=\"{px:.1}\" y1=\"{TOP}\" x2=\"{px:.1}\" y2=\"{:.1}\" stroke=\"#ddd\"/>\
             <text x=\"{px:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            TOP + ph,
            TOP + ph + 14.0,
            format_decade(d)
        );
    }
    for d in y0..=y1 {
        let py = y(10f64.powi(d));
        s += &format!(
            "<line x1=\"{LEFT}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"#ddd\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            LEFT + pw,
            LEFT - 4.0,
            py + 4.0,
            format_decade(d)
        );
    }
    s += &format!(
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">cost [ms]: GPU frame (blue) or CPU render (red)</text>\
         <text x=\"14\" y=\"{:.1}\" transform=\"rotate(-90 14 {:.1})\" text-anchor=\"middle\">relMSE</text>",
        LEFT + pw / 2.0,
        H - 6.0,
        TOP + ph / 2.0,
        TOP + ph / 2.0
    );
    let mut placed: Vec<(f64, f64, f64)> = vec![];
    for p in pts {
        let (px, py) = (x(p.cost_ms), y(p.relmse));
        let colour = if p.gpu { "#1f5fbf" } else { "#c0392b" };
        let (lx, ly) = label_place(&mut placed, px + 6.0, py + 4.0, p.label.chars().count());
        s += &format!(
            "<circle cx=\"{px:.1}\" cy=\"{py:.1}\" r=\"4\" fill=\"{colour}\"><title>{l}: {c:.3} ms, relMSE {e:.5}</title></circle>\
             <text x=\"{lx:.1}\" y=\"{ly:.1}\">{l}</text>",
            l = escape(&p.label),
            c = p.cost_ms,
            e = p.relmse
        );
    }
    s + "</svg>"
}

/// Where a label of `chars` characters goes near (x, y): the first of y, y ± 12, y ± 24, …
/// whose box overlaps no label placed so far (boxes as (x, baseline y, width)).
fn label_place(placed: &mut Vec<(f64, f64, f64)>, x: f64, y: f64, chars: usize) -> (f64, f64) {
    let w = 6.5 * chars as f64;
    let clear = |y: f64| {
        placed
            .iter()
            .all(|&(px, py, pw)| (py - y).abs() >= 12.0 || x + w <= px || px + pw <= x)
    };
    let y = (0..12)
        .map(|k| y + 12.0 * ((k + 1) / 2) as f64 * if k % 2 == 1 { 1.0 } else { -1.0 })
        .find(|&y| clear(y))
        .unwrap_or(y);
    placed.push((x, y, w));
    (x, y)
}

/// 10^d as a short label.
fn format_decade(d: i32) -> String {
    match d {
        -2..=0 => format!("{}", 10f64.powi(d)),
        1..=4 => format!("{}", 10i64.pow(d as u32)),
        _ => format!("1e{d}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_land_inside_the_plot_in_order() {
        let p = |label: &str, cost_ms, relmse| Point {
            label: label.into(),
            cost_ms,
            relmse,
            gpu: true,
        };
        let svg = error_cost_svg(&[p("a", 2.0, 0.5), p("b", 300.0, 0.004), p("c", 0.0, 1.0)]);
        let cx: Vec<f64> = svg
            .match_indices("cx=\"")
            .map(|(i, _)| svg[i + 4..].split('"').next().unwrap().parse().unwrap())
            .collect();
        // The point without a cost is left out; the others are inside the frame, a left of b.
        assert_eq!(cx.len(), 2);
        assert!(cx[0] < cx[1] && cx[0] > LEFT && cx[1] < W - RIGHT);
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
        assert!(error_cost_svg(&[]).is_empty());
    }
}
