//! The viewer's orbit camera: a target point, a distance and two angles, so that dragging turns
//! the view around what it looks at and the keys move both together.

use glam::{Mat4, Vec3};
use lightlab_scene::Camera;

/// Yaw/pitch orbit around `target` (y up). Roll is not represented: a scene camera with roll
/// comes back level.
#[derive(Clone, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target: Vec3,
    pub distance: f32,
    /// Angle of the eye around +y, from +z towards +x (radians).
    pub yaw: f32,
    /// Elevation of the eye above the target's horizontal plane (radians).
    pub pitch: f32,
    pub yfov: f32,
    pub znear: f32,
    pub zfar: Option<f32>,
}

/// Pitch stays inside ±89° so that the view never flips over the pole.
const PITCH_LIMIT: f32 = 1.553;

impl OrbitCamera {
    /// The orbit that reproduces `c` (without roll), looking at the point `distance` ahead.
    pub fn from_camera(c: &Camera, distance: f32) -> OrbitCamera {
        let back = c.transform.z_axis.truncate().normalize_or(Vec3::Z);
        OrbitCamera {
            target: c.position() - back * distance,
            distance,
            yaw: back.x.atan2(back.z),
            pitch: back
                .y
                .clamp(-1.0, 1.0)
                .asin()
                .clamp(-PITCH_LIMIT, PITCH_LIMIT),
            yfov: c.yfov,
            znear: c.znear,
            zfar: c.zfar,
        }
    }

    /// The orbit for a scene camera, its target at the depth of the scene's bounds centre.
    pub fn for_scene(c: &Camera, bounds: Option<(Vec3, Vec3)>) -> OrbitCamera {
        let forward = -c.transform.z_axis.truncate().normalize_or(Vec3::Z);
        let distance = bounds
            .map(|(lo, hi)| {
                let radius = (hi - lo).length() * 0.5;
                ((lo + hi) * 0.5 - c.position())
                    .dot(forward)
                    .max(0.1 * radius)
            })
            .unwrap_or(1.0)
            .max(1e-2);
        OrbitCamera::from_camera(c, distance)
    }

    /// Unit vector from the target to the eye.
    pub fn back(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(cp * sy, sp, cp * cy)
    }

    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// The scene camera of this orbit.
    pub fn camera(&self) -> Camera {
        let back = self.back();
        let right = Vec3::Y.cross(back).normalize_or(Vec3::X);
        let up = back.cross(right);
        Camera {
            name: "viewer".into(),
            transform: Mat4::from_cols(
                right.extend(0.0),
                up.extend(0.0),
                back.extend(0.0),
                self.eye().extend(1.0),
            ),
            yfov: self.yfov,
            znear: self.znear,
            zfar: self.zfar,
            lens: None,
        }
    }

    /// Turn around the target by a mouse drag of (dx, dy) pixels.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.005;
        self.pitch = (self.pitch + dy * 0.005).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Move towards (positive steps) or away from the target; the distance never reaches 0.
    pub fn dolly(&mut self, steps: f32) {
        self.distance = (self.distance * 0.85f32.powf(steps)).max(1e-3);
    }

    /// Move eye and target together by `local` = (right, up, forward) in the view's frame.
    pub fn translate(&mut self, local: Vec3) {
        let back = self.back();
        let right = Vec3::Y.cross(back).normalize_or(Vec3::X);
        let up = back.cross(right);
        self.target += right * local.x + up * local.y - back * local.z;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_camera_round_trips() {
        let eye = Vec3::new(1.0, 2.0, 5.0);
        let target = Vec3::new(0.0, 1.0, 0.0);
        let c = Camera::look_at("c", eye, target, Vec3::Y, 0.7);
        let o = OrbitCamera::from_camera(&c, eye.distance(target));
        assert!(o.target.distance(target) < 1e-5, "{:?}", o.target);
        assert!(o.eye().distance(eye) < 1e-5);
        let back = o.camera();
        for (a, b) in back
            .transform
            .to_cols_array()
            .iter()
            .zip(c.transform.to_cols_array())
        {
            assert!(
                (a - b).abs() < 1e-5,
                "{:?} vs {:?}",
                back.transform,
                c.transform
            );
        }
    }

    #[test]
    fn orbit_keeps_the_target_and_distance() {
        let c = Camera::look_at("c", Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 0.7);
        let mut o = OrbitCamera::from_camera(&c, 4.0);
        o.orbit(300.0, 2000.0);
        assert!(o.pitch <= PITCH_LIMIT);
        assert!((o.eye().distance(Vec3::ZERO) - 4.0).abs() < 1e-4);
        // The camera still looks at the target.
        let cam = o.camera();
        let fwd = -cam.transform.z_axis.truncate();
        assert!((fwd - (Vec3::ZERO - o.eye()).normalize()).length() < 1e-4);
        o.dolly(1.0);
        assert!((o.distance - 3.4).abs() < 1e-4);
        o.translate(Vec3::new(0.0, 0.0, 1.0));
        assert!((o.target - (-o.back())).length() < 1e-4);
    }
}
