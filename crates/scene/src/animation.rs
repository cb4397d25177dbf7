//! Rigid animation of instances: what moves in the `prt-dynamic` scene and what `--frame K`
//! poses, in the path tracer and in every technique alike.
//!
//! A [`Track`] moves one instance rigidly: at time t its world transform is `M(t) · rest`,
//! with `rest` the instance's transform as loaded (the pose its bakes see) and `M(t)` a
//! rotation then a translation interpolated between keys (linear and spherical-linear, held
//! before the first key and after the last). Frame K is time (K mod frames) / fps.

use crate::Scene;
use glam::{Mat4, Quat, Vec3};

/// The scene's animation.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Frames per second (frame K is time K / fps).
    pub fps: f32,
    /// Frames in one loop of the animation (what `lightlab view` plays).
    pub frames: u32,
    pub tracks: Vec<Track>,
}

/// The rigid motion of one instance.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub instance: usize,
    /// Key times in seconds, increasing.
    pub times: Vec<f32>,
    pub translations: Vec<Vec3>,
    pub rotations: Vec<Quat>,
}

impl Track {
    /// The motion M(t).
    pub fn motion(&self, t: f32) -> Mat4 {
        let n = self.times.len();
        let (a, b, f) = if n == 0 {
            return Mat4::IDENTITY;
        } else if t <= self.times[0] {
            (0, 0, 0.0)
        } else if t >= self.times[n - 1] {
            (n - 1, n - 1, 0.0)
        } else {
            let b = self.times.partition_point(|&k| k <= t);
            let a = b - 1;
            (a, b, (t - self.times[a]) / (self.times[b] - self.times[a]))
        };
        let tr = self.translations[a].lerp(self.translations[b], f);
        let rot = self.rotations[a].slerp(self.rotations[b], f).normalize();
        Mat4::from_rotation_translation(rot, tr)
    }
}

impl Animation {
    /// Time of frame `k` in seconds; frames wrap round the loop of `frames`.
    pub fn time(&self, frame: u32) -> f32 {
        (frame % self.frames.max(1)) as f32 / self.fps
    }

    /// Whether instance `i` moves.
    pub fn moves(&self, i: usize) -> bool {
        self.tracks.iter().any(|t| t.instance == i)
    }

    /// The refusal of a malformed animation, naming the track and the problem.
    pub fn check(&self, instances: usize) -> Result<(), String> {
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(format!(
                "frames per second must be positive, not {}",
                self.fps
            ));
        }
        let mut seen = vec![false; instances];
        for (k, t) in self.tracks.iter().enumerate() {
            let what = format!("track {k}");
            if t.instance >= instances {
                return Err(format!(
                    "{what} moves instance {}, of {instances}",
                    t.instance
                ));
            }
            if std::mem::replace(&mut seen[t.instance], true) {
                return Err(format!("{what}: instance {} has two tracks", t.instance));
            }
            if t.times.is_empty()
                || t.translations.len() != t.times.len()
                || t.rotations.len() != t.times.len()
            {
                return Err(format!(
                    "{what} needs as many translations and rotations as key times (at least one)"
                ));
            }
            if t.times
                .windows(2)
                .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
                || t.times.iter().any(|x| !x.is_finite())
            {
                return Err(format!("{what}: key times must be finite and increasing"));
            }
            if t.translations.iter().any(|v| !v.is_finite())
                || t.rotations
                    .iter()
                    .any(|q| !q.is_finite() || q.length() < 1e-6)
            {
                return Err(format!(
                    "{what}: a key is not a finite translation or rotation"
                ));
            }
        }
        Ok(())
    }
}

impl Scene {
    /// The scene posed at frame `k` of its animation (the scene itself without one).
    pub fn posed(&self, frame: u32) -> Scene {
        let mut s = self.clone();
        s.pose(frame);
        s
    }

    /// Pose the instances at frame `k` (from their rest transforms, which this replaces:
    /// pose a clone of the rest scene, as [`Scene::posed`] does).
    pub fn pose(&mut self, frame: u32) {
        let Some(a) = &self.animation else { return };
        let t = a.time(frame);
        for tr in &a.tracks {
            let rest = self.instances[tr.instance].transform;
            self.instances[tr.instance].transform = tr.motion(t) * rest;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track() -> Track {
        Track {
            instance: 0,
            times: vec![0.0, 1.0],
            translations: vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)],
            rotations: vec![
                Quat::IDENTITY,
                Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            ],
        }
    }

    #[test]
    fn keys_interpolate_and_hold() {
        let t = track();
        let mid = t.motion(0.5);
        assert!(mid.transform_point3(Vec3::ZERO).abs_diff_eq(Vec3::X, 1e-6));
        let (_, r, _) = mid.to_scale_rotation_translation();
        assert!((r.angle_between(Quat::IDENTITY) - std::f32::consts::FRAC_PI_4).abs() < 1e-5);
        assert_eq!(t.motion(-1.0), Mat4::IDENTITY);
        assert_eq!(t.motion(5.0), t.motion(1.0));
    }

    #[test]
    fn malformed_tracks_are_refused() {
        let ok = Animation {
            fps: 24.0,
            frames: 24,
            tracks: vec![track()],
        };
        assert!(ok.check(1).is_ok());
        assert!(ok.check(0).unwrap_err().contains("instance 0"));
        let mut bad = ok.clone();
        bad.tracks[0].times = vec![1.0, 0.0];
        assert!(bad.check(1).unwrap_err().contains("increasing"));
        let mut bad = ok.clone();
        bad.tracks[0].rotations.pop();
        assert!(bad.check(1).unwrap_err().contains("as many"));
        let mut bad = ok.clone();
        bad.fps = 0.0;
        assert!(bad.check(1).is_err());
        let mut bad = ok;
        bad.tracks.push(track());
        assert!(bad.check(1).unwrap_err().contains("two tracks"));
        // Validation refuses it as it refuses any bad content.
        let mut s = crate::builtin::builtin("prt-dynamic").unwrap();
        s.animation.as_mut().unwrap().tracks[0].instance = 10_000;
        let e = crate::validate::validate(&mut s, "d".as_ref(), Default::default()).unwrap_err();
        assert!(e.to_string().contains("animation"), "{e}");
    }
}
