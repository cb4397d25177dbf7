//! The lights of the path tracer: punctual (point, spot), the sun (a directional light with an
//! angular diameter, sampled as a cone), emissive triangles (area lights, chosen by power) and
//! the environment map (importance-sampled by luminance × sinθ).

use glam::{Vec2, Vec3};
use lightlab_core::color::luminance;
use lightlab_core::sampling::{
    Distribution1D, Distribution2D, Frame, uniform_cone_1mc, uniform_triangle,
};
use lightlab_scene::{Environment, LightKind, Scene};
use std::f32::consts::PI;

/// An emissive triangle in world space.
#[derive(Clone, Debug)]
pub struct EmitTri {
    pub p: [Vec3; 3],
    pub uv: [lightlab_scene::Attrs; 3],
    /// Unit normal of the authored (front) side.
    pub n: Vec3,
    pub area: f32,
    pub material: usize,
    pub double_sided: bool,
    /// The emitted radiance where it is uniform (no emissive texture), else None.
    pub uniform: Option<Vec3>,
}

/// Everything needed to sample and evaluate light in the scene.
pub struct LightSet {
    pub emitters: Vec<EmitTri>,
    emit_dist: Option<Distribution1D>,
    /// First emitter index of each instance (u32::MAX when the instance does not emit).
    instance_base: Vec<u32>,
    env_dist: Option<Distribution2D>,
}

/// A light sample for next-event estimation.
pub struct LightSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// Distance to the light (infinity for distant lights).
    pub dist: f32,
    /// Incident radiance (for area/environment) or irradiance-like value (for delta lights)
    /// already divided by the selection pdf; multiply by f·cosθ.
    pub value: Vec3,
    /// Solid-angle pdf for multiple importance sampling; 0 for delta lights.
    pub pdf: f32,
}

/// Emitted radiance of a material at `uv` (emissive texture applied).
pub fn emission(scene: &Scene, material: usize, uv: lightlab_scene::Attrs) -> Vec3 {
    let m = &scene.materials[material];
    let mut e = m.emission();
    if let Some(r) = m.emissive_texture {
        e *= scene.sample(r, uv).truncate();
    }
    e
}

impl LightSet {
    pub fn new(scene: &Scene) -> LightSet {
        let mut emitters = vec![];
        let mut instance_base = vec![u32::MAX; scene.instances.len()];
        for (ii, inst) in scene.instances.iter().enumerate() {
            let mesh = &scene.meshes[inst.mesh];
            let mat = &scene.materials[mesh.material];
            if !mat.is_emissive() {
                continue;
            }
            instance_base[ii] = emitters.len() as u32;
            for t in mesh.indices.chunks_exact(3) {
                let p = [t[0], t[1], t[2]]
                    .map(|i| inst.transform.transform_point3(mesh.positions[i as usize]));
                let c = (p[1] - p[0]).cross(p[2] - p[0]);
                emitters.push(EmitTri {
                    p,
                    uv: mesh.corners(t),
                    n: c.normalize_or_zero(),
                    area: 0.5 * c.length(),
                    material: mesh.material,
                    double_sided: mat.double_sided,
                    uniform: mat.emissive_texture.is_none().then(|| mat.emission()),
                });
            }
        }
        let emit_dist = (!emitters.is_empty()).then(|| {
            let w: Vec<f32> = emitters
                .iter()
                .map(|e| e.area * luminance(scene.materials[e.material].emission()).max(1e-6))
                .collect();
            Distribution1D::new(&w)
        });
        let env_dist = scene.environment.as_ref().map(|env| {
            let (w, h) = (env.image.width as usize, env.image.height as usize);
            let weights: Vec<f32> = (0..w * h)
                .map(|i| {
                    let y = i / w;
                    let sin = (PI * (y as f32 + 0.5) / h as f32).sin();
                    // A floor keeps every direction reachable (the pdf never vanishes).
                    (luminance(env.image.data[i]) + 1e-4) * sin
                })
                .collect();
            Distribution2D::new(&weights, w, h)
        });
        LightSet {
            emitters,
            emit_dist,
            instance_base,
            env_dist,
        }
    }

    pub fn has_emitters(&self) -> bool {
        self.emit_dist.is_some()
    }

    /// Index of the emitter for triangle `tri` of instance `instance`, if it emits.
    pub fn emitter_index(&self, instance: u32, tri: u32) -> Option<usize> {
        let b = self.instance_base[instance as usize];
        (b != u32::MAX).then(|| (b + tri) as usize)
    }

    /// Solid-angle pdf with which [`Self::sample_emitter`] picks the direction that hits
    /// emitter `idx` at distance `dist` with cosine `cos_l` at the light.
    pub fn emitter_pdf(&self, idx: usize, dist: f32, cos_l: f32) -> f32 {
        let Some(d) = &self.emit_dist else { return 0.0 };
        let e = &self.emitters[idx];
        if cos_l.abs() <= 1e-8 {
            return 0.0;
        }
        d.discrete_pdf(idx) / e.area * dist * dist / cos_l.abs()
    }

