//! Sphere parameterisations: direction ↔ texture maps and per-texel solid angles.
//!
//! | map | faces | frame | solid angle per texel |
//! |---|---|---|---|
//! | lat-long | 1 | lightlab's environment convention (y up, see `sh_env`) | exact, closed form |
//! | angular (light probe) | 1 | +z at the centre, −z on the rim | disc-clipped quadrature |
//! | sphere map (OpenGL) | 1 | viewer on +z: +z at the centre, −z on the rim | 4 × (texel ∩ disc area), closed form per slice |
//! | octahedral | 1 | upper (+z) hemisphere in the centre square | exact: spherical polygons |
//! | dual paraboloid (Heidrich ch. 8) | 2 | face 0: +z hemisphere, face 1: −z | closed form inside the disc, quadrature on rim texels |
//! | cube | 6 | +X, −X, +Y, −Y, +Z, −Z with the OpenGL/Vulkan face orientation | exact, closed form |
//!
//! `uv ∈ [0,1]²`; texel (x, y) of a W×H face covers [x/W, (x+1)/W] × [y/H, (y+1)/H].
//!
//! Sampling density: the dual paraboloid is the stereographic projection, dω = 4/(1+r²)² dA,
//! so centre and rim texels differ by a factor 4 (Heidrich); the cube's dω = (1+s²+t²)^(−3/2)
//! dA gives 3√3 between the centre and a corner.

use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// A sphere parameterisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Param {
    LatLong,
    Angular,
    SphereMap,
    Octahedral,
    DualParaboloid,
    Cube,
}

impl Param {
    pub const ALL: [Param; 6] = [
        Param::LatLong,
        Param::Angular,
        Param::SphereMap,
        Param::Octahedral,
        Param::DualParaboloid,
        Param::Cube,
    ];

    pub fn faces(self) -> usize {
        match self {
            Param::DualParaboloid => 2,
            Param::Cube => 6,
            _ => 1,
        }
    }

