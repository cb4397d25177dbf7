//! Luminaires: lamp geometry (instances marked `luminaire`, glTF `extras.lightlab.luminaire`)
//! whose light reaches the rest of the scene through a window in front of it (Heidrich 1999
//! ch. 7).
//!
//! - **The window** of a luminaire: its first instance's local +Z is the direction it emits
//!   into, its local X the window's u axis; the window covers the luminaire's geometry across
//!   that axis (2 % margin) just in front of it. All of a lamp's light must leave forwards
//!   through it: a reflector lamp, a projector, a recessed fitting.
//! - **[`LampEmitter`]**: the luminaire's real geometry as a light of the path tracer: a
//!   point P uniform on the window, the radiance leaving the lamp through P towards x traced in
//!   a scene of the luminaire alone (reflectors, lenses and the emitter, every bounce). This is
//!   the reference a canned light is measured against: it reaches light that only specular
//!   paths inside the lamp carry, which paths from the room almost never find.
//! - **[`bake_slab`]**: the lamp's light slab (`bake --method light-field`): from each (u,v)
//!   grid point, the radiance leaving through it towards each (s,t) sample (jittered within
//!   the (s,t) cell), traced the same way.
//! - **[`split`]**: a scene without its luminaires' geometry, and the luminaires.

use crate::Accel;
use crate::lights::LightSet;
use crate::render::{PathTracer, RenderSettings, WindowEmitter};
use glam::{Vec2, Vec3};
use lightlab_core::light_slab::{Far, LightSlab};
use lightlab_core::sampling::Rng;
use lightlab_scene::Scene;
use rayon::prelude::*;
use std::sync::Arc;

/// A luminaire's window: where its light leaves, along `u × v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    pub centre: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub half: Vec2,
}

impl Window {
    pub fn normal(&self) -> Vec3 {
        self.u.cross(self.v)
    }

    pub fn area(&self) -> f32 {
        4.0 * self.half.x * self.half.y
    }

    /// The point of window coordinates `c` ∈ [−1, 1]².
    pub fn point(&self, c: Vec2) -> Vec3 {
        self.centre + self.u * (c.x * self.half.x) + self.v * (c.y * self.half.y)
    }
}

/// The names of the scene's luminaires, in order of first appearance.
pub fn names(scene: &Scene) -> Vec<String> {
    let mut out: Vec<String> = vec![];
    for i in &scene.instances {
        if let Some(l) = &i.luminaire
            && !out.contains(l)
        {
            out.push(l.clone());
        }
    }
    out
}

/// The scene of luminaire `name` alone: its instances, the scene's meshes and materials, no
/// lights and no environment.
pub fn lamp_scene(scene: &Scene, name: &str) -> Scene {
    let mut s = scene.clone();
    s.instances.retain(|i| i.luminaire.as_deref() == Some(name));
    s.lights.clear();
    s.environment = None;
    s.animation = None;
    s
}

/// `scene` without the geometry of any luminaire.
pub fn without_luminaires(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.instances.retain(|i| i.luminaire.is_none());
    s.animation = None;
    s
}

/// `scene` without the geometry of the luminaires `names` (the others stay).
pub fn without(scene: &Scene, names: &[&str]) -> Scene {
    let mut s = scene.clone();
    s.instances
        .retain(|i| !i.luminaire.as_deref().is_some_and(|l| names.contains(&l)));
    s.animation = None;
    s
}

/// Where luminaire `name`'s (s,t) window belongs by default: the plane through its focus
/// (`Scene::luminaire_focus`, measured from its first instance's origin; here from its
/// window), or infinity for a lamp without one.
pub fn default_far(scene: &Scene, name: &str, window: &Window) -> Far {
    let origin = scene
        .instances
        .iter()
        .find(|i| i.luminaire.as_deref() == Some(name))
        .map(|i| i.transform.w_axis.truncate())
        .unwrap_or(window.centre);
    match scene.luminaire_focus.get(name) {
        Some(&focus) => {
            let d = focus - (window.centre - origin).dot(window.normal());
            if d > 1e-3 {
                Far::Plane(d)
            } else {
                Far::Infinity
            }
        }
        None => Far::Infinity,
    }
}