    /// Sample a point on the emissive triangles as seen from `p`.
    pub fn sample_emitter(
        &self,
        scene: &Scene,
        p: Vec3,
        u_sel: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        let d = self.emit_dist.as_ref()?;
        let (idx, p_sel) = d.sample_discrete(u_sel);
        let e = &self.emitters[idx];
        let b = uniform_triangle(u);
        let q = e.p[0] * (1.0 - b.x - b.y) + e.p[1] * b.x + e.p[2] * b.y;
        let to = q - p;
        let dist2 = to.length_squared();
        if dist2 <= 1e-16 {
            return None;
        }
        let dist = dist2.sqrt();
        // One division each for the direction and the value (a vector divided by a scalar is
        // three).
        let wi = to * (1.0 / dist);
        let cos_l = -wi.dot(e.n);
        if cos_l <= 0.0 && !e.double_sided {
            return None;
        }
        let le = e.uniform.unwrap_or_else(|| {
            let uv = lightlab_scene::Attrs::weighted(&e.uv, [1.0 - b.x - b.y, b.x, b.y]);
            emission(scene, e.material, uv)
        });
        let pdf = p_sel * dist2 / (e.area * cos_l.abs().max(1e-8));
        Some(LightSample {
            wi,
            dist,
            value: le * (1.0 / pdf),
            pdf,
        })
    }

    /// Sample the environment map.
    pub fn sample_env(&self, env: &Environment, u: Vec2) -> Option<LightSample> {
        let d = self.env_dist.as_ref()?;
        let (uv, pdf_uv) = d.sample(u);
        let (wi, sin) = lightlab_core::sh_env::latlong_uv_to_dir_sin(uv);
        if sin <= 0.0 || pdf_uv <= 0.0 {
            return None;
        }
        let pdf = pdf_uv / (2.0 * PI * PI * sin);
        Some(LightSample {
            wi,
            dist: f32::INFINITY,
            // The sampled texel itself (no round trip through the direction).
            value: env.radiance_uv(uv) / pdf,
            pdf,
        })
    }

    /// Solid-angle pdf of [`Self::sample_env`] for direction `wi`.
    pub fn env_pdf(&self, wi: Vec3) -> f32 {
        self.env_pdf_uv(Environment::dir_to_uv(wi))
    }

    fn env_pdf_uv(&self, uv: Vec2) -> f32 {
        let Some(d) = &self.env_dist else { return 0.0 };
        let sin = (uv.y * PI).sin();
        if sin <= 0.0 {
            return 0.0;
        }
        d.pdf(uv) / (2.0 * PI * PI * sin)
    }

    /// The environment's radiance along `wi` and [`Self::env_pdf`] of `wi`, from one
    /// direction-to-uv conversion (a path that escapes needs both).
    pub fn env_lookup(&self, env: &Environment, wi: Vec3) -> (Vec3, f32) {
        let uv = Environment::dir_to_uv(wi);
        (env.radiance_uv(uv), self.env_pdf_uv(uv))
    }
}

/// Sample punctual light `i` (point, spot or sun) from point `p`. Delta lights have pdf 0 (no
/// MIS); the sun with a non-zero angular diameter is a uniform cone of radiance
/// E/(π·sin²α), α its angular radius, which gives irradiance E at normal incidence.
pub fn sample_punctual(scene: &Scene, i: usize, p: Vec3, u: Vec2) -> Option<LightSample> {
    let l = &scene.lights[i];
    match &l.kind {
        LightKind::Point | LightKind::Spot { .. } | LightKind::Goniometric { .. } => {
            let to = l.position - p;
            let dist2 = to.length_squared();
            if dist2 <= 1e-16 {
                return None;
            }
            let dist = dist2.sqrt();
            if let Some(r) = l.range
                && dist > r
            {
                return None;
            }
            let wi = to / dist;
            let spot = l.emission(-wi);
            if spot <= 0.0 {
                return None;
            }
            Some(LightSample {
                wi,
                dist,
                value: l.color * l.intensity * spot / dist2,
                pdf: 0.0,
            })
        }
        LightKind::Directional { angular_diameter } => {
            let to_sun = -l.direction;
            let half = angular_diameter * 0.5;
            if half <= 0.0 {
                return Some(LightSample {
                    wi: to_sun,
                    dist: f32::INFINITY,
                    value: l.color * l.intensity,
                    pdf: 0.0,
                });
            }
            // 1 − cos α = 2 sin²(α/2), exact in f32 even for the sun's 1e-5.
            let one_minus_cos = 2.0 * (half * 0.5).sin().powi(2);
            let local = uniform_cone_1mc(u, one_minus_cos);
            let wi = Frame::from_normal(to_sun).to_world(local);
            // radiance / pdf = E/(π sin²α) · 2π(1 − cos α) = E / cos²(α/2)
            let value = l.color * l.intensity / (half * 0.5).cos().powi(2);
            Some(LightSample {
                wi,
                dist: f32::INFINITY,
                value,
                pdf: 0.0,
            })
        }
    }
}
