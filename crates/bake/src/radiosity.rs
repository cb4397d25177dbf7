//! Radiosity light-maps after CaLight (Fuchs 2005, §3.3; `reference/seed-000` §2.4–2.6).
//!
//! One patch per valid light-map texel. Steps, in CaLight's order:
//!
//! 1. **Direct light.** Punctual lights (point, spot) deposit `ΔE = I·spot·cosθ/d²` at every
//!    patch with an unoccluded ray; below one patch size, `d` is clamped to the patch size and
//!    the cosine dropped (CaLight's guard against a diverging point light). The sun is
//!    **multi-sampled**: `sun_samples` jittered points across the patch and across the sun's
//!    disc, `ΔE = E_sun·hits/samples·cosθ`, then CaLight's 3×3 smoothing (weights 1, ¼,
//!    1/16 over valid patches). The sky (the environment) is an emitter in the same way:
//!    `sky_samples` cosine-distributed rays per patch, `ΔE = π·mean(L_sky)` over unoccluded
//!    rays. Emissive surfaces get their exitance `π·L_e` as unshot radiosity and shoot like
//!    every other patch.
//! 2. **Bounce light: progressive-refinement shooting** (Southwell / Cohen–Wallace). Each step
//!    selects a shooter: for every surface (an instance) `min(10, patches/2)` random n×n blocks,
//!    the best by unshot R+G+B averaged over the block; below the threshold a full search takes
//!    the best patch of the first surface that still holds one above it; with none, stop. The
//!    block's patches (same instance, normals within 25°) are grouped: power `Φ = Σ U_k·A_k`,
//!    centre and normal averaged. Every receiver j the group faces gets
//!    `ΔE_j = (Φ/A_I)·F_{j←I}` with visibility by a BVH ray from centre to centre, and
//!    `ρ_j·ΔE_j` joins j's unshot radiosity. Receivers within 3 group sizes are shot from the
//!    group's patches one by one instead (the thesis's future work: "choose n by receiver
//!    distance"); receivers farther than 3 block sizes share one visibility ray per n×n block
//!    of their own (hierarchical receivers, which cuts the rays of a shot about n²-fold).
//!    Receiver clusters (planar faces, curved instances) that no source of the shot can reach
//!    by the plane tests are skipped whole ([`Clusters`]). The group's unshot radiosity is
//!    then zero: absorbed energy leaves the system, which guarantees progress.
//! 3. The light-map value is `E/π` (incident irradiance over π): rendered radiance is
//!    albedo × light-map, as Fuchs's "diffuse texture × light-map".
//!
//! Deviations, each for a reason: (a) ρ is the material's diffuse albedo per channel (CaLight
//! uses one global 0.3; the thesis speaks of "the diffuse reflectivity of the surface"); (b) the
//! group shoots its summed *power* rather than its summed radiosity times the mean area, which
//! is the same for equal patches and exact for unequal ones; (c) the stop threshold is relative
//! to the largest initial unshot radiosity rather than absolute in CaLight's units, so one
//! default works for any scene scale; the unshot energy left is reported; (d) the form factor
//! is Wallace et al.'s (1989) disc approximation `A·cosθ_I cosθ_j/(π r² + A)` instead of
//! CaLight's `min(1, A·cos·cos/(π·max(r², A)))`, together with the near-field subdivision
//! above: CaLight's clamp over-counts patches near a grouped shooter, and a closed furnace
//! then converges 4 % high instead of within 1 %; (e) there is no
//! surface-to-surface PVS: the plane test is done per receiver (cosθ ≤ 0 skips) and the BVH
//! makes a ray cheap; (f) a receiver within 10 µm per metre of the source's plane, or a
//! source that near the receiver's, counts as lying in it and gets nothing ([`plane_tol`]),
//! where CaLight's exact sign test would let f32 rounding decide.
//!
//! Energy is accumulated in f64. During the shooting each block holds its members' radiosity,
//! so a shot updates the blocks it reaches in parallel.

