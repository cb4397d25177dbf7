//! An 8-wide BVH for the CPU, traversed with SIMD: eight child boxes tested at once (AVX via
//! `wide`'s f32x8), the hit children visited nearest first, and leaves of up to sixteen
//! triangles tested eight at a time (f32x8).
//!
//! The tree is built by obvhs (PLOC with pre-splits, re-insertion, SAH leaf collapse; see
//! [`build`]) as a binary BVH and collapsed here into 8-wide nodes by the surface-area-optimal
//! dynamic programme of Ylitie et al. (2017) ([`plan`]): each node's eight slots go to the
//! descendants that make its subtree cheapest, and a subtree becomes a leaf where that is
//! cheaper. Against the greedy collapse it replaced (open the child of largest surface area
//! until eight are reached) it filled prt's nodes with 6.5 children instead of 4.3 and traced
//! incoherent rays 8–10 % faster on prt, 4–6 % on bush (docs/reference-path-tracer.md).
//! Written here rather than
//! taken from obvhs: its compressed wide BVH (CWBVH) is laid out for GPUs (quantised child boxes,
//! octant-ordered children, one triangle at a time), and on a CPU it traversed incoherent rays
//! at about half of Embree's rate. This layout is Embree's for the CPU (full-precision child
//! boxes in structure-of-arrays form, distance-sorted traversal, eight-triangle blocks in the leaves; Embree uses four).
//!
//! Triangle blocks are eight wide, not Embree's four: on this AVX-512 machine a f32x8 test costs
//! what a f32x4 one does, and with the hit lanes read from a mask (no scan of eight distances
//! when nothing is hit) eight-wide blocks traced incoherent rays faster on every scene
//! (`lightlab bench trace`, 1 thread, median of four: prt 3.25 against 3.03 Mrays/s, bush 3.29
//! against 3.03, cornell 16.3 against 12.5).
//!
//! Traversal is per ray and deterministic: the same ray finds the same hit whatever thread casts
//! it.

use glam::Vec3;
use obvhs::triangle::Triangle;
use obvhs::{BvhBuildParams, bvh2::Bvh2};
use wide::{CmpGe, CmpGt, CmpLe, f32x8};

/// A child reference: an inner node's index, or `LEAF | first_block << 2 | (blocks − 1)`.
const LEAF: u32 = 1 << 31;
/// An unused child slot (its box is empty, so it is never entered).
const EMPTY: u32 = u32::MAX;
/// Triangles per leaf, at most (two blocks of eight).
pub const MAX_LEAF: u32 = 16;
/// Triangles per block, and the SIMD type that tests them.
const LANES: usize = 8;
type Tri = f32x8;

/// Eight children: their boxes (min x, y, z, max x, y, z; an empty slot has min +∞, max −∞)
/// and references.
#[repr(C, align(32))]
#[derive(Clone, Copy)]
struct Node8 {
    bounds: [f32x8; 6],
    child: [u32; 8],
}

impl Node8 {
    fn empty() -> Node8 {
        let inf = f32x8::splat(f32::INFINITY);
        Node8 {
            bounds: [inf, inf, inf, -inf, -inf, -inf],
            child: [EMPTY; 8],
        }
    }

    fn set(&mut self, lane: usize, min: Vec3, max: Vec3, child: u32) {
        for a in 0..3 {
            self.bounds[a].as_array_mut()[lane] = min[a];
            self.bounds[a + 3].as_array_mut()[lane] = max[a];
        }
        self.child[lane] = child;
    }
}

/// `LANES` triangles in structure-of-arrays form, as Möller–Trumbore reads them:
/// `e1 = v0 − v1`, `e2 = v2 − v0` (obvhs's `RtTriangle` layout; its `ng = e1 × e2` is
/// recomputed in the test). Unused lanes are all zero, which no ray hits (their determinant
/// is 0).
#[repr(C, align(32))]
#[derive(Clone, Copy)]
struct TriBlock {
    v0: [Tri; 3],
    e1: [Tri; 3],
    e2: [Tri; 3],
}

