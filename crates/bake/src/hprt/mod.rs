//! Hierarchical PRT (McKenzie Chapter 2010 ch. 5): shadows between moving objects for
//! textured PRT, relit every frame.
//!
//! Each object's transfer holds its own self-shadowing only (the bake of an animated scene
//! gives every moving object an occlusion group of its own). Every frame, at each mesh node's
//! light sample points, a **filter** — the SH projection of the directions the point sees
//! unblocked by the other objects — is combined with the incident light, and the textured PRT
//! renderer takes the result as it takes any SH light.
//!
//! - **Tree** ([`Tree`]): mesh nodes and composite nodes, by hand, from instance names, flat
//!   or by proximity.
//! - **Filters** ([`FilterMode`]): `mask` (default) casts each point's directions against its
//!   occluder set — the siblings of its node and of each ancestor, so a direction blocked at
//!   two levels is removed once — and projects the boolean mask: F = UNIT − Σ_blocked w·Y(ω)
//!   with w = 4π/n and the exact unit filter (DC √4π). `descent` is the thesis's §5.1.6:
//!   a child's filter is its parent's (at the parent's nearest sample point) less the
//!   directions its siblings block, so a direction blocked at two levels is removed twice
//!   (the extraction's erratum 8, kept as the faithful variant).
//! - **Scope** ([`Scope`]): a filter per sample point (§6.3.2's "multisampling", default), or
//!   one per node from its centre (the cheap, all-or-nothing variant).
//! - **Occlusion** ([`Occlusion`]): occluders' faces, or their bounding boxes ("blob" shadows,
//!   §5.3).
//! - **Combining** ([`Combine`]): `masked` (adopted by McKenzie): the triple product of the
//!   Hann-windowed filter and light over the sparse Γ table (1 158 entries at 5 bands);
//!   `product`: the plain triple product, then the window; `subtract`: the light less the
//!   occluded region's projection scaled by the light's mean over it, Lʹ = L − (⟨L,O⟩/⟨O,O⟩)·O
//!   with O = UNIT − F (our reading of "subtract the total filtering representation from the
//!   total lighting representation"), then the window. An unoccluded point gets the windowed
//!   light in all three, exactly `prt-textured`'s light: the light is not windowed twice.
//! - **Caching** (§5.3): a node's filters are recomputed only when something it depends on
//!   moved — itself, or an instance under one of its occluders (with blob occlusion: an
//!   occluder whose box changed) — which is "a moved node dirties its siblings and their
//!   descendants", applied up the tree.

mod filter;
pub mod tree;

pub use filter::{Blocker, FilterStats, PointFilter};
pub use tree::Tree;

use crate::sh_light::ShLighting;
use filter::{Caster, Placement};
use glam::{DMat3, DVec3, Mat4, Vec3};
use lightlab_core::quadrature::DirectionSet;
use lightlab_core::sh::{self, TripleProduct, Window};
use lightlab_scene::Scene;
use lightlab_trace::Accel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::ops::Not;

/// How filter and light combine at a sample point (§5.1.7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Combine {
    Masked,
    Product,
    Subtract,
}
lightlab_core::named_enum!(Combine, "filter combination", {
    Masked => "masked", Product => "product", Subtract => "subtract",
});

/// How filters are accumulated down the tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FilterMode {
    Mask,
    Descent,
}
lightlab_core::named_enum!(FilterMode, "filter mode", { Mask => "mask", Descent => "descent" });

/// Where filters are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scope {
    Point,
    Node,
}
lightlab_core::named_enum!(Scope, "filter scope", { Point => "point", Node => "node" });

/// What blocks a filter's rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Occlusion {
    Faces,
    Blob,
}
lightlab_core::named_enum!(Occlusion, "filter occlusion", { Faces => "faces", Blob => "blob" });

/// Settings of hierarchical PRT.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HprtSettings {
    pub bands: usize,
    /// Run-time sampler directions per filter (a stratified set of about this many).
    pub samples: usize,
    pub combine: Combine,
    pub filters: FilterMode,
    pub scope: Scope,
    pub occlusion: Occlusion,
    /// Keep filters across frames and recompute only the dirty ones.
    pub cache: bool,
    /// Blocked directions see the occluder's diffuse radiance (beyond the thesis, whose
    /// occluders are black): ρ·E/π at the first hit, E from the occluder's own filtered light
    /// at its nearest sample point. Face occlusion only.
    pub bounce: bool,
    /// The window of the light (Hann at the band count, as `prt-textured`).
    #[serde(skip, default = "default_window")]
    pub window: Window,
    pub seed: u64,
}

fn default_window() -> Window {
    Window::Hann { size: 5.0 }
}

