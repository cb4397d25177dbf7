//! Heidrich's image-based lens model (1999 §11.2; Heidrich, Slusallek & Seidel 1997): a
//! traced lens approximated by perspective projections plus image morphs.
//!
//! Per sample point Pᵢ of the lens's aperture stop (a rank-1 lattice over its disc), a grid
//! of film points sends rays through Pᵢ (ray aiming: each film point's ray is found by Newton
//! steps so that it crosses the stop at Pᵢ) and out of the lens. They do not meet in one point; a virtual centre of projection (COP) is fitted to
//! them (§11.2.3), either as the least-squares point closest to every ray [Gremban88] or by
//! minimising the angles between each ray and its stand-in from the COP through the same
//! point of the image plane (Gauss–Newton steps on a 3 × 3 system, started from the least
//! squares point). Where the largest angle exceeds the threshold the film cell splits into
//! four (the quad tree of §11.2.2). Each leaf is one perspective render from its COP through
//! the window its rays span on the image plane (the plane of focus); the render is then
//! morphed onto the leaf's film grid, each vertex reading the render where its traced ray
//! meets the image plane, weighted by its share of the exposure, and accumulated over cells
//! and sample points. Exposure (the seed leaves it to [Heidrich97a]): each film point
//! receives the traced camera's exposure (Kolb et al.'s cos⁴ / Z² and vignetting), shared
//! equally among the sample points whose rays pass the lens there, so that the few sample
//! points only sample the blur.
//!
//! Deviation: Heidrich places the sample points on the rear lens surface. With a wide field,
//! the film's corners see the scene through a part of the rear surface that few of ten such
//! points fall in (the exit pupil moves across it), and their image goes dark or is carried by
//! one point; points on the stop are seen from every film point the lens does not vignette.
//! Rays that miss the lens's surfaces or cannot be aimed carry no light and read where the
//! cell's affine fit of the others says.

use super::system::LensSystem;
use crate::sampling::{concentric_disc, r2};
use glam::{DMat3, DVec2, DVec3, Mat4, Vec2, Vec3, Vec4};

/// How a cell's centre of projection is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CopFit {
    /// The point closest to every ray in the least-squares sense.
    LeastSquares,
    /// The point minimising the squared angles between the rays and their stand-ins.
    #[default]
    Angle,
}

/// Settings of the image-based model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageModelSettings {
    /// Sample points on the rear plane (Heidrich used 10).
    pub samples: u32,
    /// Largest angle (radians) between a traced ray and its stand-in before a cell splits
    /// (Heidrich: 0.05°).
    pub max_angle: f64,
    pub fit: CopFit,
    /// Film-grid vertices per side of a cell (its morph mesh; 65: a vertex every 1/64 of the
    /// film, so that the bilinear morph follows the distortion near the lens's rim).
    pub grid: usize,
    /// Deepest subdivision (a cell of the film's 1/2^depth on each side).
    pub max_depth: u32,
}

impl Default for ImageModelSettings {
    fn default() -> Self {
        ImageModelSettings {
            samples: 10,
            max_angle: 0.05f64.to_radians(),
            fit: CopFit::Angle,
            grid: 65,
            max_depth: 5,
        }
    }
}

/// A vertex of a cell's morph mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MorphVertex {
    /// Where the vertex lands in the output image (NDC, y up).
    pub ndc: [f32; 2],
    /// Where it reads the cell's render (texture coordinates, v down).
    pub uv: [f32; 2],
    /// Its exposure weight.
    pub weight: f32,
}

/// One perspective render and its morph.
#[derive(Clone, Debug, PartialEq)]
pub struct Projection {
    /// The sample point on the rear plane (camera space).
    pub point: DVec3,
    /// The centre of projection (camera space).
    pub cop: DVec3,
    /// The window on the image plane, as tangents (x/−z, y/−z) seen from the COP.
    pub window: (DVec2, DVec2),
    /// The film cell (output NDC rectangle).
    pub cell: (DVec2, DVec2),
    /// `grid` × `grid` vertices, row by row from the cell's low corner.
    pub vertices: Vec<MorphVertex>,
    pub grid: usize,
    /// Largest angle between a traced ray and its stand-in (radians).
    pub max_angle: f64,
}

