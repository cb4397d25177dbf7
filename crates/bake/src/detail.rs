//! Detail from a high-poly mesh on its decimated copy (McKenzie Chapter 2010 §4.2.4 and
//! §6.2.2; extraction `seed-001` §3.3): textured PRT's defining step, and the same thing a
//! normal/occlusion bake does for a game asset.
//!
//! A mesh that names a `detail_source` (see `lightlab_scene::simplify`) is rendered with its
//! own, decimated geometry, but its baked data comes from the source surface:
//!
//! 1. **Projection along a cage.** Each texel (p, n) of the decimated mesh is moved to the
//!    nearest point of the source surface along the line p ± t·n, |t| ≤ cage (two rays, the
//!    nearer hit wins; only the instance's own source mesh is hit). The source's interpolated
//!    vertex normal there is the baked normal; its geometric normal offsets the ray origins.
//! 2. **Occlusion against the source.** Transfer rays are cast from that point against the
//!    *detail scene*: the scene with every decimated instance replaced by its source mesh,
//!    so grooves shadow themselves and the decimated object shadows its surroundings with
//!    its true shape. (The thesis's literal §4.2.5 — low-poly position and occluders, high-poly
//!    normal only in the cosine — is what a texel that misses the cage falls back to, minus the
//!    normal.)
//!
//! The thesis does not say how its normal map was baked (tool, cage, ray direction); this is
//! the extraction's recommended procedure. Misses (no source surface within the cage) are
//! counted and keep the decimated surface's own position and normal.

use glam::Vec3;
use lightlab_scene::{Instance, Scene};
use lightlab_trace::Accel;
use serde::{Deserialize, Serialize};

/// How far the projection searches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DetailSettings {
    /// The cage distance as a fraction of the source mesh's bounding-box diagonal.
    pub cage: f32,
}

impl Default for DetailSettings {
    fn default() -> Self {
        DetailSettings { cage: 0.05 }
    }
}

/// How many texels were projected.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DetailStats {
    /// Texels of decimated instances.
    pub texels: usize,
    /// Of those, texels with no source surface within the cage (kept on the decimated surface).
    pub misses: usize,
    /// Mean |t| of the projection, metres.
    pub mean_offset: f32,
}

impl DetailStats {
    /// Add another batch's figures.
    pub fn merge(&mut self, o: &DetailStats) {
        let (a, b) = (
            (self.texels - self.misses) as f64,
            (o.texels - o.misses) as f64,
        );
        if a + b > 0.0 {
            self.mean_offset =
                ((self.mean_offset as f64 * a + o.mean_offset as f64 * b) / (a + b)) as f32;
        }
        self.texels += o.texels;
        self.misses += o.misses;
    }
}

/// Whether any instance of `scene` is drawn with a decimated mesh that names its source.
pub fn has_detail(scene: &Scene) -> bool {
    scene
        .instances
        .iter()
        .any(|i| scene.meshes[i.mesh].detail_source.is_some())
}

/// The scene as the source meshes have it: every instance of a decimated mesh shows the mesh
/// it was simplified from (same transform, same instance order).
pub fn detail_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for inst in &mut s.instances {
        if let Some(src) = scene.meshes[inst.mesh].detail_source {
            inst.mesh = src;
        }
    }
    s
}

/// A point on a surface: position, geometric normal, shading normal (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub p: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
}

/// Projects points of decimated instances onto their source surfaces.
pub struct DetailProjector {
    /// Per instance of the scene: the source mesh alone at the instance's transform, its BVH,
    /// and the absolute cage distance.
    per_instance: Vec<Option<(Scene, Accel, f32)>>,
}