    /// Direction (unit) → (face, uv).
    pub fn dir_to_uv(self, d: DVec3) -> (usize, DVec2) {
        match self {
            Param::LatLong => {
                let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
                (
                    0,
                    DVec2::new(u.rem_euclid(1.0), d.y.clamp(-1.0, 1.0).acos() / PI),
                )
            }
            Param::Angular => {
                let theta = d.z.clamp(-1.0, 1.0).acos();
                let r = theta / PI;
                let s = (d.x * d.x + d.y * d.y).sqrt();
                let (c, sn) = if s > 0.0 {
                    (d.x / s, d.y / s)
                } else {
                    (1.0, 0.0)
                };
                (0, DVec2::new((r * c + 1.0) * 0.5, (1.0 - r * sn) * 0.5))
            }
            Param::SphereMap => {
                let m = 2.0 * (d.x * d.x + d.y * d.y + (d.z + 1.0) * (d.z + 1.0)).sqrt();
                let m = if m > 0.0 { m } else { f64::MIN_POSITIVE };
                (0, DVec2::new(d.x / m + 0.5, d.y / m + 0.5))
            }
            Param::Octahedral => {
                let p = d / (d.x.abs() + d.y.abs() + d.z.abs());
                let q = if p.z >= 0.0 {
                    DVec2::new(p.x, p.y)
                } else {
                    DVec2::new((1.0 - p.y.abs()) * sign(p.x), (1.0 - p.x.abs()) * sign(p.y))
                };
                (0, (q + DVec2::ONE) * 0.5)
            }
            Param::DualParaboloid => {
                let face = if d.z >= 0.0 { 0 } else { 1 };
                let q = DVec2::new(d.x, d.y) / (1.0 + d.z.abs());
                (face, (q + DVec2::ONE) * 0.5)
            }
            Param::Cube => {
                let a = d.abs();
                let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
                    if d.x > 0.0 {
                        (0, -d.z, -d.y, a.x)
                    } else {
                        (1, d.z, -d.y, a.x)
                    }
                } else if a.y >= a.z {
                    if d.y > 0.0 {
                        (2, d.x, d.z, a.y)
                    } else {
                        (3, d.x, -d.z, a.y)
                    }
                } else if d.z > 0.0 {
                    (4, d.x, -d.y, a.z)
                } else {
                    (5, -d.x, -d.y, a.z)
                };
                (
                    face,
                    DVec2::new((sc / ma + 1.0) * 0.5, (tc / ma + 1.0) * 0.5),
                )
            }
        }
    }

    /// (face, uv) → unit direction; None outside the map's valid region (the discs of the
    /// angular, sphere and paraboloid maps).
    pub fn uv_to_dir(self, face: usize, uv: DVec2) -> Option<DVec3> {
        let q = uv * 2.0 - DVec2::ONE;
        match self {
            Param::LatLong => {
                let phi = (uv.x - 0.5) * 2.0 * PI;
                let theta = uv.y * PI;
                Some(DVec3::new(
                    theta.sin() * phi.sin(),
                    theta.cos(),
                    -theta.sin() * phi.cos(),
                ))
            }
            Param::Angular => {
                let (u, v) = (q.x, -q.y);
                let r = (u * u + v * v).sqrt();
                if r > 1.0 {
                    return None;
                }
                let theta = PI * r;
                let phi = v.atan2(u);
                Some(DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ))
            }
            Param::SphereMap => {
                let r2 = q.length_squared();
                if r2 > 1.0 {
                    return None;
                }
                let nz = (1.0 - r2).sqrt();
                // Reflect the view vector (0,0,1) about the sphere normal (q, nz).
                Some(DVec3::new(
                    2.0 * nz * q.x,
                    2.0 * nz * q.y,
                    2.0 * nz * nz - 1.0,
                ))
            }
            Param::Octahedral => {
                let z = 1.0 - q.x.abs() - q.y.abs();
                let (x, y) = if z >= 0.0 {
                    (q.x, q.y)
                } else {
                    ((1.0 - q.y.abs()) * sign(q.x), (1.0 - q.x.abs()) * sign(q.y))
                };
                Some(DVec3::new(x, y, z).normalize())
            }
            Param::DualParaboloid => {
                let r2 = q.length_squared();
                if r2 > 1.0 {
                    return None;
                }
                // Inverse stereographic projection.
                let z = (1.0 - r2) / (1.0 + r2);
                let s = 2.0 / (1.0 + r2);
                Some(DVec3::new(q.x * s, q.y * s, if face == 0 { z } else { -z }))
            }
            Param::Cube => {
                let (s, t) = (q.x, q.y);
                let d = match face {
                    0 => DVec3::new(1.0, -t, -s),
                    1 => DVec3::new(-1.0, -t, s),
                    2 => DVec3::new(s, 1.0, t),
                    3 => DVec3::new(s, -1.0, -t),
                    4 => DVec3::new(s, -t, 1.0),
                    _ => DVec3::new(-s, -t, -1.0),
                };
                Some(d.normalize())
            }
        }
    }

    /// Solid angle of texel (x, y) of a `w × h` face.
    pub fn texel_solid_angle(self, x: u32, y: u32, w: u32, h: u32) -> f64 {
        let (u0, u1) = (x as f64 / w as f64, (x + 1) as f64 / w as f64);
        let (v0, v1) = (y as f64 / h as f64, (y + 1) as f64 / h as f64);
        // The same rectangle in [−1, 1]² coordinates.
        let (s0, s1, t0, t1) = (
            2.0 * u0 - 1.0,
            2.0 * u1 - 1.0,
            2.0 * v0 - 1.0,
            2.0 * v1 - 1.0,
        );
        match self {
            Param::LatLong => 2.0 * PI * (u1 - u0) * ((PI * v0).cos() - (PI * v1).cos()),
            Param::Cube => {
                let a = |s: f64, t: f64| (s * t / (s * s + t * t + 1.0).sqrt()).atan();
                a(s1, t1) - a(s0, t1) - a(s1, t0) + a(s0, t0)
            }
            Param::DualParaboloid => {
                if corner_max_r2(s0, s1, t0, t1) <= 1.0 {
                    // Wholly inside the disc: ∫∫ 4/(1+x²+y²)² in closed form.
                    let g = |x: f64, y: f64| {
                        let (ax, ay) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
                        0.5 * (x / ax * (y / ax).atan() + y / ay * (x / ay).atan())
                    };
                    4.0 * (g(s1, t1) - g(s0, t1) - g(s1, t0) + g(s0, t0))
                } else {
                    disc_integral(s0, s1, t0, t1, |x, y| 4.0 / (1.0 + x * x + y * y).powi(2))
                }
            }
            // dω = 4 ds dt in disc coordinates (see the module doc of `sh_env` for the angular
            // map): 4 × the area of the texel inside the unit disc.
            Param::SphereMap => 4.0 * disc_area(s0, s1, t0, t1),
            Param::Angular => disc_integral(s0, s1, t0, t1, |x, y| {
                let r = (x * x + y * y).sqrt();
                // dω = sin(πr)·π/r ds dt
                if r < 1e-12 {
                    PI * PI
                } else {
                    (PI * r).sin() * PI / r
                }
            }),
            Param::Octahedral => octahedral_texel(s0, s1, t0, t1),
        }
    }
}