/// A lens's projections for one set of settings.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageModel {
    pub projections: Vec<Projection>,
    /// Sample points that some film point sees the scene through.
    pub points_used: usize,
}

/// A traced film ray: where it leaves the lens, its direction, its exposure weight, and the
/// rear-plane point it was aimed at.
struct FilmRay {
    ray: Option<(DVec3, DVec3)>,
    weight: f64,
    aimed: Option<DVec2>,
}

impl Projection {
    /// Camera space → the space whose standard projection (vertical field of view `yfov`,
    /// `aspect`) shows this projection's window: translate to the COP, then scale and shear
    /// x, y by z so the window's tangents fill the camera's. Compose as
    /// `projection · view() · camera view`.
    pub fn view(&self, yfov: f32, aspect: f32) -> Mat4 {
        let t = (0.5 * yfov).tan();
        let (lo, hi) = (self.window.0.as_vec2(), self.window.1.as_vec2());
        let scale = Vec2::new(2.0 * t * aspect, 2.0 * t) / (hi - lo);
        let shift = scale * (lo + hi) * 0.5;
        let m = Mat4::from_cols(
            Vec4::new(scale.x, 0.0, 0.0, 0.0),
            Vec4::new(0.0, scale.y, 0.0, 0.0),
            Vec4::new(shift.x, shift.y, 1.0, 0.0),
            Vec4::W,
        );
        m * Mat4::from_translation(-self.eye())
    }

    /// The COP as the eye (camera space).
    pub fn eye(&self) -> Vec3 {
        self.cop.as_vec3()
    }

    /// Triangle-list indices of the morph mesh.
    pub fn indices(&self) -> Vec<u32> {
        let g = self.grid as u32;
        (0..g - 1)
            .flat_map(|j| (0..g - 1).map(move |i| (i, j)))
            .flat_map(|(i, j)| {
                let a = j * g + i;
                [a, a + 1, a + g + 1, a, a + g + 1, a + g]
            })
            .collect()
    }
}

impl ImageModel {
    /// The point of the plane of focus (camera space, at depth `focus_distance`) that the
    /// model images at film point `ndc`: over the projections whose cell holds it, the
    /// exposure-weighted mean of where the morph reads the render. The distortion curve's
    /// object height. None where no projection carries light.
    pub fn focus_point(&self, ndc: DVec2, focus_distance: f64) -> Option<DVec3> {
        let (mut sum, mut total) = (DVec3::ZERO, 0.0);
        for p in &self.projections {
            let (lo, hi) = p.cell;
            if ndc.cmplt(lo).any() || ndc.cmpgt(hi).any() {
                continue;
            }
            let g = p.grid;
            let x = (ndc - lo) / (hi - lo) * (g - 1) as f64;
            let (i, j) = ((x.x as usize).min(g - 2), (x.y as usize).min(g - 2));
            let (fx, fy) = (x.x - i as f64, x.y - j as f64);
            let mut uv = DVec2::ZERO;
            let mut w = 0.0;
            for (a, b, k) in [
                (i, j, (1.0 - fx) * (1.0 - fy)),
                (i + 1, j, fx * (1.0 - fy)),
                (i, j + 1, (1.0 - fx) * fy),
                (i + 1, j + 1, fx * fy),
            ] {
                let v = &p.vertices[b * g + a];
                uv += Vec2::from(v.uv).as_dvec2() * k;
                w += v.weight as f64 * k;
            }
            let (wl, wh) = p.window;
            let t = DVec2::new(wl.x + uv.x * (wh.x - wl.x), wh.y - uv.y * (wh.y - wl.y));
            let depth = p.cop.z + focus_distance;
            sum += (p.cop + (t * depth).extend(-depth)) * w;
            total += w;
        }
        (total > 0.0).then(|| sum / total)
    }
}

