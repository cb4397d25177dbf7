//! CPU ray casting over an 8-wide SIMD BVH ([`crate::bvh8`], built by obvhs's PLOC).
//!
//! The scene's instances are flattened into world-space triangles stored in BVH leaf order, so a
//! leaf's triangles are contiguous in memory. Closest-hit queries return the distance,
//! barycentrics and the (instance, triangle) that was hit; any-hit queries answer shadow rays.
//! Alpha-tested (MASK, and BLEND treated as MASK at 0.5) triangles are tested against their
//! texture inside the traversal, so holes in leaves let rays through.

use crate::bvh_settings::BvhSettings;
use crate::bvh8::Bvh8;
use glam::{Mat3, Vec2, Vec3, Vec3A};
use lightlab_scene::{AlphaMode, Scene, Texture};
use obvhs::ray::Ray;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use rayon::prelude::*;

/// Where a triangle came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrimRef {
    pub instance: u32,
    /// Triangle index within the instance's mesh.
    pub triangle: u32,
}

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: PrimRef,
    /// Barycentric weights of the triangle's second and third vertices (the first has
    /// 1 − b.x − b.y).
    pub bary: Vec2,
    /// The triangle's slot in the BVH (for [`Accel::world_triangle`]).
    pub slot: u32,
}

struct AlphaTri {
    /// The corners' coordinates for the base colour texture (its transform applied).
    uv: [Vec2; 3],
    /// The corners' vertex-colour alpha (COLOR_0; 1 without).
    vertex_alpha: [f32; 3],
    texture: Option<u32>,
    base_alpha: f32,
    cutoff: f32,
}

/// The acceleration structure of a scene.
pub struct Accel {
    bvh: Bvh8,
    /// Triangles by BVH slot (unused slots hold a degenerate triangle).
    tris: Vec<RtTriangle>,
    prims: Vec<PrimRef>,
    /// Index into `alpha` per BVH primitive, u32::MAX when opaque.
    alpha_index: Vec<u32>,
    alpha: Vec<AlphaTri>,
    textures: Vec<Texture>,
    /// Per-instance normal matrices (inverse transpose of the upper 3×3).
    pub normal_matrices: Vec<Mat3>,
    rays: RayCounter,
}

/// Rays cast through an [`Accel`], counted on one cache line per thread. The first
/// [`RayCounter::SHARDS`] threads of the process each own a shard for life and count with a
/// plain load and store (no locked instruction: `fetch_add`'s full barrier per ray cost 3 % of
/// incoherent ray casting on prt); later threads share one more shard through `fetch_add`.
struct RayCounter(Box<[PaddedCount]>);

#[repr(align(128))]
#[derive(Default)]
struct PaddedCount(std::sync::atomic::AtomicU64);

/// The next thread's shard number (never reused, so a shard has one writer).
static NEXT_SHARD: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

thread_local! {
    static SHARD: usize = NEXT_SHARD.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
}

impl RayCounter {
    const SHARDS: usize = 64;

    fn new() -> RayCounter {
        RayCounter((0..=Self::SHARDS).map(|_| PaddedCount::default()).collect())
    }

    #[inline(always)]
    fn add(&self) {
        use std::sync::atomic::Ordering::Relaxed;
        let i = SHARD.with(|s| *s);
        if i < Self::SHARDS {
            // This thread is the shard's only writer.
            let c = &self.0[i].0;
            c.store(c.load(Relaxed) + 1, Relaxed);
        } else {
            self.0[Self::SHARDS].0.fetch_add(1, Relaxed);
        }
    }

    fn total(&self) -> u64 {
        self.0
            .iter()
            .map(|c| c.0.load(std::sync::atomic::Ordering::Relaxed))
            .sum()
    }
}

/// A ray in obvhs's form, for its barycentrics (the inverse direction, which only obvhs's own
/// traversal reads, is left out). Negative zeros in the direction are made positive
/// (`−0.0 + 0.0 = +0.0`), so that every query sees the same direction.
#[inline(always)]
fn make_ray(origin: Vec3, dir: Vec3, tmax: f32) -> Ray {
    Ray {
        origin: origin.into(),
        direction: (dir + Vec3::ZERO).into(),
        inv_direction: Vec3A::ZERO,
        tmin: 0.0,
        tmax,
    }
}

