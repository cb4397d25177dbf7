//! Moving objects in the viewer: the mirror-like objects (those that get dynamic environment
//! maps, `lightlab_gpu::raster::env_dynamic::dynamic_instances`) circle slowly around where
//! they stand, so that their reflections of each other, and their neighbours' shadows, can be
//! watched as they change (`--dynamic-env` updates the maps every `--dynamic-env-every`
//! frames).

use glam::{Mat4, Vec3};
use lightlab_gpu::GpuContext;
use lightlab_gpu::raster::Renderer;
use lightlab_scene::Scene;

/// Seconds per circle.
const PERIOD: f32 = 8.0;

/// The moving instances and the scene posed at the last time given.
pub struct Motion {
    scene: Scene,
    /// (instance, rest transform, circle radius, phase).
    movers: Vec<(usize, Mat4, f32, f32)>,
}

impl Motion {
    /// Motion for `scene`'s mirror-like objects; None when it has none.
    pub fn new(scene: &Scene) -> Option<Motion> {
        let ids = lightlab_gpu::raster::env_dynamic::dynamic_instances(scene);
        let movers: Vec<_> = ids
            .iter()
            .enumerate()
            .filter_map(|(k, &i)| {
                let (lo, hi) = scene.instance_bounds(i)?;
                let radius = 0.3 * (hi - lo).max_element();
                let phase = k as f32 * std::f32::consts::TAU / ids.len() as f32;
                Some((i, scene.instances[i].transform, radius, phase))
            })
            .collect();
        (!movers.is_empty()).then(|| Motion {
            scene: scene.clone(),
            movers,
        })
    }

    /// The offset of a mover at time `t` (seconds): zero at t = 0.
    fn offset(radius: f32, phase: f32, t: f32) -> Vec3 {
        let a = phase + t * std::f32::consts::TAU / PERIOD;
        radius * (Vec3::new(a.cos(), 0.0, a.sin()) - Vec3::new(phase.cos(), 0.0, phase.sin()))
    }

    /// Pose the movers at time `t` in `renderer`.
    pub fn apply(&mut self, ctx: &GpuContext, renderer: &mut Renderer, t: f32) {
        for &(i, rest, radius, phase) in &self.movers {
            self.scene.instances[i].transform =
                Mat4::from_translation(Self::offset(radius, phase, t)) * rest;
            renderer.move_instance(ctx, &self.scene, i);
        }
    }
}

/// Pose `motion`'s movers at `clock` in `renderer` (nothing before they first moved).
pub fn pose(motion: &mut Option<Motion>, clock: f32, ctx: &GpuContext, renderer: &mut Renderer) {
    if let Some(m) = motion
        && clock > 0.0
    {
        m.apply(ctx, renderer, clock);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spheres_mirrors_move_in_circles_from_where_they_stand() {
        let scene = lightlab_scene::builtin::builtin("spheres").unwrap();
        let m = Motion::new(&scene).expect("spheres has mirror-like objects");
        assert_eq!(m.movers.len(), 3);
        for &(_, _, r, phase) in &m.movers {
            assert!(Motion::offset(r, phase, 0.0).length() < 1e-6);
            let half = Motion::offset(r, phase, PERIOD / 2.0).length();
            assert!(
                (half - 2.0 * r).abs() < 1e-4 * r.max(1.0),
                "{half} vs {}",
                2.0 * r
            );
            assert!(Motion::offset(r, phase, PERIOD).length() < 1e-4);
        }
        assert!(Motion::new(&lightlab_scene::builtin::builtin("cornell").unwrap()).is_none());
    }
}
