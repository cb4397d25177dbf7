//! Seam stitching (Fuchs §3.3.6 step 2, generalised).
//!
//! A seam is a place where one continuous surface is stored twice in the light-map: an edge
//! where the unwrap cut a smooth mesh into two charts, or an edge where two coplanar,
//! same-facing faces meet (CaLight's "neighbour surfaces": different meshes, such as wall
//! pieces around a window). Bilinear sampling on the two sides reads different texels, so the
//! rendered light jumps there unless the texels agree.
//!
//! The seams are found geometrically: chart-boundary edges (triangle edges with no neighbour of
//! the same UVs in their instance) that are collinear and overlapping with another such edge,
//! with nearly parallel normals and their triangles on opposite sides. Along each shared
//! stretch, sample pairs are placed every half texel; each pair asks that the bilinear
//! light-map values on both sides be equal. A Gauss–Seidel least-squares pass moves the texels
//! of each pair's two footprints towards their mean until the sides agree.
//!
//! Anti-bleeding (CaLight's visibility guard): a pair is used only where the texels of both
//! footprints held valid samples before repair, so two floors meeting under a wall are not
//! stitched through it.

use crate::layout::Layout;
use glam::{Vec2, Vec3};
use lightlab_core::image::Image;
use lightlab_scene::Scene;

/// What stitching did.
#[derive(Clone, Copy, Debug, Default)]
pub struct StitchReport {
    pub pairs: usize,
    /// Largest |a−b| / max(mean(a,b), floor) over the pairs after stitching.
    pub max_difference: f32,
}

/// One seam sample pair: page coordinates on each side.
#[derive(Clone, Copy, Debug)]
pub struct SeamPair {
    pub a: (u32, Vec2),
    pub b: (u32, Vec2),
    /// World position.
    pub p: Vec3,
}

#[derive(Clone, Copy)]
struct BEdge {
    a: Vec3,
    b: Vec3,
    /// Third vertex of the triangle (to know its side).
    c: Vec3,
    n: Vec3,
    page: u32,
    ua: Vec2,
    ub: Vec2,
    /// Page size in texels.
    size: Vec2,
}

/// Find seam sample pairs of a laid-out scene.
pub fn find_pairs(scene: &Scene, layout: &Layout) -> Vec<SeamPair> {
    let mut edges: Vec<BEdge> = vec![];
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for pl in layout.placed(scene) {
        let (inst, mesh, rect, uv1) = (pl.instance, pl.mesh, pl.rect, pl.uv1);
        let size = layout.page_size(rect.page);
        // Count edges by (position, uv) keys: interior chart edges appear twice.
        let key = |i: u32| {
            let p = mesh.positions[i as usize];
            let u = uv1[i as usize];
            (
                p.x.to_bits(),
                p.y.to_bits(),
                p.z.to_bits(),
                u.x.to_bits(),
                u.y.to_bits(),
            )
        };
        let mut count: std::collections::HashMap<_, u32> = Default::default();
        for t in mesh.indices.chunks_exact(3) {
            for k in 0..3 {
                let (i, j) = (key(t[k]), key(t[(k + 1) % 3]));
                let e = if i < j { (i, j) } else { (j, i) };
                *count.entry(e).or_default() += 1;
            }
        }
        for t in mesh.indices.chunks_exact(3) {
            let pw = [t[0], t[1], t[2]]
                .map(|i| inst.transform.transform_point3(mesh.positions[i as usize]));
            let n = (pw[1] - pw[0]).cross(pw[2] - pw[0]).normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            for k in 0..3 {
                let (i, j) = (key(t[k]), key(t[(k + 1) % 3]));
                let e = if i < j { (i, j) } else { (j, i) };
                if count[&e] != 1 {
                    continue;
                }
                let (a, b, c) = (pw[k], pw[(k + 1) % 3], pw[(k + 2) % 3]);
                lo = lo.min(a).min(b);
                hi = hi.max(a).max(b);
                edges.push(BEdge {
                    a,
                    b,
                    c,
                    n,
                    page: rect.page,
                    ua: rect.page_uv(uv1[t[k] as usize]),
                    ub: rect.page_uv(uv1[t[(k + 1) % 3] as usize]),
                    size,
                });
            }
        }
    }
    let tol = 1e-4 * (hi - lo).max_element().max(1e-3);
    // Sort by the lower x of each edge's box for a sweep.
    let mut order: Vec<usize> = (0..edges.len()).collect();
    order.sort_by(|&i, &j| {
        let (a, b) = (&edges[i], &edges[j]);
        a.a.x.min(a.b.x).total_cmp(&b.a.x.min(b.b.x))
    });
    let mut pairs = vec![];
    for (oi, &i) in order.iter().enumerate() {
        let e = edges[i];
        let e_hi = e.a.x.max(e.b.x) + tol;
        for &j in &order[oi + 1..] {
            let f = edges[j];
            if f.a.x.min(f.b.x) > e_hi {
                break;
            }
            if e.n.dot(f.n) < 0.98 {
                continue;
            }
            let d = e.b - e.a;
            let len = d.length();
            if len <= tol {
                continue;
            }
            let dir = d / len;
            // f's endpoints on e's line.
            let dist = |p: Vec3| (p - e.a - dir * dir.dot(p - e.a)).length();
            if dist(f.a) > tol || dist(f.b) > tol {
                continue;
            }
            // Opposite sides within the (common) plane.
            let side = |c: Vec3| dir.cross(c - e.a).dot(e.n);
            if side(e.c) * side(f.c) >= 0.0 {
                continue;
            }
            let (sa, sb) = (dir.dot(f.a - e.a), dir.dot(f.b - e.a));
            let (s0, s1) = (sa.min(sb).max(0.0), sa.max(sb).min(len));
            if s1 - s0 <= tol {
                continue;
            }
            // Samples every half texel of the finer side.
            let texels_e = ((e.ub - e.ua) * e.size).length() * (s1 - s0) / len;
            let texels_f = ((f.ub - f.ua) * f.size).length() * (s1 - s0) / (f.b - f.a).length();
            let n = ((texels_e.max(texels_f) * 2.0).ceil() as usize).clamp(2, 4096);
            for k in 0..n {
                let s = s0 + (s1 - s0) * (k as f32 + 0.5) / n as f32;
                let p = e.a + dir * s;
                let te = s / len;
                let tf = (dir.dot(p - f.a) / dir.dot(f.b - f.a)).clamp(0.0, 1.0);
                pairs.push(SeamPair {
                    a: (e.page, e.ua.lerp(e.ub, te)),
                    b: (f.page, f.ua.lerp(f.ub, tf)),
                    p,
                });
            }
        }
    }
    pairs
}