/// The BVH build: obvhs's slow preset (PLOC with pre-splits and re-insertion; a build is a
/// small part of any render) with its SAH leaf collapse at up to sixteen triangles (two SIMD
/// blocks of eight) and a traversal cost of 4. Measured with `lightlab bench trace` (incoherent
/// rays, 1 thread, Mrays/s, median of five runs alternated): prt 3.68 against 3.39 for up to 8
/// triangles at cost 3 (3.44 at 16/3, 3.38 at 8/5); bush and cornell within noise. Earlier,
/// with four-triangle blocks: leaves of up to 8 against up to 4, bush 3.81 / 3.64; obvhs's
/// medium preset −5 to −10 %, very-slow within noise at twice the build time; no pre-splits
/// −5 % on bush.
/// A ray for batch queries.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmax: f32,
}

impl Accel {
    /// Build the BVH of all instances of `scene` (PLOC with pre-splits, parallel).
    pub fn new(scene: &Scene) -> Accel {
        Self::with_alpha_test(scene, true)
    }

    /// As [`Accel::new`]; `alpha_test = false` treats every triangle as opaque (for
    /// like-for-like benchmarks against ray casters that do no alpha test).
    pub fn with_alpha_test(scene: &Scene, alpha_test: bool) -> Accel {
        Self::with_settings(scene, alpha_test, BvhSettings::default())
    }

    /// As [`Accel::with_alpha_test`], the BVH built with `bvh` (`bench trace --bvh`).
    pub fn with_settings(scene: &Scene, alpha_test: bool, bvh: BvhSettings) -> Accel {
        let mut tris = Vec::with_capacity(scene.triangle_count());
        let mut prims = Vec::with_capacity(tris.capacity());
        let mut alpha_of: Vec<Option<AlphaTri>> = Vec::with_capacity(tris.capacity());
        for (ii, inst) in scene.instances.iter().enumerate() {
            let mesh = &scene.meshes[inst.mesh];
            let mat = &scene.materials[mesh.material];
            let cutoff = match mat.alpha_mode {
                _ if !alpha_test => None,
                AlphaMode::Opaque => None,
                AlphaMode::Mask { cutoff } => Some(cutoff),
                AlphaMode::Blend => Some(0.5),
            };
            for (ti, t) in mesh.indices.chunks_exact(3).enumerate() {
                let p = [t[0], t[1], t[2]].map(|i| {
                    Vec3A::from(inst.transform.transform_point3(mesh.positions[i as usize]))
                });
                tris.push(Triangle {
                    v0: p[0],
                    v1: p[1],
                    v2: p[2],
                });
                prims.push(PrimRef {
                    instance: ii as u32,
                    triangle: ti as u32,
                });
                // The corners' UVs for the base colour texture (an affine transform commutes
                // with the barycentric interpolation).
                let corners = mesh.corners(t);
                let r = mat.base_color_texture;
                alpha_of.push(cutoff.map(|cutoff| AlphaTri {
                    uv: corners.map(|c| r.map_or(Vec2::ZERO, |r| r.uv(&c))),
                    vertex_alpha: corners.map(|c| c.color.w),
                    texture: mat.base_color_texture.map(|r| r.texture as u32),
                    base_alpha: mat.base_color.w,
                    cutoff,
                }));
            }
        }
        let bvh = Bvh8::build(&tris, bvh.params, bvh.wide, |i| alpha_of[i].is_some());
        // Per slot: the triangle, where it came from and its alpha record (pre-splits may put
        // one triangle in several leaves; unused slots get a degenerate triangle no ray hits).
        let unused = Triangle {
            v0: Vec3A::ZERO,
            v1: Vec3A::ZERO,
            v2: Vec3A::ZERO,
        };
        let order = &bvh.slot_triangle;
        let rt: Vec<RtTriangle> = order
            .iter()
            .map(|&i| RtTriangle::from(tris.get(i as usize).unwrap_or(&unused)))
            .collect();
        let prims_o: Vec<PrimRef> = order
            .iter()
            .map(|&i| {
                prims.get(i as usize).copied().unwrap_or(PrimRef {
                    instance: u32::MAX,
                    triangle: u32::MAX,
                })
            })
            .collect();
        let mut alpha = vec![];
        let orig_alpha: Vec<u32> = alpha_of
            .into_iter()
            .map(|a| match a {
                Some(a) => {
                    alpha.push(a);
                    alpha.len() as u32 - 1
                }
                None => u32::MAX,
            })
            .collect();
        let alpha_index: Vec<u32> = order
            .iter()
            .map(|&i| orig_alpha.get(i as usize).copied().unwrap_or(u32::MAX))
            .collect();
        // Only the textures alpha tests read are kept (a copy of every texture doubled the
        // memory of a textured scene); AlphaTri::texture is renumbered into this list.
        let mut kept: Vec<u32> = alpha.iter().filter_map(|a| a.texture).collect();
        kept.sort_unstable();
        kept.dedup();
        for a in &mut alpha {
            a.texture = a
                .texture
                .map(|t| kept.binary_search(&t).expect("listed above") as u32);
        }
        let textures = kept
            .iter()
            .map(|&t| scene.textures[t as usize].clone())
            .collect();
        Accel {
            bvh,
            tris: rt,
            prims: prims_o,
            alpha_index,
            alpha,
            textures,
            normal_matrices: scene.instances.iter().map(|i| i.normal_matrix()).collect(),
            rays: RayCounter::new(),
        }
    }

