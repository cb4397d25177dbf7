//! Filters (McKenzie Chapter §5.1.5–5.1.6): the SH projection of what a sample point sees
//! unblocked, found by casting the run-time sampler's directions against the point's
//! occluders — bounding boxes first, then the occluders' faces (each mesh's object-space BVH,
//! the ray carried into the instance's frame), or the boxes alone ("blob" shadows, §5.3).

use super::tree::Tree;
use super::{Occlusion, Scope};
use glam::{Mat4, Vec3};
use lightlab_scene::Scene;
use lightlab_trace::Accel;

/// Where the scene's instances are this frame, and what each node covers.
pub(crate) struct Placement {
    pub inverse: Vec<Mat4>,
    /// World bounds per instance (an empty mesh: an empty box).
    pub bounds: Vec<(Vec3, Vec3)>,
    /// World bounds per node (the union over its instances).
    pub node_bounds: Vec<(Vec3, Vec3)>,
}

impl Placement {
    pub fn new(scene: &Scene, tree: &Tree, under: &[Vec<usize>]) -> Placement {
        let empty = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let bounds: Vec<(Vec3, Vec3)> = (0..scene.instances.len())
            .map(|i| scene.instance_bounds(i).unwrap_or(empty))
            .collect();
        let node_bounds = (0..tree.nodes.len())
            .map(|k| {
                under[k].iter().fold(empty, |(lo, hi), &i| {
                    (lo.min(bounds[i].0), hi.max(bounds[i].1))
                })
            })
            .collect();
        Placement {
            inverse: scene
                .instances
                .iter()
                .map(|i| i.transform.inverse())
                .collect(),
            bounds,
            node_bounds,
        }
    }

    /// A node's sample points: its box's face centres (McKenzie §4.3.3), with the ray origins
    /// drawn 1 % of the way in towards the box's centre, so that a point where the object
    /// touches another (a ball on the ground) starts its rays on the right side of the contact.
    /// `Scope::Node`: the box's centre for all six.
    pub fn origins(&self, node: usize, scope: Scope) -> Vec<Vec3> {
        let (lo, hi) = self.node_bounds[node];
        let c = 0.5 * (lo + hi);
        crate::sh_light::box_face_centres(lo, hi)
            .into_iter()
            .map(|p| match scope {
                Scope::Point => p + 0.01 * (c - p),
                Scope::Node => c,
            })
            .collect()
    }
}

/// Ray–box slab test for t ∈ (0, ∞).
#[inline]
pub(crate) fn hits_box(o: Vec3, inv_d: Vec3, b: (Vec3, Vec3)) -> bool {
    let t0 = (b.0 - o) * inv_d;
    let t1 = (b.1 - o) * inv_d;
    let near = t0.min(t1).max_element();
    let far = t0.max(t1).min_element();
    // NaN (a zero direction component on a box face) compares false: counted as a miss.
    far >= near.max(0.0)
}

/// Counters of one frame's filtering.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FilterStats {
    /// Directions cast (per point, per direction).
    pub rays: u64,
    /// Rays that reached an instance's faces (passed its box).
    pub face_queries: u64,
    /// Nodes whose filters were (re)computed.
    pub nodes: usize,
}

/// A blocked direction's first hit (face occlusion): the direction's index in the sampler,
/// the instance hit, and the world point and geometric normal there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blocker {
    pub dir: u32,
    pub instance: u32,
    pub point: Vec3,
    pub normal: Vec3,
}

/// One sample point's filter and, when occluders reflect, what its blocked rays hit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointFilter {
    pub coeffs: Vec<f64>,
    pub hits: Vec<Blocker>,
}

/// What one point's rays test: per occluder node its box and, for face occlusion, its
/// instances.
pub(crate) struct Caster<'a> {
    pub scene: &'a Scene,
    pub under: &'a [Vec<usize>],
    pub accels: &'a [Option<Accel>],
    pub place: &'a Placement,
    pub occlusion: Occlusion,
}

