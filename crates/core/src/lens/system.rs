//! A traced lens system (Heidrich 1999 §11.1, "geometric lens model"; Kolb et al. 1995): the
//! surfaces of a prescription placed in camera space, focused and framed for one camera, and
//! traced with Snell's law at every surface.
//!
//! Placement (camera space, looking down −z): the front vertex sits at the camera's position,
//! the lens extends behind it (+z) and the film lies behind the rear vertex. Focusing moves
//! the film (the paraxial image of the plane at `focus_distance` in front of the front
//! vertex). The film is as large as keeps the pinhole's framing paraxially: the plane of
//! focus shows what the pinhole camera shows there, so that a lens adds only blur,
//! distortion and fall-off. The image on the film is inverted; film point `film_point(ndc)`
//! is where the upright image's `ndc` lands.
//!
//! Exposure follows Kolb et al.: a film point's irradiance is ∫ L cos⁴θ / Z² dA over the
//! rear plane (Z: the film's axial distance to it, θ: the ray's angle with the axis). We
//! divide by the value at the film's centre for L = 1, so the centre of the image keeps the
//! scene's radiance scale and the rest falls off by cos⁴ and vignetting. Rays are sampled
//! over the exit pupil: for rings of film radius, the box of the rear plane through which any
//! ray reaches the scene, found once by tracing a grid.

use super::prescription::{Element, Prescription};
use glam::{DVec2, DVec3};

/// Rings of film radius with their own exit-pupil box.
const PUPIL_RINGS: usize = 64;
/// Grid side of the rear plane traced per ring.
const PUPIL_GRID: usize = 48;

/// A lens that cannot be placed for a camera.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LensSystemError {
    #[error("the lens does not focus light (its power is {0:.3e} per metre)")]
    NoPower(f64),
    #[error("the lens cannot focus at {0} m: the image would lie in front of its rear surface")]
    CannotFocus(f64),
    #[error("no ray from the film's centre passes through the lens")]
    Blocked,
    #[error("{0} must be finite and > 0 (got {1})")]
    Setting(&'static str, f64),
}

/// How to place a prescription for a camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensSetup {
    /// Multiply every length of the prescription (1: as written).
    pub scale: f64,
    /// Replace the stop's diameter (metres, after scaling); None: as written.
    pub stop_diameter: Option<f64>,
    /// Depth of the plane in focus, from the front vertex (metres).
    pub focus_distance: f64,
    /// The camera's vertical field of view (radians) and aspect (width / height).
    pub yfov: f64,
    pub aspect: f64,
}

/// A ray leaving the lens into the scene (camera space) and its exposure weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensRay {
    pub origin: DVec3,
    pub dir: DVec3,
    pub weight: f64,
}

/// A prescription placed, focused and framed for one camera.
#[derive(Clone, Debug, PartialEq)]
pub struct LensSystem {
    pub name: String,
    pub elements: Vec<Element>,
    /// Camera-space z of each surface's vertex (the front one at 0).
    pub vertex_z: Vec<f64>,
    /// Camera-space z of the film.
    pub film_z: f64,
    /// Half the film's width and height (metres).
    pub film_half: DVec2,
    /// The effective focal length (paraxial).
    pub focal_length: f64,
    pub focus_distance: f64,
    /// Per ring of film radius, the exit-pupil box on the rear plane (for film points on +x).
    pupil: Vec<(DVec2, DVec2)>,
    /// Irradiance at the film's centre for unit radiance (the exposure's normaliser).
    exposure0: f64,
    pupil_radius: f64,
}

/// The paraxial matrix [[A, B], [C, D]] of a lens from its front vertex to its rear vertex,
/// acting on (height, index × angle).
pub fn paraxial_matrix(elements: &[Element]) -> [[f64; 2]; 2] {
    let mul = |a: [[f64; 2]; 2], b: [[f64; 2]; 2]| {
        [
            [
                a[0][0] * b[0][0] + a[0][1] * b[1][0],
                a[0][0] * b[0][1] + a[0][1] * b[1][1],
            ],
            [
                a[1][0] * b[0][0] + a[1][1] * b[1][0],
                a[1][0] * b[0][1] + a[1][1] * b[1][1],
            ],
        ]
    };
    let mut m = [[1.0, 0.0], [0.0, 1.0]];
    let mut n = 1.0;
    for (i, e) in elements.iter().enumerate() {
        let power = if e.radius == 0.0 || e.stop {
            0.0
        } else {
            (e.ior - n) / e.radius
        };
        m = mul([[1.0, 0.0], [-power, 1.0]], m);
        if i + 1 < elements.len() {
            m = mul([[1.0, e.thickness / e.ior], [0.0, 1.0]], m);
        }
        n = e.ior;
    }
    m
}