use crate::texels::{TexelSample, Texels};
use crate::{BakeError, LightMode, Progress};
use glam::{DVec3, Vec3};
use lightlab_core::sampling::{Frame, Rng, cosine_hemisphere, hammersley};
use lightlab_scene::{LightKind, Scene};
use lightlab_trace::Accel;
use lightlab_trace::lights::sample_punctual;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RadiositySettings {
    /// Shooter grouping n (n×n patches; CaLight's BlockSize, default 3, range 1..8).
    pub block_size: u32,
    /// Stop when no patch holds unshot radiosity (R+G+B) above this fraction of the largest
    /// initial one (CaLight's StopUE, made relative).
    pub stop: f64,
    /// Sun samples per patch (CaLight: 13 for an unclipped patch).
    pub sun_samples: u32,
    /// Sky rays per patch.
    pub sky_samples: u32,
    /// Safety limit on shooting steps.
    pub max_shots: u64,
    /// Skip, per shot, the receiver clusters that no source of the shot can reach (see
    /// [`Clusters`]). The light-maps are the same bit for bit either way; off only to measure
    /// what the culling saves.
    #[serde(default = "yes")]
    pub cull_clusters: bool,
}

fn yes() -> bool {
    true
}

impl Default for RadiositySettings {
    fn default() -> Self {
        RadiositySettings {
            block_size: 3,
            stop: 1e-4,
            sun_samples: 16,
            sky_samples: 256,
            max_shots: 2_000_000,
            cull_clusters: true,
        }
    }
}

/// What the solver reports.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RadiosityStats {
    pub patches: usize,
    pub shots: u64,
    /// Patch-to-light and patch-to-patch transfers evaluated (each needs a visibility answer,
    /// some shared by a receiver block); the rays actually cast are `BakeStats::rays`.
    /// Receivers in clusters that a shot cannot reach are not counted.
    pub transfers: u64,
    /// Unshot power left over total power emitted and reflected (a measure of convergence).
    pub unshot_fraction: f64,
    /// Whether `max_shots` ended the loop before the threshold was met.
    pub hit_shot_limit: bool,
}

struct Patch {
    p: Vec3,
    n: Vec3,
    ng: Vec3,
    area: f64,
    rho: DVec3,
    page: usize,
    x: u32,
    y: u32,
    instance: u32,
}

/// Solve. Returns the light-map values (E/π per texel and page; zero where invalid).
#[allow(clippy::too_many_arguments)]
pub fn solve(
    scene: &Scene,
    accel: &Accel,
    texels: &Texels,
    valid: &[Vec<bool>],
    modes: &[LightMode],
    settings: &RadiositySettings,
    seed: u64,
    progress: Progress,
) -> Result<(Vec<Vec<Vec3>>, RadiosityStats), BakeError> {
    if !(1..=8).contains(&settings.block_size) {
        return Err(BakeError::Settings(format!(
            "radiosity block size must be in 1..8, got {}",
            settings.block_size
        )));
    }
    if !(settings.stop > 0.0 && settings.stop < 1.0) {
        return Err(BakeError::Settings(format!(
            "radiosity stop threshold must be in (0, 1), got {}",
            settings.stop
        )));
    }
    let (patches, index) = make_patches(texels, valid);
    let np = patches.len();
    let mut s = Solver {
        scene,
        accel,
        texels,
        settings,
        seed,
        patches,
        total: vec![DVec3::ZERO; np],
        unshot: vec![DVec3::ZERO; np],
        stats: RadiosityStats {
            patches: np,
            ..Default::default()
        },
    };
    progress("radiosity: direct light", 0, np);
    s.direct_light(&index, modes);
    s.sky_light();
    // Emitters: exitance π·L_e, shot like any radiosity.
    for k in 0..np {
        let e = s.sample(k).emission.as_dvec3() * PI;
        s.unshot[k] += e;
    }
    s.shoot(progress)?;
    Ok((to_pages(texels, &index, &s.total), s.stats))
}

/// One patch per valid texel with area, and a texel → patch index per page.
fn make_patches(texels: &Texels, valid: &[Vec<bool>]) -> (Vec<Patch>, Vec<Vec<u32>>) {
    let mut patches: Vec<Patch> = vec![];
    let mut index: Vec<Vec<u32>> = vec![];
    for (pi, (page, valid)) in texels.pages.iter().zip(valid).enumerate() {
        let mut idx = vec![u32::MAX; page.samples.len()];
        for (i, s) in page.samples.iter().enumerate() {
            if let Some(s) = s
                && valid[i]
                && s.area > 0.0
            {
                idx[i] = patches.len() as u32;
                patches.push(Patch {
                    p: s.p,
                    n: s.ns,
                    ng: s.ng,
                    area: s.area as f64,
                    rho: s.albedo.as_dvec3().clamp(DVec3::ZERO, DVec3::splat(0.999)),
                    page: pi,
                    x: i as u32 % page.width,
                    y: i as u32 / page.width,
                    instance: s.instance,
                });
            }
        }
        index.push(idx);
    }
    (patches, index)
}