impl Default for HprtSettings {
    fn default() -> Self {
        HprtSettings {
            bands: 5,
            samples: 1024,
            combine: Combine::Masked,
            filters: FilterMode::Mask,
            scope: Scope::Point,
            occlusion: Occlusion::Faces,
            cache: true,
            bounce: true,
            window: default_window(),
            seed: 1,
        }
    }
}

/// The instance transforms and node bounds cached filters were found with.
type Seen = (Vec<Mat4>, Vec<(Vec3, Vec3)>);

/// Hierarchical PRT's per-frame state: the tree, the sampler, the Γ table, each mesh's BVH
/// and the cached filters.
pub struct Hierarchy {
    pub tree: Tree,
    pub settings: HprtSettings,
    dirs: Vec<Vec3>,
    /// Per direction, the basis weighted by 4π/n (n·bands² values).
    basis: Vec<f64>,
    unit: Vec<f64>,
    gamma: TripleProduct,
    accels: Vec<Option<Accel>>,
    under: Vec<Vec<usize>>,
    leaf_of: Vec<Option<usize>>,
    /// Transforms and node bounds the cached filters were found with.
    seen: Option<Seen>,
    /// Per node, per sample point, the filter (mesh nodes; composites in descent mode).
    filters: Vec<Option<Vec<PointFilter>>>,
    /// Diffuse albedo per instance (what a blocked ray's bounce reflects).
    albedo: Vec<DVec3>,
    /// The last frame's counters.
    pub stats: FilterStats,
}

impl Hierarchy {
    /// Set up for `scene` (any pose: meshes and the tree are what matter).
    pub fn new(scene: &Scene, tree: Tree, settings: HprtSettings) -> Hierarchy {
        let set = DirectionSet::stratified(settings.samples.max(1), settings.seed);
        let nc = sh::num_coeffs(settings.bands);
        let mut basis = Vec::with_capacity(set.dirs.len() * nc);
        for (d, w) in set.dirs.iter().zip(&set.weights) {
            basis.extend(sh::eval(settings.bands, *d).into_iter().map(|y| y * w));
        }
        let mut unit = vec![0.0; nc];
        unit[0] = (4.0 * std::f64::consts::PI).sqrt();
        let under = (0..tree.nodes.len())
            .map(|k| tree.instances_under(k))
            .collect();
        let albedo = scene
            .instances
            .iter()
            .map(|i| {
                let m = &scene.materials[scene.meshes[i.mesh].material];
                (m.base_color.truncate() * (1.0 - m.metallic)).as_dvec3()
            })
            .collect();
        Hierarchy {
            albedo,
            accels: filter::mesh_accels(scene, &tree),
            leaf_of: tree.leaf_of(scene.instances.len()),
            filters: vec![None; tree.nodes.len()],
            dirs: set.dirs.iter().map(|d| d.as_vec3()).collect(),
            basis,
            unit,
            gamma: TripleProduct::new(settings.bands),
            under,
            tree,
            settings,
            seen: None,
            stats: FilterStats::default(),
        }
    }

    /// Directions per filter.
    pub fn directions(&self) -> usize {
        self.dirs.len()
    }

    /// Bring the filters up to date with `scene`'s pose (recomputing the dirty nodes, or all
    /// of them without caching).
    pub fn update(&mut self, scene: &Scene) {
        let transforms: Vec<Mat4> = scene.instances.iter().map(|i| i.transform).collect();
        let place = Placement::new(scene, &self.tree, &self.under);
        let dirty = self.dirty(&transforms, &place);
        let caster = Caster {
            scene,
            under: &self.under,
            accels: &self.accels,
            place: &place,
            occlusion: self.settings.occlusion,
        };
        let mut stats = FilterStats::default();
        let mut fresh = self.filters.clone();
        // Levels top-down (descent reads the parent's filters); the nodes of a level in
        // parallel.
        let order = self.top_down();
        let depth = |k: usize| self.tree.path_up(k).len();
        let mut at = 0;
        while at < order.len() {
            let d = depth(order[at]);
            let level: Vec<usize> = order[at..]
                .iter()
                .copied()
                .take_while(|&k| depth(k) == d)
                .collect();
            at += level.len();
            let todo: Vec<usize> = level
                .into_iter()
                .filter(|&k| {
                    dirty[k]
                        && (self.tree.nodes[k].instance.is_some()
                            || self.settings.filters == FilterMode::Descent)
                })
                .collect();
            let done: Vec<(usize, Vec<PointFilter>, FilterStats)> = todo
                .par_iter()
                .map(|&k| {
                    let mut st = FilterStats::default();
                    let f = self.node_filters(k, &caster, &fresh, &mut st);
                    (k, f, st)
                })
                .collect();
            for (k, f, st) in done {
                fresh[k] = Some(f);
                stats.rays += st.rays;
                stats.face_queries += st.face_queries;
                stats.nodes += 1;
            }
        }
        self.filters = fresh;
        self.stats = stats;
        self.seen = Some((transforms, place.node_bounds));
    }

