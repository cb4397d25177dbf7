//! Shadowing hierarchies (McKenzie Chapter §5.1.3–5.1.4): trees of mesh nodes (leaves, one
//! instance each) and composite nodes (inner), one or more roots.
//!
//! Built three ways:
//! - [`Tree::flat`]: one root composite over every instance (McKenzie's test A);
//! - [`Tree::from_scene`]: the glTF node hierarchy (each instance's `nodes`, the names of the
//!   nodes above it) with the instance's name read as a path below it — `a/b/leaf` puts the
//!   leaf under the composites `a` and `a/b` ([`Tree::from_names`]); the built-in
//!   `prt-dynamic` groups its ground tiles under `ground` / `block_I_J`;
//! - [`Tree::by_proximity`]: single-linkage clustering of the instances' bounding boxes — two
//!   instances whose boxes lie within `gap` of each other share a composite — the automatic
//!   grouping the thesis leaves to future work. A cluster of one is a leaf of the root.
//! - or by hand, with [`Tree::add`]; several roots are separate trees, which never shadow
//!   each other.

use glam::Vec3;

/// One node.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub name: String,
    pub parent: Option<usize>,
    pub children: Vec<usize>,
    /// The instance of a mesh node; None for a composite.
    pub instance: Option<usize>,
}

/// A forest of shadowing hierarchies over a scene's instances.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tree {
    pub nodes: Vec<Node>,
}

impl Tree {
    /// Add a node under `parent`; returns its index.
    pub fn add(&mut self, name: &str, parent: Option<usize>, instance: Option<usize>) -> usize {
        let id = self.nodes.len();
        self.nodes.push(Node {
            name: name.into(),
            parent,
            children: vec![],
            instance,
        });
        if let Some(p) = parent {
            self.nodes[p].children.push(id);
        }
        id
    }

    /// One root over every instance.
    pub fn flat(instances: usize) -> Tree {
        let mut t = Tree::default();
        let root = t.add("root", None, None);
        for i in 0..instances {
            t.add(&format!("instance {i}"), Some(root), Some(i));
        }
        t
    }

    /// The tree the instance names spell (`a/b/leaf`), under one root.
    pub fn from_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Tree {
        Tree::from_paths(
            names
                .into_iter()
                .map(|n| n.split('/').map(String::from).collect()),
        )
    }

    /// The tree of a scene's glTF node hierarchy (`Instance::nodes`) with each instance's
    /// name read as a path below it, under one root.
    pub fn from_scene(scene: &lightlab_scene::Scene) -> Tree {
        Tree::from_paths(scene.instances.iter().map(|i| {
            let mut p = i.nodes.clone();
            p.extend(i.name.split('/').map(String::from));
            p
        }))
    }

    /// The tree of instance paths (each a list of names, the instance's own last).
    pub fn from_paths(paths: impl IntoIterator<Item = Vec<String>>) -> Tree {
        let mut t = Tree::default();
        let root = t.add("root", None, None);
        let mut composites: std::collections::HashMap<String, usize> = Default::default();
        for (i, parts) in paths.into_iter().enumerate() {
            let mut parent = root;
            let name = parts.join("/");
            for k in 0..parts.len().saturating_sub(1) {
                let path = parts[..=k].join("/");
                parent = *composites
                    .entry(path.clone())
                    .or_insert_with(|| t.add(&path, Some(parent), None));
            }
            t.add(&name, Some(parent), Some(i));
        }
        t
    }