/// The window of luminaire `name` (None when it has no geometry).
pub fn window(scene: &Scene, name: &str) -> Option<Window> {
    let first = scene
        .instances
        .iter()
        .find(|i| i.luminaire.as_deref() == Some(name))?;
    let m = first.transform;
    let u = m.x_axis.truncate().normalize_or(Vec3::X);
    let v0 = m.y_axis.truncate();
    let v = (v0 - u * v0.dot(u)).normalize_or(u.any_orthonormal_vector());
    let n = u.cross(v);
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for inst in scene
        .instances
        .iter()
        .filter(|i| i.luminaire.as_deref() == Some(name))
    {
        for p in &scene.meshes[inst.mesh].positions {
            let w = inst.transform.transform_point3(*p);
            let q = Vec3::new(w.dot(u), w.dot(v), w.dot(n));
            lo = lo.min(q);
            hi = hi.max(q);
        }
    }
    if lo.x > hi.x {
        return None;
    }
    let size = (hi - lo).max_element().max(1e-4);
    let mid = (lo + hi) * 0.5;
    let half = Vec2::new(hi.x - lo.x, hi.y - lo.y) * 0.51 + Vec2::splat(1e-4 * size);
    let centre = u * mid.x + v * mid.y + n * (hi.z + 1e-3 * size);
    Some(Window { centre, u, v, half })
}

/// A luminaire's real geometry as a light of the path tracer, seen through its window.
pub struct LampEmitter {
    pub name: String,
    pub window: Window,
    scene: Scene,
    accel: Accel,
    lights: Arc<LightSet>,
    settings: RenderSettings,
}

impl LampEmitter {
    /// Luminaire `name` of `scene` (None when it has no geometry); paths inside it scatter at
    /// most `max_depth` times.
    pub fn new(scene: &Scene, name: &str, max_depth: u32) -> Option<LampEmitter> {
        let window = window(scene, name)?;
        let scene = lamp_scene(scene, name);
        let accel = Accel::new(&scene);
        let lights = Arc::new(LightSet::new(&scene));
        Some(LampEmitter {
            name: name.into(),
            window,
            scene,
            accel,
            lights,
            settings: RenderSettings {
                max_depth,
                ..Default::default()
            },
        })
    }

    fn tracer(&self) -> PathTracer<'_> {
        PathTracer {
            scene: &self.scene,
            accel: &self.accel,
            lights: self.lights.clone(),
            light_use: vec![],
            windows: vec![],
        }
    }

    /// Radiance leaving the lamp through window point `p` along unit `d` (forwards).
    pub fn radiance_through(&self, p: Vec3, d: Vec3, rng: &mut Rng) -> Vec3 {
        self.tracer().radiance(p, -d, &self.settings, rng)
    }
}

impl WindowEmitter for LampEmitter {
    fn sample(&self, x: Vec3, rng: &mut Rng) -> Option<(Vec3, Vec3)> {
        let w = &self.window;
        let u = rng.next_vec2();
        let p = w.point(u * 2.0 - Vec2::ONE);
        let r = x - p;
        let r2 = r.length_squared();
        if r2 <= 1e-12 {
            return None;
        }
        let d = r / r2.sqrt();
        let cos = d.dot(w.normal());
        if cos <= 0.0 {
            return None;
        }
        let l = self.radiance_through(p, d, rng);
        Some((p, l * (cos * w.area() / r2)))
    }
}

