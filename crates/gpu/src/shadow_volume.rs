//! Stencil shadow volumes (Fuchs 2005 §4.3, after Everitt & Kilgard 2002 and McGuire et al.
//! 2003): silhouette extraction from edge adjacency on the CPU and volume geometry in
//! homogeneous coordinates, extruded to infinity with `w = 0`.
//!
//! # Casters
//! - **Closed meshes** (every edge shared by exactly two triangles of opposite orientation after
//!   welding equal positions): the triangles *facing away* from the light are the casters, which
//!   is Fuchs's choice (c) of §4.3.1. The near cap then lies on surfaces that are unlit anyway
//!   (N·L < 0), so cap/surface depth ties cannot darken a lit surface.
//! - **Open meshes** (anything else): every triangle blocks light from both sides in the path
//!   tracer, so every triangle is a caster, oriented away from the light. Their volume starts a
//!   relative 10⁻³ of the light distance behind the surface, so a lit triangle is not inside its
//!   own volume (the one approximation: a receiver within that distance behind an open caster
//!   is not shadowed).
//! - Alpha-masked materials do not cast volumes (the stencil cannot see texture holes); shadow
//!   maps handle them.
//!
//! # Silhouettes
//! Each caster is oriented so its normal points away from the light. An edge's side quad is
//! emitted once per unit of the signed sum of the casters' traversals of it (+1 for a→b, −1 for
//! b→a). For closed meshes that is the classic silhouette (a caster next to a non-caster);
//! for open and non-manifold meshes it still gives a closed volume (each caster's prism, with
//! interior faces cancelled). Every face points out of the volume (counter-clockwise seen from
//! outside), which z-fail needs.
//!
//! Written here rather than taken from a crate: no maintained Rust crate builds shadow volumes.

use glam::{Vec3, Vec4};
use std::collections::HashMap;

/// An edge (a < b) with the triangles using it: (triangle, +1 if it goes a→b, −1 if b→a).
pub type Edge = ([u32; 2], Vec<(u32, i8)>);

/// One object's triangles with welded vertices and edge adjacency, in world space.
#[derive(Clone, Debug)]
pub struct VolumeMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Unit normals of the triangles (counter-clockwise winding).
    pub normals: Vec<Vec3>,
    /// Edges (a < b) with the triangles using them: (triangle, +1 if it goes a→b, −1 if b→a).
    pub edges: Vec<Edge>,
    pub closed: bool,
    pub bounds: (Vec3, Vec3),
}

impl VolumeMesh {
    /// Move the mesh rigidly by `m` (a rotation, translation and positive scale: the edges
    /// keep their orientation).
    pub fn transform(&mut self, m: glam::Mat4) {
        let nm = glam::Mat3::from_mat4(m).inverse().transpose();
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        for n in &mut self.normals {
            *n = (nm * *n).normalize_or_zero();
        }
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in &self.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        self.bounds = (lo, hi);
    }

    /// Weld positions closer than 10⁻⁵ of the mesh size (parametric seams and poles are equal
    /// only up to rounding), drop zero-area triangles and build the edge list.
    pub fn new(positions: &[Vec3], indices: &[u32]) -> VolumeMesh {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let eps = ((hi - lo).max_element() * 1e-5).max(1e-9);
        let cell = |p: Vec3| (p / eps).floor().as_ivec3();
        let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
        let mut pos: Vec<Vec3> = vec![];
        let remap: Vec<u32> = positions
            .iter()
            .map(|p| {
                let c = cell(*p);
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            if let Some(list) = grid.get(&(c + glam::IVec3::new(dx, dy, dz))) {
                                for &i in list {
                                    if pos[i as usize].distance(*p) <= eps {
                                        return i;
                                    }
                                }
                            }
                        }
                    }
                }
                pos.push(*p);
                let i = (pos.len() - 1) as u32;
                grid.entry(c).or_default().push(i);
                i
            })
            .collect();
        let mut triangles = vec![];
        let mut normals = vec![];
        for t in indices.chunks_exact(3) {
            let tri = [
                remap[t[0] as usize],
                remap[t[1] as usize],
                remap[t[2] as usize],
            ];
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                continue;
            }
            let [a, b, c] = tri.map(|i| pos[i as usize]);
            let n = (b - a).cross(c - a);
            if n.length_squared() <= 0.0 || !n.is_finite() {
                continue;
            }
            triangles.push(tri);
            normals.push(n.normalize());
        }
        let mut edge_index: HashMap<[u32; 2], usize> = HashMap::new();
        let mut edges: Vec<Edge> = vec![];
        for (ti, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let (key, sign) = if a < b { ([a, b], 1) } else { ([b, a], -1) };
                let e = *edge_index.entry(key).or_insert_with(|| {
                    edges.push((key, vec![]));
                    edges.len() - 1
                });
                edges[e].1.push((ti as u32, sign));
            }
        }
        let closed = !triangles.is_empty()
            && edges
                .iter()
                .all(|(_, f)| f.len() == 2 && f[0].1 + f[1].1 == 0);
        VolumeMesh {
            positions: pos,
            triangles,
            normals,
            edges,
            closed,
            bounds: (lo, hi),
        }
    }
}