/// The solver's state: incident irradiance counted in the light-map (`total`) and unshot
/// radiosity per patch.
struct Solver<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    texels: &'a Texels,
    settings: &'a RadiositySettings,
    seed: u64,
    patches: Vec<Patch>,
    total: Vec<DVec3>,
    unshot: Vec<DVec3>,
    stats: RadiosityStats,
}

impl Solver<'_> {
    fn sample(&self, k: usize) -> &TexelSample {
        let p = &self.patches[k];
        let page = &self.texels.pages[p.page];
        page.samples[(p.y * page.width + p.x) as usize]
            .as_ref()
            .expect("patches are valid texels")
    }

    /// Step 1 for the punctual lights and the sun.
    fn direct_light(&mut self, index: &[Vec<u32>], modes: &[LightMode]) {
        let np = self.patches.len();
        for li in 0..self.scene.lights.len() {
            let mode = modes.get(li).copied().unwrap_or(LightMode::Baked);
            if mode == LightMode::Realtime {
                continue;
            }
            let is_sun = matches!(self.scene.lights[li].kind, LightKind::Directional { .. });
            let n_samples = if is_sun {
                self.settings.sun_samples.max(1)
            } else {
                1
            };
            let de: Vec<DVec3> = (0..np)
                .into_par_iter()
                .map(|k| self.direct_at(k, li, is_sun, n_samples))
                .collect();
            let de = if is_sun {
                smooth(&self.patches, index, self.texels, de)
            } else {
                de
            };
            self.stats.transfers += (np as u64) * n_samples as u64;
            for (k, de) in de.into_iter().enumerate() {
                if mode == LightMode::Baked {
                    self.total[k] += de;
                }
                self.unshot[k] += self.patches[k].rho * de;
            }
        }
    }

    /// Irradiance from light `li` at patch `k`, averaged over `n_samples` points.
    fn direct_at(&self, k: usize, li: usize, is_sun: bool, n_samples: u32) -> DVec3 {
        let pa = &self.patches[k];
        let s = self.sample(k);
        let mut rng = Rng::new(self.seed ^ ((li as u64 + 1) * 0x9e37), k as u64);
        let mut sum = DVec3::ZERO;
        for j in 0..n_samples {
            // Jitter across fully covered patches (CaLight samples the patch polygon).
            let p = if is_sun && s.coverage >= 0.999 && n_samples > 1 {
                let u = hammersley(j, n_samples) - 0.5;
                pa.p + s.dpdx * u.x + s.dpdy * u.y
            } else {
                pa.p
            };
            let Some(ls) = sample_punctual(self.scene, li, p, rng.next_vec2()) else {
                continue;
            };
            let cos = pa.n.dot(ls.wi);
            if cos <= 0.0 || ls.wi.dot(pa.ng) <= 0.0 {
                continue;
            }
            let o = p + pa.ng * ray_eps(p);
            let (dir, tmax) = if ls.dist.is_finite() {
                (p + ls.wi * ls.dist - o, 1.0 - 1e-4)
            } else {
                (ls.wi, f32::INFINITY)
            };
            if self.accel.occluded(o, dir, tmax) {
                continue;
            }
            let mut v = ls.value.as_dvec3() * cos as f64;
            if ls.dist.is_finite() {
                // CaLight's near-field guard: below one patch size, d := patch size and the
                // cosine is dropped.
                let size = pa.area.sqrt();
                let d = ls.dist as f64;
                if d < size {
                    v = ls.value.as_dvec3() * (d * d) / (size * size);
                }
            }
            sum += v;
        }
        sum / n_samples as f64
    }

    /// Step 1 for the environment: cosine-distributed rays per patch.
    fn sky_light(&mut self) {
        let Some(env) = &self.scene.environment else {
            return;
        };
        let np = self.patches.len();
        let n = self.settings.sky_samples.max(1);
        let de: Vec<DVec3> = (0..np)
            .into_par_iter()
            .map(|k| {
                let pa = &self.patches[k];
                let mut rng = Rng::new(self.seed ^ 0x5c1e5, k as u64);
                let off = rng.next_vec2();
                let frame = Frame::from_normal(pa.n);
                let o = pa.p + pa.ng * ray_eps(pa.p);
                let mut sum = DVec3::ZERO;
                for j in 0..n {
                    let d = frame.to_world(cosine_hemisphere((hammersley(j, n) + off).fract_gl()));
                    if d.dot(pa.ng) <= 0.0 || self.accel.occluded(o, d, f32::INFINITY) {
                        continue;
                    }
                    sum += env.radiance(d).as_dvec3();
                }
                sum * PI / n as f64
            })
            .collect();
        self.stats.transfers += np as u64 * n as u64;
        for (k, de) in de.into_iter().enumerate() {
            self.total[k] += de;
            self.unshot[k] += self.patches[k].rho * de;
        }
    }

    /// Step 2: progressive refinement until the threshold or the shot limit.
    fn shoot(&mut self, progress: Progress) -> Result<(), BakeError> {
        let np = self.patches.len();
        let initial_max = self.unshot.iter().map(|&u| key(u)).fold(0.0, f64::max);
        if initial_max <= 0.0 {
            return Ok(());
        }
        let emitted_power: f64 = (0..np)
            .map(|k| key(self.unshot[k]) * self.patches[k].area)
            .sum();
        let threshold = self.settings.stop * initial_max;
        let mut select = Selector::new(&self.patches, &self.unshot, threshold);
        let mut blocks = make_blocks(&self.patches, self.settings.block_size);
        blocks.load(&self.total, &self.unshot);
        let clusters = Clusters::new(&self.patches, &blocks.list);
        let mut alive = vec![true; blocks.list.len()];
        let mut rng = Rng::new(self.seed, 0x5407);
        let mut shots = 0u64;
        while let Some(shooter) = select.next(&blocks, &mut rng) {
            if shots >= self.settings.max_shots {
                self.stats.hit_shot_limit = true;
                break;
            }
            let b = blocks.id[shooter] as usize;
            let (whole, members) = blocks.list[b].sources(&self.patches, shooter);
            self.stats.transfers +=
                clusters.reachable((&whole, &members), self.settings.cull_clusters, &mut alive);
            let group = &mut blocks.list[b];
            for (u, &j) in group.unshot.iter_mut().zip(&group.members) {
                *u = DVec3::ZERO;
                select.shot(j);
            }
            let crossed = receive(
                self.accel,
                &mut blocks.list,
                &alive,
                (&whole, &members),
                select.threshold,
            );
            for j in crossed {
                select.crossed(j);
            }
            shots += 1;
            if shots.is_multiple_of(64) && !progress("radiosity: shooting", shots as usize, 0) {
                return Err(BakeError::Cancelled);
            }
        }
        blocks.store(&mut self.total, &mut self.unshot);
        let left: f64 = (0..np)
            .map(|k| key(self.unshot[k]) * self.patches[k].area)
            .sum();
        self.stats.shots = shots;
        self.stats.unshot_fraction = left / emitted_power.max(1e-300);
        Ok(())
    }
}

