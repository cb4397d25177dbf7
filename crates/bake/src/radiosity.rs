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
//!    of their own (hierarchical receivers, which cuts the rays of a shot about n²-fold). The
//!    group's unshot radiosity is then zero: absorbed energy leaves the system,
//!    which guarantees progress.
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
//! makes a ray cheap.
//!
//! Energy is accumulated in f64.

use crate::texels::{TexelSample, Texels};
use crate::{BakeError, LightMode, Progress};
use glam::{DVec3, Vec3};
use lightlab_core::sampling::{Frame, Rng, cosine_hemisphere, hammersley};
use lightlab_scene::{LightKind, Scene};
use lightlab_trace::Accel;
use lightlab_trace::lights::sample_punctual;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
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
}

impl Default for RadiositySettings {
    fn default() -> Self {
        RadiositySettings {
            block_size: 3,
            stop: 1e-4,
            sun_samples: 16,
            sky_samples: 256,
            max_shots: 2_000_000,
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
    // Patches and a texel → patch index per page.
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
    let np = patches.len();
    let mut stats = RadiosityStats {
        patches: np,
        ..Default::default()
    };
    // Incident irradiance counted in the light-map, and unshot radiosity.
    let mut total = vec![DVec3::ZERO; np];
    let mut unshot = vec![DVec3::ZERO; np];
    let sample_of = |k: usize| -> &TexelSample {
        let p = &patches[k];
        let page = &texels.pages[p.page];
        page.samples[(p.y * page.width + p.x) as usize]
            .as_ref()
            .expect("patches are valid texels")
    };

    // 1. Direct light.
    progress("radiosity: direct light", 0, np);
    let eps = |p: Vec3| 2e-5 * (1.0 + p.abs().max_element());
    for (li, light) in scene.lights.iter().enumerate() {
        let mode = modes.get(li).copied().unwrap_or(LightMode::Baked);
        if mode == LightMode::Realtime {
            continue;
        }
        let is_sun = matches!(light.kind, LightKind::Directional { .. });
        let n_samples = if is_sun {
            settings.sun_samples.max(1)
        } else {
            1
        };
        let de: Vec<DVec3> = (0..np)
            .into_par_iter()
            .map(|k| {
                let pa = &patches[k];
                let s = sample_of(k);
                let mut rng = Rng::new(seed ^ ((li as u64 + 1) * 0x9e37), k as u64);
                let mut sum = DVec3::ZERO;
                for j in 0..n_samples {
                    // Jitter across fully covered patches (CaLight samples the patch polygon).
                    let p = if is_sun && s.coverage >= 0.999 && n_samples > 1 {
                        let u = hammersley(j, n_samples) - 0.5;
                        pa.p + s.dpdx * u.x + s.dpdy * u.y
                    } else {
                        pa.p
                    };
                    let Some(ls) = sample_punctual(scene, li, p, rng.next_vec2()) else {
                        continue;
                    };
                    let cos = pa.n.dot(ls.wi);
                    if cos <= 0.0 || ls.wi.dot(pa.ng) <= 0.0 {
                        continue;
                    }
                    let o = p + pa.ng * eps(p);
                    let (dir, tmax) = if ls.dist.is_finite() {
                        (p + ls.wi * ls.dist - o, 1.0 - 1e-4)
                    } else {
                        (ls.wi, f32::INFINITY)
                    };
                    if accel.occluded(o, dir, tmax) {
                        continue;
                    }
                    let mut v = ls.value.as_dvec3() * cos as f64;
                    if ls.dist.is_finite() {
                        // CaLight's near-field guard: below one patch size, d := patch size and
                        // the cosine is dropped.
                        let size = pa.area.sqrt();
                        let d = ls.dist as f64;
                        if d < size {
                            v = ls.value.as_dvec3() * (d * d) / (size * size);
                        }
                    }
                    sum += v;
                }
                sum / n_samples as f64
            })
            .collect();
        let de = if is_sun {
            smooth(&patches, &index, texels, de)
        } else {
            de
        };
        stats.transfers += (np as u64) * n_samples as u64;
        for k in 0..np {
            if mode == LightMode::Baked {
                total[k] += de[k];
            }
            unshot[k] += patches[k].rho * de[k];
        }
    }
    if let Some(env) = &scene.environment {
        let n = settings.sky_samples.max(1);
        let de: Vec<DVec3> = (0..np)
            .into_par_iter()
            .map(|k| {
                let pa = &patches[k];
                let mut rng = Rng::new(seed ^ 0x5c1e5, k as u64);
                let off = rng.next_vec2();
                let frame = Frame::from_normal(pa.n);
                let o = pa.p + pa.ng * eps(pa.p);
                let mut sum = DVec3::ZERO;
                for j in 0..n {
                    let d = frame.to_world(cosine_hemisphere((hammersley(j, n) + off).fract_gl()));
                    if d.dot(pa.ng) <= 0.0 || accel.occluded(o, d, f32::INFINITY) {
                        continue;
                    }
                    sum += env.radiance(d).as_dvec3();
                }
                sum * PI / n as f64
            })
            .collect();
        stats.transfers += np as u64 * n as u64;
        for k in 0..np {
            total[k] += de[k];
            unshot[k] += patches[k].rho * de[k];
        }
    }
    // Emitters: exitance π·L_e, shot like any radiosity.
    for (k, u) in unshot.iter_mut().enumerate() {
        *u += sample_of(k).emission.as_dvec3() * PI;
    }

    // 2. Progressive refinement.
    let key = |u: DVec3| u.x + u.y + u.z;
    let initial_max = unshot.iter().map(|&u| key(u)).fold(0.0, f64::max);
    let mut emitted_power: f64 = (0..np).map(|k| key(unshot[k]) * patches[k].area).sum();
    if initial_max <= 0.0 {
        return Ok((to_pages(texels, &index, &total), stats));
    }
    let threshold = settings.stop * initial_max;
    // Surfaces: patches per instance.
    let mut surfaces: Vec<Vec<u32>> = vec![];
    {
        let mut by_inst: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
        for (k, p) in patches.iter().enumerate() {
            by_inst.entry(p.instance).or_default().push(k as u32);
        }
        surfaces.extend(by_inst.into_values());
    }
    let n = settings.block_size;
    // Blocks: n×n texels of one instance with similar normals. They group shooters (CaLight's
    // BlockSize) and, for far shooters, receivers.
    let mut block_id = vec![0u32; np];
    let blocks: Vec<Block> = {
        let mut map: std::collections::HashMap<(usize, u32, u32, u32), usize> = Default::default();
        let mut blocks: Vec<Block> = vec![];
        for (k, p) in patches.iter().enumerate() {
            let key = (p.page, p.x / n, p.y / n, p.instance);
            let slot = map
                .get(&key)
                .copied()
                .filter(|&b| blocks[b].ng.dot(p.ng) > 0.9);
            let b = match slot {
                Some(b) => b,
                None => {
                    blocks.push(Block {
                        members: vec![],
                        centre: Vec3::ZERO,
                        ng: p.ng,
                        area: 0.0,
                    });
                    map.insert(key, blocks.len() - 1);
                    blocks.len() - 1
                }
            };
            block_id[k] = b as u32;
            blocks[b].members.push(k as u32);
            blocks[b].centre += p.p;
            blocks[b].area += p.area;
        }
        for b in &mut blocks {
            b.centre /= b.members.len() as f32;
        }
        blocks
    };
    let block_of = |k: usize| -> &[u32] { &blocks[block_id[k] as usize].members };
    let block_value = |k: usize, unshot: &[DVec3]| -> f64 {
        let b = block_of(k);
        b.iter().map(|&j| key(unshot[j as usize])).sum::<f64>() / b.len() as f64
    };
    let mut rng = Rng::new(seed, 0x5407);
    let mut shots = 0u64;
    loop {
        // Select: random blocks per surface, the best of all.
        let mut best = (0.0f64, usize::MAX);
        for surf in &surfaces {
            let samples = 10.min((surf.len() / 2).max(1));
            for _ in 0..samples {
                let k = surf[(rng.next_u32() as usize) % surf.len()] as usize;
                let v = block_value(k, &unshot);
                if v > best.0 {
                    best = (v, k);
                }
            }
        }
        if best.0 < threshold {
            // Full search: the best patch of the first surface that holds one above threshold.
            best = (0.0, usize::MAX);
            for surf in &surfaces {
                for &k in surf {
                    let v = key(unshot[k as usize]);
                    if v >= threshold && v > best.0 {
                        best = (v, k as usize);
                    }
                }
                if best.1 != usize::MAX {
                    break;
                }
            }
            if best.1 == usize::MAX {
                break;
            }
        }
        if shots >= settings.max_shots {
            stats.hit_shot_limit = true;
            break;
        }
        // Group and shoot.
        let group = &blocks[block_id[best.1] as usize];
        let (c, area) = (group.centre, group.area);
        let members: Vec<(Vec3, Vec3, Vec3, f64, DVec3)> = group
            .members
            .iter()
            .map(|&j| {
                let q = &patches[j as usize];
                (q.p, q.n, q.ng, q.area, unshot[j as usize])
            })
            .collect();
        let power: DVec3 = members.iter().map(|m| m.4 * m.3).sum();
        let nrm = members
            .iter()
            .map(|m| m.1.as_dvec3())
            .sum::<DVec3>()
            .normalize_or_zero()
            .as_vec3();
        let ng = patches[best.1].ng;
        for &j in &group.members {
            unshot[j as usize] = DVec3::ZERO;
        }
        // Receivers closer than `NEAR` group sizes get the members' own shots (the thesis's
        // future work "choose n by receiver distance"); the rest get the group's.
        let near2 = NEAR * NEAR * area;
        let o = c + ng * ray_eps(c);
        let shoot_one = |j: usize, vis: Option<bool>| -> Option<(usize, DVec3)> {
            let q = &patches[j];
            let far = ((q.p - c).length_squared() as f64) >= near2 || members.len() == 1;
            let e = if far {
                transfer(accel, (c, nrm, ng, area), power / area, q, vis)?
            } else {
                let mut e = DVec3::ZERO;
                for m in &members {
                    if let Some(v) = transfer(accel, (m.0, m.1, m.2, m.3), m.4, q, None) {
                        e += v;
                    }
                }
                e
            };
            (e != DVec3::ZERO).then_some((j, e))
        };
        let de: Vec<(usize, DVec3)> = blocks
            .par_iter()
            .flat_map_iter(|b| {
                // Far receiver blocks share one visibility ray (hierarchical receivers).
                let d2 = (b.centre - c).length_squared() as f64;
                let shared = b.members.len() > 1 && d2 >= NEAR * NEAR * (area + b.area);
                let vis = if shared {
                    let r = b.centre - c;
                    if r.dot(ng) <= 0.0 || -r.dot(b.ng) <= 0.0 {
                        Some(false)
                    } else {
                        let target = b.centre + b.ng * ray_eps(b.centre);
                        Some(!accel.occluded(o, target - o, 1.0 - 1e-4))
                    }
                } else {
                    None
                };
                let shoot_one = &shoot_one;
                b.members.iter().filter_map(move |&j| match vis {
                    Some(false) => None,
                    v => shoot_one(j as usize, v.map(|_| true)),
                })
            })
            .collect();
        stats.transfers += np as u64;
        for (j, e) in de {
            total[j] += e;
            unshot[j] += patches[j].rho * e;
        }
        shots += 1;
        if shots.is_multiple_of(64) && !progress("radiosity: shooting", shots as usize, 0) {
            return Err(BakeError::Cancelled);
        }
    }
    let left: f64 = (0..np).map(|k| key(unshot[k]) * patches[k].area).sum();
    emitted_power = emitted_power.max(1e-300);
    stats.shots = shots;
    stats.unshot_fraction = left / emitted_power;
    Ok((to_pages(texels, &index, &total), stats))
}

/// An n×n block of patches of one instance with similar normals: a shooter group, and for
/// far shooters a receiver group reached with one visibility ray.
struct Block {
    members: Vec<u32>,
    centre: Vec3,
    ng: Vec3,
    area: f64,
}

/// Receivers nearer than this many group sizes (√A) are shot from the group's patches.
const NEAR: f64 = 3.0;

fn ray_eps(p: Vec3) -> f32 {
    2e-5 * (1.0 + p.abs().max_element())
}

/// Irradiance that a source (point, shading normal, geometric normal, area) with unshot
/// radiosity `u` delivers to patch `q`: `u·F`, `F = A·cosθ_s·cosθ_q/(π r² + A)`, zero when
/// either faces away or the centre-to-centre ray is blocked.
fn transfer(
    accel: &Accel,
    (sp, sn, sng, area): (Vec3, Vec3, Vec3, f64),
    u: DVec3,
    q: &Patch,
    visible: Option<bool>,
) -> Option<DVec3> {
    let r = q.p - sp;
    let r2 = r.length_squared() as f64;
    if r2 <= 0.0 {
        return None;
    }
    let cos_s = sn.dot(r) as f64;
    let cos_q = -(q.n.dot(r)) as f64;
    if cos_s <= 0.0 || cos_q <= 0.0 || r.dot(sng) <= 0.0 || -r.dot(q.ng) <= 0.0 {
        return None;
    }
    let visible = visible.unwrap_or_else(|| {
        let o = sp + sng * ray_eps(sp);
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
    let f = area * g * r2 / (PI * r2 + area);
    Some(u * f)
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