impl Caster<'_> {
    /// Each instance under `occluders` whose boxes (its node's, its own) the ray from `o`
    /// along `d` passes, with its BVH and its world-to-object transform, until `f` says stop.
    /// Counts the instances reached as face queries.
    fn candidates(
        &self,
        o: Vec3,
        d: Vec3,
        occluders: &[usize],
        faces: &mut u64,
        mut f: impl FnMut(usize, &Accel, Mat4) -> bool,
    ) {
        let inv_d = d.recip();
        for &n in occluders {
            if !hits_box(o, inv_d, self.place.node_bounds[n]) {
                continue;
            }
            for &i in &self.under[n] {
                if !hits_box(o, inv_d, self.place.bounds[i]) {
                    continue;
                }
                if let Some(accel) = &self.accels[self.scene.instances[i].mesh] {
                    *faces += 1;
                    if f(i, accel, self.place.inverse[i]) {
                        return;
                    }
                }
            }
        }
    }

    /// Whether the ray from `o` along `d` hits one of `occluders` (its box, as a blob).
    pub fn blocked(&self, o: Vec3, d: Vec3, occluders: &[usize], faces: &mut u64) -> bool {
        if self.occlusion == Occlusion::Blob {
            let inv_d = d.recip();
            return occluders
                .iter()
                .any(|&n| hits_box(o, inv_d, self.place.node_bounds[n]));
        }
        let mut hit = false;
        self.candidates(o, d, occluders, faces, |_, accel, m| {
            hit = accel.occluded(m.transform_point3(o), m.transform_vector3(d), f32::INFINITY);
            hit
        });
        hit
    }

    /// The first face of `occluders` the ray from `o` along `d` hits.
    pub fn closest(
        &self,
        o: Vec3,
        d: Vec3,
        occluders: &[usize],
        faces: &mut u64,
    ) -> Option<Blocker> {
        let mut best: Option<(f32, Blocker)> = None;
        self.candidates(o, d, occluders, faces, |i, accel, m| {
            let tmax = best.map_or(f32::INFINITY, |b| b.0);
            if let Some(h) = accel.intersect(m.transform_point3(o), m.transform_vector3(d), tmax) {
                let w = accel.world_triangle(h.slot);
                let n_obj = (w[1] - w[0]).cross(w[2] - w[0]);
                let normal = m.transpose().transform_vector3(n_obj).normalize_or(-d);
                let b = Blocker {
                    dir: 0,
                    instance: i as u32,
                    point: o + d * h.t,
                    // Facing the ray.
                    normal: if normal.dot(d) > 0.0 { -normal } else { normal },
                };
                best = Some((h.t, b));
            }
            false
        });
        best.map(|b| b.1)
    }

    /// The blocked directions' weighted basis, summed (what the point's filter loses), and
    /// with `hits` their first hits.
    pub fn blocked_sum(
        &self,
        o: Vec3,
        dirs: &[Vec3],
        basis: &[f64],
        occluders: &[usize],
        hits: bool,
        stats: &mut FilterStats,
    ) -> (Vec<f64>, Vec<Blocker>) {
        let nc = basis.len() / dirs.len().max(1);
        let mut out = vec![0.0; nc];
        let mut found = vec![];
        if occluders.is_empty() {
            return (out, found);
        }
        let hits = hits && self.occlusion == Occlusion::Faces;
        for (s, d) in dirs.iter().enumerate() {
            stats.rays += 1;
            let blocked = if hits {
                let b = self.closest(o, *d, occluders, &mut stats.face_queries);
                if let Some(b) = b {
                    found.push(Blocker { dir: s as u32, ..b });
                }
                b.is_some()
            } else {
                self.blocked(o, *d, occluders, &mut stats.face_queries)
            };
            if blocked {
                for (a, b) in out.iter_mut().zip(&basis[s * nc..(s + 1) * nc]) {
                    *a += b;
                }
            }
        }
        (out, found)
    }
}

/// Each mesh used by a leaf of the tree alone in its object space, with its BVH (alpha test
/// off: a filter is a coarse, band-limited quantity).
pub(crate) fn mesh_accels(scene: &Scene, tree: &Tree) -> Vec<Option<Accel>> {
    let mut used = vec![false; scene.meshes.len()];
    for n in &tree.nodes {
        if let Some(i) = n.instance.filter(|&i| i < scene.instances.len()) {
            used[scene.instances[i].mesh] = true;
        }
    }
    scene
        .meshes
        .iter()
        .zip(used)
        .map(|(m, u)| {
            u.then(|| {
                let alone = Scene {
                    meshes: vec![lightlab_scene::Mesh {
                        material: 0,
                        ..m.clone()
                    }],
                    materials: vec![Default::default()],
                    instances: vec![lightlab_scene::Instance {
                        name: m.name.clone(),
                        mesh: 0,
                        transform: Mat4::IDENTITY,
                        nodes: vec![],
                        luminaire: None,
                    }],
                    ..Default::default()
                };
                Accel::with_alpha_test(&alone, false)
            })
        })
        .collect()
}