/// Sum of the channels: the shooting's measure of unshot radiosity.
fn key(u: DVec3) -> f64 {
    u.x + u.y + u.z
}

/// CaLight's shooter selection. Surfaces are the instances' patches, in instance order.
struct Selector {
    surfaces: Vec<Vec<u32>>,
    surface_of: Vec<u32>,
    /// Per surface, its patches whose unshot radiosity is at or above the threshold, which is
    /// all the full search needs to read. Unshot radiosity only grows until the patch is shot,
    /// so a patch joins once, when it crosses the threshold, and leaves when it is shot.
    above: Vec<BTreeSet<u32>>,
    threshold: f64,
}

impl Selector {
    fn new(patches: &[Patch], unshot: &[DVec3], threshold: f64) -> Selector {
        let mut by_inst: BTreeMap<u32, Vec<u32>> = Default::default();
        for (k, p) in patches.iter().enumerate() {
            by_inst.entry(p.instance).or_default().push(k as u32);
        }
        let surfaces: Vec<Vec<u32>> = by_inst.into_values().collect();
        let mut surface_of = vec![0u32; patches.len()];
        let mut above = vec![BTreeSet::new(); surfaces.len()];
        for (si, surf) in surfaces.iter().enumerate() {
            for &k in surf {
                surface_of[k as usize] = si as u32;
                if key(unshot[k as usize]) >= threshold {
                    above[si].insert(k);
                }
            }
        }
        Selector {
            surfaces,
            surface_of,
            above,
            threshold,
        }
    }

