//! Run-time SH lighting of the PRT techniques (Fuchs 2005 §5.5's "SH light source"; McKenzie
//! Chapter 2010 §4.3.3–4.3.5): the scene's dynamic lights projected on SH each frame at a few
//! *incident-light sample points*, rotated into an object's frame when the object has turned
//! since its transfer was baked, and windowed against ringing.
//!
//! **What is projected.** Incident radiance L(ω) = Σ lᵢ Yᵢ(ω) at a sample point q, RGB:
//! - the environment map (× its intensity), projected by exact texel solid angles;
//! - point and spot lights as delta lights from q: lᵢ = E·Yᵢ(ω_q), E = I·spot/d² (the
//!   irradiance at normal incidence, cut at the glTF range) — McKenzie's π·Yᵢ lobe with the
//!   colour, intensity and distance fall-off his listing leaves out;
//! - directional lights: a delta (zero angular diameter) or a uniform disc of radiance
//!   E/(π·sin²α) (the path tracer's sun), projected exactly (`sh::project_disc`).
//!
//! **Sample points** (McKenzie §4.3.3): one point for the whole scene (distant light, as Fuchs's
//! SHL), or the six centres of an object's bounding-box faces ("both extremes of x, y and z").
//! A shading point blends the points' lighting with weights ∝ 1/distance normalised to sum 1
//! (§4.3.4 with its printed ratio inverted, as the text intends; Euclidean distance, where the
//! thesis leaves "surface distance" open). The weights are evaluated per fragment, not stored
//! per vertex.
//!
//! **Windowing**: `sh::Window` (Hann or Lanczos σ-factors) on the light before the dot product.
//! Windowing the light is the same as windowing the product's transfer side for the diffuse
//! dot product, and keeps the transfer data untouched.

use glam::{DMat3, DVec3, Vec3};
use lightlab_core::sh::{self, Window};
use lightlab_scene::{LightKind, Scene};

/// Where incident light is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplePoints {
    /// One point at the centre of the scene's bounds (distant lighting, Fuchs's SHL).
    Scene,
    /// Six points per instance: its bounding-box face centres (McKenzie §4.3.3).
    PerObject,
}

/// Settings of the run-time projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShLightSettings {
    pub bands: usize,
    pub points: SamplePoints,
    pub window: Window,
    /// Include the environment map.
    pub environment: bool,
    /// Include the punctual lights.
    pub punctual: bool,
}

impl Default for ShLightSettings {
    fn default() -> Self {
        ShLightSettings {
            bands: 4,
            points: SamplePoints::Scene,
            window: Window::None,
            environment: true,
            punctual: true,
        }
    }
}

/// The environment's radiance projected on `bands` bands (zero without an environment).
pub fn project_environment(scene: &Scene, bands: usize) -> Vec<DVec3> {
    match &scene.environment {
        Some(env) => lightlab_core::sh_env::project_env(
            &env.image,
            lightlab_core::sh_env::EnvFormat::LatLong,
            bands,
        )
        .into_iter()
        .map(|c| c * env.intensity as f64)
        .collect(),
        None => vec![DVec3::ZERO; sh::num_coeffs(bands)],
    }
}