    /// Nodes parents first.
    fn top_down(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.tree.nodes.len()).collect();
        order.sort_by_key(|&k| self.tree.path_up(k).len());
        order
    }

    /// Which nodes' filters must be recomputed for this pose.
    fn dirty(&self, transforms: &[Mat4], place: &Placement) -> Vec<bool> {
        let n = self.tree.nodes.len();
        let Some(seen) = self.seen.as_ref().filter(|_| self.settings.cache) else {
            return vec![true; n];
        };
        let (seen_t, seen_b) = seen;
        let moved: Vec<bool> = transforms.iter().zip(seen_t).map(|(a, b)| a != b).collect();
        // A node changed when an instance under it moved (its own sample points move with
        // its box); as a blob occluder only its box matters.
        let changed: Vec<bool> = (0..n)
            .map(|k| self.under[k].iter().any(|&i| moved[i]))
            .collect();
        let as_occluder = |k: usize| match self.settings.occlusion {
            Occlusion::Faces => changed[k],
            Occlusion::Blob => same_blob(place.node_bounds[k], seen_b[k]).not(),
        };
        let mut dirty: Vec<bool> = (0..n)
            .map(|k| changed[k] || self.tree.occluders(k).into_iter().any(as_occluder))
            .collect();
        if self.settings.filters == FilterMode::Descent {
            for k in self.top_down() {
                if let Some(p) = self.tree.nodes[k].parent {
                    dirty[k] |= dirty[p];
                }
            }
        }
        dirty
    }

    /// One node's filters, per sample point.
    fn node_filters(
        &self,
        k: usize,
        caster: &Caster,
        fresh: &[Option<Vec<PointFilter>>],
        stats: &mut FilterStats,
    ) -> Vec<PointFilter> {
        let origins = caster.place.origins(k, self.settings.scope);
        let (occluders, parent) = match self.settings.filters {
            FilterMode::Mask => (self.tree.occluders(k), None),
            FilterMode::Descent => (
                self.tree.siblings(k),
                self.tree.nodes[k].parent.map(|p| {
                    let pts = caster.place.origins(p, Scope::Point);
                    (pts, fresh[p].clone().unwrap_or_default())
                }),
            ),
        };
        let mut memo: Option<(Vec3, Vec<f64>, Vec<Blocker>)> = None;
        origins
            .iter()
            .map(|&o| {
                let start = match &parent {
                    Some((pts, f)) if !f.is_empty() => f[nearest(pts, o)].coeffs.clone(),
                    _ => self.unit.clone(),
                };
                // A per-node filter casts once for its six identical origins.
                let (lost, hits) = match &memo {
                    Some((p, l, h)) if *p == o => (l.clone(), h.clone()),
                    _ => {
                        let (l, h) = caster.blocked_sum(
                            o,
                            &self.dirs,
                            &self.basis,
                            &occluders,
                            self.settings.bounce,
                            stats,
                        );
                        memo = Some((o, l.clone(), h.clone()));
                        (l, h)
                    }
                };
                PointFilter {
                    coeffs: start.iter().zip(&lost).map(|(a, b)| a - b).collect(),
                    hits,
                }
            })
            .collect()
    }

    /// The filters of instance `i`'s six sample points (None: not in the tree, or not yet
    /// updated).
    pub fn filters_of(&self, instance: usize) -> Option<&[PointFilter]> {
        let k = self.leaf_of.get(instance).copied().flatten()?;
        self.filters[k].as_deref()
    }

    /// This frame's light for the textured PRT renderer: `world` is the scene's light
    /// projected at each instance's six sample points, unwindowed and in world axes
    /// (`SamplePoints::PerObject`, `Window::None`, no rotations); each point's light is
    /// combined with its filter and windowed, then turned into the instance's baked frame by
    /// `rotations` (each instance's rotation since its bake).
    pub fn relight(&self, world: &ShLighting, rotations: Option<&[DMat3]>) -> ShLighting {
        let mut out = world.clone();
        out.coeffs
            .par_iter_mut()
            .enumerate()
            .for_each(|(i, group)| {
                let filters = self.filters_of(i);
                for (k, light) in group.iter_mut().enumerate() {
                    *light = match filters.and_then(|f| f.get(k)) {
                        Some(f) => self.combine(&f.coeffs, light),
                        None => {
                            let mut l = light.clone();
                            self.settings.window.apply(&mut l);
                            l
                        }
                    };
                }
            });
        if self.settings.bounce {
            let bounce = self.bounce(&out);
            for (group, b) in out.coeffs.iter_mut().zip(bounce) {
                for (light, b) in group.iter_mut().zip(b) {
                    for (l, b) in light.iter_mut().zip(b) {
                        *l += b;
                    }
                }
            }
        }
        for (i, group) in out.coeffs.iter_mut().enumerate() {
            if let Some(r) = rotations.and_then(|r| r.get(i)) {
                let rs = sh::Rotation::new(self.settings.bands, r.transpose());
                for light in group.iter_mut() {
                    *light = rs.apply(light);
                }
            }
        }
        out
    }

    /// Per instance and sample point, the light its blocked rays receive from what blocks
    /// them (windowed): Σ_hits w·Y(ωₛ)·ρ·E/π, E the occluder's filtered light `lit` at its
    /// sample point nearest the hit, integrated against the clamped cosine of the hit's normal.
    fn bounce(&self, lit: &ShLighting) -> Vec<Vec<Vec<DVec3>>> {
        let bands = self.settings.bands;
        let nc = sh::num_coeffs(bands);
        // The clamped cosine about n is Σ s_l·Y_lm(n)·Y_lm (zonal rotation, `sh::zonal_to_axis`).
        let cosine = sh::clamped_cosine_zonal(bands);
        let scale: Vec<f64> = (0..nc)
            .map(|c| {
                let l = (c as f64).sqrt() as usize;
                (4.0 * std::f64::consts::PI / (2 * l + 1) as f64).sqrt() * cosine[l]
            })
            .collect();
        (0..lit.coeffs.len())
            .into_par_iter()
            .map(|i| {
                let Some(filters) = self.filters_of(i) else {
                    return vec![vec![DVec3::ZERO; nc]; lit.coeffs[i].len()];
                };
                let mut y = vec![0.0f64; nc];
                filters
                    .iter()
                    .map(|f| {
                        let mut b = vec![DVec3::ZERO; nc];
                        for h in &f.hits {
                            let j = h.instance as usize;
                            let q = nearest(&lit.points[j], h.point);
                            let n = h.normal.as_dvec3();
                            sh::eval_f64(bands, n.x, n.y, n.z, &mut y);
                            let e: DVec3 = lit.coeffs[j][q]
                                .iter()
                                .zip(y.iter().zip(&scale))
                                .map(|(l, (y, s))| *l * (y * s))
                                .sum();
                            let rad = self.albedo[j] * e.max(DVec3::ZERO) / std::f64::consts::PI;
                            let basis = &self.basis[h.dir as usize * nc..(h.dir as usize + 1) * nc];
                            for (o, yb) in b.iter_mut().zip(basis) {
                                *o += rad * *yb;
                            }
                        }
                        self.settings.window.apply(&mut b);
                        b
                    })
                    .collect()
            })
            .collect()
    }

    /// Filter ∘ light at one sample point.
    pub fn combine(&self, filter: &[f64], light: &[DVec3]) -> Vec<DVec3> {
        let w = self.settings.window;
        let mut c = match self.settings.combine {
            Combine::Masked => return self.gamma.masked_product(filter, light, w),
            Combine::Product => self.gamma.product(filter, light),
            Combine::Subtract => {
                let o: Vec<f64> = self.unit.iter().zip(filter).map(|(u, f)| u - f).collect();
                let oo: f64 = o.iter().map(|x| x * x).sum();
                let mut l = light.to_vec();
                if oo > 1e-12 {
                    let lo: DVec3 = light.iter().zip(&o).map(|(l, o)| *l * *o).sum();
                    let s = lo / oo;
                    for (l, o) in l.iter_mut().zip(&o) {
                        *l -= s * *o;
                    }
                }
                l
            }
        };
        w.apply(&mut c);
        c
    }
}

/// Whether two boxes are the same blob: corners within 1 % of the box's diagonal (a polygonal
/// object turning in place changes its box by a little).
fn same_blob(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> bool {
    let tol = 0.01 * (a.1 - a.0).length();
    a.0.distance(b.0) <= tol && a.1.distance(b.1) <= tol
}

/// Index of the point of `pts` nearest to `p`.
fn nearest(pts: &[Vec3], p: Vec3) -> usize {
    (0..pts.len())
        .min_by(|&a, &b| {
            pts[a]
                .distance_squared(p)
                .total_cmp(&pts[b].distance_squared(p))
        })
        .unwrap_or(0)
}