    /// The next shooter (a patch; its block shoots): random blocks per surface, the best of
    /// all; below the threshold a full search, the best patch of the first surface that holds
    /// one above it; `None` when no patch does.
    fn next(&self, blocks: &Blocks, rng: &mut Rng) -> Option<usize> {
        let block_value = |k: usize| -> f64 {
            let u = &blocks.list[blocks.id[k] as usize].unshot;
            u.iter().map(|&u| key(u)).sum::<f64>() / u.len() as f64
        };
        let mut best = (0.0f64, usize::MAX);
        for surf in &self.surfaces {
            let samples = 10.min((surf.len() / 2).max(1));
            for _ in 0..samples {
                let k = surf[(rng.next_u32() as usize) % surf.len()] as usize;
                let v = block_value(k);
                if v > best.0 {
                    best = (v, k);
                }
            }
        }
        if best.0 >= self.threshold {
            return Some(best.1);
        }
        let set = self.above.iter().find(|s| !s.is_empty())?;
        best = (0.0, usize::MAX);
        for &k in set {
            let v = key(blocks.unshot(k as usize));
            if v > best.0 {
                best = (v, k as usize);
            }
        }
        Some(best.1)
    }

    /// Patch `k` was shot (its unshot radiosity is zero).
    fn shot(&mut self, k: u32) {
        self.above[self.surface_of[k as usize] as usize].remove(&k);
    }

    /// Patch `k` received and its unshot radiosity crossed the threshold.
    fn crossed(&mut self, k: u32) {
        self.above[self.surface_of[k as usize] as usize].insert(k);
    }
}

/// Blocks of n×n texels of one instance with similar normals. They group shooters (CaLight's
/// BlockSize) and, for far shooters, receivers; during the shooting they hold their members'
/// radiosity, so that a shot updates the blocks it reaches in parallel.
struct Blocks {
    list: Vec<Block>,
    /// Each patch's block, and its place among the block's members.
    id: Vec<u32>,
    pos: Vec<u32>,
}

fn make_blocks(patches: &[Patch], n: u32) -> Blocks {
    let mut id = vec![0u32; patches.len()];
    let mut pos = vec![0u32; patches.len()];
    let mut map: std::collections::HashMap<(usize, u32, u32, u32), usize> = Default::default();
    let mut list: Vec<Block> = vec![];
    for (k, p) in patches.iter().enumerate() {
        let key = (p.page, p.x / n, p.y / n, p.instance);
        let slot = map
            .get(&key)
            .copied()
            .filter(|&b| list[b].ng.dot(p.ng) > 0.9);
        let b = match slot {
            Some(b) => b,
            None => {
                list.push(Block {
                    members: vec![],
                    centre: Vec3::ZERO,
                    ng: p.ng,
                    area: 0.0,
                    recv: vec![],
                    total: vec![],
                    unshot: vec![],
                });
                map.insert(key, list.len() - 1);
                list.len() - 1
            }
        };
        id[k] = b as u32;
        pos[k] = list[b].members.len() as u32;
        list[b].members.push(k as u32);
        list[b].recv.push(Receiver {
            p: p.p,
            n: p.n,
            ng: p.ng,
            rho: p.rho,
        });
        list[b].centre += p.p;
        list[b].area += p.area;
    }
    for b in &mut list {
        b.centre /= b.members.len() as f32;
    }
    Blocks { list, id, pos }
}

impl Blocks {
    /// Take the patches' radiosity into the blocks.
    fn load(&mut self, total: &[DVec3], unshot: &[DVec3]) {
        for b in &mut self.list {
            b.total = b.members.iter().map(|&k| total[k as usize]).collect();
            b.unshot = b.members.iter().map(|&k| unshot[k as usize]).collect();
        }
    }

    /// Give it back.
    fn store(&self, total: &mut [DVec3], unshot: &mut [DVec3]) {
        for b in &self.list {
            for (i, &k) in b.members.iter().enumerate() {
                total[k as usize] = b.total[i];
                unshot[k as usize] = b.unshot[i];
            }
        }
    }

    fn unshot(&self, k: usize) -> DVec3 {
        self.list[self.id[k] as usize].unshot[self.pos[k] as usize]
    }
}

/// A shooting source: a patch, or a whole block as one (centre, mean normal, summed area).
struct Source {
    p: Vec3,
    n: Vec3,
    ng: Vec3,
    area: f64,
    /// Unshot radiosity.
    u: DVec3,
    /// Distance from a plane below which a point counts as lying in it ([`plane_tol`]).
    tol: f32,
}

impl Source {
    fn new(p: Vec3, n: Vec3, ng: Vec3, area: f64, u: DVec3) -> Source {
        Source {
            p,
            n,
            ng,
            area,
            u,
            tol: plane_tol(p),
        }
    }
}