impl TriBlock {
    fn zeroed() -> TriBlock {
        let z = [Tri::ZERO; 3];
        TriBlock {
            v0: z,
            e1: z,
            e2: z,
        }
    }

    fn set(&mut self, lane: usize, t: &Triangle) {
        let (v0, v1, v2) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
        let e1 = v0 - v1;
        let e2 = v2 - v0;
        for a in 0..3 {
            self.v0[a].as_array_mut()[lane] = v0[a];
            self.e1[a].as_array_mut()[lane] = e1[a];
            self.e2[a].as_array_mut()[lane] = e2[a];
        }
    }
}

/// The 8-wide BVH. Triangles are addressed by *slot*: `LANES · block + lane`.
pub struct Bvh8 {
    nodes: Vec<Node8>,
    blocks: Vec<TriBlock>,
    /// Per block, the lanes whose triangle needs the caller's alpha test (bit k = lane k).
    alpha_lanes: Vec<u8>,
    /// Per slot, the index of the triangle in the input (`u32::MAX` for an unused lane).
    /// Pre-splits may list one triangle in several leaves.
    pub slot_triangle: Vec<u32>,
}

/// Nodes kept on a traversal's stack before it spills onto the heap (a tree this deep is
/// pathological; the spill keeps it correct).
const STACK: usize = 32;

/// A traversal stack of (child reference, entry distance).
struct Stack {
    items: [(u32, f32); STACK],
    len: usize,
    spill: Vec<(u32, f32)>,
}

impl Stack {
    #[inline(always)]
    fn new() -> Stack {
        Stack {
            items: [(0, 0.0); STACK],
            len: 0,
            spill: Vec::new(),
        }
    }
    #[inline(always)]
    fn push(&mut self, item: (u32, f32)) {
        if self.len < STACK {
            self.items[self.len] = item;
            self.len += 1;
        } else {
            self.spill.push(item);
        }
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        if let Some(item) = self.spill.pop() {
            return Some(item);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.items[self.len])
    }
}

/// A ray prepared for box tests: origin × inverse direction, inverse direction, and which
/// bound (min or max) is the near one per axis.
struct BoxRay {
    o_inv: [f32x8; 3],
    inv: [f32x8; 3],
    near: [usize; 3],
    far: [usize; 3],
}

impl BoxRay {
    #[inline(always)]
    fn new(o: Vec3, d: Vec3) -> BoxRay {
        // A zero component would give 0 · ∞ = NaN in the slab test: keep it tiny instead.
        // (Written out per axis: array `map`s were left as calls in the hot path.)
        let inv_of = |c: f32| {
            if c.abs() < 1e-30 {
                1.0 / 1e-30f32.copysign(c)
            } else {
                1.0 / c
            }
        };
        let inv = Vec3::new(inv_of(d.x), inv_of(d.y), inv_of(d.z));
        let oi = o * inv;
        let near_of = |a: usize| if inv[a] >= 0.0 { a } else { a + 3 };
        let near = [near_of(0), near_of(1), near_of(2)];
        BoxRay {
            o_inv: [f32x8::splat(oi.x), f32x8::splat(oi.y), f32x8::splat(oi.z)],
            inv: [
                f32x8::splat(inv.x),
                f32x8::splat(inv.y),
                f32x8::splat(inv.z),
            ],
            near,
            far: [(near[0] + 3) % 6, (near[1] + 3) % 6, (near[2] + 3) % 6],
        }
    }