/// Incident radiance from the scene's punctual lights at `q`, projected on `bands` bands.
pub fn project_punctual(scene: &Scene, bands: usize, q: Vec3) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; sh::num_coeffs(bands)];
    for l in &scene.lights {
        let rgb = (l.color * l.intensity).as_dvec3();
        let (coeffs, e) = match l.kind {
            LightKind::Point | LightKind::Spot { .. } | LightKind::Goniometric { .. } => {
                let to = l.position - q;
                let d2 = to.length_squared();
                if d2 <= 1e-12 || l.range.is_some_and(|r| d2 > r * r) {
                    continue;
                }
                let wi = to / d2.sqrt();
                let spot = l.emission(-wi);
                if spot <= 0.0 {
                    continue;
                }
                (sh::eval(bands, wi.as_dvec3()), rgb * (spot / d2) as f64)
            }
            LightKind::Directional { angular_diameter } => {
                let to_sun = (-l.direction).as_dvec3();
                let alpha = 0.5 * angular_diameter as f64;
                if alpha <= 0.0 {
                    (sh::eval(bands, to_sun), rgb)
                } else {
                    // Radiance E/(π sin²α) over the disc gives irradiance E at normal incidence
                    // (up to the disc's own cosine weighting, as the tracer's sun).
                    let radiance = 1.0 / (std::f64::consts::PI * alpha.sin().powi(2));
                    (sh::project_disc(bands, to_sun, alpha, radiance), rgb)
                }
            }
        };
        for (o, c) in out.iter_mut().zip(coeffs) {
            *o += e * c;
        }
    }
    out
}

/// The centres of the six faces of a bounding box.
pub fn box_face_centres(lo: Vec3, hi: Vec3) -> Vec<Vec3> {
    let c = 0.5 * (lo + hi);
    let mut out = vec![];
    for axis in 0..3 {
        for end in [lo, hi] {
            let mut p = c;
            p[axis] = end[axis];
            out.push(p);
        }
    }
    out
}

/// Blend weights of `points` for a shading point `p`: ∝ 1/distance, summing to 1 (a point
/// within 1 µm of `p` takes all the weight).
pub fn point_weights(points: &[Vec3], p: Vec3, out: &mut [f32]) {
    let mut total = 0.0;
    for (o, q) in out.iter_mut().zip(points) {
        *o = 1.0 / (p - *q).length().max(1e-6);
        total += *o;
    }
    for o in out.iter_mut() {
        *o /= total;
    }
}

/// One frame's SH lighting: per group (the scene, or each instance) its sample points and the
/// light projected at each.
#[derive(Clone, Debug)]
pub struct ShLighting {
    pub bands: usize,
    /// Per group, the sample points.
    pub points: Vec<Vec<Vec3>>,
    /// Per group, per sample point, the (windowed, rotated) incident radiance coefficients.
    pub coeffs: Vec<Vec<Vec<DVec3>>>,
    /// Group of each instance (all 0 with `SamplePoints::Scene`).
    pub group: Vec<usize>,
}

/// Per-frame projection with the static part (the environment map) projected once.
#[derive(Clone, Debug)]
pub struct ShProjector {
    pub settings: ShLightSettings,
    env: Vec<DVec3>,
}

impl ShProjector {
    pub fn new(scene: &Scene, s: &ShLightSettings) -> ShProjector {
        let env = if s.environment {
            project_environment(scene, s.bands)
        } else {
            vec![DVec3::ZERO; sh::num_coeffs(s.bands)]
        };
        ShProjector { settings: *s, env }
    }

    /// This frame's lighting (the scene's current lights and object rotations).
    pub fn project(&self, scene: &Scene, rotations: Option<&[DMat3]>) -> ShLighting {
        ShLighting::with_environment(scene, &self.settings, &self.env, rotations)
    }
}

impl ShLighting {
    /// Project the scene's lights for this frame. `rotations[i]`, when given, is the rotation of
    /// instance i since its transfer was baked: its light is turned into the baked frame.
    pub fn new(scene: &Scene, s: &ShLightSettings, rotations: Option<&[DMat3]>) -> ShLighting {
        ShProjector::new(scene, s).project(scene, rotations)
    }