/// Points nearer than this to a source's plane, or a source this near a receiver's plane, do
/// not exchange light: 10 µm per metre of the source's distance from the origin. The rounding
/// of `transfer`'s dot products stays below 0.5 µm per metre of coordinates and
/// [`Cluster::missed_by`] allows 2, so coplanar patches are told apart from facing ones
/// robustly and a shooter's own face can be culled.
fn plane_tol(p: Vec3) -> f32 {
    1e-5 * (1.0 + p.abs().max_element())
}

/// Shoot: the receivers of the blocks flagged `alive` get their irradiance from one shot (far
/// receivers from the `whole` group, receivers within `NEAR` group sizes from its `members`
/// one by one: the thesis's future work "choose n by receiver distance"); far receiver blocks
/// share one visibility ray (hierarchical receivers). Returns the patches whose unshot
/// radiosity crossed `threshold`.
fn receive(
    accel: &Accel,
    blocks: &mut [Block],
    alive: &[bool],
    (whole, members): (&Source, &[Source]),
    threshold: f64,
) -> Vec<u32> {
    let (c, ng, area) = (whole.p, whole.ng, whole.area);
    let near2 = NEAR * NEAR * area;
    let o = c + ng * ray_eps(c);
    let shoot_one = |q: &Receiver, vis: Option<bool>| -> Option<DVec3> {
        let far = ((q.p - c).length_squared() as f64) >= near2 || members.len() == 1;
        let e = if far {
            transfer(accel, whole, q, vis)?
        } else {
            let mut e = DVec3::ZERO;
            for m in members {
                if let Some(v) = transfer(accel, m, q, None) {
                    e += v;
                }
            }
            e
        };
        (e != DVec3::ZERO).then_some(e)
    };
    blocks
        .par_iter_mut()
        .zip(alive)
        .filter(|(_, alive)| **alive)
        .flat_map_iter(|(b, _)| {
            let d2 = (b.centre - c).length_squared() as f64;
            let shared = b.members.len() > 1 && d2 >= NEAR * NEAR * (area + b.area);
            let vis = if shared {
                let r = b.centre - c;
                if r.dot(ng) <= 0.0 || -r.dot(b.ng) <= 0.0 {
                    return vec![];
                }
                let target = b.centre + b.ng * ray_eps(b.centre);
                if accel.occluded(o, target - o, 1.0 - 1e-4) {
                    return vec![];
                }
                Some(true)
            } else {
                None
            };
            let mut crossed = vec![];
            for (i, (&j, q)) in b.members.iter().zip(&b.recv).enumerate() {
                if let Some(e) = shoot_one(q, vis) {
                    let before = key(b.unshot[i]);
                    b.total[i] += e;
                    b.unshot[i] += q.rho * e;
                    if before < threshold && key(b.unshot[i]) >= threshold {
                        crossed.push(j);
                    }
                }
            }
            crossed
        })
        .collect()
}

/// An n×n block of patches of one instance with similar normals: a shooter group, and for
/// far shooters a receiver group reached with one visibility ray.
struct Block {
    members: Vec<u32>,
    centre: Vec3,
    ng: Vec3,
    area: f64,
    /// The members as receivers, and their irradiance and unshot radiosity while shooting
    /// (kept with the block for locality).
    recv: Vec<Receiver>,
    total: Vec<DVec3>,
    unshot: Vec<DVec3>,
}

/// What a shot reads of a receiving patch.
struct Receiver {
    p: Vec3,
    n: Vec3,
    ng: Vec3,
    rho: DVec3,
}

impl Block {
    /// The sources of a shot from this block, selected through its patch `shooter`: the block
    /// as one (centre, mean shading normal, the shooter's geometric normal, summed power over
    /// summed area) and its members one by one.
    fn sources(&self, patches: &[Patch], shooter: usize) -> (Source, Vec<Source>) {
        let members: Vec<Source> = self
            .members
            .iter()
            .zip(&self.unshot)
            .map(|(&j, &u)| {
                let q = &patches[j as usize];
                Source::new(q.p, q.n, q.ng, q.area, u)
            })
            .collect();
        let power: DVec3 = members.iter().map(|m| m.u * m.area).sum();
        let nrm = members
            .iter()
            .map(|m| m.n.as_dvec3())
            .sum::<DVec3>()
            .normalize_or_zero()
            .as_vec3();
        let ng = patches[shooter].ng;
        let whole = Source::new(self.centre, nrm, ng, self.area, power / self.area);
        (whole, members)
    }
}