/// Build the image-based model of `lens`.
pub fn build(lens: &LensSystem, s: &ImageModelSettings) -> ImageModel {
    let (radius, z) = lens.stop_disc();
    let n = s.samples.max(1);
    let mut projections = Vec::new();
    let mut points_used = 0;
    let points: Vec<DVec3> = (0..n)
        .map(|i| (concentric_disc(r2(i, Vec2::ZERO)).as_dvec2() * radius).extend(z))
        .collect();
    for &point in &points {
        let before = projections.len();
        let root = (DVec2::splat(-1.0), DVec2::ONE);
        subdivide(lens, s, point, root, 0, &mut projections);
        points_used += usize::from(projections.len() > before);
    }
    normalise_exposure(lens, &points, &mut projections);
    ImageModel {
        projections,
        points_used,
    }
}

/// Give each film point the traced lens's exposure, shared equally among the sample points
/// whose rays pass there: with few sample points their share of the pupil is a poor estimate
/// of it (10 points: ±20 % brightness), so only the blur is sampled. The film's relative
/// exposure is tabulated on a 33² grid (a 16² pupil integral each) and read bilinearly.
fn normalise_exposure(lens: &LensSystem, points: &[DVec3], projections: &mut [Projection]) {
    const N: usize = 33;
    let at = |i: usize, j: usize| DVec2::new(i as f64, j as f64) / (N - 1) as f64 * 2.0 - 1.0;
    let table: Vec<f64> = (0..N * N)
        .map(|k| lens.relative_exposure(at(k % N, k / N), 16))
        .collect();
    let exposure = |ndc: DVec2| {
        let x = (ndc + 1.0) * 0.5 * (N - 1) as f64;
        let (i, j) = ((x.x as usize).min(N - 2), (x.y as usize).min(N - 2));
        let (fx, fy) = (x.x - i as f64, x.y - j as f64);
        let t = |a: usize, b: usize| table[b * N + a];
        (t(i, j) * (1.0 - fx) + t(i + 1, j) * fx) * (1.0 - fy)
            + (t(i, j + 1) * (1.0 - fx) + t(i + 1, j + 1) * fx) * fy
    };
    // Cells of different sample points share film points: their totals are made once.
    let mut totals = std::collections::HashMap::new();
    for p in projections {
        for v in &mut p.vertices {
            if v.weight <= 0.0 {
                continue;
            }
            let ndc = Vec2::from(v.ndc).as_dvec2();
            let total = *totals.entry(v.ndc.map(f32::to_bits)).or_insert_with(|| {
                points
                    .iter()
                    .map(|q| film_ray(lens, ndc, *q).weight)
                    .sum::<f64>()
            });
            let own = film_ray(lens, ndc, p.point).weight;
            v.weight = (own / total * exposure(ndc)) as f32;
        }
    }
}

/// Fit the cell; keep it, split it, or drop it when no ray of it reaches the scene.
fn subdivide(
    lens: &LensSystem,
    s: &ImageModelSettings,
    point: DVec3,
    cell: (DVec2, DVec2),
    depth: u32,
    out: &mut Vec<Projection>,
) {
    let g = s.grid.max(2);
    let ndc: Vec<DVec2> = (0..g * g)
        .map(|k| {
            let f = DVec2::new((k % g) as f64, (k / g) as f64) / (g - 1) as f64;
            cell.0 + (cell.1 - cell.0) * f
        })
        .collect();
    // Each film point's aiming starts from its left or lower neighbour's solution.
    let mut rays: Vec<FilmRay> = Vec::with_capacity(g * g);
    for (k, &c) in ndc.iter().enumerate() {
        let near = [(k % g > 0).then(|| k - 1), k.checked_sub(g)];
        let hint = near.iter().flatten().find_map(|&n| rays[n].aimed);
        rays.push(film_ray_from(lens, c, point, hint));
    }
    if rays.iter().all(|r| r.weight <= 0.0) {
        return;
    }
    let plane = -lens.focus_distance;
    // The fit and its criterion concern the rays that carry light; the others (beyond the
    // edge of vignetting) only give their vertices a texture coordinate.
    let valid: Vec<(DVec3, DVec3)> = rays
        .iter()
        .filter(|r| r.weight > 0.0)
        .filter_map(|r| r.ray)
        .filter(|(_, d)| d.z < -1e-9)
        .map(|(o, d)| (o + d * ((plane - o.z) / d.z), d))
        .collect();
    let Some((cop, max_angle)) = fit(&valid, s.fit) else {
        return;
    };
    if max_angle > s.max_angle && depth < s.max_depth {
        let mid = (cell.0 + cell.1) * 0.5;
        for (a, b) in [
            (cell.0, mid),
            (DVec2::new(mid.x, cell.0.y), DVec2::new(cell.1.x, mid.y)),
            (DVec2::new(cell.0.x, mid.y), DVec2::new(mid.x, cell.1.y)),
            (mid, cell.1),
        ] {
            subdivide(lens, s, point, (a, b), depth + 1, out);
        }
        return;
    }
    let mut p = projection(lens, cop, max_angle, cell, g, &ndc, &rays);
    p.point = point;
    out.push(p);
}