/// Where the light is: a point (point and spot lights) or a direction of travel (directional).
#[derive(Clone, Copy, Debug)]
pub enum LightPos {
    Point(Vec3),
    Directional(Vec3),
}

impl LightPos {
    /// The direction light travels at `p` (not normalised for points).
    fn away(&self, p: Vec3) -> Vec3 {
        match *self {
            LightPos::Point(l) => p - l,
            LightPos::Directional(d) => d,
        }
    }
}

/// Append the shadow volume of `mesh` for `light` to `out` (triangle list of homogeneous world
/// positions). Returns the number of triangles added.
pub fn build_volume(mesh: &VolumeMesh, light: LightPos, out: &mut Vec<Vec4>) -> usize {
    let far = |i: u32| -> Vec4 { light.away(mesh.positions[i as usize]).extend(0.0) };
    // A directional light's far cap collapses to one point at infinity: no area, not drawn.
    let far_cap = !matches!(light, LightPos::Directional(_));
    build_volume_with(mesh, light, out, far, far_cap)
}

/// [`build_volume`] with the far vertices given by `far` (tests make them finite).
fn build_volume_with(
    mesh: &VolumeMesh,
    light: LightPos,
    out: &mut Vec<Vec4>,
    far: impl Fn(u32) -> Vec4,
    far_cap: bool,
) -> usize {
    let start = out.len();
    // Orientation of each triangle: +1 caster as wound, −1 caster reversed, 0 not a caster.
    let orient: Vec<i8> = mesh
        .triangles
        .iter()
        .zip(&mesh.normals)
        .map(|(t, n)| {
            let f = n.dot(light.away(mesh.positions[t[0] as usize]));
            if f > 0.0 {
                1
            } else if !mesh.closed && f < 0.0 {
                -1
            } else {
                0
            }
        })
        .collect();
    // Open casters start slightly behind their surface (see the module doc).
    let push = if mesh.closed { 0.0 } else { 1e-3 };
    let near = |i: u32| -> Vec4 {
        let p = mesh.positions[i as usize];
        let q = match light {
            LightPos::Point(_) => p + light.away(p) * push,
            LightPos::Directional(d) => {
                let scale = (mesh.bounds.1 - mesh.bounds.0).length().max(1.0);
                p + d * (push * scale)
            }
        };
        q.extend(1.0)
    };
    for (t, &o) in mesh.triangles.iter().zip(&orient) {
        if o == 0 {
            continue;
        }
        let [a, b, c] = if o > 0 { *t } else { [t[0], t[2], t[1]] };
        // Near cap faces the light (reversed), far cap faces away.
        out.extend([near(a), near(c), near(b)]);
        if far_cap {
            out.extend([far(a), far(b), far(c)]);
        }
    }
    for ([a, b], uses) in &mesh.edges {
        let sum: i32 = uses
            .iter()
            .map(|&(t, s)| (orient[t as usize] * s) as i32)
            .sum();
        let (p, q) = if sum > 0 { (*a, *b) } else { (*b, *a) };
        for _ in 0..sum.abs() {
            // Side quad (p, q, q∞, p∞), outward for a caster traversing p→q.
            out.extend([near(p), near(q), far(q), near(p), far(q), far(p)]);
        }
    }
    (out.len() - start) / 3
}

#[cfg(test)]
mod tests {
    use super::*;
    use lightlab_scene::builtin::geom;