    /// World-space vertices of the triangle in BVH slot `slot`, in the mesh's winding order.
    #[inline]
    pub fn world_triangle(&self, slot: u32) -> [Vec3; 3] {
        let t = &self.tris[slot as usize];
        [t.v0.into(), (t.v0 - t.e1).into(), (t.v0 + t.e2).into()]
    }

    /// Whether the ray passes through the alpha-tested hole of BVH primitive `slot` at the
    /// intersection found with `ray`.
    #[inline]
    fn alpha_rejects(&self, slot: usize, ray: &Ray) -> bool {
        let ai = self.alpha_index[slot];
        if ai == u32::MAX {
            return false;
        }
        let a = &self.alpha[ai as usize];
        let b = self.tris[slot].compute_barycentric(ray);
        let bw = [1.0 - b.x - b.y, b.x, b.y];
        let uv = a.uv[0] * bw[0] + a.uv[1] * bw[1] + a.uv[2] * bw[2];
        let vertex_alpha =
            a.vertex_alpha[0] * bw[0] + a.vertex_alpha[1] * bw[1] + a.vertex_alpha[2] * bw[2];
        let alpha = a.base_alpha
            * vertex_alpha
            * match a.texture {
                Some(t) => self.textures[t as usize].sample(uv).w,
                None => 1.0,
            };
        alpha < a.cutoff
    }