/// The ray from film point `ndc` through stop point `point`, traced out of the lens without
/// its apertures (for the map); its weight is 1 when it passes them, else 0.
fn film_ray(lens: &LensSystem, ndc: DVec2, point: DVec3) -> FilmRay {
    film_ray_from(lens, ndc, point, None)
}

/// [`film_ray`], aiming from rear-plane point `hint`.
fn film_ray_from(lens: &LensSystem, ndc: DVec2, point: DVec3, hint: Option<DVec2>) -> FilmRay {
    let film = lens.film_point(ndc).extend(lens.film_z);
    let aimed = lens
        .aim_from(film, point.truncate(), hint)
        .or_else(|| hint.and_then(|_| lens.aim_from(film, point.truncate(), None)));
    let Some((d, q)) = aimed else {
        return FilmRay {
            ray: None,
            weight: 0.0,
            aimed: None,
        };
    };
    FilmRay {
        aimed: Some(q),
        ray: lens.trace(film, d, false),
        weight: if lens.trace(film, d, true).is_some() {
            1.0
        } else {
            0.0
        },
    }
}

/// The COP of rays given as (point on the image plane, unit direction), and the largest
/// angle between a ray and the line from the COP through its image-plane point.
pub fn fit(rays: &[(DVec3, DVec3)], how: CopFit) -> Option<(DVec3, f64)> {
    if rays.len() < 3 {
        return None;
    }
    let mut a = DMat3::ZERO;
    let mut b = DVec3::ZERO;
    for (q, d) in rays {
        let m = DMat3::IDENTITY - outer(*d, *d);
        a += m;
        b += m * *q;
    }
    if a.determinant().abs() < 1e-24 {
        return None;
    }
    let mut c = a.inverse() * b;
    if how == CopFit::Angle {
        c = angle_newton(rays, c);
    }
    let worst = rays
        .iter()
        .map(|(q, d)| (*q - c).normalize().dot(*d).clamp(-1.0, 1.0).acos())
        .fold(0.0, f64::max);
    worst.is_finite().then_some((c, worst))
}

/// Gauss–Newton on Σ |uₖ − dₖ|² (≈ Σ angle²), uₖ the unit vector from C to qₖ: each step
/// solves the 3 × 3 normal equations.
fn angle_newton(rays: &[(DVec3, DVec3)], c: DVec3) -> DVec3 {
    let worst = |c: DVec3| {
        rays.iter()
            .map(|(q, d)| ((*q - c).normalize() - *d).length())
            .fold(0.0, f64::max)
    };
    // Σ angle² first, then reweighted towards the largest angle (weights (θ/θmax)⁶, an
    // L⁸ fit), which is what the subdivision tests; the best point seen, the least-squares
    // start included, is kept.
    let mut best = (worst(c), c);
    let mut c = gauss_newton(rays, c, |_| 1.0);
    if worst(c) < best.0 {
        best = (worst(c), c);
    }
    for _ in 0..12 {
        let top = best.0.max(1e-300);
        c = gauss_newton(rays, c, |r: f64| (r / top).powi(6));
        let w = worst(c);
        if w < best.0 {
            best = (w, c);
        }
    }
    best.1
}