/// Receiver clusters for culling: the blocks of one instance whose geometric normals fall in
/// one cell of a coarse grid of directions (one planar face), or all the blocks of a curved
/// instance (more than [`CURVED_FACES`] such cells). A shot skips a cluster when every one of
/// its sources fails [`transfer`]'s own plane tests for every point of the cluster: the
/// cluster's box lies behind the source's plane, or the source lies behind the plane of every
/// member (bounded through the face's normal and its members' largest deviation from it).
/// These bounds are conservative, with a margin above f32 rounding, so culling changes which
/// receivers are visited and not one bit of the result.
struct Clusters {
    list: Vec<Cluster>,
}

struct Cluster {
    blocks: Vec<u32>,
    /// Patches in the blocks.
    members: u64,
    lo: Vec3,
    hi: Vec3,
    /// For a planar face: its mean geometric normal `axis`, the largest |ng − axis| of a
    /// member, and the range of p·axis over the members.
    plane: Option<Plane>,
}

struct Plane {
    axis: Vec3,
    spread: f32,
    min: f32,
    max: f32,
}

/// An instance whose blocks face more direction cells than this is one curved cluster.
const CURVED_FACES: usize = 64;

impl Clusters {
    fn new(patches: &[Patch], blocks: &[Block]) -> Clusters {
        let cell = |n: Vec3| -> (i32, i32, i32) {
            let q = (n * 4.0).round();
            (q.x as i32, q.y as i32, q.z as i32)
        };
        type Faces = BTreeMap<(i32, i32, i32), Vec<u32>>;
        let mut by_inst: BTreeMap<u32, Faces> = BTreeMap::new();
        for (bi, b) in blocks.iter().enumerate() {
            let inst = patches[b.members[0] as usize].instance;
            by_inst
                .entry(inst)
                .or_default()
                .entry(cell(b.ng))
                .or_default()
                .push(bi as u32);
        }
        let mut list = vec![];
        for faces in by_inst.into_values() {
            if faces.len() > CURVED_FACES {
                let all: Vec<u32> = faces.into_values().flatten().collect();
                list.push(Cluster::new(patches, blocks, all, false));
            } else {
                for f in faces.into_values() {
                    list.push(Cluster::new(patches, blocks, f, true));
                }
            }
        }
        Clusters { list }
    }

    /// Flag in `alive` the blocks of the clusters that some source of a shot can reach (all of
    /// them when `cull` is off); returns how many patches they hold.
    fn reachable(
        &self,
        (whole, members): (&Source, &[Source]),
        cull: bool,
        alive: &mut [bool],
    ) -> u64 {
        let mut count = 0;
        for c in &self.list {
            let reached = !(cull && c.missed_by(whole) && members.iter().all(|m| c.missed_by(m)));
            for &b in &c.blocks {
                alive[b as usize] = reached;
            }
            if reached {
                count += c.members;
            }
        }
        count
    }
}

impl Cluster {
    fn new(patches: &[Patch], blocks: &[Block], ids: Vec<u32>, planar: bool) -> Cluster {
        let members = || {
            ids.iter()
                .flat_map(|&b| blocks[b as usize].members.iter())
                .map(|&k| &patches[k as usize])
        };
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let (mut nsum, mut count) = (Vec3::ZERO, 0);
        for q in members() {
            count += 1;
            lo = lo.min(q.p);
            hi = hi.max(q.p);
            nsum += q.ng;
        }
        let plane = planar.then(|| {
            let axis = nsum.normalize_or_zero();
            let (mut spread, mut min, mut max) = (0.0f32, f32::INFINITY, f32::NEG_INFINITY);
            for q in members() {
                spread = spread.max((q.ng - axis).length());
                min = min.min(q.p.dot(axis));
                max = max.max(q.p.dot(axis));
            }
            Plane {
                axis,
                spread,
                min,
                max,
            }
        });
        Cluster {
            blocks: ids,
            members: count,
            lo,
            hi,
            plane,
        }
    }

    /// Whether `transfer` from source `s` returns nothing for every member, by its tests
    /// r·ng_s ≤ tol (the receiver behind or in the source's plane) or −r·ng_q ≤ tol (the
    /// source behind or in the receiver's), r = q − s. Bounds on those dot products over the
    /// cluster must stay below `tol` by more than the f32 rounding of `transfer`'s own
    /// arithmetic (`slack`).
    fn missed_by(&self, s: &Source) -> bool {
        let reach = self.lo.abs().max(self.hi.abs()).max_element();
        let slack = 2e-6 * (reach + s.p.abs().max_element() + 1.0);
        let limit = s.tol - slack;
        // Largest |q − s| over the box.
        let far = (self.lo - s.p).abs().max((self.hi - s.p).abs()).length();
        // Largest (q − s)·ng_s: over the box, and for a face through its plane.
        let (a, b) = ((self.lo - s.p) * s.ng, (self.hi - s.p) * s.ng);
        let mut front = a.max(b).element_sum();
        if let Some(pl) = &self.plane {
            // (q − s)·ng_s = (q − s)·axis + (q − s)·(ng_s − axis).
            let d = (s.ng - pl.axis).length();
            front = front.min(pl.max - s.p.dot(pl.axis) + far * d);
        }
        if front <= limit {
            return true;
        }
        // Largest (s − q)·ng_q ≤ (s − q)·axis + |s − q|·spread.
        self.plane
            .as_ref()
            .is_some_and(|pl| s.p.dot(pl.axis) - pl.min + far * pl.spread <= limit)
    }
}