/// The half-size of the (s,t) window `far` that holds the lamp's beam: a probe of 8 × 8
/// window points × 4096 directions over the forward hemisphere (cosine-distributed, so each
/// ray's radiance is its share of the flux); per axis, the extent on the (s,t) window (slopes
/// at infinity, at most 8; metres on a plane) that holds 98 % of the flux, with a 5 %
/// margin. Stray light (the housing's glow, reflections in a lens) is left out. None when no probe ray carries light.
pub fn fit_far_half(lamp: &LampEmitter, far: Far, seed: u64) -> Option<Vec2> {
    const POINTS: usize = 8;
    const RAYS: usize = 4096;
    let w = lamp.window;
    let n = w.normal();
    let hits: Vec<(Vec2, f32)> = (0..POINTS * POINTS)
        .into_par_iter()
        .flat_map_iter(|g| {
            let mut rng = Rng::new(seed ^ 0x05ee_df17, g as u64);
            let c = Vec2::new((g / POINTS) as f32, (g % POINTS) as f32);
            let p = w.point((c + 0.5) / POINTS as f32 * 2.0 - Vec2::ONE);
            (0..RAYS)
                .map(|_| {
                    let e = rng.next_vec2();
                    let (r, phi) = (e.x.sqrt(), e.y * std::f32::consts::TAU);
                    let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - e.x).sqrt());
                    let d = w.u * local.x + w.v * local.y + n * local.z.max(1e-4);
                    let l = lamp.radiance_through(p, d, &mut rng);
                    let dn = d.dot(n);
                    let st = match far {
                        Far::Infinity => Vec2::new(d.dot(w.u), d.dot(w.v)) / dn,
                        Far::Plane(dist) => {
                            let q = p + d * (dist / dn) - (w.centre + n * dist);
                            Vec2::new(q.dot(w.u), q.dot(w.v))
                        }
                    };
                    (st, l.max_element())
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let total: f32 = hits.iter().map(|h| h.1).sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    // Per axis, the smallest |coordinate| that holds 98 % of the probe's flux.
    let quantile = |axis: usize| {
        let mut v: Vec<(f32, f32)> = hits.iter().map(|h| (h.0[axis].abs(), h.1)).collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut sum = 0.0;
        for (x, l) in &v {
            sum += l;
            if sum >= 0.98 * total {
                return *x;
            }
        }
        v.last().map_or(0.0, |h| h.0)
    };
    let extent = Vec2::new(quantile(0), quantile(1));
    let fitted = extent * 1.05;
    Some(match far {
        // Slopes beyond 8 (83° off the axis) are left out: they would spread the samples thin.
        Far::Infinity => fitted.min(Vec2::splat(8.0)),
        Far::Plane(_) => fitted,
    })
}

/// The light slab of a lamp: `n_uv` grid points on its window, `n_st` samples over the
/// (s,t) window `far_half` (slopes at infinity, metres on a far plane), `spp` paths per
/// sample jittered over its (s,t) cell.
pub fn bake_slab(
    lamp: &LampEmitter,
    n_uv: [usize; 2],
    far: Far,
    far_half: Vec2,
    n_st: [usize; 2],
    spp: u32,
    seed: u64,
) -> LightSlab {
    let w = lamp.window;
    let mut slab = LightSlab::black(w.centre, w.u, w.v, w.half, n_uv, far, far_half, n_st);
    slab.luminaire = Some(lamp.name.clone());
    let per_point: Vec<Vec<Vec3>> = (0..n_uv[0] * n_uv[1])
        .into_par_iter()
        .map(|g| {
            let (iu, iv) = (g / n_uv[1], g % n_uv[1]);
            let p = slab.uv_point(iu, iv);
            let mut rng = Rng::new(seed, g as u64);
            let mut out = Vec::with_capacity(n_st[0] * n_st[1]);
            for is in 0..n_st[0] {
                for it in 0..n_st[1] {
                    let mut sum = Vec3::ZERO;
                    for _ in 0..spp {
                        let j = rng.next_vec2();
                        let st = Vec2::new(
                            (is as f32 + j.x) / n_st[0] as f32 * 2.0 - 1.0,
                            (it as f32 + j.y) / n_st[1] as f32 * 2.0 - 1.0,
                        );
                        let d = slab.ray_direction(p, st).normalize();
                        sum += lamp.radiance_through(p, d, &mut rng);
                    }
                    out.push(sum / spp.max(1) as f32);
                }
            }
            out
        })
        .collect();
    for (g, values) in per_point.into_iter().enumerate() {
        let (iu, iv) = (g / n_uv[1], g % n_uv[1]);
        for (k, l) in values.into_iter().enumerate() {
            slab.set(iu, iv, k / n_st[1], k % n_st[1], l);
        }
    }
    slab
}

/// `scene` ready for the path tracer: without its luminaires' geometry, and each luminaire as
/// a [`LampEmitter`] (paths inside a lamp scatter at most `max_depth` times).
pub fn prepare(scene: &Scene, max_depth: u32) -> (Scene, Vec<Arc<dyn WindowEmitter>>) {
    let lamps = names(scene)
        .iter()
        .filter_map(|n| LampEmitter::new(scene, n, max_depth))
        .map(|l| Arc::new(l) as Arc<dyn WindowEmitter>)
        .collect();
    (without_luminaires(scene), lamps)
}