    /// The children whose boxes the ray enters within [tmin, tmax] (bit k = child k), and the
    /// entry distances.
    #[inline(always)]
    fn test(&self, node: &Node8, tmin: f32, tmax: f32) -> (u32, f32x8) {
        let b = &node.bounds;
        let t = |i: usize, a: usize| b[i].mul_sub(self.inv[a], self.o_inv[a]);
        let tn = t(self.near[0], 0)
            .fast_max(t(self.near[1], 1))
            .fast_max(t(self.near[2], 2))
            .fast_max(f32x8::splat(tmin));
        // Widened by a few ulps so that rounding never loses a box the ray grazes (a flat box
        // around an axis-aligned floor, say).
        let tf = (t(self.far[0], 0)
            .fast_min(t(self.far[1], 1))
            .fast_min(t(self.far[2], 2))
            * f32x8::splat(1.0 + 4.0 * f32::EPSILON))
        .fast_min(f32x8::splat(tmax));
        (tn.cmp_le(tf).move_mask() as u32, tn)
    }
}

/// A ray splatted over the lanes of a triangle block.
struct TriRay {
    o: [Tri; 3],
    d: [Tri; 3],
}

impl TriRay {
    #[inline(always)]
    fn new(o: Vec3, d: Vec3) -> TriRay {
        TriRay {
            o: [Tri::splat(o.x), Tri::splat(o.y), Tri::splat(o.z)],
            d: [Tri::splat(d.x), Tri::splat(d.y), Tri::splat(d.z)],
        }
    }

    /// The lanes of `tri` hit within (tmin, tmax] (bit k = lane k) and the distances (valid
    /// in those lanes only).
    #[inline(always)]
    fn test(&self, tri: &TriBlock, tmin: f32, tmax: f32) -> (u32, Tri) {
        let [dx, dy, dz] = self.d;
        // The normal is recomputed rather than stored: a block is a quarter smaller (288 bytes),
        // and the traversal waits on memory more than on arithmetic (prt and bush within
        // noise of the stored normal, +2 %).
        let [e1, e2] = [&tri.e1, &tri.e2];
        let ng = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let det = ng[0] * dx + ng[1] * dy + ng[2] * dz;
        let c = [
            tri.v0[0] - self.o[0],
            tri.v0[1] - self.o[1],
            tri.v0[2] - self.o[2],
        ];
        let r = [
            dy * c[2] - dz * c[1],
            dz * c[0] - dx * c[2],
            dx * c[1] - dy * c[0],
        ];
        // Barycentrics and distance scaled by |det| (the sign folded in), so that the division
        // waits until some lane is hit.
        let sign = det & Tri::splat(-0.0);
        let abs_det = det ^ sign;
        let u = (r[0] * tri.e2[0] + r[1] * tri.e2[1] + r[2] * tri.e2[2]) ^ sign;
        let v = (r[0] * tri.e1[0] + r[1] * tri.e1[1] + r[2] * tri.e1[2]) ^ sign;
        let hit = abs_det.cmp_gt(Tri::ZERO)
            & u.cmp_ge(Tri::ZERO)
            & v.cmp_ge(Tri::ZERO)
            & (u + v).cmp_le(abs_det);
        if hit.none() {
            return (0, Tri::ZERO);
        }
        let t = ((ng[0] * c[0] + ng[1] * c[1] + ng[2] * c[2]) ^ sign) / abs_det;
        let hit = hit & t.cmp_gt(Tri::splat(tmin)) & t.cmp_le(Tri::splat(tmax));
        (hit.move_mask() as u32, t)
    }
}

/// The cost model of the collapse: a visit to an 8-wide node (eight box tests) and the test of
/// one block of eight triangles, each paid in proportion to the surface area of the box that
/// leads to it (the surface area heuristic).
#[derive(Clone, Copy, Debug)]
pub struct WideCosts {
    pub node: f32,
    pub block: f32,
}

impl Default for WideCosts {
    /// Equal costs: block costs from 0.6 to 2.5 node visits traced incoherent rays within
    /// noise of each other on prt and bush (docs/reference-path-tracer.md).
    fn default() -> Self {
        WideCosts {
            node: 1.0,
            block: 1.0,
        }
    }
}