    /// Closest hit along `origin + t·dir`, t ∈ (0, tmax]. `dir` need not be normalised
    /// (t is in units of `dir`).
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        self.rays.add();
        let ray = make_ray(origin, dir, tmax);
        let dir = Vec3::from(ray.direction);
        let (slot, t) = self.bvh.closest(origin, dir, 0.0, tmax, |slot, t| {
            self.alpha_rejects(slot, &Ray { tmax: t, ..ray })
        })?;
        Some(self.hit(&ray, slot, t))
    }

    /// The hit of `ray` on the triangle in `slot` at distance `t`.
    #[inline]
    fn hit(&self, ray: &Ray, slot: u32, t: f32) -> Hit {
        let at = Ray { tmax: t, ..*ray };
        // obvhs's (u, v) are the weights of v1 and v2 (v0 gets 1 − u − v).
        let b = self.tris[slot as usize].compute_barycentric(&at);
        Hit {
            t,
            prim: self.prims[slot as usize],
            bary: b,
            slot,
        }
    }

    /// Whether anything blocks `origin + t·dir` for t ∈ (0, tmax].
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        self.rays.add();
        let ray = make_ray(origin, dir, tmax);
        self.bvh
            .any(origin, Vec3::from(ray.direction), 0.0, tmax, |slot, t| {
                self.alpha_rejects(slot, &Ray { tmax: t, ..ray })
            })
    }

    /// Rays cast through this structure so far (closest-hit and occlusion queries).
    pub fn rays_cast(&self) -> u64 {
        self.rays.total()
    }

    /// Closest hits of a batch of rays, across threads.
    pub fn intersect_batch(&self, rays: &[RayQuery]) -> Vec<Option<Hit>> {
        rays.par_iter()
            .with_min_len(256)
            .map(|r| self.intersect(r.origin, r.dir, r.tmax))
            .collect()
    }

    /// Occlusion of a batch of rays, across threads.
    pub fn occluded_batch(&self, rays: &[RayQuery]) -> Vec<bool> {
        rays.par_iter()
            .with_min_len(256)
            .map(|r| self.occluded(r.origin, r.dir, r.tmax))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Vec4};
    use lightlab_scene::{Instance, Material, Mesh, TextureRef};

    fn one_triangle_scene(material: Material, textures: Vec<Texture>) -> Scene {
        let mut s = Scene::default();
        s.materials.push(material);
        s.textures = textures;
        s.meshes.push(Mesh {
            name: "t".into(),
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            normals: vec![Vec3::Z; 3],
            uv0: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 1.0),
            ],
            indices: vec![0, 1, 2],
            ..Default::default()
        });
        s.instances.push(Instance {
            name: "t".into(),
            mesh: 0,
            transform: Mat4::from_translation(Vec3::new(0.0, 0.0, -2.0)),
            nodes: vec![],
            luminaire: None,
        });
        s
    }

    #[test]
    fn closest_hit_distance_and_barycentrics() {
        let s = one_triangle_scene(Material::default(), vec![]);
        let a = Accel::new(&s);
        let h = a
            .intersect(Vec3::new(0.25, 0.5, 0.0), -Vec3::Z, f32::INFINITY)
            .unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        // p = (1−u−v)·v0 + u·v1 + v·v2 with v1 = (1,0), v2 = (0,1): u = 0.25, v = 0.5.
        assert!(
            (h.bary - Vec2::new(0.25, 0.5)).length() < 1e-6,
            "{}",
            h.bary
        );
        assert!(
            a.intersect(Vec3::new(0.8, 0.8, 0.0), -Vec3::Z, f32::INFINITY)
                .is_none()
        );
        assert!(
            a.intersect(Vec3::new(0.25, 0.5, 0.0), -Vec3::Z, 1.5)
                .is_none()
        );
        assert!(a.occluded(Vec3::new(0.25, 0.5, 0.0), -Vec3::Z, 3.0));
        assert!(!a.occluded(Vec3::new(0.25, 0.5, 0.0), -Vec3::Z, 1.9));
        // Hits from behind count too.
        assert!(
            a.intersect(Vec3::new(0.25, 0.5, -4.0), Vec3::Z, f32::INFINITY)
                .is_some()
        );
    }

    #[test]
    fn alpha_test_makes_holes() {
        // A 2×1 texture: left half opaque, right half transparent.
        let tex = Texture {
            name: "mask".into(),
            width: 2,
            height: 1,
            texels: lightlab_scene::Texels::Rgba32F(vec![
                Vec4::new(1.0, 1.0, 1.0, 1.0),
                Vec4::new(1.0, 1.0, 1.0, 0.0),
            ]),
            srgb: true,
        };
        let mat = Material {
            base_color_texture: Some(TextureRef::new(0, 0)),
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            ..Default::default()
        };
        let s = one_triangle_scene(mat, vec![tex]);
        let a = Accel::new(&s);
        assert!(
            a.intersect(Vec3::new(0.1, 0.1, 0.0), -Vec3::Z, f32::INFINITY)
                .is_some()
        );
        assert!(
            a.intersect(Vec3::new(0.8, 0.1, 0.0), -Vec3::Z, f32::INFINITY)
                .is_none()
        );
        assert!(!a.occluded(Vec3::new(0.8, 0.1, 0.0), -Vec3::Z, 10.0));
        assert!(a.occluded(Vec3::new(0.1, 0.1, 0.0), -Vec3::Z, 10.0));
    }

    #[test]
    fn batch_matches_single_queries() {
        let s = lightlab_scene::builtin::builtin("cornell").unwrap();
        let a = Accel::new(&s);
        let mut rng = lightlab_core::sampling::Rng::new(1, 0);
        let rays: Vec<RayQuery> = (0..2000)
            .map(|_| RayQuery {
                origin: Vec3::new(0.278, 0.27, 0.28),
                // Towards the back of the box (its front is open).
                dir: {
                    let mut d = lightlab_core::sampling::uniform_sphere(rng.next_vec2());
                    d.z = d.z.abs();
                    d
                },
                tmax: f32::INFINITY,
            })
            .collect();
        let batch = a.intersect_batch(&rays);
        for (r, b) in rays.iter().zip(&batch) {
            assert_eq!(*b, a.intersect(r.origin, r.dir, r.tmax));
            // Every ray towards the back of the box hits a wall.
            assert!(b.is_some());
        }
    }
}