    fn with_environment(
        scene: &Scene,
        s: &ShLightSettings,
        env: &[DVec3],
        rotations: Option<&[DMat3]>,
    ) -> ShLighting {
        let project = |q: Vec3| -> Vec<DVec3> {
            let mut c = env.to_vec();
            if s.punctual {
                for (o, p) in c.iter_mut().zip(project_punctual(scene, s.bands, q)) {
                    *o += p;
                }
            }
            s.window.apply(&mut c);
            c
        };
        let (points, group): (Vec<Vec<Vec3>>, Vec<usize>) = match s.points {
            SamplePoints::Scene => {
                let (lo, hi) = scene.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
                (vec![vec![0.5 * (lo + hi)]], vec![0; scene.instances.len()])
            }
            SamplePoints::PerObject => (
                (0..scene.instances.len())
                    .map(|i| {
                        let (lo, hi) = scene.instance_bounds(i).unwrap_or_default();
                        box_face_centres(lo, hi)
                    })
                    .collect(),
                (0..scene.instances.len()).collect(),
            ),
        };
        let mut coeffs: Vec<Vec<Vec<DVec3>>> = points
            .iter()
            .map(|ps| ps.iter().map(|q| project(*q)).collect())
            .collect();
        // A per-object group turns its own light; the scene group cannot turn per object.
        if let (Some(rot), SamplePoints::PerObject) = (rotations, s.points) {
            for (c, r) in coeffs.iter_mut().zip(rot) {
                // The object turned by R: its baked frame sees the world turned by R⁻¹.
                let rs = sh::Rotation::new(s.bands, r.transpose());
                for pc in c.iter_mut() {
                    *pc = rs.apply(pc);
                }
            }
        }
        ShLighting {
            bands: s.bands,
            points,
            coeffs,
            group,
        }
    }

    /// One light for everything (a single sample point far away: no blending).
    pub fn uniform(coeffs: Vec<DVec3>, instances: usize) -> ShLighting {
        ShLighting {
            bands: sh::bands_of(coeffs.len()),
            points: vec![vec![Vec3::ZERO]],
            coeffs: vec![vec![coeffs]],
            group: vec![0; instances],
        }
    }

    /// Sample points (group-major) and their coefficients (group, point, coefficient), flat
    /// and in f32: the GPU renderer's `set_sh_light` input.
    pub fn flattened(&self) -> (Vec<Vec3>, Vec<Vec3>) {
        let points = self.points.iter().flatten().copied().collect();
        let coeffs = self
            .coeffs
            .iter()
            .flatten()
            .flatten()
            .map(|c| c.as_vec3())
            .collect();
        (points, coeffs)
    }