/// Per binary node, the cheapest way to cover its subtree with up to i = 1..=8 slots of an
/// 8-wide node.
#[derive(Clone, Copy, Default)]
struct Plan {
    /// `cost[i − 1]`: with at most i slots.
    cost: [f32; 8],
    /// `split[i − 1]`: slots given to the first child (the rest to the second), or 0 where the
    /// node itself takes one slot.
    split: [u8; 8],
    /// As one slot: a leaf of all its triangles (else an 8-wide node).
    leaf: bool,
    /// As an 8-wide node: the slots its first child gets of the eight.
    inner_split: u8,
}

/// The optimal collapse of the binary tree into 8-wide nodes under `costs` (the dynamic
/// programme of Ylitie, Karras and Laine 2017, "Efficient incoherent ray traversal on GPUs
/// through compressed wide BVHs", with leaves priced per block of eight triangles instead of
/// per triangle). A subtree becomes a leaf where it holds at most [`MAX_LEAF`] triangles and
/// that is cheaper than a node over its parts; a node's eight slots go to the descendants that
/// make the subtree cheapest.
fn plan(b2: &Bvh2, costs: WideCosts) -> Vec<Plan> {
    // Pre-order from the root; reversed, every child comes before its parent.
    let mut order = Vec::with_capacity(b2.nodes.len());
    let mut stack = vec![0usize];
    while let Some(k) = stack.pop() {
        order.push(k);
        let node = &b2.nodes[k];
        if node.prim_count == 0 {
            stack.extend([node.first_index as usize, node.first_index as usize + 1]);
        }
    }
    let mut plans = vec![Plan::default(); b2.nodes.len()];
    let mut count = vec![0u32; b2.nodes.len()];
    for &k in order.iter().rev() {
        let node = &b2.nodes[k];
        let area = node.aabb.half_area();
        let kids = (node.prim_count == 0)
            .then(|| (node.first_index as usize, node.first_index as usize + 1));
        let n = match kids {
            None => node.prim_count,
            Some((l, r)) => count[l] + count[r],
        };
        count[k] = n;
        let leaf_cost = if n <= MAX_LEAF || kids.is_none() {
            area * costs.block * n.div_ceil(LANES as u32) as f32
        } else {
            f32::INFINITY
        };
        let mut p = Plan::default();
        let (mut inner_cost, mut inner_split) = (f32::INFINITY, 0u8);
        if let Some((l, r)) = kids {
            for j in 1..8 {
                let c = plans[l].cost[j - 1] + plans[r].cost[8 - j - 1];
                if c < inner_cost {
                    (inner_cost, inner_split) = (c, j as u8);
                }
            }
            inner_cost += area * costs.node;
        }
        p.leaf = leaf_cost <= inner_cost;
        p.inner_split = inner_split;
        let single = leaf_cost.min(inner_cost);
        for i in 1..=8 {
            let (mut best, mut split) = (single, 0u8);
            if let Some((l, r)) = kids {
                for j in 1..i {
                    let c = plans[l].cost[j - 1] + plans[r].cost[i - j - 1];
                    if c < best {
                        (best, split) = (c, j as u8);
                    }
                }
            }
            p.cost[i - 1] = best;
            p.split[i - 1] = split;
        }
        plans[k] = p;
    }
    plans
}

/// The binary nodes that take the (at most) `i` slots given to `n`'s subtree.
fn slots(b2: &Bvh2, plans: &[Plan], n: usize, i: usize, out: &mut Vec<usize>) {
    match plans[n].split[i - 1] as usize {
        0 => out.push(n),
        j => {
            let first = b2.nodes[n].first_index as usize;
            slots(b2, plans, first, j, out);
            slots(b2, plans, first + 1, i - j, out);
        }
    }
}

