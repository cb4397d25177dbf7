//! Mesh simplification (decimation) through meshoptimizer's edge-collapse simplifier (the
//! `meshopt` crate, a maintained binding of zeux's C++ library: it preserves topology and
//! attribute seams and reports the error it reached — nothing to gain from writing our own).
//!
//! What lightlab adds around it:
//! - **Seam snapping.** Procedural and imported meshes often duplicate vertices along UV seams
//!   with positions that differ in the last bits (a closed surface evaluated at u = 0 and u = 1).
//!   meshoptimizer recognises a seam only where positions are bit-identical, and would tear the
//!   surface open elsewhere; positions within `weld` of each other are snapped to one value first
//!   (vertices stay distinct, so UV seams survive).
//! - **Compaction** of the vertex buffer to the vertices still referenced.
//! - **Normals** recomputed on the decimated surface, area-weighted and smoothed across seams
//!   (the high-poly normals at the surviving vertices describe the detail the decimation removed;
//!   that detail is baked into textures instead, see `lightlab_bake::prt`'s detail transfer).
//!
//! The result names its source: `detail_source` = the high-poly mesh, which the bakers use to
//! bake normals and occlusion onto the decimated copy (McKenzie Chapter 2010 §4.2, §6.2.2).

use crate::model::Mesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// What to aim for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimplifySettings {
    /// Target triangle count (the simplifier may stop above it when the error bound or the
    /// topology forbids further collapses).
    pub target_triangles: usize,
    /// Largest allowed deviation, relative to the mesh's extent (meshoptimizer's measure).
    pub max_error: f32,
    /// Positions closer than this (relative to the extent) are snapped together.
    pub weld: f32,
}

impl Default for SimplifySettings {
    fn default() -> Self {
        SimplifySettings {
            target_triangles: 1000,
            max_error: 0.05,
            weld: 1e-5,
        }
    }
}

/// The decimated mesh and what the simplifier reached.
#[derive(Clone, Debug)]
pub struct Simplified {
    pub mesh: Mesh,
    /// The deviation reached, relative to the mesh's extent.
    pub error: f32,
}

/// Errors of simplification.
#[derive(Debug, thiserror::Error)]
pub enum SimplifyError {
    #[error("mesh '{0}' has no triangles to simplify")]
    Empty(String),
    #[error("mesh '{mesh}': {problem}")]
    Settings { mesh: String, problem: String },
}

/// Snap positions closer than `eps` (absolute) to the first of them. Returns for each vertex
/// the index of its position group's representative.
fn snap_groups(positions: &[Vec3], eps: f32) -> Vec<u32> {
    let cell = |p: Vec3| (p / eps).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    let mut group = vec![0u32; positions.len()];
    for (i, &p) in positions.iter().enumerate() {
        let c = cell(p);
        let mut found = None;
        'search: for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(list) = grid.get(&(c + glam::IVec3::new(dx, dy, dz)))
                        && let Some(&j) = list
                            .iter()
                            .find(|&&j| positions[j as usize].distance(p) <= eps)
                    {
                        found = Some(j);
                        break 'search;
                    }
                }
            }
        }
        match found {
            Some(j) => group[i] = group[j as usize],
            None => {
                group[i] = i as u32;
                grid.entry(c).or_default().push(i as u32);
            }
        }
    }
    group
}