/// Paraxial properties of a lens in air: effective focal length, and the distances of the
/// principal planes from the front vertex (towards the film positive) and from the rear
/// vertex (likewise).
pub fn cardinal_points(elements: &[Element]) -> (f64, f64, f64) {
    let [[a, _], [c, d]] = paraxial_matrix(elements);
    let f = -1.0 / c;
    // Front focal point at D/C from the front vertex (negative: in front); the front
    // principal plane one focal length behind it. Rear focal point at −A/C from the rear
    // vertex; the rear principal plane one focal length in front of it.
    (f, d / c + f, -a / c - f)
}

/// The paraxial image distance behind the rear vertex of an object `s` in front of the
/// front vertex, and the lateral magnification.
pub fn paraxial_image(elements: &[Element], s: f64) -> (f64, f64) {
    let [[a, b], [c, d]] = paraxial_matrix(elements);
    let x = -(a * s + b) / (c * s + d);
    (x, a + x * c)
}

impl LensSystem {
    /// Place `p` for a camera (see the module doc).
    pub fn new(p: &Prescription, setup: LensSetup) -> Result<LensSystem, LensSystemError> {
        for (what, v) in [
            ("the lens scale", setup.scale),
            ("the focus distance", setup.focus_distance),
            ("the field of view", setup.yfov),
            ("the aspect", setup.aspect),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(LensSystemError::Setting(what, v));
            }
        }
        let mut p = p.scaled(setup.scale);
        if let Some(d) = setup.stop_diameter {
            if !(d.is_finite() && d > 0.0) {
                return Err(LensSystemError::Setting("the stop's diameter", d));
            }
            p.elements
                .iter_mut()
                .filter(|e| e.stop)
                .for_each(|e| e.aperture = d);
        }
        let [[_, _], [c, _]] = paraxial_matrix(&p.elements);
        if c.abs() < 1e-9 {
            return Err(LensSystemError::NoPower(c));
        }
        let (x, m) = paraxial_image(&p.elements, setup.focus_distance);
        if !(x.is_finite() && x > 0.0) {
            return Err(LensSystemError::CannotFocus(setup.focus_distance));
        }
        let mut vertex_z = Vec::with_capacity(p.elements.len());
        let mut z = 0.0;
        for e in &p.elements {
            vertex_z.push(z);
            z += e.thickness;
        }
        let rear = *vertex_z.last().expect("a prescription has surfaces");
        let half_h = m.abs() * setup.focus_distance * (0.5 * setup.yfov).tan();
        let mut lens = LensSystem {
            name: p.name.clone(),
            elements: p.elements,
            vertex_z,
            film_z: rear + x,
            film_half: DVec2::new(half_h * setup.aspect, half_h),
            focal_length: -1.0 / c,
            focus_distance: setup.focus_distance,
            pupil: Vec::new(),
            exposure0: 0.0,
            pupil_radius: 0.0,
        };
        (lens.pupil, lens.pupil_radius) = lens.pupil_boxes();
        lens.exposure0 = lens.centre_exposure();
        if lens.exposure0 <= 0.0 {
            return Err(LensSystemError::Blocked);
        }
        Ok(lens)
    }

    /// The camera-space z of the rear plane (through the rear vertex).
    pub fn rear_z(&self) -> f64 {
        *self.vertex_z.last().expect("a lens has surfaces")
    }

    /// The film point (camera space x, y) where the upright image's `ndc` lands.
    pub fn film_point(&self, ndc: DVec2) -> DVec2 {
        -ndc * self.film_half
    }

    /// Trace a ray from the film side (camera space, travelling towards −z) through every
    /// surface; `clip`: stop at the apertures. None when it misses a surface, is blocked or
    /// is totally reflected. Returns the ray leaving the front surface.
    pub fn trace(&self, o: DVec3, d: DVec3, clip: bool) -> Option<(DVec3, DVec3)> {
        self.trace_until(o, d, clip, 0)
    }

    /// [`trace`](Self::trace) through the surfaces from the film's side down to surface
    /// `first` (inclusive): the ray leaving it.
    pub fn trace_until(
        &self,
        mut o: DVec3,
        mut d: DVec3,
        clip: bool,
        first: usize,
    ) -> Option<(DVec3, DVec3)> {
        for i in (first..self.elements.len()).rev() {
            let e = &self.elements[i];
            let zv = self.vertex_z[i];
            let (p, normal) = if e.radius == 0.0 || e.stop {
                let t = (zv - o.z) / d.z;
                if !(t.is_finite() && t > 0.0) {
                    return None;
                }
                (o + d * t, DVec3::Z)
            } else {
                let c = DVec3::new(0.0, 0.0, zv + e.radius);
                let oc = o - c;
                let b = oc.dot(d);
                let disc = b * b - (oc.length_squared() - e.radius * e.radius);
                if disc < 0.0 {
                    return None;
                }
                let sq = disc.sqrt();
                // The cap around the vertex: where (p − c)·z has the sign of −radius.
                let t = [-b - sq, -b + sq]
                    .into_iter()
                    .find(|&t| t > 1e-12 && ((o.z + d.z * t) - c.z) * -e.radius > 0.0)?;
                let p = o + d * t;
                (p, (p - c) / e.radius.abs())
            };
            if clip && p.truncate().length_squared() > 0.25 * e.aperture * e.aperture {
                return None;
            }
            o = p;
            if !e.stop {
                let outside = if i == 0 {
                    1.0
                } else {
                    self.elements[i - 1].ior
                };
                d = refract(d, normal, e.ior / outside)?;
            }
        }
        Some((o, d))
    }

    /// The aperture stop: the `stop` surface, else the one with the smallest aperture.
    pub fn stop_index(&self) -> usize {
        self.elements
            .iter()
            .position(|e| e.stop)
            .or_else(|| {
                (0..self.elements.len()).min_by(|&a, &b| {
                    self.elements[a]
                        .aperture
                        .total_cmp(&self.elements[b].aperture)
                })
            })
            .expect("a lens has surfaces")
    }

    /// Ray aiming: the unit direction from film point `film` (camera space) whose ray meets
    /// the stop's plane (through its vertex) at `target` (x, y), ignoring apertures. Newton
    /// steps on the rear-plane point the ray is aimed at, with a finite-difference Jacobian,
    /// from a start inside the film point's exit pupil. None when it does not converge.
    pub fn aim(&self, film: DVec3, target: DVec2) -> Option<DVec3> {
        self.aim_from(film, target, None).map(|(d, _)| d)
    }

    /// [`aim`](Self::aim) from a start on the rear plane (a neighbouring film point's
    /// solution, say); returns the direction and the rear-plane point it aims at.
    pub fn aim_from(
        &self,
        film: DVec3,
        target: DVec2,
        start: Option<DVec2>,
    ) -> Option<(DVec3, DVec2)> {
        let stop = self.stop_index();
        let at_stop = |q: DVec2| -> Option<DVec2> {
            let d = (q.extend(self.rear_z()) - film).normalize();
            let (o, d) = self.trace_until(film, d, false, stop + 1)?;
            let t = (self.vertex_z[stop] - o.z) / d.z;
            Some((o + d * t).truncate())
        };
        let (lo, hi) = self.pupil_box(film.truncate().length());
        let r_stop = 0.5 * self.elements[stop].aperture;
        let rot = film.truncate().try_normalize().unwrap_or(DVec2::X);
        let turn = |v: DVec2| DVec2::new(rot.x * v.x - rot.y * v.y, rot.y * v.x + rot.x * v.y);
        let mut q = start
            .unwrap_or_else(|| turn((lo + hi) * 0.5) + target * (0.5 * (hi.x - lo.x) / r_stop));
        let h = 1e-4 * r_stop.max(1e-6);
        let mut g = at_stop(q)? - target;
        // A one-sided difference, taken backwards where the forward ray misses a surface.
        let slope = |q: DVec2, g: DVec2, e: DVec2| {
            at_stop(q + e * h)
                .map(|p| (p - target - g) / h)
                .or_else(|| at_stop(q - e * h).map(|p| (g - (p - target)) / h))
        };
        for _ in 0..24 {
            if g.length() < 1e-9 * r_stop.max(1e-3) {
                return Some(((q.extend(self.rear_z()) - film).normalize(), q));
            }
            let gx = slope(q, g, DVec2::X)?;
            let gy = slope(q, g, DVec2::Y)?;
            let det = gx.x * gy.y - gx.y * gy.x;
            if det.abs() < 1e-18 {
                return None;
            }
            let step = DVec2::new(gy.y * g.x - gy.x * g.y, -gx.y * g.x + gx.x * g.y) / det;
            // Damped: halve the step until the ray still passes and the miss shrinks.
            let mut k = 1.0;
            loop {
                if let Some(n) = at_stop(q - step * k).map(|p| p - target)
                    && n.length() < g.length()
                {
                    q -= step * k;
                    g = n;
                    break;
                }
                k *= 0.5;
                if k < 1e-4 {
                    return None;
                }
            }
        }
        None
    }

    /// The stop's radius and the camera-space z of its plane.
    pub fn stop_disc(&self) -> (f64, f64) {
        let stop = self.stop_index();
        (0.5 * self.elements[stop].aperture, self.vertex_z[stop])
    }

    /// The exit-pupil box of the ring containing film radius `r`.
    fn pupil_box(&self, r: f64) -> (DVec2, DVec2) {
        let r_max = self.film_half.length();
        let k = ((r / r_max) * PUPIL_RINGS as f64) as usize;
        self.pupil[k.min(PUPIL_RINGS - 1)]
    }

    /// Per ring of film radius, the box of the rear plane through which rays from film
    /// points on +x at the ring's inner, middle and outer radius pass, grown by a grid cell;
    /// and the radius of the disc holding them all. A coarse grid over the widest aperture
    /// finds the box, a second grid over it (grown by a coarse cell) refines it, so that a
    /// small stop's pupil is found and bounded tightly.
    fn pupil_boxes(&self) -> (Vec<(DVec2, DVec2)>, f64) {
        // The rear surface's rim may lie behind its vertex: cover the widest aperture.
        let a = 0.5 * self.elements.iter().map(|e| e.aperture).fold(0.0, f64::max);
        let r_max = self.film_half.length();
        let mut radius = 0.0f64;
        let boxes = (0..PUPIL_RINGS)
            .map(|k| {
                let radii = [0.0, 0.5, 1.0].map(|f| (k as f64 + f) / PUPIL_RINGS as f64 * r_max);
                let coarse = (DVec2::splat(-a), DVec2::splat(a));
                let Some(found) = self.passing_box(&radii, coarse, 2 * PUPIL_GRID) else {
                    return (DVec2::ZERO, DVec2::ZERO);
                };
                let fine = self.passing_box(&radii, found, PUPIL_GRID).unwrap_or(found);
                radius = radius.max(fine.0.length().max(fine.1.length()));
                radius = radius.max(DVec2::new(fine.0.x, fine.1.y).length());
                radius = radius.max(DVec2::new(fine.1.x, fine.0.y).length());
                fine
            })
            .collect();
        (boxes, radius)
    }

    /// The box of an `n`² grid's points over `region` of the rear plane through which rays
    /// from film points at `radii` (on +x) pass, grown by a cell; None when none passes.
    fn passing_box(
        &self,
        radii: &[f64],
        region: (DVec2, DVec2),
        n: usize,
    ) -> Option<(DVec2, DVec2)> {
        let cell = (region.1 - region.0) / n as f64;
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for &r in radii {
            let film = DVec3::new(r, 0.0, self.film_z);
            for (i, j) in (0..n).flat_map(|i| (0..n).map(move |j| (i, j))) {
                let q = region.0 + cell * DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
                let d = (q.extend(self.rear_z()) - film).normalize();
                if self.trace(film, d, true).is_some() {
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
        }
        (lo.x <= hi.x).then(|| (lo - cell, hi + cell))
    }

    /// ∫ cos⁴θ / Z² dA over the rear plane for the film's centre, counting rays that pass.
    fn centre_exposure(&self) -> f64 {
        let (lo, hi) = self.pupil[0];
        let n = 160;
        let step = (hi - lo) / n as f64;
        let film = DVec3::new(0.0, 0.0, self.film_z);
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let q = lo + step * DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
                sum += self.exposure_term(film, q.extend(self.rear_z()));
            }
        }
        sum * step.x * step.y
    }

    /// cos⁴θ / Z² for the ray from `film` towards rear-plane point `q`, when it passes.
    fn exposure_term(&self, film: DVec3, q: DVec3) -> f64 {
        let d = (q - film).normalize();
        if self.trace(film, d, true).is_none() {
            return 0.0;
        }
        let z = self.film_z - self.rear_z();
        d.z.powi(4) / (z * z)
    }

    /// A ray for the film point of `ndc`, sampled uniformly over its exit-pupil box with
    /// `u` ∈ [0, 1)², with its exposure weight (1 on average at the film's centre). None when
    /// the lens blocks it.
    pub fn sample_ray(&self, ndc: DVec2, u: DVec2) -> Option<LensRay> {
        let fp = self.film_point(ndc);
        let (lo, hi) = self.pupil_box(fp.length());
        let area = (hi.x - lo.x) * (hi.y - lo.y);
        if area <= 0.0 {
            return None;
        }
        let q = lo + (hi - lo) * u;
        // The boxes were found for film points on +x: turn to this point's azimuth.
        let (s, c) = if fp.length() > 0.0 {
            let a = fp.normalize();
            (a.y, a.x)
        } else {
            (0.0, 1.0)
        };
        let q = DVec2::new(c * q.x - s * q.y, s * q.x + c * q.y);
        let film = fp.extend(self.film_z);
        let d = (q.extend(self.rear_z()) - film).normalize();
        let (origin, dir) = self.trace(film, d, true)?;
        let z = self.film_z - self.rear_z();
        Some(LensRay {
            origin,
            dir,
            weight: d.z.powi(4) / (z * z) * area / self.exposure0,
        })
    }

    /// Exposure of `ndc`'s film point for unit radiance, relative to the centre (cos⁴ and
    /// vignetting), integrated on an `n`² grid over its pupil box.
    pub fn relative_exposure(&self, ndc: DVec2, n: usize) -> f64 {
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = DVec2::new((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                sum += self.sample_ray(ndc, u).map_or(0.0, |r| r.weight);
            }
        }
        sum / (n * n) as f64
    }

    /// The point of the plane of focus (camera space) imaged at the film point of `ndc`:
    /// the exposure-weighted mean of where its rays, over an `n`² grid of its pupil box, meet
    /// that plane (the distortion curve's object height). None when the lens blocks every
    /// ray.
    pub fn focus_point(&self, ndc: DVec2, n: usize) -> Option<DVec3> {
        let (mut sum, mut total) = (DVec3::ZERO, 0.0);
        for i in 0..n * n {
            let u = DVec2::new((i % n) as f64 + 0.5, (i / n) as f64 + 0.5) / n as f64;
            if let Some(r) = self.sample_ray(ndc, u) {
                let t = (-self.focus_distance - r.origin.z) / r.dir.z;
                sum += (r.origin + r.dir * t) * r.weight;
                total += r.weight;
            }
        }
        (total > 0.0).then(|| sum / total)
    }

    /// The radius of the rear-plane disc through which some film point sees the scene: the
    /// farthest passing point of the rings' traced grids, plus a grid cell.
    pub fn pupil_radius(&self) -> f64 {
        self.pupil_radius
    }

    /// The exposure normaliser (irradiance at the film's centre for unit radiance).
    pub fn exposure0(&self) -> f64 {
        self.exposure0
    }
}