/// Gauss–Newton steps on Σ wₖ |uₖ − dₖ|², wₖ = `weight`(|uₖ − dₖ|) fixed per step.
fn gauss_newton(rays: &[(DVec3, DVec3)], mut c: DVec3, weight: impl Fn(f64) -> f64) -> DVec3 {
    for _ in 0..8 {
        let mut h = DMat3::ZERO;
        let mut g = DVec3::ZERO;
        for (q, d) in rays {
            let v = *q - c;
            let len = v.length();
            let u = v / len;
            let w = weight((u - *d).length());
            // ∂u/∂C = −(I − u uᵀ)/|q − C| (symmetric).
            let j = (DMat3::IDENTITY - outer(u, u)) * (-1.0 / len);
            h += j * j * w;
            g += j * (u - *d) * w;
        }
        if h.determinant().abs() < 1e-300 {
            break;
        }
        let step = -(h.inverse() * g);
        c += step;
        if step.length() < 1e-14 {
            break;
        }
    }
    c
}

/// The mean of the straight-line continuations t(k+d)·2 − t(k+2d) over the grid directions
/// d in which vertex `k` has two valid neighbours.
fn extrapolate(tangent: &[Option<DVec2>], g: usize, k: usize) -> Option<DVec2> {
    let (i, j) = ((k % g) as i64, (k / g) as i64);
    let at = |a: i64, b: i64| {
        (a >= 0 && b >= 0 && a < g as i64 && b < g as i64)
            .then(|| tangent[(b * g as i64 + a) as usize])
            .flatten()
    };
    let found: Vec<DVec2> = [(1, 0), (-1, 0), (0, 1), (0, -1)]
        .iter()
        .filter_map(|(dx, dy)| Some(at(i + dx, j + dy)? * 2.0 - at(i + 2 * dx, j + 2 * dy)?))
        .collect();
    (!found.is_empty()).then(|| found.iter().sum::<DVec2>() / found.len() as f64)
}