impl DetailProjector {
    pub fn new(scene: &Scene, s: &DetailSettings) -> DetailProjector {
        let per_instance = scene
            .instances
            .iter()
            .map(|inst| {
                let src = scene.meshes[inst.mesh].detail_source?;
                // Only the geometry matters (the projection treats the source as opaque).
                let mesh = lightlab_scene::Mesh {
                    material: 0,
                    ..scene.meshes[src].clone()
                };
                let (lo, hi) = mesh
                    .positions
                    .iter()
                    .map(|p| inst.transform.transform_point3(*p))
                    .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
                        (a.min(p), b.max(p))
                    });
                let cage = s.cage * (hi - lo).length();
                let alone = Scene {
                    meshes: vec![mesh],
                    instances: vec![Instance {
                        name: inst.name.clone(),
                        mesh: 0,
                        transform: inst.transform,
                        nodes: vec![],
                        luminaire: None,
                    }],
                    materials: vec![Default::default()],
                    ..Default::default()
                };
                let accel = Accel::with_alpha_test(&alone, false);
                Some((alone, accel, cage))
            })
            .collect();
        DetailProjector { per_instance }
    }

    /// Whether instance `i` has a source to project onto.
    pub fn applies(&self, i: usize) -> bool {
        self.per_instance.get(i).is_some_and(|x| x.is_some())
    }

    /// The source surface's point nearest to `p` along ±`n` within the cage, and |t|; None for
    /// instances without a source, or when nothing lies within the cage.
    pub fn project(&self, instance: usize, p: Vec3, n: Vec3) -> Option<(SurfacePoint, f32)> {
        let (scene, accel, cage) = self.per_instance.get(instance)?.as_ref()?;
        let n = n.normalize_or_zero();
        if n == Vec3::ZERO {
            return None;
        }
        let out = accel.intersect(p, n, *cage);
        let inw = accel.intersect(p, -n, *cage);
        let (h, dir) = match (out, inw) {
            (Some(a), Some(b)) => {
                if a.t <= b.t {
                    (a, n)
                } else {
                    (b, -n)
                }
            }
            (Some(a), None) => (a, n),
            (None, Some(b)) => (b, -n),
            (None, None) => return None,
        };
        let inst = &scene.instances[0];
        let mesh = &scene.meshes[0];
        let tri = h.prim.triangle as usize;
        let w = accel.world_triangle(h.slot);
        let mut ng = (w[1] - w[0]).cross(w[2] - w[0]).normalize_or(n);
        let b = [1.0 - h.bary.x - h.bary.y, h.bary.x, h.bary.y];
        let ns = if mesh.normals.len() == mesh.positions.len() {
            let nm = inst.normal_matrix();
            let s: Vec3 = (0..3)
                .map(|k| mesh.normals[mesh.indices[tri * 3 + k] as usize] * b[k])
                .sum();
            (nm * s).normalize_or(ng)
        } else {
            ng
        };
        if ng.dot(ns) < 0.0 {
            ng = -ng;
        }
        let hp = p + dir * h.t;
        Some((SurfacePoint { p: hp, ng, ns }, h.t))
    }

    /// Project many (instance, point) pairs; misses and instances without a source keep their
    /// own point. Returns the points and the stats (counted over instances with a source).
    pub fn project_all(
        &self,
        points: &[(usize, SurfacePoint)],
    ) -> (Vec<SurfacePoint>, DetailStats) {
        use rayon::prelude::*;
        let res: Vec<(SurfacePoint, Option<f32>, bool)> = points
            .par_iter()
            .map(|&(i, sp)| {
                if !self.applies(i) {
                    return (sp, None, false);
                }
                match self.project(i, sp.p, sp.ns) {
                    Some((q, t)) => (q, Some(t), true),
                    None => (sp, None, true),
                }
            })
            .collect();
        let mut st = DetailStats::default();
        let mut sum = 0.0f64;
        for (_, t, applies) in &res {
            if *applies {
                st.texels += 1;
                match t {
                    Some(t) => sum += *t as f64,
                    None => st.misses += 1,
                }
            }
        }
        let hit = st.texels - st.misses;
        st.mean_offset = if hit > 0 {
            (sum / hit as f64) as f32
        } else {
            0.0
        };
        (res.into_iter().map(|r| r.0).collect(), st)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lightlab_scene::Mesh;
    use lightlab_scene::builtin::geom::{quad, ridged_torus_knot};

    /// A flat quad decimated from a corrugated one: projection lands on the corrugations and
    /// takes their normals.
    #[test]
    fn projection_finds_the_source_surface() {
        let mut s = Scene::default();
        let mat = s.add_material(lightlab_scene::Material::diffuse("m", Vec3::ONE));
        // Source: a sheet corrugated as y = 0.05·sin(2πx) over [-1, 1]², facing +y.
        let n = 64u32;
        let mut high = Mesh {
            name: "high".into(),
            material: mat,
            ..Default::default()
        };
        let h = |x: f32| 0.05 * (std::f32::consts::TAU * x).sin();
        for j in 0..=n {
            for i in 0..=n {
                let x = -1.0 + 2.0 * i as f32 / n as f32;
                let z = -1.0 + 2.0 * j as f32 / n as f32;
                high.positions.push(Vec3::new(x, h(x), z));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = j * (n + 1) + i;
                high.indices
                    .extend([a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2]);
            }
        }
        high.compute_normals();
        let src = s.add_mesh(high, glam::Mat4::IDENTITY);
        let mut low = quad(
            "low",
            [
                Vec3::new(-1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(-1.0, 0.0, -1.0),
            ],
            mat,
        );
        low.detail_source = Some(src);
        s.add_mesh(low, glam::Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0)));
        let proj = DetailProjector::new(&s, &DetailSettings { cage: 0.05 });
        assert!(!proj.applies(0) && proj.applies(1));
        for x in [-0.8f32, -0.3, 0.1, 0.25, 0.6] {
            let p = Vec3::new(x, 0.0, 5.2);
            let (q, t) = proj.project(1, p, Vec3::Y).expect("within the cage");
            assert!((q.p.y - h(x)).abs() < 2e-3, "x {x}: {} vs {}", q.p.y, h(x));
            assert!((t - h(x).abs()).abs() < 2e-3);
            // The corrugation's slope: n ∝ (−h'(x), 1, 0).
            let slope = 0.05 * std::f32::consts::TAU * (std::f32::consts::TAU * x).cos();
            let want = Vec3::new(-slope, 1.0, 0.0).normalize();
            assert!(q.ns.dot(want) > 0.995, "x {x}: {} vs {want}", q.ns);
            assert!(q.ng.dot(q.ns) > 0.9);
        }
        // Outside the cage: a miss.
        assert!(
            proj.project(1, Vec3::new(0.25, 0.5, 5.0), Vec3::Y)
                .is_none()
        );
        // The detail scene shows the source at the decimated instance's place.
        let d = detail_scene(&s);
        assert_eq!(d.instances[1].mesh, src);
        assert_eq!(d.instances[1].transform, s.instances[1].transform);
        assert!(has_detail(&s) && !has_detail(&d));
    }

    #[test]
    fn decimated_knot_projects_onto_its_ridges() {
        let mut s = Scene::default();
        let mat = s.add_material(lightlab_scene::Material::diffuse("m", Vec3::ONE));
        let high = ridged_torus_knot("k", 2.0, 3.0, 1.0, 0.22, 7.0, 0.35, 300, 24, mat);
        let low = lightlab_scene::simplify::simplify(
            &high,
            0,
            &lightlab_scene::simplify::SimplifySettings {
                target_triangles: 800,
                ..Default::default()
            },
        )
        .unwrap()
        .mesh;
        s.add_mesh(high, glam::Mat4::IDENTITY);
        s.add_mesh(low, glam::Mat4::IDENTITY);
        let proj = DetailProjector::new(&s, &DetailSettings::default());
        let low = &s.meshes[1];
        let pts: Vec<(usize, SurfacePoint)> = low
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| low.positions[i as usize]);
                let ng = (b - a).cross(c - a).normalize();
                let n: Vec3 = [t[0], t[1], t[2]]
                    .map(|i| low.normals[i as usize])
                    .iter()
                    .sum::<Vec3>()
                    .normalize();
                (
                    1,
                    SurfacePoint {
                        p: (a + b + c) / 3.0,
                        ng,
                        ns: n,
                    },
                )
            })
            .collect();
        let (q, st) = proj.project_all(&pts);
        println!("{st:?}");
        assert_eq!(st.texels, pts.len());
        assert!(st.misses * 100 < st.texels, "{st:?}");
        // The ridges come back: many projected normals differ from the decimated ones.
        let differs = q
            .iter()
            .zip(&pts)
            .filter(|(a, b)| a.ns.dot(b.1.ns) < 0.95)
            .count();
        assert!(differs * 5 > pts.len(), "{differs} of {}", pts.len());
    }
}