    /// Single-linkage clusters of instance bounds within `gap` of each other, each cluster of
    /// two or more a composite under the root.
    pub fn by_proximity(bounds: &[(Vec3, Vec3)], gap: f32) -> Tree {
        let n = bounds.len();
        let mut cluster: Vec<usize> = (0..n).collect();
        fn find(c: &mut [usize], mut i: usize) -> usize {
            while c[i] != i {
                c[i] = c[c[i]];
                i = c[i];
            }
            i
        }
        for a in 0..n {
            for b in a + 1..n {
                if box_gap(bounds[a], bounds[b]) <= gap {
                    let (ra, rb) = (find(&mut cluster, a), find(&mut cluster, b));
                    cluster[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut t = Tree::default();
        let root = t.add("root", None, None);
        let mut composite: std::collections::HashMap<usize, usize> = Default::default();
        for i in 0..n {
            let r = find(&mut cluster, i);
            let members = (0..n).filter(|&j| find(&mut cluster, j) == r).count();
            let parent = if members > 1 {
                *composite
                    .entry(r)
                    .or_insert_with(|| t.add(&format!("cluster {r}"), Some(root), None))
            } else {
                root
            };
            t.add(&format!("instance {i}"), Some(parent), Some(i));
        }
        t
    }

    /// The mesh node of each instance (None where the tree leaves it out).
    pub fn leaf_of(&self, instances: usize) -> Vec<Option<usize>> {
        let mut out = vec![None; instances];
        for (k, n) in self.nodes.iter().enumerate() {
            if let Some(i) = n.instance.filter(|&i| i < instances) {
                out[i] = Some(k);
            }
        }
        out
    }

    /// The node's siblings: the other children of its parent. A root has none: separate
    /// trees never shadow each other (McKenzie §5.1.3: each group of nearby objects is its
    /// own shadowing hierarchy, which is what restricts the shadow checks).
    pub fn siblings(&self, node: usize) -> Vec<usize> {
        match self.nodes[node].parent {
            Some(p) => self.nodes[p]
                .children
                .iter()
                .copied()
                .filter(|&k| k != node)
                .collect(),
            None => vec![],
        }
    }

    /// What shadows a node's sample points, each occluder once: the siblings of the node and
    /// of each of its ancestors (the extraction's fix of the thesis's double subtraction).
    pub fn occluders(&self, node: usize) -> Vec<usize> {
        let mut out = vec![];
        let mut at = Some(node);
        while let Some(n) = at {
            out.extend(self.siblings(n));
            at = self.nodes[n].parent;
        }
        out
    }

    /// The instances under `node` (itself, for a mesh node).
    pub fn instances_under(&self, node: usize) -> Vec<usize> {
        let mut out = vec![];
        let mut stack = vec![node];
        while let Some(n) = stack.pop() {
            out.extend(self.nodes[n].instance);
            stack.extend(self.nodes[n].children.iter().copied());
        }
        out
    }

    /// `node` and its ancestors, the node first.
    pub fn path_up(&self, node: usize) -> Vec<usize> {
        let mut out = vec![node];
        while let Some(p) = self.nodes[*out.last().expect("non-empty")].parent {
            out.push(p);
        }
        out
    }

    /// Depth of the deepest node (a lone root: 0).
    pub fn depth(&self) -> usize {
        (0..self.nodes.len())
            .map(|k| self.path_up(k).len() - 1)
            .max()
            .unwrap_or(0)
    }
}

/// The distance between two boxes (0 when they touch or overlap).
pub fn box_gap(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> f32 {
    let d = (a.0 - b.1).max(b.0 - a.1).max(Vec3::ZERO);
    d.length()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_make_composites_and_occluder_sets_count_each_once() {
        let t = Tree::from_names(["ground/a", "ground/b", "ball", "rig/arm/hand", "rig/body"]);
        let leaf = t.leaf_of(5);
        let hand = leaf[3].unwrap();
        assert_eq!(t.path_up(hand).len(), 4, "hand, arm, rig, root");
        let occ: Vec<&str> = t
            .occluders(hand)
            .iter()
            .map(|&k| t.nodes[k].name.as_str())
            .collect();
        // The hand's arm has a sibling (body); the rig has ground and ball; the hand none.
        assert_eq!(occ, vec!["rig/body", "ground", "ball"]);
        let ground = t.nodes[leaf[0].unwrap()].parent.unwrap();
        assert_eq!(t.instances_under(ground).len(), 2);
        assert_eq!(t.depth(), 3);
    }

    #[test]
    fn proximity_groups_touching_boxes() {
        let b = |x: f32| (Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0));
        let t = Tree::by_proximity(&[b(0.0), b(1.05), b(5.0)], 0.1);
        let leaf = t.leaf_of(3);
        let p0 = t.nodes[leaf[0].unwrap()].parent;
        assert_eq!(p0, t.nodes[leaf[1].unwrap()].parent);
        assert_ne!(p0, Some(0), "the two near boxes share a composite");
        assert_eq!(t.nodes[leaf[2].unwrap()].parent, Some(0));
        assert!((box_gap(b(0.0), b(3.0)) - 2.0).abs() < 1e-6);
    }
}
