//! Camera lens models (Heidrich 1999 ch. 11): the pinhole; the thin lens of the Gaussian
//! lens law and the thick lens (a thin lens plus an axial shift), as the path tracer traces
//! them and as the GPU approximates them by accumulating off-axis perspective projections,
//! one per aperture sample (Haeberli & Akeley 1990, the seed's §11.1); and traced lens
//! systems (`system`, from a `prescription`), which the GPU approximates by the image-based
//! model (`image_model`, §11.2).
//!
//! Conventions: camera space (x right, y up, looking down −z); `aperture` is the lens's
//! diameter and `focus_distance` the depth (along −z, from the camera's position) of the plane
//! imaged sharply, both in scene units (metres). A thin lens sits in the plane z = 0 at the
//! camera's position. A thick lens has two principal planes `thickness` apart; rays cross
//! between them parallel to the axis, so the scene sees a thin lens in the front plane
//! z = −thickness while the rear plane stays at the camera's position. The image keeps the
//! pinhole camera's field of view: the lens images the plane of focus with the pinhole's
//! framing from its front principal point, so that a thin lens only adds blur.

pub mod image_model;
pub mod prescription;
pub mod system;

use crate::sampling::{concentric_disc, r2};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// How a camera forms its image.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum CameraModel {
    #[default]
    Pinhole,
    /// A thin lens, or a thick one (`thickness` ≠ 0).
    ThinLens(ThinLens),
    /// A traced lens system.
    Traced(std::sync::Arc<system::LensSystem>),
}

impl CameraModel {
    /// A one-line description that differs when the images would: the model and every
    /// number that shapes it (recorded by sharded renders, so that parts through different
    /// lenses do not merge).
    pub fn describe(&self) -> String {
        match self {
            CameraModel::Pinhole => "pinhole".into(),
            CameraModel::ThinLens(l) => format!(
                "thin lens: aperture {} focus {} thickness {}",
                l.aperture, l.focus_distance, l.thickness
            ),
            CameraModel::Traced(s) => {
                let surfaces: Vec<String> = s
                    .elements
                    .iter()
                    .map(|e| {
                        let kind = if e.stop { "stop" } else { "surface" };
                        format!(
                            "{kind} {} {} {} {}",
                            e.radius, e.thickness, e.ior, e.aperture
                        )
                    })
                    .collect();
                format!(
                    "lens '{}': focus {} film {}×{}; {}",
                    s.name,
                    s.focus_distance,
                    2.0 * s.film_half.x,
                    2.0 * s.film_half.y,
                    surfaces.join("; ")
                )
            }
        }
    }
}

/// A thin (or thick) lens: aperture diameter, focus distance and the separation of the
/// principal planes (0: thin), in scene units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    pub aperture: f32,
    pub focus_distance: f32,
    /// Signed distance from the rear principal plane (at the camera) to the front one,
    /// towards the scene.
    pub thickness: f32,
}

/// A lens that cannot form an image.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LensError {
    #[error("the aperture must be a finite diameter ≥ 0 (got {0})")]
    Aperture(f32),
    #[error("the focus distance must be finite and beyond the lens's front plane (got {0})")]
    Focus(f32),
    #[error("the thickness must be finite and less than the focus distance (got {0})")]
    Thickness(f32),
}

impl ThinLens {
    pub fn validate(&self) -> Result<(), LensError> {
        if !(self.aperture.is_finite() && self.aperture >= 0.0) {
            return Err(LensError::Aperture(self.aperture));
        }
        if !(self.focus_distance.is_finite() && self.focus_distance > 0.0) {
            return Err(LensError::Focus(self.focus_distance));
        }
        if !(self.thickness.is_finite() && self.thickness < self.focus_distance) {
            return Err(LensError::Thickness(self.thickness));
        }
        Ok(())
    }

    /// Distance from the front principal plane to the plane of focus.
    fn reach(&self) -> f32 {
        self.focus_distance - self.thickness
    }

    /// The point of the lens for sample `u` ∈ [0, 1)² (uniform over the disc; x, y of the
    /// front principal plane).
    pub fn lens_point(&self, u: Vec2) -> Vec2 {
        concentric_disc(u) * (0.5 * self.aperture)
    }

    /// The camera-space ray (origin on the lens, unit direction) for the pixel whose pinhole
    /// direction is `d` (camera space, d.z < 0) and lens sample `u`: from the lens point
    /// towards where the chief ray (from the front principal point along `d`) meets the
    /// plane of focus.
    pub fn ray(&self, d: Vec3, u: Vec2) -> (Vec3, Vec3) {
        let front = Vec3::new(0.0, 0.0, -self.thickness);
        let focus = front + d * (self.reach() / (-d.z).max(1e-12));
        let o = self.lens_point(u).extend(-self.thickness);
        (o, (focus - o).normalize())
    }

    /// The camera-space eye of lens point `p` (on the front principal plane).
    pub fn eye(&self, p: Vec2) -> Vec3 {
        p.extend(-self.thickness)
    }