/// The triangles under binary node `n`, each once (pre-splits may list one in several leaves).
fn subtree_prims(b2: &Bvh2, n: usize) -> Vec<u32> {
    let mut prims = Vec::new();
    let mut stack = vec![n];
    while let Some(k) = stack.pop() {
        let node = &b2.nodes[k];
        if node.prim_count == 0 {
            stack.extend([node.first_index as usize + 1, node.first_index as usize]);
        } else {
            let first = node.first_index as usize;
            for &p in &b2.primitive_indices[first..first + node.prim_count as usize] {
                if !prims.contains(&p) {
                    prims.push(p);
                }
            }
        }
    }
    prims
}

impl Bvh8 {
    /// Build over `tris`; `alpha(i)` says whether input triangle i needs the alpha test.
    pub fn build(
        tris: &[Triangle],
        params: BvhBuildParams,
        costs: WideCosts,
        alpha: impl Fn(usize) -> bool,
    ) -> Bvh8 {
        let params = BvhBuildParams {
            max_prims_per_leaf: params.max_prims_per_leaf.clamp(1, MAX_LEAF),
            ..params
        };
        let b2 = obvhs::bvh2::builder::build_bvh2_from_tris(
            tris,
            params,
            &mut std::time::Duration::default(),
        );
        let mut bvh = Bvh8 {
            nodes: vec![],
            blocks: vec![],
            alpha_lanes: vec![],
            slot_triangle: vec![],
        };
        if tris.is_empty() || b2.nodes.is_empty() {
            bvh.nodes.push(Node8::empty());
            return bvh;
        }
        bvh.collapse(&b2, tris, costs, &alpha);
        bvh
    }

    /// Turn the binary tree into 8-wide nodes, as [`plan`] chose them. A node's inner children
    /// are laid out next to each other (and its leaves' blocks likewise), subtrees depth first
    /// after them.
    fn collapse(
        &mut self,
        b2: &Bvh2,
        tris: &[Triangle],
        costs: WideCosts,
        alpha: &impl Fn(usize) -> bool,
    ) {
        let plans = plan(b2, costs);
        self.nodes.push(Node8::empty());
        if b2.nodes[0].prim_count > 0 {
            let prims = subtree_prims(b2, 0);
            let a = &b2.nodes[0].aabb;
            let reference = self.leaf(&prims, tris, alpha);
            self.nodes[0].set(0, a.min.into(), a.max.into(), reference);
            return;
        }
        // (binary node, the 8-wide node made of it, allocated already).
        let mut work: Vec<(usize, usize)> = vec![(0, 0)];
        let mut kids = Vec::with_capacity(8);
        while let Some((n, me)) = work.pop() {
            kids.clear();
            let first = b2.nodes[n].first_index as usize;
            let j = plans[n].inner_split as usize;
            slots(b2, &plans, first, j, &mut kids);
            slots(b2, &plans, first + 1, 8 - j, &mut kids);
            let mut inner = vec![];
            for (l, &k) in kids.iter().enumerate() {
                let a = &b2.nodes[k].aabb;
                let reference = if plans[k].leaf {
                    self.leaf(&subtree_prims(b2, k), tris, alpha)
                } else {
                    self.nodes.push(Node8::empty());
                    inner.push((k, self.nodes.len() - 1));
                    (self.nodes.len() - 1) as u32
                };
                self.nodes[me].set(l, a.min.into(), a.max.into(), reference);
            }
            // In reverse, so that the first child's subtree is laid out first.
            work.extend(inner.into_iter().rev());
        }
    }

    /// A leaf of the triangles `prims` (at most [`MAX_LEAF`]) as blocks of `LANES`; its child
    /// reference.
    fn leaf(&mut self, prims: &[u32], tris: &[Triangle], alpha: &impl Fn(usize) -> bool) -> u32 {
        let block0 = self.blocks.len();
        for chunk in prims.chunks(LANES) {
            let mut block = TriBlock::zeroed();
            let mut mask = 0u8;
            for (lane, &p) in chunk.iter().enumerate() {
                block.set(lane, &tris[p as usize]);
                if alpha(p as usize) {
                    mask |= 1 << lane;
                }
            }
            self.blocks.push(block);
            self.alpha_lanes.push(mask);
            self.slot_triangle.extend(chunk.iter().copied());
            self.slot_triangle
                .extend(std::iter::repeat_n(u32::MAX, LANES - chunk.len()));
        }
        let blocks = (self.blocks.len() - block0) as u32;
        debug_assert!((1..=4).contains(&blocks));
        LEAF | (block0 as u32) << 2 | (blocks - 1)
    }

