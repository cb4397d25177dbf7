//! Tangent frames for meshes without glTF TANGENT: MikkTSpace, as glTF asks ("client
//! implementations SHOULD calculate tangents using default MikkTSpace algorithms"), so a normal
//! map baked by another tool against MikkTSpace reads back as it was baked. The algorithm is
//! the `bevy_mikktspace` crate (a safe Rust port, byte-identical to the reference C code).
//!
//! MikkTSpace gives a frame per triangle corner. Corners of one vertex agree inside a smooth
//! region; where they differ (a UV seam, mirrored UVs, a hard tangent edge) the vertex is split
//! into one copy per frame, every attribute copied, as exporters do.

use crate::model::Mesh;
use bevy_mikktspace::{Geometry, TangentSpace, generate_tangents};
use glam::{Vec3, Vec4};

/// The mesh seen by MikkTSpace, collecting one tangent per triangle corner.
struct Corners<'a> {
    mesh: &'a Mesh,
    out: Vec<Vec4>,
}

impl Corners<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.indices[face * 3 + vert] as usize
    }
}

impl Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.indices.len() / 3
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.vertex(face, vert)].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.mesh.uv0[self.vertex(face, vert)].to_array()
    }
    fn set_tangent(&mut self, t: Option<TangentSpace>, face: usize, vert: usize) {
        if let Some(t) = t {
            self.out[face * 3 + vert] = Vec4::from_array(t.tangent_encoded());
        }
    }
}

/// Any unit tangent orthogonal to `n`, right-handed.
fn fallback(n: Vec3) -> Vec4 {
    lightlab_core::sampling::orthonormal_basis(n).0.extend(1.0)
}

/// Whether two corner frames are the same (MikkTSpace gives corners of one smooth group the
/// same value; the tolerance absorbs rounding only).
fn same(a: Vec4, b: Vec4) -> bool {
    a.w == b.w && a.truncate().dot(b.truncate()) > 0.9999
}

/// Set `mesh.tangents` (see the module doc). Normals must be present.
pub fn compute(mesh: &mut Mesh) {
    let nv = mesh.positions.len();
    let normal = |m: &Mesh, i: usize| m.normals.get(i).copied().unwrap_or(Vec3::Y);
    if mesh.uv0.len() != nv || mesh.normals.len() != nv || mesh.indices.len() < 3 {
        mesh.tangents = (0..nv).map(|i| fallback(normal(mesh, i))).collect();
        return;
    }
    let mut corners = Corners {
        mesh,
        out: vec![Vec4::ZERO; mesh.indices.len() / 3 * 3],
    };
    if generate_tangents(&mut corners).is_err() {
        mesh.tangents = (0..nv).map(|i| fallback(normal(mesh, i))).collect();
        return;
    }
    let out = corners.out;
    let mut tangents: Vec<Option<Vec4>> = vec![None; nv];
    // Extra copies of a vertex, by frame: (original vertex, frame, new index).
    let mut copies: Vec<(usize, Vec4, u32)> = vec![];
    for (c, t) in out.into_iter().enumerate() {
        let v = mesh.indices[c] as usize;
        let t = if t.truncate().length_squared() > 0.5 {
            t
        } else {
            fallback(mesh.normals[v])
        };
        match tangents[v] {
            None => tangents[v] = Some(t),
            Some(first) if same(first, t) => {}
            Some(_) => {
                let found = copies
                    .iter()
                    .find(|(o, f, _)| *o == v && same(*f, t))
                    .map(|c| c.2);
                mesh.indices[c] = match found {
                    Some(i) => i,
                    None => {
                        let i = duplicate(mesh, v);
                        tangents.push(Some(t));
                        copies.push((v, t, i));
                        i
                    }
                };
            }
        }
    }
    mesh.tangents = tangents
        .iter()
        .enumerate()
        .map(|(i, t)| t.unwrap_or_else(|| fallback(normal(mesh, i))))
        .collect();
}

/// Append a copy of vertex `v` (every attribute) and return its index.
fn duplicate(mesh: &mut Mesh, v: usize) -> u32 {
    fn push<T: Copy>(a: &mut Vec<T>, v: usize) {
        if let Some(x) = a.get(v).copied() {
            a.push(x);
        }
    }
    push(&mut mesh.positions, v);
    push(&mut mesh.normals, v);
    push(&mut mesh.uv0, v);
    if let Some(uv1) = &mut mesh.uv1 {
        push(uv1, v);
    }
    push(&mut mesh.colors, v);
    (mesh.positions.len() - 1) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    fn quad(uv: [Vec2; 4]) -> Mesh {
        Mesh {
            name: "quad".into(),
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            normals: vec![Vec3::Z; 4],
            tangents: vec![],
            uv0: uv.to_vec(),
            uv1: None,
            colors: vec![],
            indices: vec![0, 1, 2, 0, 2, 3],
            material: 0,
            detail_source: None,
        }
    }

    #[test]
    fn tangent_follows_u_and_handedness_follows_v() {
        let mut m = quad([
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ]);
        compute(&mut m);
        assert_eq!(m.positions.len(), 4, "a flat quad needs no split");
        for t in &m.tangents {
            assert!((t.truncate() - Vec3::X).length() < 1e-5, "{t}");
            // glTF: bitangent = cross(normal, tangent) · w = +Y = the direction of +v.
            assert_eq!(t.w, 1.0);
        }
        // Mirrored in u: the tangent turns round, the handedness stays.
        let mut m = quad([
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
        ]);
        compute(&mut m);
        for t in &m.tangents {
            assert!((t.truncate() + Vec3::X).length() < 1e-5, "{t}");
            assert_eq!(t.w, -1.0);
        }
    }

    #[test]
    fn a_uv_seam_splits_the_shared_vertices() {
        // Two triangles sharing the edge 0–2, the second one's u mirrored (it runs along −x):
        // the shared vertices get two frames each, so they are split (4 → 6 vertices).
        let mut m = quad([
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 0.0),
        ]);
        m.positions[3] = Vec3::new(-1.0, 0.0, 0.0);
        m.indices = vec![0, 1, 2, 0, 2, 3];
        let before: Vec<Vec3> = m.indices.iter().map(|&i| m.positions[i as usize]).collect();
        compute(&mut m);
        assert_eq!(m.positions.len(), 6);
        assert_eq!(m.tangents.len(), 6);
        let after: Vec<Vec3> = m.indices.iter().map(|&i| m.positions[i as usize]).collect();
        assert_eq!(before, after, "the triangles keep their corners");
        for tri in m.indices.chunks(3) {
            let t0 = m.tangents[tri[0] as usize];
            for &i in tri {
                assert!(
                    same(m.tangents[i as usize], t0),
                    "one frame per triangle here"
                );
            }
        }
        assert!((m.tangents[m.indices[0] as usize].truncate() - Vec3::X).length() < 1e-5);
        assert!((m.tangents[m.indices[3] as usize].truncate() + Vec3::X).length() < 1e-5);
    }

    #[test]
    fn meshes_without_uvs_get_orthogonal_tangents() {
        let mut m = quad([Vec2::ZERO; 4]);
        m.uv0.clear();
        compute(&mut m);
        for (t, n) in m.tangents.iter().zip(&m.normals) {
            assert!(
                t.truncate().dot(*n).abs() < 1e-6 && (t.truncate().length() - 1.0).abs() < 1e-5
            );
        }
    }
}