    /// Diameter of the blur circle of a point at depth `depth` (along −z), in pixels of an
    /// image `height` pixels high with vertical field of view `yfov`: its rays through the
    /// aperture cover a disc of diameter A·|d − s|/d on the plane of focus, which the image
    /// frames at 2·s·tan(yfov/2) per `height` pixels.
    pub fn circle_of_confusion(&self, depth: f32, yfov: f32, height: u32) -> f32 {
        // Depths from the front principal plane, where the aperture is.
        let (s, depth) = (self.reach(), depth - self.thickness);
        let on_focus_plane = self.aperture * (depth - s).abs() / depth.max(1e-12);
        on_focus_plane * height as f32 / (2.0 * s * (0.5 * yfov).tan())
    }

    /// The aperture samples of an `n`-sample accumulation: a rank-1 lattice (R2) mapped onto
    /// the disc, so that any prefix is spread over it.
    pub fn samples(&self, n: u32) -> Vec<Vec2> {
        (0..n.max(1))
            .map(|i| self.lens_point(r2(i, Vec2::splat(0.5))))
            .collect()
    }

    /// Camera space → the camera space of the pinhole at lens point `p`, sheared so that the
    /// plane of focus projects as the front principal point's does (the off-axis projection
    /// of Haeberli & Akeley): x' = (x − p.x) − (p.x/s)·z', y' likewise, z' = z + thickness,
    /// with s the plane of focus's distance from the lens. Compose as
    /// `projection · lens_view(p) · view`.
    pub fn lens_view(&self, p: Vec2) -> Mat4 {
        let s = self.reach();
        // Shift to the lens point, then shear x, y by z so that z = −s maps back.
        let shear = Mat4::from_cols(
            Vec4::X,
            Vec4::Y,
            Vec4::new(-p.x / s, -p.y / s, 1.0, 0.0),
            Vec4::W,
        );
        shear * Mat4::from_translation(-self.eye(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens() -> ThinLens {
        ThinLens {
            aperture: 0.2,
            focus_distance: 4.0,
            thickness: 0.0,
        }
    }

    /// Rays of one pixel meet on the plane of focus, and a point on that plane projects, from
    /// any lens point, where the pinhole at the front principal point projects it; for a
    /// thin lens and a thick one.
    #[test]
    fn the_plane_of_focus_is_sharp_from_every_lens_point() {
        for thickness in [0.0, 0.5] {
            let l = ThinLens {
                thickness,
                ..lens()
            };
            let d = Vec3::new(0.3, -0.2, -1.0);
            let front = Vec3::new(0.0, 0.0, -thickness);
            let target = front + d * (4.0 - thickness);
            for i in 0..16 {
                let (o, dir) = l.ray(d, r2(i, Vec2::ZERO));
                assert!((o.z + thickness).abs() < 1e-6);
                let t = (target.z - o.z) / dir.z;
                assert!((o + dir * t - target).length() < 1e-5);
                // The sheared view of the lens point maps the focus-plane point onto the
                // front pinhole's projected position (x/−z, y/−z).
                let p = l.lens_point(r2(i, Vec2::ZERO));
                let q = l.lens_view(p).transform_point3(target);
                let rel = target - front;
                let (a, b) = (q.truncate() / -q.z, rel.truncate() / -rel.z);
                assert!((a - b).length() < 1e-6, "{a} vs {b}");
            }
        }
    }

    /// The blur circle of a point off the plane of focus, measured by intersecting the lens's
    /// rays through it with the plane of focus, against the analytic diameter.
    #[test]
    fn the_circle_of_confusion_has_its_analytic_diameter() {
        for thickness in [0.0, 0.5] {
            let l = ThinLens {
                thickness,
                ..lens()
            };
            let (yfov, h) = (0.8f32, 512u32);
            let s = l.focus_distance - thickness;
            for depth in [1.5f32, 3.0, 8.0, 40.0] {
                let point = Vec3::new(0.0, 0.0, -depth);
                // Lens points on the rim: their rays through the point reach the rim of the
                // blur on the plane of focus.
                let mut widest = 0.0f32;
                for k in 0..360 {
                    let a = (k as f32).to_radians();
                    let o = (Vec2::new(a.cos(), a.sin()) * (0.5 * l.aperture)).extend(-thickness);
                    let dir = point - o;
                    let at = o + dir * (s / (depth - thickness));
                    widest = widest.max(2.0 * at.truncate().length());
                }
                let px = widest * h as f32 / (2.0 * s * (0.5 * yfov).tan());
                let analytic = l.circle_of_confusion(depth, yfov, h);
                assert!(
                    (px - analytic).abs() <= 0.01 * analytic,
                    "{depth}: {px} vs {analytic}"
                );
            }
            assert!(l.circle_of_confusion(4.0, yfov, h) < 1e-6);
        }
    }

    #[test]
    fn bad_lenses_are_refused() {
        let mut l = lens();
        l.aperture = -1.0;
        assert_eq!(l.validate(), Err(LensError::Aperture(-1.0)));
        let mut l = lens();
        l.focus_distance = 0.0;
        assert_eq!(l.validate(), Err(LensError::Focus(0.0)));
        let l = ThinLens {
            thickness: 5.0,
            ..lens()
        };
        assert_eq!(l.validate(), Err(LensError::Thickness(5.0)));
        assert!(lens().validate().is_ok());
    }
}