    /// A single-sided 2×2 quad in the plane y = 0, facing up.
    fn unit_quad() -> lightlab_scene::Mesh {
        geom::quad(
            "q",
            [
                Vec3::new(-1.0, 0.0, -1.0),
                Vec3::new(-1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, -1.0),
            ],
            0,
        )
    }

    fn mesh_of(m: &lightlab_scene::Mesh) -> VolumeMesh {
        VolumeMesh::new(&m.positions, &m.indices)
    }

    /// Signed volume of a closed triangle soup of finite points (divergence theorem).
    fn signed_volume(tris: &[Vec4]) -> f32 {
        tris.chunks_exact(3)
            .map(|t| t[0].truncate().dot(t[1].truncate().cross(t[2].truncate())) / 6.0)
            .sum()
    }

    #[test]
    fn builtin_solids_are_closed_and_planes_are_not() {
        let bx = geom::aabb_box("b", Vec3::ZERO, Vec3::ONE, 0);
        assert!(mesh_of(&bx).closed, "box");
        assert!(mesh_of(&geom::sphere("s", 1.0, 16, 8, 0)).closed, "sphere");
        assert!(
            mesh_of(&geom::cylinder("c", 0.3, 2.0, 12, 0)).closed,
            "cylinder"
        );
        let q = unit_quad();
        assert!(!mesh_of(&q).closed);
    }

    /// Closed: every directed edge is matched by its reverse.
    fn assert_closed(tris: &[Vec4]) {
        let mut count: HashMap<([u32; 4], [u32; 4]), i32> = HashMap::new();
        let key = |v: Vec4| v.to_array().map(f32::to_bits);
        for t in tris.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                if a < b {
                    *count.entry((a, b)).or_default() += 1;
                } else {
                    *count.entry((b, a)).or_default() -= 1;
                }
            }
        }
        assert!(count.values().all(|&c| c == 0), "volume is not closed");
    }

    /// With the points at infinity made finite (extruded k units), a volume is a closed,
    /// outward surface: its signed volume is positive and equals the swept solid's.
    #[test]
    fn volume_of_a_cube_under_a_directional_light_is_its_shadow_prism() {
        let m = mesh_of(&geom::aabb_box("b", Vec3::ZERO, Vec3::ONE, 0));
        let light = LightPos::Directional(-Vec3::Y);
        let mut out = vec![];
        let n = build_volume(&m, light, &mut out);
        // Bottom face as the near cap + 4 silhouette quads (the far cap collapses).
        assert_eq!(n, 2 + 4 * 2);
        let mut finite = vec![];
        let far = |i: u32| (m.positions[i as usize] - Vec3::Y * 10.0).extend(1.0);
        build_volume_with(&m, light, &mut finite, far, true);
        assert_closed(&finite);
        let v = signed_volume(&finite);
        assert!((v - 10.0).abs() < 1e-3, "volume {v}");
    }

    #[test]
    fn a_point_light_volume_is_closed_and_outward() {
        for (mesh, closed) in [
            (geom::sphere("s", 1.0, 12, 6, 0), true),
            (unit_quad(), false),
        ] {
            let m = mesh_of(&mesh);
            assert_eq!(m.closed, closed);
            let light = Vec3::new(0.3, 4.0, 0.2);
            let lp = LightPos::Point(light);
            let mut out = vec![];
            build_volume(&m, lp, &mut out);
            assert!(out.iter().any(|v| v.w == 0.0) && out.iter().any(|v| v.w == 1.0));
            let mut finite = vec![];
            let far = |i: u32| {
                let p = m.positions[i as usize];
                (p + (p - light) * 5.0).extend(1.0)
            };
            build_volume_with(&m, lp, &mut finite, far, true);
            assert_closed(&finite);
            let v = signed_volume(&finite);
            assert!(v > 0.1, "{}: volume {v}", mesh.name);
        }
    }

    #[test]
    fn an_open_quad_casts_from_both_sides() {
        let q = unit_quad();
        let m = mesh_of(&q);
        for light in [Vec3::new(0.0, 3.0, 0.0), Vec3::new(0.0, -3.0, 0.0)] {
            let mut out = vec![];
            let n = build_volume(&m, LightPos::Point(light), &mut out);
            // 2 triangles × (near + far cap) + 4 boundary edges × 2.
            assert_eq!(n, 4 + 8, "light at {light}");
        }
    }
}
