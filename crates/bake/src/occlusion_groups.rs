//! Occlusion groups of an animated scene's transfer bake (McKenzie Chapter §4.1: each mesh's
//! transfer is its own self-shadowing). In a scene with an animation, every moving instance
//! is a group of its own and the still instances one more: a texel's rays see only its
//! group's geometry, so the transfer stays true wherever the objects move. What moving
//! objects do to each other and to the still ones is then the business of hierarchical PRT's
//! filters (`crate::hprt`), not of the bake. `TransferSettings::self_only` makes every
//! instance a group of its own (McKenzie's per-mesh transfer), in any scene.

use crate::prt::{TransferSettings, VertexTransfer};
use lightlab_scene::Scene;
use lightlab_trace::Accel;

/// One group: the scene holding only its instances (in their order), its BVH, and the
/// per-vertex bounces inter-reflected transfer gathers from inside it.
pub(crate) struct Part {
    pub scene: Scene,
    pub accel: Accel,
    pub sources: Vec<VertexTransfer>,
}

/// The groups of a bake.
pub(crate) struct Groups {
    /// Group of each instance of the bake's scene.
    pub of_instance: Vec<usize>,
    pub parts: Vec<Part>,
}

/// The group of each instance: with `self_only` each its own; else 0 for the still ones and
/// 1, 2, … for each moving one; None for a still scene (one group: everything occludes
/// everything).
pub fn assign(scene: &Scene, self_only: bool) -> Option<Vec<usize>> {
    if self_only {
        return Some((0..scene.instances.len()).collect());
    }
    let a = scene.animation.as_ref()?;
    let mut next = 1;
    Some(
        (0..scene.instances.len())
            .map(|i| {
                if a.moves(i) {
                    next += 1;
                    next - 1
                } else {
                    0
                }
            })
            .collect(),
    )
}

/// Build the groups of `tscene` (the scene transfer is computed against).
pub(crate) fn build(
    tscene: &Scene,
    of_instance: Vec<usize>,
    s: &TransferSettings,
    with_sources: bool,
) -> Result<Groups, crate::BakeError> {
    let count = of_instance.iter().max().map_or(0, |m| m + 1);
    let mut parts = vec![];
    for g in 0..count {
        let mut scene = tscene.clone();
        scene.animation = None;
        scene.instances = tscene
            .instances
            .iter()
            .zip(&of_instance)
            .filter(|(_, og)| **og == g)
            .map(|(inst, _)| inst.clone())
            .collect();
        let accel = Accel::new(&scene);
        let sources = if with_sources
            && matches!(s.kind, crate::prt::TransferKind::Interreflected { .. })
            && !scene.instances.is_empty()
        {
            crate::prt::vertex_transfer(&scene, &accel, s)?.1
        } else {
            vec![]
        };
        parts.push(Part {
            scene,
            accel,
            sources,
        });
    }
    Ok(Groups { of_instance, parts })
}

/// Per-vertex transfer of `scene`, each moving object of an animated scene against its own
/// geometry only (the still scene: [`crate::prt::vertex_transfer`] as it is).
pub fn vertex_transfer(
    scene: &Scene,
    s: &TransferSettings,
) -> Result<VertexTransfer, crate::prt::TransferError> {
    let Some(of_instance) = assign(scene, s.self_only) else {
        return Ok(crate::prt::vertex_transfer(scene, &Accel::new(scene), s)?.0);
    };
    let mut out = VertexTransfer {
        bands: s.bands,
        instances: vec![vec![]; scene.instances.len()],
    };
    let count = of_instance.iter().max().map_or(0, |m| m + 1);
    for g in 0..count {
        let members: Vec<usize> = (0..scene.instances.len())
            .filter(|&i| of_instance[i] == g)
            .collect();
        if members.is_empty() {
            continue;
        }
        let mut part = scene.clone();
        part.animation = None;
        part.instances = members
            .iter()
            .map(|&i| scene.instances[i].clone())
            .collect();
        let vt = crate::prt::vertex_transfer(&part, &Accel::new(&part), s)?.0;
        for (i, t) in members.into_iter().zip(vt.instances) {
            out.instances[i] = t;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_instances_get_groups_of_their_own() {
        let s = lightlab_scene::builtin::builtin("prt-dynamic").unwrap();
        let g = assign(&s, false).unwrap();
        let moving: Vec<usize> = g.iter().copied().filter(|&x| x > 0).collect();
        assert_eq!(moving, vec![1, 2, 3]);
        assert_eq!(
            g.iter().filter(|&&x| x == 0).count(),
            144,
            "the ground's tiles"
        );
        let prt = lightlab_scene::builtin::builtin("prt").unwrap();
        assert!(assign(&prt, false).is_none());
        assert_eq!(assign(&prt, true).unwrap(), vec![0, 1, 2]);
    }
}