/// Bilinear footprint of page coordinates: 4 (index, weight) pairs.
fn footprint(w: u32, h: u32, uv: Vec2) -> [(usize, f32); 4] {
    let x = uv.x * w as f32 - 0.5;
    let y = uv.y * h as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |xi: f32, yi: f32| {
        let xi = (xi as i64).clamp(0, w as i64 - 1) as usize;
        let yi = (yi as i64).clamp(0, h as i64 - 1) as usize;
        yi * w as usize + xi
    };
    [
        (at(x0, y0), (1.0 - fx) * (1.0 - fy)),
        (at(x0 + 1.0, y0), fx * (1.0 - fy)),
        (at(x0, y0 + 1.0), (1.0 - fx) * fy),
        (at(x0 + 1.0, y0 + 1.0), fx * fy),
    ]
}

/// Largest relative difference across the pairs (bilinear values).
pub fn max_difference(pages: &[Image], pairs: &[SeamPair]) -> f32 {
    pairs
        .iter()
        .map(|p| {
            let a = crate::sample_bilinear(&pages[p.a.0 as usize], p.a.1);
            let b = crate::sample_bilinear(&pages[p.b.0 as usize], p.b.1);
            relative_difference(a, b)
        })
        .fold(0.0, f32::max)
}

/// |a−b| / mean, per channel, the largest; with a floor so black-on-black is 0.
pub fn relative_difference(a: Vec3, b: Vec3) -> f32 {
    let m = ((a + b) * 0.5).max(Vec3::splat(1e-6));
    ((a - b).abs() / m).max_element()
}

/// Stitch the seams of baked pages. `inside` marks texels that held a valid sample before
/// repair (the anti-bleeding guard).
pub fn stitch(
    scene: &Scene,
    layout: &Layout,
    pages: &mut [Image],
    inside: &[Vec<bool>],
) -> StitchReport {
    let all = find_pairs(scene, layout);
    // Keep pairs whose footprints are backed by valid samples on both sides (weighted ≥ ½).
    let backed = |page: u32, uv: Vec2| {
        let (w, h) = (pages[page as usize].width, pages[page as usize].height);
        footprint(w, h, uv)
            .iter()
            .filter(|(i, _)| inside[page as usize][*i])
            .map(|(_, wt)| wt)
            .sum::<f32>()
            >= 0.5
    };
    let pairs: Vec<SeamPair> = all
        .into_iter()
        .filter(|p| backed(p.a.0, p.a.1) && backed(p.b.0, p.b.1))
        .collect();
    // Kaczmarz projections onto each constraint Σ_a w·T − Σ_b w·T = 0 (coefficients of texels
    // that both footprints share are merged), which converges for any consistent system.
    for _ in 0..200 {
        let mut worst = 0.0f32;
        for p in &pairs {
            let (pa, pb) = (p.a.0 as usize, p.b.0 as usize);
            let mut g: Vec<((usize, usize), f32)> = Vec::with_capacity(8);
            let mut add = |key: (usize, usize), w: f32| {
                if let Some(e) = g.iter_mut().find(|e| e.0 == key) {
                    e.1 += w;
                } else {
                    g.push((key, w));
                }
            };
            for (i, w) in footprint(pages[pa].width, pages[pa].height, p.a.1) {
                add((pa, i), w);
            }
            for (i, w) in footprint(pages[pb].width, pages[pb].height, p.b.1) {
                add((pb, i), -w);
            }
            let c: Vec3 = g.iter().map(|&((pg, i), w)| pages[pg].data[i] * w).sum();
            let norm: f32 = g.iter().map(|e| e.1 * e.1).sum();
            if norm < 1e-8 {
                continue;
            }
            let va = crate::sample_bilinear(&pages[pa], p.a.1);
            worst = worst.max(relative_difference(va, va - c));
            for &((pg, i), w) in &g {
                pages[pg].data[i] -= c * (w / norm);
            }
        }
        if worst < 1e-4 {
            break;
        }
    }
    for p in pages.iter_mut() {
        for v in &mut p.data {
            *v = v.max(Vec3::ZERO);
        }
    }
    StitchReport {
        pairs: pairs.len(),
        max_difference: max_difference(pages, &pairs),
    }
}