/// Snell's law: `d` through a surface with unit normal `n` (either side) from index
/// `eta_ratio` × the far side's; None on total internal reflection.
fn refract(d: DVec3, n: DVec3, eta_ratio: f64) -> Option<DVec3> {
    let n = if n.dot(d) > 0.0 { -n } else { n };
    let cos_i = -n.dot(d);
    let k = 1.0 - eta_ratio * eta_ratio * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| (d * eta_ratio + n * (eta_ratio * cos_i - k.sqrt())).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup(focus: f64) -> LensSetup {
        LensSetup {
            scale: 1.0,
            stop_diameter: None,
            focus_distance: focus,
            yfov: 0.7,
            aspect: 1.0,
        }
    }

    /// Where a near-axis ray from the film's centre, traced out of the lens, crosses the axis
    /// (camera-space z).
    fn axis_crossing(l: &LensSystem) -> f64 {
        let film = DVec3::new(0.0, 0.0, l.film_z);
        let q = DVec3::new(1e-5, 0.0, l.rear_z());
        let (o, d) = l.trace(film, (q - film).normalize(), false).unwrap();
        o.z - o.x / d.x * d.z
    }

    /// The shipped double Gauss has the focal length of its name: the prescription's numbers
    /// are read and traced as the design has them.
    #[test]
    fn the_double_gauss_is_a_50mm_lens() {
        let p = Prescription::builtin("double-gauss").unwrap();
        let (f, _, _) = cardinal_points(&p.elements);
        assert!((f - 0.050).abs() < 0.001, "{f}");
        for (name, _) in super::super::prescription::BUILTIN {
            let p = Prescription::builtin(name).unwrap();
            let f = cardinal_points(&p.elements).0;
            assert!((0.048..0.052).contains(&f), "{name}: {f}");
        }
    }

    /// A thin single lens traced near its axis images as 1/s + 1/s' = 1/f with the
    /// lensmaker's f.
    #[test]
    fn a_thin_lens_follows_the_gaussian_lens_law() {
        let (r, n) = (0.2, 1.5);
        let p = Prescription::parse(&format!(
            "units m\nsurface {r} 0.0001 {n} 0.02\nsurface {} 0.1 1 0.02\n",
            -r
        ))
        .unwrap();
        let f = 1.0 / ((n - 1.0) * (2.0 / r));
        for s in [0.5, 1.0, 4.0] {
            let l = LensSystem::new(&p, setup(s)).unwrap();
            let image = l.film_z - 0.0001;
            let lhs = 1.0 / s + 1.0 / image;
            assert!((lhs * f - 1.0).abs() < 1e-3, "{s}: {} vs {}", 1.0 / lhs, f);
            // Traced: the near-axis ray from the film's centre meets the axis at the object.
            assert!((axis_crossing(&l) + s).abs() < 1e-4 * s, "{s}");
        }
    }

    /// A thick lens images as its principal-plane model says (Heidrich §11.1: a thin lens
    /// between two principal planes, rays parallel to the axis between them), and the traced
    /// rays agree.
    #[test]
    fn a_thick_lens_follows_its_principal_planes() {
        let p =
            Prescription::parse("units m\nsurface 0.03 0.025 1.7 0.03\nsurface -0.05 0.1 1 0.03\n")
                .unwrap();
        let (f, h, h2) = cardinal_points(&p.elements);
        assert!(h > 0.001 && h2 < -0.001, "{h} {h2}");
        for s in [0.3, 1.0, 5.0] {
            let l = LensSystem::new(&p, setup(s)).unwrap();
            let (s_h, image_h) = (s + h, l.film_z - l.rear_z() - h2);
            assert!(((1.0 / s_h + 1.0 / image_h) * f - 1.0).abs() < 1e-9, "{s}");
            assert!(
                (axis_crossing(&l) + s).abs() < 1e-4 * s,
                "{s}: {}",
                axis_crossing(&l)
            );
        }
    }

    /// Kolb's exposure: unit radiance gives 1 at the film's centre and falls off towards the
    /// corners (cos⁴ and vignetting); the weights are averages over the pupil box.
    #[test]
    fn exposure_is_one_at_the_centre_and_falls_off() {
        for (name, _) in super::super::prescription::BUILTIN {
            let l = LensSystem::new(&Prescription::builtin(name).unwrap(), setup(3.0)).unwrap();
            let centre = l.relative_exposure(DVec2::ZERO, 64);
            assert!((centre - 1.0).abs() < 0.01, "{name}: {centre}");
            let edge = l.relative_exposure(DVec2::new(1.0, 0.0), 64);
            let corner = l.relative_exposure(DVec2::ONE, 64);
            println!("{name}: edge {edge:.3} corner {corner:.3}");
            assert!(corner < 0.95 && edge > corner, "{name}: {edge} {corner}");
        }
    }

    /// Rays sampled over the pupil leave the front of the lens, upright image: the film
    /// point of the top right of the image sends its light to the top right of the scene.
    #[test]
    fn sampled_rays_frame_the_image_upright() {
        let l = LensSystem::new(&Prescription::builtin("doublet").unwrap(), setup(3.0)).unwrap();
        let r = (0..64)
            .find_map(|i| {
                l.sample_ray(
                    DVec2::new(0.5, 0.5),
                    DVec2::new((i as f64 + 0.5) / 64.0, 0.5),
                )
            })
            .unwrap();
        assert!(
            r.dir.x > 0.0 && r.dir.y > 0.0 && r.dir.z < 0.0,
            "{:?}",
            r.dir
        );
        assert!(r.origin.z.abs() < 0.01);
        // Paraxially the same framing as the pinhole: ndc 0.1 looks along 0.1·tan(fov/2).
        let hits: Vec<DVec3> = (0..256)
            .filter_map(|i| {
                let u = DVec2::new((i % 16) as f64 + 0.5, (i / 16) as f64 + 0.5) / 16.0;
                l.sample_ray(DVec2::new(0.1, 0.0), u)
            })
            .map(|r| r.origin + r.dir * ((-3.0 - r.origin.z) / r.dir.z))
            .collect();
        let c = hits.iter().sum::<DVec3>() / hits.len() as f64;
        let want = 0.1 * 3.0 * (0.35f64).tan();
        assert!((c.x / want - 1.0).abs() < 0.03, "{} vs {want}", c.x);
    }

    /// Sampling only the exit-pupil boxes loses no light: against the exposure integrated
    /// over the whole rear plane.
    #[test]
    fn the_pupil_boxes_hold_every_ray_that_passes() {
        for (name, _) in super::super::prescription::BUILTIN {
            let l = LensSystem::new(&Prescription::builtin(name).unwrap(), setup(3.0)).unwrap();
            let a = 0.5 * l.elements.iter().map(|e| e.aperture).fold(0.0, f64::max);
            for ndc in [
                DVec2::new(0.3, -0.2),
                DVec2::new(0.0, 1.0),
                DVec2::new(-0.9, 0.9),
            ] {
                let film = l.film_point(ndc).extend(l.film_z);
                let n = 400;
                let cell = 2.0 * a / n as f64;
                let mut sum = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        let q = DVec2::new(i as f64 + 0.5, j as f64 + 0.5) * cell - a;
                        sum += l.exposure_term(film, q.extend(l.rear_z()));
                    }
                }
                let whole = sum * cell * cell / l.exposure0();
                let sampled = l.relative_exposure(ndc, 128);
                assert!(
                    (sampled - whole).abs() < 0.02 * whole.max(0.05),
                    "{name} {ndc}: {sampled} vs {whole}"
                );
            }
        }
    }

    #[test]
    fn lenses_that_cannot_focus_are_refused() {
        let p = Prescription::builtin("biconvex").unwrap();
        assert_eq!(
            LensSystem::new(&p, setup(0.02)),
            Err(LensSystemError::CannotFocus(0.02))
        );
        let mut bad = setup(3.0);
        bad.yfov = f64::NAN;
        assert!(matches!(
            LensSystem::new(&p, bad),
            Err(LensSystemError::Setting(..))
        ));
        let flat = Prescription::parse("surface inf 2 1.5 10\nsurface inf 2 1 10\n").unwrap();
        assert!(matches!(
            LensSystem::new(&flat, setup(3.0)),
            Err(LensSystemError::NoPower(_))
        ));
    }
}