    /// The closest hit along `o + t·d`, t ∈ (tmin, tmax]: (slot, t). `reject(slot, t)` is
    /// asked for the triangles built with the alpha test: true lets the ray through.
    #[inline]
    pub fn closest(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        mut tmax: f32,
        mut reject: impl FnMut(usize, f32) -> bool,
    ) -> Option<(u32, f32)> {
        let boxes = BoxRay::new(o, d);
        let ray = TriRay::new(o, d);
        let mut stack = Stack::new();
        let mut best = None;
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mut mask, tn) = boxes.test(node, tmin, tmax);
                if mask != 0 {
                    let tn = tn.as_array_ref();
                    let first = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        cur = node.child[first];
                        continue;
                    }
                    // Two or more: push all but the nearest, farthest first.
                    let mut hits = [(0u32, 0f32); 8];
                    let mut n = 0;
                    hits[n] = (node.child[first], tn[first]);
                    n += 1;
                    while mask != 0 {
                        let k = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        // Insertion by distance, descending.
                        let item = (node.child[k], tn[k]);
                        let mut j = n;
                        while j > 0 && hits[j - 1].1 < item.1 {
                            hits[j] = hits[j - 1];
                            j -= 1;
                        }
                        hits[j] = item;
                        n += 1;
                    }
                    for &h in &hits[..n - 1] {
                        stack.push(h);
                    }
                    cur = hits[n - 1].0;
                    continue;
                }
            } else {
                let block0 = ((cur & !LEAF) >> 2) as usize;
                for b in block0..=block0 + (cur & 3) as usize {
                    let (mut live, t) = ray.test(&self.blocks[b], tmin, tmax);
                    if live == 0 {
                        continue;
                    }
                    let t = t.as_array_ref();
                    let alpha = self.alpha_lanes[b] as u32;
                    while live != 0 {
                        // The nearest live lane, the first of equals.
                        let mut k = live.trailing_zeros() as usize;
                        let mut rest = live & (live - 1);
                        while rest != 0 {
                            let j = rest.trailing_zeros() as usize;
                            rest &= rest - 1;
                            if t[j] < t[k] {
                                k = j;
                            }
                        }
                        let slot = LANES * b + k;
                        if alpha & (1 << k) != 0 && reject(slot, t[k]) {
                            live &= !(1 << k);
                            continue;
                        }
                        tmax = t[k];
                        best = Some((slot as u32, t[k]));
                        break;
                    }
                }
            }
            // Next: the nearest pushed child still in reach.
            loop {
                match stack.pop() {
                    None => return best,
                    Some((c, t)) if t <= tmax => {
                        cur = c;
                        break;
                    }
                    Some(_) => {}
                }
            }
        }
    }

    /// Whether anything (that `reject` does not let through) lies along `o + t·d`,
    /// t ∈ (tmin, tmax].
    #[inline]
    pub fn any(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        mut reject: impl FnMut(usize, f32) -> bool,
    ) -> bool {
        let boxes = BoxRay::new(o, d);
        let ray = TriRay::new(o, d);
        let mut stack = Stack::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mut mask, _) = boxes.test(node, tmin, tmax);
                while mask != 0 {
                    let k = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    stack.push((node.child[k], 0.0));
                }
            } else {
                let block0 = ((cur & !LEAF) >> 2) as usize;
                for b in block0..=block0 + (cur & 3) as usize {
                    let (mut live, t) = ray.test(&self.blocks[b], tmin, tmax);
                    let alpha = self.alpha_lanes[b] as u32;
                    if live & !alpha != 0 {
                        return true;
                    }
                    let t = t.as_array_ref();
                    while live != 0 {
                        let k = live.trailing_zeros() as usize;
                        live &= live - 1;
                        if !reject(LANES * b + k, t[k]) {
                            return true;
                        }
                    }
                }
            }
            match stack.pop() {
                None => return false,
                Some((c, _)) => cur = c,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;
    use lightlab_core::sampling::{Rng, uniform_sphere};

    /// Scalar Möller–Trumbore, written independently of the SIMD one.
    fn brute(tris: &[Triangle], o: Vec3, d: Vec3, tmax: f32) -> Option<(usize, f32)> {
        let mut best: Option<(usize, f32)> = None;
        for (i, t) in tris.iter().enumerate() {
            let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
            let (e1, e2) = (b - a, c - a);
            let p = d.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-12 {
                continue;
            }
            let s = o - a;
            let u = s.dot(p) / det;
            let q = s.cross(e1);
            let v = d.dot(q) / det;
            let t = e2.dot(q) / det;
            if u >= 0.0
                && v >= 0.0
                && u + v <= 1.0
                && t > 0.0
                && t <= tmax
                && best.is_none_or(|(_, bt)| t < bt)
            {
                best = Some((i, t));
            }
        }
        best
    }

    fn soup(n: usize, seed: u64) -> Vec<Triangle> {
        let mut rng = Rng::new(seed, 0);
        (0..n)
            .map(|_| {
                let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0 - 5.0;
                let mut v = || Vec3A::from(c + uniform_sphere(rng.next_vec2()) * 0.6);
                Triangle {
                    v0: v(),
                    v1: v(),
                    v2: v(),
                }
            })
            .collect()
    }

    fn check(tris: &[Triangle], rays: usize, seed: u64) {
        let bvh = Bvh8::build(
            tris,
            BvhBuildParams::slow_build(),
            WideCosts::default(),
            |_| false,
        );
        let mut rng = Rng::new(seed, 1);
        let (mut hits, mut near_ties) = (0, 0);
        for k in 0..rays {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 14.0 - 7.0;
            let mut d = uniform_sphere(rng.next_vec2());
            if k % 2 == 0 {
                // Aimed at (near) a triangle, so that small scenes are hit too.
                let t = &tris[(rng.next_f32() * tris.len() as f32) as usize % tris.len()];
                let (u, v) = (rng.next_f32(), rng.next_f32());
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                let aim = Vec3::from(t.v0 + (t.v1 - t.v0) * u + (t.v2 - t.v0) * v)
                    + uniform_sphere(rng.next_vec2()) * 0.01;
                d = (aim - o).normalize();
            }
            if k % 7 == 0 {
                // Axis-aligned directions, zero components included.
                d = [Vec3::X, -Vec3::Y, Vec3::Z, -Vec3::X][k % 4] + Vec3::ZERO;
            }
            let tmax = if k % 3 == 0 { 4.0 } else { f32::INFINITY };
            let want = brute(tris, o, d, tmax);
            let got = bvh.closest(o, d, 0.0, tmax, |_, _| false);
            assert_eq!(
                bvh.any(o, d, 0.0, tmax, |_, _| false),
                got.is_some(),
                "ray {k}"
            );
            match (want, got) {
                (None, None) => {}
                (Some((_, wt)), Some((slot, gt))) => {
                    hits += 1;
                    assert!(
                        (wt - gt).abs() <= 1e-4 * wt.max(1.0),
                        "ray {k}: {wt} vs {gt}"
                    );
                    let i = bvh.slot_triangle[slot as usize] as usize;
                    if brute(&tris[i..=i], o, d, tmax).is_none() {
                        near_ties += 1;
                    }
                }
                // A ray through a shared edge or a vertex may be claimed by either side.
                (w, g) => panic!("ray {k}: brute force {w:?}, BVH {g:?}"),
            }
        }
        assert!(hits > rays / 5, "only {hits} hits");
        assert!(
            near_ties <= rays / 1000,
            "{near_ties} hits the brute force rejects"
        );
    }

    #[test]
    fn closest_and_any_hit_match_brute_force() {
        check(&soup(3000, 1), 4000, 2);
        check(&soup(40, 3), 2000, 4);
        check(&soup(1, 5), 500, 6);
    }

    #[test]
    fn many_identical_triangles_stay_correct() {
        // Identical boxes give the builder no order: a deep tree, possibly a stack spill.
        let t = soup(1, 9)[0];
        check(&vec![t; 5000], 500, 10);
    }

    #[test]
    fn an_empty_tree_is_never_hit() {
        let bvh = Bvh8::build(
            &[],
            BvhBuildParams::slow_build(),
            WideCosts::default(),
            |_| false,
        );
        assert!(
            bvh.closest(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY, |_, _| false)
                .is_none()
        );
        assert!(!bvh.any(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY, |_, _| false));
    }

    #[test]
    fn rejected_hits_let_rays_through_to_the_next() {
        // Two parallel squares (two triangles each) along −z; the nearer one is a hole.
        let quad = |z: f32| {
            let p = |x: f32, y: f32| Vec3A::new(x, y, z);
            [
                Triangle {
                    v0: p(-1.0, -1.0),
                    v1: p(1.0, -1.0),
                    v2: p(1.0, 1.0),
                },
                Triangle {
                    v0: p(-1.0, -1.0),
                    v1: p(1.0, 1.0),
                    v2: p(-1.0, 1.0),
                },
            ]
        };
        let tris: Vec<Triangle> = quad(-1.0).into_iter().chain(quad(-2.0)).collect();
        let bvh = Bvh8::build(
            &tris,
            BvhBuildParams::slow_build(),
            WideCosts::default(),
            |i| i < 2,
        );
        let hole = |slot: usize, _t: f32| bvh.slot_triangle[slot] < 2;
        let o = Vec3::new(0.3, 0.1, 0.0);
        let (slot, t) = bvh.closest(o, -Vec3::Z, 0.0, f32::INFINITY, hole).unwrap();
        assert_eq!(t, 2.0);
        assert!(bvh.slot_triangle[slot as usize] >= 2);
        assert!(!bvh.any(o, -Vec3::Z, 0.0, 1.5, hole));
        assert!(bvh.any(o, -Vec3::Z, 0.0, 2.5, hole));
        let (_, t) = bvh
            .closest(o, -Vec3::Z, 0.0, f32::INFINITY, |_, _| false)
            .unwrap();
        assert_eq!(t, 1.0);
    }

    #[test]
    fn the_collapse_fills_nodes_and_covers_every_triangle() {
        let tris = soup(20_000, 11);
        let bvh = Bvh8::build(
            &tris,
            BvhBuildParams::slow_build(),
            WideCosts::default(),
            |_| false,
        );
        let used = |n: &Node8| n.child.iter().filter(|&&c| c != EMPTY).count();
        let children: usize = bvh.nodes.iter().map(used).sum();
        let fill = children as f64 / bvh.nodes.len() as f64;
        // The greedy collapse (open the widest child) averaged 4.3 children here.
        assert!(fill > 6.0, "{fill:.2} children per node");
        let mut seen = vec![false; tris.len()];
        for &t in bvh.slot_triangle.iter().filter(|&&t| t != u32::MAX) {
            seen[t as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        let leaves = bvh
            .nodes
            .iter()
            .flat_map(|n| n.child)
            .filter(|&c| c != EMPTY && c & LEAF != 0);
        assert!(
            leaves
                .map(|c| (c & 3) + 1)
                .all(|b| b * LANES as u32 <= MAX_LEAF)
        );
    }
}