/// The least-squares affine map from film NDC to tangent over the vertices that have one.
fn affine_fit(ndc: &[DVec2], tangent: &[Option<DVec2>]) -> impl Fn(DVec2) -> DVec2 {
    let mut a = DMat3::ZERO;
    let (mut bx, mut by) = (DVec3::ZERO, DVec3::ZERO);
    for (c, t) in ndc.iter().zip(tangent) {
        if let Some(t) = t {
            let v = c.extend(1.0);
            a += outer(v, v);
            bx += v * t.x;
            by += v * t.y;
        }
    }
    let inv = if a.determinant().abs() > 1e-18 {
        a.inverse()
    } else {
        DMat3::ZERO
    };
    let (px, py) = (inv * bx, inv * by);
    move |c: DVec2| DVec2::new(px.dot(c.extend(1.0)), py.dot(c.extend(1.0)))
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// A leaf: the window its rays span seen from the COP, and its morph mesh.
fn projection(
    lens: &LensSystem,
    cop: DVec3,
    max_angle: f64,
    cell: (DVec2, DVec2),
    g: usize,
    ndc: &[DVec2],
    rays: &[FilmRay],
) -> Projection {
    let plane = -lens.focus_distance;
    let depth = cop.z - plane;
    let tangent: Vec<Option<DVec2>> = rays
        .iter()
        .map(|r| {
            let (o, d) = r.ray.filter(|(_, d)| d.z < -1e-9)?;
            let q = o + d * ((plane - o.z) / d.z);
            Some((q - cop).truncate() / depth)
        })
        .collect();
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for t in tangent.iter().flatten() {
        lo = lo.min(*t);
        hi = hi.max(*t);
    }
    // A margin of a few texels' worth keeps bilinear reads inside the render.
    let pad = (hi - lo).max(DVec2::splat(1e-9)) * (1.0 / 64.0);
    let (lo, hi) = (lo - pad, hi + pad);
    let uv = |t: DVec2| {
        [
            ((t.x - lo.x) / (hi.x - lo.x)) as f32,
            ((hi.y - t.y) / (hi.y - lo.y)) as f32,
        ]
    };
    let guess = affine_fit(ndc, &tangent);
    let vertices = (0..g * g)
        .map(|k| MorphVertex {
            ndc: ndc[k].as_vec2().to_array(),
            // A vertex whose ray misses the lens reads where its valid neighbours, continued
            // in a straight line, say; else where the cell's affine fit says.
            uv: uv(tangent[k]
                .or_else(|| extrapolate(&tangent, g, k))
                .unwrap_or_else(|| guess(ndc[k]))),
            weight: if tangent[k].is_some() {
                rays[k].weight as f32
            } else {
                0.0
            },
        })
        .collect();
    Projection {
        point: DVec3::ZERO,
        cop,
        window: (lo, hi),
        cell,
        vertices,
        grid: g,
        max_angle,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::prescription::Prescription;
    use crate::lens::system::LensSetup;

    fn lens(name: &str, stop: Option<f64>, yfov: f64) -> LensSystem {
        let setup = LensSetup {
            scale: 1.0,
            stop_diameter: stop,
            focus_distance: 3.0,
            yfov,
            aspect: 1.0,
        };
        LensSystem::new(&Prescription::builtin(name).unwrap(), setup).unwrap()
    }

    /// Every leaf meets the threshold (or is as deep as allowed), and a tighter threshold
    /// needs more projections.
    #[test]
    fn the_quad_tree_meets_its_threshold() {
        // A stop in front of the glass (doublet, biconvex) makes every ray through a stop
        // point pass that point: one exact projection each. The double Gauss's stop lies
        // between its groups: the front group's pupil aberration bends them.
        let l = lens("double-gauss", None, 0.9);
        for fit in [CopFit::LeastSquares, CopFit::Angle] {
            let one = ImageModelSettings {
                max_depth: 0,
                fit,
                ..Default::default()
            };
            let worst = build(&l, &one)
                .projections
                .iter()
                .map(|p| p.max_angle)
                .fold(0.0, f64::max);
            println!(
                "{fit:?}: one projection per point, worst {:.4}°",
                worst.to_degrees()
            );
        }
        let mut last = 0;
        for deg in [0.05, 0.02, 0.01] {
            let s = ImageModelSettings {
                max_angle: f64::to_radians(deg),
                ..Default::default()
            };
            let m = build(&l, &s);
            let ls = ImageModelSettings {
                fit: CopFit::LeastSquares,
                ..s
            };
            println!(
                "{deg}°: least squares needs {} projections",
                build(&l, &ls).projections.len()
            );
            for p in &m.projections {
                let deep = (p.cell.1.x - p.cell.0.x) <= 2.0 / (1 << s.max_depth) as f64 + 1e-12;
                assert!(
                    p.max_angle <= s.max_angle || deep,
                    "{deg}: {}",
                    p.max_angle.to_degrees()
                );
            }
            assert!(m.projections.len() >= last, "{deg}");
            last = m.projections.len();
            println!("{deg}°: {} projections over {} points", last, m.points_used);
        }
        assert!(last > 2 * 10, "{last}");
    }

    fn squared_angles(rays: &[(DVec3, DVec3)], c: DVec3) -> f64 {
        rays.iter()
            .map(|(q, d)| (*q - c).normalize().dot(*d).clamp(-1.0, 1.0).acos().powi(2))
            .sum()
    }

    /// The angle fit's Gauss–Newton steps lower Σθ² below the least-squares point's, its
    /// largest angle is never larger, and both fits find the exact centre of rays that meet
    /// in one point.
    #[test]
    fn the_angle_fit_improves_on_least_squares() {
        let c = DVec3::new(0.01, -0.02, 0.03);
        let exact: Vec<(DVec3, DVec3)> = (0..25)
            .map(|k| {
                let q = DVec3::new((k % 5) as f64 - 2.0, (k / 5) as f64 - 2.0, -3.0);
                (q, (q - c).normalize())
            })
            .collect();
        for how in [CopFit::LeastSquares, CopFit::Angle] {
            let (found, worst) = fit(&exact, how).unwrap();
            assert!((found - c).length() < 1e-9 && worst < 1e-7, "{how:?}");
        }
        // Rays through one rear-plane point of a real lens do not meet.
        for name in ["doublet", "biconvex", "double-gauss"] {
            let l = lens(name, None, 1.0);
            let point = DVec3::new(0.3 * l.pupil_radius(), 0.0, l.rear_z());
            let plane = -l.focus_distance;
            let rays: Vec<(DVec3, DVec3)> = (0..81)
                .filter_map(|k| {
                    let ndc = DVec2::new((k % 9) as f64 / 4.0 - 1.0, (k / 9) as f64 / 4.0 - 1.0);
                    let film = l.film_point(ndc).extend(l.film_z);
                    let (o, d) = l.trace(film, (point - film).normalize(), false)?;
                    Some((o + d * ((plane - o.z) / d.z), d))
                })
                .collect();
            let (ls, ls_worst) = fit(&rays, CopFit::LeastSquares).unwrap();
            let (_, an_worst) = fit(&rays, CopFit::Angle).unwrap();
            // The Gauss–Newton steps lower Σθ²; the fit keeps the point with the smallest
            // largest angle.
            let l2 = gauss_newton(&rays, ls, |_| 1.0);
            let (a, b) = (squared_angles(&rays, ls), squared_angles(&rays, l2));
            println!(
                "{name}: Σθ² least squares {a:.3e}, Gauss–Newton {b:.3e}; largest angle \
                 {:.4}° and {:.4}°",
                ls_worst.to_degrees(),
                an_worst.to_degrees()
            );
            assert!(b <= a * (1.0 + 1e-9) && b > 0.0, "{name}: {b} vs {a}");
            assert!(an_worst <= ls_worst * (1.0 + 1e-12), "{name}");
        }
    }

    /// The morph reproduces the traced lens between its vertices: a film point inside a
    /// cell, read through the bilinear morph and the cell's COP, looks where the traced ray
    /// through the same sample point looks, within the subdivision's threshold (0.05°: 0.64
    /// px of a 512² image with a 40° field) and a tenth. Checked
    /// a grid square away from the edge of vignetting: there the weight fades to 0 over one
    /// square, the vertex beyond has no ray to follow, and the rays graze the lens's rim.
    #[test]
    fn the_morph_follows_the_traced_rays_between_vertices() {
        for name in ["doublet", "biconvex"] {
            let l = lens(name, None, 0.7);
            let m = build(&l, &ImageModelSettings::default());
            // A pixel of a 512² image, as an angle and on the plane of focus.
            let pixel = 0.7 / 512.0;
            let pixel_plane = 2.0 * 3.0 * 0.35f64.tan() / 512.0;
            let (mut worst, mut worst_plane) = (0.0f64, 0.0f64);
            for (i, p) in m.projections.iter().enumerate() {
                for k in 0..16 {
                    let f = r2(k + i as u32 * 16, Vec2::ZERO).as_dvec2();
                    let (err, on_plane) = morph_error(&l, p, p.point, f);
                    worst = worst.max(err);
                    worst_plane = worst_plane.max(on_plane);
                }
            }
            println!(
                "{name}: on the plane of focus {:.3} px, direction {:.3} px",
                worst_plane / pixel_plane,
                worst / pixel
            );
            let bound = 1.1 * ImageModelSettings::default().max_angle;
            assert!(
                worst_plane / 3.0 < bound,
                "{name}: {} px",
                worst_plane / pixel_plane
            );
            assert!(worst < bound, "{name}: {} px", worst / pixel);
        }
    }

    /// The distortion curve (object height on the plane of focus against image height) of
    /// the chief rays, through the stop's centre (the model's first sample point): the
    /// model's morph against the traced lens, along the film's horizontal and diagonal,
    /// between the morph grid's vertices, within half a pixel of a 512² image. The lenses
    /// distort (barrel: the edge sees wider than the pinhole would).
    #[test]
    fn the_distortion_curves_agree() {
        for name in ["doublet", "biconvex", "double-gauss"] {
            let l = lens(name, None, 0.7);
            let m = build(&l, &ImageModelSettings::default());
            let chief = ImageModel {
                projections: m
                    .projections
                    .iter()
                    .filter(|p| p.point.truncate() == DVec2::ZERO)
                    .cloned()
                    .collect(),
                points_used: 1,
            };
            let t = 0.35f64.tan();
            let px = |q: DVec3| q.truncate() / -q.z / t * 256.0;
            let mut worst = 0.0f64;
            let mut curve = vec![];
            for k in 1..=20 {
                for axis in [DVec2::X, DVec2::ONE] {
                    let ndc = axis * (0.049 * k as f64);
                    let film = l.film_point(ndc).extend(l.film_z);
                    let traced = l
                        .aim(film, DVec2::ZERO)
                        .and_then(|d| l.trace(film, d, true))
                        .map(|(o, d)| o + d * ((-l.focus_distance - o.z) / d.z));
                    let (Some(a), Some(b)) = (traced, chief.focus_point(ndc, l.focus_distance))
                    else {
                        continue;
                    };
                    worst = worst.max((px(a) - px(b)).length());
                    if axis == DVec2::X && k % 4 == 0 {
                        curve.push(format!("{:.0}→{:.1}", ndc.x * 256.0, px(a).x));
                    }
                }
            }
            println!(
                "{name}: chief-ray image height (px) → object height (px of the pinhole): {}; \
                 model against traced: worst {worst:.3} px",
                curve.join(", ")
            );
            assert!(worst < 0.5, "{name}: {worst} px");
        }
    }

    /// At fraction `f` of cell `p`: (angle between the traced ray's direction and the
    /// morph's, the distance of the morph's image-plane point from the traced one).
    fn morph_error(l: &LensSystem, p: &Projection, point: DVec3, f: DVec2) -> (f64, f64) {
        let ndc = p.cell.0 + (p.cell.1 - p.cell.0) * f;
        let film = l.film_point(ndc).extend(l.film_z);
        // Only where the lens passes light (elsewhere the morph's weight is 0).
        let Some((o, d)) = l
            .aim(film, point.truncate())
            .and_then(|d| l.trace(film, d, true))
        else {
            return (0.0, 0.0);
        };
        let g = p.grid;
        let x = f * (g - 1) as f64;
        let (i, j) = ((x.x as usize).min(g - 2), (x.y as usize).min(g - 2));
        // Away from the edge of vignetting: the square and its neighbours carry light.
        let near = (i.saturating_sub(1)..(i + 3).min(g))
            .flat_map(|a| (j.saturating_sub(1)..(j + 3).min(g)).map(move |b| (a, b)));
        if near
            .into_iter()
            .any(|(a, b)| p.vertices[b * g + a].weight <= 0.0)
        {
            return (0.0, 0.0);
        }
        let (fx, fy) = (x.x - i as f64, x.y - j as f64);
        let uv = |a: usize, b: usize| Vec2::from(p.vertices[b * g + a].uv).as_dvec2();
        let uv = (uv(i, j) * (1.0 - fx) + uv(i + 1, j) * fx) * (1.0 - fy)
            + (uv(i, j + 1) * (1.0 - fx) + uv(i + 1, j + 1) * fx) * fy;
        let (lo, hi) = p.window;
        let t = DVec2::new(lo.x + uv.x * (hi.x - lo.x), hi.y - uv.y * (hi.y - lo.y));
        let depth = p.cop.z + l.focus_distance;
        let q_morph = p.cop + (t * depth).extend(-depth);
        let q_traced = o + d * ((-l.focus_distance - o.z) / d.z);
        let seen = (q_morph - p.cop).normalize();
        (
            seen.dot(d).clamp(-1.0, 1.0).acos(),
            (q_morph - q_traced).length(),
        )
    }
}
