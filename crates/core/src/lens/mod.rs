//! Camera lens models (Heidrich 1999 ch. 11): the pinhole, and the thin lens of the Gaussian
//! lens law, as the path tracer traces it and as the GPU approximates it by accumulating
//! off-axis perspective projections, one per aperture sample (Haeberli & Akeley 1990, the
//! seed's §11.1).
//!
//! Conventions: camera space (x right, y up, looking down −z); the lens sits in the plane
//! z = 0 at the camera's position; `aperture` is the lens's diameter and `focus_distance` the
//! depth (along −z) of the plane imaged sharply, both in scene units (metres). The image keeps
//! the pinhole camera's field of view: a thin lens focused at s images the plane z = −s with
//! the pinhole's framing, so that the lens only adds blur.

pub mod prescription;
pub mod system;

use crate::sampling::{concentric_disc, r2};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// How a camera forms its image.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum CameraModel {
    #[default]
    Pinhole,
    ThinLens(ThinLens),
}

/// A thin lens: aperture diameter and focus distance (scene units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    pub aperture: f32,
    pub focus_distance: f32,
}

/// A lens that cannot form an image.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LensError {
    #[error("the aperture must be a finite diameter ≥ 0 (got {0})")]
    Aperture(f32),
    #[error("the focus distance must be finite and > 0 (got {0})")]
    Focus(f32),
}

impl ThinLens {
    pub fn validate(&self) -> Result<(), LensError> {
        if !(self.aperture.is_finite() && self.aperture >= 0.0) {
            return Err(LensError::Aperture(self.aperture));
        }
        if !(self.focus_distance.is_finite() && self.focus_distance > 0.0) {
            return Err(LensError::Focus(self.focus_distance));
        }
        Ok(())
    }

    /// The point of the lens for sample `u` ∈ [0, 1)² (uniform over the disc; camera space,
    /// z = 0).
    pub fn lens_point(&self, u: Vec2) -> Vec2 {
        concentric_disc(u) * (0.5 * self.aperture)
    }

    /// The camera-space ray (origin on the lens, unit direction) for the pixel whose pinhole
    /// direction is `d` (camera space, d.z < 0) and lens sample `u`: from the lens point
    /// towards where the pinhole ray meets the plane of focus.
    pub fn ray(&self, d: Vec3, u: Vec2) -> (Vec3, Vec3) {
        let focus = d * (self.focus_distance / (-d.z).max(1e-12));
        let o = self.lens_point(u).extend(0.0);
        (o, (focus - o).normalize())
    }

    /// Diameter of the blur circle of a point at depth `depth` (along −z), in pixels of an
    /// image `height` pixels high with vertical field of view `yfov`: its rays through the
    /// aperture cover a disc of diameter A·|d − s|/d on the plane of focus, which the image
    /// frames at 2·s·tan(yfov/2) per `height` pixels.
    pub fn circle_of_confusion(&self, depth: f32, yfov: f32, height: u32) -> f32 {
        let s = self.focus_distance;
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
    /// plane of focus projects as the centre's does (the off-axis projection of Haeberli &
    /// Akeley): x' = (x − p.x) − (p.x/s)·z, y' likewise, z' = z. Compose as
    /// `projection · lens_view(p) · view`.
    pub fn lens_view(&self, p: Vec2) -> Mat4 {
        let s = self.focus_distance;
        // Shift to the lens point, then shear x, y by z so that z = −s maps back.
        let shear = Mat4::from_cols(
            Vec4::X,
            Vec4::Y,
            Vec4::new(-p.x / s, -p.y / s, 1.0, 0.0),
            Vec4::W,
        );
        shear * Mat4::from_translation(-p.extend(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens() -> ThinLens {
        ThinLens {
            aperture: 0.2,
            focus_distance: 4.0,
        }
    }

    /// Rays of one pixel meet on the plane of focus, and a point on that plane projects, from
    /// any lens point, where the pinhole projects it.
    #[test]
    fn the_plane_of_focus_is_sharp_from_every_lens_point() {
        let l = lens();
        let d = Vec3::new(0.3, -0.2, -1.0);
        let target = d * 4.0;
        for i in 0..16 {
            let (o, dir) = l.ray(d, r2(i, Vec2::ZERO));
            let t = (target.z - o.z) / dir.z;
            assert!((o + dir * t - target).length() < 1e-5);
            // The sheared view of the lens point maps the focus-plane point onto the pinhole's
            // projected position (x/−z, y/−z).
            let p = l.lens_point(r2(i, Vec2::ZERO));
            let q = l.lens_view(p).transform_point3(target);
            let (a, b) = (q.truncate() / -q.z, target.truncate() / -target.z);
            assert!((a - b).length() < 1e-6, "{a} vs {b}");
        }
    }

    /// The blur circle of a point off the plane of focus, measured by intersecting the lens's
    /// rays through it with the plane of focus, against the analytic diameter.
    #[test]
    fn the_circle_of_confusion_has_its_analytic_diameter() {
        let l = lens();
        let (yfov, h) = (0.8f32, 512u32);
        for depth in [1.5f32, 3.0, 8.0, 40.0] {
            let point = Vec3::new(0.0, 0.0, -depth);
            // Lens points on the rim: their rays through the point reach the rim of the blur.
            let mut widest = 0.0f32;
            for k in 0..360 {
                let a = (k as f32).to_radians();
                let o = Vec3::new(a.cos(), a.sin(), 0.0) * (0.5 * l.aperture);
                let dir = point - o;
                let at = o + dir * (l.focus_distance / depth);
                widest = widest.max(2.0 * at.truncate().length());
            }
            let px = widest * h as f32 / (2.0 * l.focus_distance * (0.5 * yfov).tan());
            let analytic = l.circle_of_confusion(depth, yfov, h);
            assert!(
                (px - analytic).abs() <= 0.01 * analytic,
                "{depth}: {px} vs {analytic}"
            );
        }
        assert!(l.circle_of_confusion(4.0, yfov, h) < 1e-6);
    }

    #[test]
    fn bad_lenses_are_refused() {
        let mut l = lens();
        l.aperture = -1.0;
        assert_eq!(l.validate(), Err(LensError::Aperture(-1.0)));
        let mut l = lens();
        l.focus_distance = 0.0;
        assert_eq!(l.validate(), Err(LensError::Focus(0.0)));
        assert!(lens().validate().is_ok());
    }
}