/// Receivers nearer than this many group sizes (√A) are shot from the group's patches.
const NEAR: f64 = 3.0;

fn ray_eps(p: Vec3) -> f32 {
    2e-5 * (1.0 + p.abs().max_element())
}

/// Irradiance that source `s` with unshot radiosity `s.u` delivers to patch `q`: `u·F`,
/// `F = A·cosθ_s·cosθ_q/(π r² + A)`, zero when either faces away (or lies in the other's
/// plane, within `s.tol`) or the centre-to-centre ray is blocked (`visible` answers that when
/// it is known).
#[inline]
fn transfer(accel: &Accel, s: &Source, q: &Receiver, visible: Option<bool>) -> Option<DVec3> {
    let r = q.p - s.p;
    let r2 = r.length_squared() as f64;
    if r2 <= 0.0 {
        return None;
    }
    let cos_s = s.n.dot(r) as f64;
    let cos_q = -(q.n.dot(r)) as f64;
    if cos_s <= 0.0 || cos_q <= 0.0 || r.dot(s.ng) <= s.tol || -r.dot(q.ng) <= s.tol {
        return None;
    }
    let visible = visible.unwrap_or_else(|| {
        let o = s.p + s.ng * ray_eps(s.p);
        let target = q.p + q.ng * ray_eps(q.p);
        !accel.occluded(o, target - o, 1.0 - 1e-4)
    });
    if !visible {
        return None;
    }
    // cosθ_s·cosθ_q/r² from the unnormalised r: (n·r)(−n_q·r)/r⁴, no square roots.
    let g = cos_s * cos_q / (r2 * r2);
    // Wallace et al.'s disc form factor A·cos·cos/(π r² + A): finite as r → 0, where
    // CaLight's clamp r ≥ √A with min(F, 1) over-counts near neighbours.
    let f = s.area * g * r2 / (PI * r2 + s.area);
    Some(s.u * f)
}

/// CaLight's sun smoothing: a weighted 3×3 average over valid patches of the same instance
/// (centre 1, edges ¼, corners 1/16), from the values before smoothing.
fn smooth(patches: &[Patch], index: &[Vec<u32>], texels: &Texels, de: Vec<DVec3>) -> Vec<DVec3> {
    (0..patches.len())
        .into_par_iter()
        .map(|k| {
            let p = &patches[k];
            let page = &texels.pages[p.page];
            let (mut sum, mut wsum) = (DVec3::ZERO, 0.0);
            for dy in -1i32..=1 {
                for dx in -1i32..=1 {
                    let (x, y) = (p.x as i32 + dx, p.y as i32 + dy);
                    if x < 0 || y < 0 || x >= page.width as i32 || y >= page.height as i32 {
                        continue;
                    }
                    let j = index[p.page][(y as u32 * page.width + x as u32) as usize];
                    if j == u32::MAX {
                        continue;
                    }
                    let q = &patches[j as usize];
                    if q.instance != p.instance || q.ng.dot(p.ng) < 0.9 {
                        continue;
                    }
                    let w = match dx.abs() + dy.abs() {
                        0 => 1.0,
                        1 => 0.25,
                        _ => 0.0625,
                    };
                    sum += de[j as usize] * w;
                    wsum += w;
                }
            }
            sum / wsum
        })
        .collect()
}

fn to_pages(texels: &Texels, index: &[Vec<u32>], total: &[DVec3]) -> Vec<Vec<Vec3>> {
    texels
        .pages
        .iter()
        .zip(index)
        .map(|(_, idx)| {
            idx.iter()
                .map(|&k| {
                    if k == u32::MAX {
                        Vec3::ZERO
                    } else {
                        (total[k as usize] / PI).as_vec3()
                    }
                })
                .collect()
        })
        .collect()
}