/// Decimate `mesh` (index `source` in its scene) with meshoptimizer.
pub fn simplify(
    mesh: &Mesh,
    source: usize,
    s: &SimplifySettings,
) -> Result<Simplified, SimplifyError> {
    if mesh.indices.len() < 3 || mesh.positions.is_empty() {
        return Err(SimplifyError::Empty(mesh.name.clone()));
    }
    let positive = |v: f32| v.is_finite() && v > 0.0;
    if s.target_triangles == 0 || !positive(s.max_error) || !(s.weld == 0.0 || positive(s.weld)) {
        return Err(SimplifyError::Settings {
            mesh: mesh.name.clone(),
            problem: format!(
                "target triangles must be ≥ 1 and the error bound > 0 (got {} and {})",
                s.target_triangles, s.max_error
            ),
        });
    }
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let extent = (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let group = snap_groups(&mesh.positions, s.weld * extent);
    let snapped: Vec<[f32; 3]> = group
        .iter()
        .map(|&g| mesh.positions[g as usize].to_array())
        .collect();
    let bytes: Vec<u8> = snapped
        .iter()
        .flat_map(|p| p.iter().flat_map(|f| f.to_le_bytes()))
        .collect();
    let adapter =
        meshopt::VertexDataAdapter::new(&bytes, 12, 0).map_err(|e| SimplifyError::Settings {
            mesh: mesh.name.clone(),
            problem: format!("vertex data: {e:?}"),
        })?;
    let mut error = 0.0f32;
    let indices = meshopt::simplify(
        &mesh.indices,
        &adapter,
        s.target_triangles * 3,
        s.max_error,
        meshopt::SimplifyOptions::empty(),
        Some(&mut error),
    );
    if indices.is_empty() {
        return Err(SimplifyError::Empty(mesh.name.clone()));
    }
    // Compact: the vertices still referenced, in first-use order.
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    let mut kept = vec![];
    let new_indices: Vec<u32> = indices
        .iter()
        .map(|&i| {
            if remap[i as usize] == u32::MAX {
                remap[i as usize] = kept.len() as u32;
                kept.push(i as usize);
            }
            remap[i as usize]
        })
        .collect();
    let pick2 = |v: &[Vec2]| -> Vec<Vec2> {
        if v.len() == mesh.positions.len() {
            kept.iter().map(|&i| v[i]).collect()
        } else {
            vec![]
        }
    };
    let mut out = Mesh {
        name: format!("{}_simplified", mesh.name),
        positions: kept.iter().map(|&i| Vec3::from_array(snapped[i])).collect(),
        normals: vec![],
        tangents: vec![],
        uv0: pick2(&mesh.uv0),
        uv1: None,
        colors: if mesh.colors.len() == mesh.positions.len() {
            kept.iter().map(|&i| mesh.colors[i]).collect()
        } else {
            vec![]
        },
        indices: new_indices,
        material: mesh.material,
        detail_source: Some(source),
    };
    // Area-weighted normals, summed over each position group so that seams stay smooth.
    let groups: Vec<u32> = kept.iter().map(|&i| group[i]).collect();
    let mut acc: HashMap<u32, Vec3> = HashMap::new();
    for t in out.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| out.positions[i as usize]);
        let f = (b - a).cross(c - a);
        for &i in t {
            *acc.entry(groups[i as usize]).or_default() += f;
        }
    }
    out.normals = groups
        .iter()
        .map(|g| acc.get(g).copied().unwrap_or(Vec3::Y).normalize_or(Vec3::Y))
        .collect();
    if !mesh.tangents.is_empty() && !out.uv0.is_empty() {
        out.compute_tangents();
    }
    Ok(Simplified { mesh: out, error })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin::geom::ridged_torus_knot;

    #[test]
    fn decimated_knot_stays_closed_and_close() {
        let high = ridged_torus_knot("k", 2.0, 3.0, 1.0, 0.22, 7.0, 0.35, 300, 24, 0);
        let s = simplify(
            &high,
            3,
            &SimplifySettings {
                target_triangles: 1500,
                max_error: 0.05,
                weld: 1e-5,
            },
        )
        .unwrap();
        let m = &s.mesh;
        assert_eq!(m.detail_source, Some(3));
        assert!(
            m.triangle_count() <= 1600,
            "{} triangles",
            m.triangle_count()
        );
        assert!(
            m.triangle_count() >= 500,
            "{} triangles",
            m.triangle_count()
        );
        assert!(s.error <= 0.05, "error {}", s.error);
        // Closed: every edge (by snapped position) has exactly one opposite.
        let key = |p: Vec3| (p * 1e4).round().as_ivec3().to_array();
        let mut edges: HashMap<([i32; 3], [i32; 3]), i32> = HashMap::new();
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (
                    key(m.positions[t[k] as usize]),
                    key(m.positions[t[(k + 1) % 3] as usize]),
                );
                *edges.entry((a, b)).or_default() += 1;
                *edges.entry((b, a)).or_default() -= 1;
            }
        }
        let open = edges.values().filter(|&&c| c != 0).count();
        assert_eq!(open, 0, "{open} unmatched directed edges");
        // Outward-facing like the source, unit normals.
        let signed_volume: f32 = m
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(signed_volume > 0.0, "inside out: {signed_volume}");
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((n.length() - 1.0).abs() < 1e-4);
            assert!(p.is_finite());
        }
    }

    #[test]
    fn bad_settings_are_errors() {
        let high = ridged_torus_knot("k", 2.0, 3.0, 1.0, 0.22, 7.0, 0.35, 30, 8, 0);
        let bad = SimplifySettings {
            target_triangles: 0,
            ..Default::default()
        };
        assert!(matches!(
            simplify(&high, 0, &bad),
            Err(SimplifyError::Settings { .. })
        ));
        let empty = Mesh::default();
        assert!(matches!(
            simplify(&empty, 0, &Default::default()),
            Err(SimplifyError::Empty(_))
        ));
    }
}