    /// The incident radiance coefficients at `p` on instance `instance` (sample points blended).
    pub fn at(&self, instance: usize, p: Vec3) -> Vec<DVec3> {
        let g = self.group.get(instance).copied().unwrap_or(0);
        let pts = &self.points[g];
        let mut w = vec![0.0f32; pts.len()];
        point_weights(pts, p, &mut w);
        let mut out = vec![DVec3::ZERO; sh::num_coeffs(self.bands)];
        for (wk, c) in w.iter().zip(&self.coeffs[g]) {
            for (o, v) in out.iter_mut().zip(c) {
                *o += *v * *wk as f64;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;
    use lightlab_scene::{Instance, Light, Mesh};

    fn one_triangle_scene(lights: Vec<Light>) -> Scene {
        let mesh = Mesh {
            name: "tri".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Z],
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        Scene {
            name: "t".into(),
            meshes: vec![mesh],
            materials: vec![lightlab_scene::Material::diffuse("m", Vec3::ONE)],
            textures: vec![],
            instances: vec![Instance {
                name: "i".into(),
                mesh: 0,
                transform: Mat4::IDENTITY,
                nodes: vec![],
                luminaire: None,
            }],
            lights,
            environment: None,
            cameras: vec![],
            warnings: vec![],
            animation: None,
            luminaire_focus: Default::default(),
        }
    }

    fn light(kind: LightKind, position: Vec3, direction: Vec3, intensity: f32) -> Light {
        Light {
            name: "l".into(),
            kind,
            color: Vec3::new(1.0, 0.5, 0.25),
            intensity,
            position,
            direction,
            range: None,
        }
    }

    #[test]
    fn point_light_is_a_delta_of_its_irradiance() {
        let s = one_triangle_scene(vec![light(
            LightKind::Point,
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::NEG_Y,
            8.0,
        )]);
        let c = project_punctual(&s, 4, Vec3::ZERO);
        let y = sh::eval(4, DVec3::Y);
        for (ci, yi) in c.iter().zip(&y) {
            // E = 8/2² = 2, times the colour.
            let want = DVec3::new(1.0, 0.5, 0.25) * 2.0 * *yi;
            assert!((*ci - want).length() < 1e-6, "{ci} vs {want}");
        }
        // Out of range: nothing.
        let mut s2 = s.clone();
        s2.lights[0].range = Some(1.5);
        assert!(
            project_punctual(&s2, 4, Vec3::ZERO)
                .iter()
                .all(|c| *c == DVec3::ZERO)
        );
    }

    #[test]
    fn sun_disc_has_the_irradiance_of_the_delta() {
        // A small disc and a delta from the same direction give nearly the same low-band light.
        let d = Vec3::new(0.3, -1.0, 0.2).normalize();
        let disc = one_triangle_scene(vec![light(
            LightKind::Directional {
                angular_diameter: 0.0093,
            },
            Vec3::ZERO,
            d,
            3.0,
        )]);
        let mut delta = disc.clone();
        delta.lights[0].kind = LightKind::Directional {
            angular_diameter: 0.0,
        };
        let a = project_punctual(&disc, 5, Vec3::ZERO);
        let b = project_punctual(&delta, 5, Vec3::ZERO);
        for (x, y) in a.iter().zip(&b) {
            assert!((*x - *y).length() < 1e-3 * b[0].length(), "{x} vs {y}");
        }
    }

    #[test]
    fn weights_favour_the_nearest_point_and_sum_to_one() {
        let pts = box_face_centres(Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut w = [0.0f32; 6];
        point_weights(&pts, Vec3::ZERO, &mut w);
        assert!(w.iter().all(|x| (x - 1.0 / 6.0).abs() < 1e-6), "{w:?}");
        point_weights(&pts, Vec3::new(0.999, 0.0, 0.0), &mut w);
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!(w[1] > 0.9, "{w:?}");
    }

    #[test]
    fn a_turned_object_sees_its_light_in_the_baked_frame() {
        // Transfer baked facing +x (unshadowed clamped cosine / π); the object has since turned
        // 90° about z, so it faces +y, where the light now comes from: it must be fully lit, as
        // an unturned object facing a light from +x.
        let bands = 4;
        let zonal: Vec<f64> = sh::clamped_cosine_zonal(bands)
            .into_iter()
            .map(|z| z / std::f64::consts::PI)
            .collect();
        let t: Vec<f32> = sh::zonal_to_axis(&zonal, DVec3::X)
            .iter()
            .map(|v| *v as f32)
            .collect();
        let lit = |dir: Vec3, rot: Option<DMat3>| {
            let s = one_triangle_scene(vec![light(
                LightKind::Directional {
                    angular_diameter: 0.0,
                },
                Vec3::ZERO,
                -dir,
                1.0,
            )]);
            let settings = ShLightSettings {
                bands,
                points: SamplePoints::PerObject,
                ..Default::default()
            };
            let rots = rot.map(|r| vec![r]);
            let l = ShLighting::new(&s, &settings, rots.as_deref());
            crate::prt::shade(&t, &l.at(0, Vec3::ZERO))
        };
        let facing = lit(Vec3::X, None);
        let turned = lit(
            Vec3::Y,
            Some(DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2)),
        );
        let unturned = lit(Vec3::Y, None);
        assert!(facing.x > 0.25, "{facing}");
        assert!(
            (turned - facing).length() < 1e-4 * facing.length(),
            "{turned} vs {facing}"
        );
        // Without the rotation the light grazes the baked normal: far darker.
        assert!(unturned.x < 0.2 * facing.x, "{unturned}");
    }
}