#[inline]
fn sign(v: f64) -> f64 {
    if v >= 0.0 { 1.0 } else { -1.0 }
}

fn corner_max_r2(s0: f64, s1: f64, t0: f64, t1: f64) -> f64 {
    let m = |a: f64, b: f64| a.abs().max(b.abs());
    m(s0, s1).powi(2) + m(t0, t1).powi(2)
}

/// Break points in [x0, x1] where the disc boundary √(1−x²) crosses y = t0 or t1 (and ±1).
fn x_breaks(x0: f64, x1: f64, t0: f64, t1: f64) -> Vec<f64> {
    let mut b = vec![x0, x1];
    for t in [t0, t1] {
        if t.abs() < 1.0 {
            let x = (1.0 - t * t).sqrt();
            b.extend([x, -x]);
        }
    }
    b.extend([-1.0, 1.0]);
    let mut b: Vec<f64> = b.into_iter().filter(|v| *v >= x0 && *v <= x1).collect();
    b.sort_by(|a, c| a.partial_cmp(c).unwrap());
    b.dedup_by(|a, c| (*a - *c).abs() < 1e-15);
    b
}

/// Area of [x0,x1]×[y0,y1] ∩ unit disc, in closed form per slice.
fn disc_area(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    // ∫ √(1−x²) dx = (x√(1−x²) + asin x)/2
    let s_int = |x: f64| 0.5 * (x * (1.0 - x * x).max(0.0).sqrt() + x.clamp(-1.0, 1.0).asin());
    let b = x_breaks(x0.max(-1.0), x1.min(1.0), y0, y1);
    let mut area = 0.0;
    for w in b.windows(2) {
        let (a, c) = (w[0], w[1]);
        if c <= a {
            continue;
        }
        let m = 0.5 * (a + c);
        let s = (1.0 - m * m).max(0.0).sqrt();
        // On this piece the top is either y1 or the circle, the bottom y0 or the lower circle.
        let top_is_circle = s < y1;
        let bottom_is_circle = -s > y0;
        let top = if top_is_circle { s } else { y1 };
        let bottom = if bottom_is_circle { -s } else { y0 };
        if top <= bottom {
            continue;
        }
        let top_int = if top_is_circle {
            s_int(c) - s_int(a)
        } else {
            y1 * (c - a)
        };
        let bottom_int = if bottom_is_circle {
            -(s_int(c) - s_int(a))
        } else {
            y0 * (c - a)
        };
        area += top_int - bottom_int;
    }
    area
}

/// Gauss–Legendre nodes on [−1, 1] for [`disc_integral`]: 4 (`rim` false) or 24 (`rim` true),
/// each computed once. A call runs Newton's method on every root, and a map's rim texels asked
/// for them thousands of times per map.
fn disc_nodes(rim: bool) -> &'static (Vec<f64>, Vec<f64>) {
    static INSIDE: std::sync::OnceLock<(Vec<f64>, Vec<f64>)> = std::sync::OnceLock::new();
    static RIM: std::sync::OnceLock<(Vec<f64>, Vec<f64>)> = std::sync::OnceLock::new();
    if rim {
        RIM.get_or_init(|| crate::quadrature::gauss_legendre(24))
    } else {
        INSIDE.get_or_init(|| crate::quadrature::gauss_legendre(4))
    }
}

/// ∫∫ f over [x0,x1]×[y0,y1] ∩ unit disc: Gauss–Legendre over x pieces split where the
/// boundary changes, and over each vertical chord.
fn disc_integral(x0: f64, x1: f64, y0: f64, y1: f64, f: impl Fn(f64, f64) -> f64) -> f64 {
    // Texels inside the disc carry a smooth integrand: 4 nodes per axis are exact to ~1e-12 over
    // a texel; rim texels (a √-shaped chord) get 24.
    let (gx, gw) = disc_nodes(corner_max_r2(x0, x1, y0, y1) > 1.0);
    let b = x_breaks(x0.max(-1.0), x1.min(1.0), y0, y1);
    let mut total = 0.0;
    for w in b.windows(2) {
        let (a, c) = (w[0], w[1]);
        if c <= a {
            continue;
        }
        for (xi, wi) in gx.iter().zip(gw) {
            let x = a + (c - a) * 0.5 * (xi + 1.0);
            let s = (1.0 - x * x).max(0.0).sqrt();
            let (lo, hi) = (y0.max(-s), y1.min(s));
            if hi <= lo {
                continue;
            }
            let mut inner = 0.0;
            for (yj, wj) in gx.iter().zip(gw) {
                let y = lo + (hi - lo) * 0.5 * (yj + 1.0);
                inner += wj * f(x, y);
            }
            total += wi * (c - a) * 0.5 * inner * (hi - lo) * 0.5;
        }
    }
    total
}

/// Solid angle of the spherical triangle with unit-direction vertices (Van Oosterom–Strackee).
fn spherical_triangle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let num = a.dot(b.cross(c)).abs();
    let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * num.atan2(den)
}

/// Octahedral texel: the texel square is split along the fold |s| + |t| = 1 of its quadrant
/// (the axes fall on texel edges for even resolutions; pieces are clipped at them anyway), each
/// convex piece maps affinely onto one planar octahedron face, and a planar polygon projects to
/// the spherical polygon with the same vertices: exact.
fn octahedral_texel(s0: f64, s1: f64, t0: f64, t1: f64) -> f64 {
    let to_dir = |p: DVec2| {
        Param::Octahedral
            .uv_to_dir(0, (p + DVec2::ONE) * 0.5)
            .unwrap()
    };
    let mut total = 0.0;
    // Split at the axes first (quadrants), then along each quadrant's diagonal.
    let xs = split(s0, s1, 0.0);
    let ys = split(t0, t1, 0.0);
    for &(a, b) in &xs {
        for &(c, d) in &ys {
            let sx = if a + b >= 0.0 { 1.0 } else { -1.0 };
            let sy = if c + d >= 0.0 { 1.0 } else { -1.0 };
            let rect = [
                DVec2::new(a, c),
                DVec2::new(b, c),
                DVec2::new(b, d),
                DVec2::new(a, d),
            ];
            // Half-plane sx·x + sy·y ≤ 1 (inner, upper hemisphere) and its complement.
            let inner = clip(&rect, |p| 1.0 - (sx * p.x + sy * p.y));
            let outer = clip(&rect, |p| (sx * p.x + sy * p.y) - 1.0);
            for poly in [inner, outer] {
                if poly.len() < 3 {
                    continue;
                }
                let v: Vec<DVec3> = poly.iter().map(|p| to_dir(*p)).collect();
                for k in 1..v.len() - 1 {
                    total += spherical_triangle(v[0], v[k], v[k + 1]);
                }
            }
        }
    }
    total
}

fn split(a: f64, b: f64, at: f64) -> Vec<(f64, f64)> {
    if a < at && b > at {
        vec![(a, at), (at, b)]
    } else {
        vec![(a, b)]
    }
}

/// Sutherland–Hodgman: keep the part of a convex polygon where `side(p) ≥ 0`.
fn clip(poly: &[DVec2], side: impl Fn(DVec2) -> f64) -> Vec<DVec2> {
    let mut out = vec![];
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(p);
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            let t = sp / (sp - sq);
            out.push(p + (q - p) * t);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, uniform_sphere};

    #[test]
    fn round_trips_to_1e6() {
        let mut rng = Rng::new(1, 0);
        for p in Param::ALL {
            for _ in 0..20_000 {
                let d = uniform_sphere(rng.next_vec2()).as_dvec3().normalize();
                // The angular and sphere maps collapse −z onto their rim.
                if matches!(p, Param::Angular | Param::SphereMap) && d.z < -0.999 {
                    continue;
                }
                let (f, uv) = p.dir_to_uv(d);
                assert!(
                    f < p.faces() && (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y),
                    "{p:?} {uv}"
                );
                let back = p.uv_to_dir(f, uv).unwrap();
                assert!((back - d).length() < 1e-6, "{p:?}: {d} → {uv} → {back}");
            }
        }
    }

    fn total(p: Param, n: u32) -> f64 {
        let (w, h) = if p == Param::LatLong {
            (2 * n, n)
        } else {
            (n, n)
        };
        let mut sum = 0.0;
        for _ in 0..p.faces() {
            for y in 0..h {
                for x in 0..w {
                    sum += p.texel_solid_angle(x, y, w, h);
                }
            }
        }
        sum
    }

    #[test]
    fn solid_angles_sum_to_4pi_at_512() {
        for p in Param::ALL {
            let t = total(p, 512);
            eprintln!(
                "{p:?}: Σ texel solid angles at 512² = {t:.9} (4π {:+.2e})",
                t - 4.0 * PI
            );
            assert!((t - 4.0 * PI).abs() < 1e-4, "{p:?}: {t}");
        }
    }

    #[test]
    fn texel_solid_angles_match_corner_directions_where_planar() {
        // For the cube, a texel's solid angle equals the spherical quad of its corners.
        let n = 16;
        for y in 0..n {
            for x in 0..n {
                let c = |i: u32, j: u32| {
                    Param::Cube
                        .uv_to_dir(4, DVec2::new(i as f64 / n as f64, j as f64 / n as f64))
                        .unwrap()
                };
                let (a, b, cc, d) = (c(x, y), c(x + 1, y), c(x + 1, y + 1), c(x, y + 1));
                let quad = spherical_triangle(a, b, cc) + spherical_triangle(a, cc, d);
                assert!((quad - Param::Cube.texel_solid_angle(x, y, n, n)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn centre_to_rim_ratios() {
        let n = 512;
        // Dual paraboloid: centre texel vs the texel on the +x axis just inside the rim.
        let c = Param::DualParaboloid.texel_solid_angle(n / 2, n / 2, n, n);
        let r = Param::DualParaboloid.texel_solid_angle(n - 1, n / 2, n, n);
        let ratio = c / r;
        eprintln!("dual paraboloid centre/rim texel solid angle at 512²: {ratio:.4} (4)");
        assert!((ratio - 4.0).abs() < 0.05, "paraboloid {ratio}");
        // Cube: centre vs corner texel: 3√3.
        let c = Param::Cube.texel_solid_angle(n / 2, n / 2, n, n);
        let r = Param::Cube.texel_solid_angle(n - 1, n - 1, n, n);
        let ratio = c / r;
        eprintln!("cube centre/corner texel solid angle at 512²: {ratio:.4} (3√3 = 5.1962)");
        assert!((ratio - 3.0 * 3f64.sqrt()).abs() < 0.05, "cube {ratio}");
    }
}
