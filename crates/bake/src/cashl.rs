//! CaSHL's bounce transfer by **shooting** SH vectors (Fuchs 2005 §5.4.3; extraction `seed-000`
//! §4.6.3): progressive-refinement radiosity with bands² "colour channels", the counterpart of
//! the gathering bounces in [`crate::prt`].
//!
//! Transfer is linear in the light (Fuchs eq. 11/12), so the inter-reflected transfer of every
//! patch (light-map texel) solves one radiosity problem per SH coefficient, all at once:
//!
//! ```text
//! T_j = T_j^direct + Σ_I F_{j←I} ρ_I T_I          (T: E/π per unit incident radiance)
//! ```
//!
//! 1. Every patch starts with its shadowed (direct) transfer as total T and ρ·T as *unshot*
//!    U (CaSHL: `Unradiated := Total` after the direct step; here ρ is the texel's mean
//!    albedo, a scalar transfer as in the gathering variant, where CaSHL uses one global 0.3).
//! 2. Repeat: the n×n block (CaLight's BlockSize; same instance and page, normals within 25°)
//!    holding the most unshot *power* Σ |U|₁·A (CaSHL's selection is the L1 norm of the
//!    coefficients) shoots: every receiver j it faces gets ΔT_j = (Φ/A_I)·F_{j←I}, Φ = Σ U_k A_k,
//!    with Wallace's disc form factor F = A_I cosθ_I cosθ_j/(π r² + A_I) and a visibility ray
//!    from the block's centre; receivers within three block sizes are shot from the block's
//!    patches one by one (the near field, where one centre misjudges the angles, as in
//!    [`crate::radiosity`]). T_j += ΔT_j, U_j += ρ_j ΔT_j; the block's unshot transfer becomes 0.
//! 3. Stop when no block holds more than `stop` × the largest initial unshot power.
//!
//! Each block holds its members' total and unshot transfer while the solver runs, so that a
//! shot updates every receiving block in place, in parallel (one rayon task per block), with
//! no per-patch vectors collected and applied serially; the result is the same bit for bit.
//!
//! Deviations: the form factor (Wallace instead of CaLight's clamped point-to-point one, see
//! `radiosity`'s module doc for why), the relative stop threshold (CaSHL's StopUT 0.1 is in its
//! own units), per-texel albedo, and no tone mapping of the transfer (CaSHL tone-maps it
//! with Ward Larson's operator; lightlab keeps physical units so that renders compare with the
//! reference). Cost: O(shots × patches) rays; the gathering variant costs O(patches × samples ×
//! bounces) and is the default.

use glam::Vec3;
use lightlab_trace::Accel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Shooting settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShootSettings {
    /// Shooter grouping n (n×n patches; CaSHL's BlockSize, default 3, 1..8).
    pub block_size: u32,
    /// Stop when no block holds more unshot power than this fraction of the largest initial one.
    pub stop: f32,
    /// Safety limit on shots.
    pub max_shots: u64,
}

impl Default for ShootSettings {
    fn default() -> Self {
        ShootSettings {
            block_size: 3,
            stop: 1e-3,
            max_shots: 1_000_000,
        }
    }
}

/// What the solver did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShootStats {
    pub patches: usize,
    pub shots: u64,
    /// Unshot power left over the initial unshot power.
    pub unshot_fraction: f64,
    pub hit_shot_limit: bool,
}

/// A shooting and receiving patch.
#[derive(Clone, Copy, Debug)]
pub struct ShootPatch {
    /// Surface point (on the surface; rays are offset along `ng`).
    pub p: Vec3,
    /// Shading normal.
    pub n: Vec3,
    /// Geometric normal.
    pub ng: Vec3,
    pub area: f32,
    /// Scalar diffuse reflectance (mean of the RGB albedo).
    pub rho: f32,
    /// Grouping key: page, texel x, texel y, instance.
    pub page: u32,
    pub x: u32,
    pub y: u32,
    pub instance: u32,
}

/// An n×n block of patches of one instance and page with similar normals: a shooter, and a
/// unit of the parallel update. It holds its members' transfer while the solver runs (so that
/// a shot updates every block in place, in parallel, without collecting per-patch vectors).
struct Block {
    members: Vec<u32>,
    centre: Vec3,
    n: Vec3,
    ng: Vec3,
    area: f32,
    /// The members' total and unshot transfer (member-major, `nc` each).
    total: Vec<f32>,
    unshot: Vec<f32>,
    /// An upper bound of the unshot power Σ |U|₁·A (exact after [`Block::power`]).
    power: f64,
}

impl Block {
    /// The exact unshot power Σ |U|₁·A.
    fn power(&self, patches: &[ShootPatch], nc: usize) -> f64 {
        self.members
            .iter()
            .zip(self.unshot.chunks_exact(nc))
            .map(|(&k, u)| {
                u.iter().map(|v| v.abs() as f64).sum::<f64>() * patches[k as usize].area as f64
            })
            .sum()
    }
}

/// What one shot sends: the shooting block as one source (centre, mean shading normal,
/// geometric normal, area, unshot power per coefficient) and, for the near field, its members
/// with their own unshot transfer.
struct Shot {
    c: Vec3,
    n: Vec3,
    ng: Vec3,
    area: f32,
    phi: Vec<f32>,
    members: Vec<(ShootPatch, Vec<f32>)>,
}

/// Receivers closer than this many block sizes are shot from the block's patches one by one.
const NEAR: f32 = 3.0;

fn ray_eps(p: Vec3) -> f32 {
    2e-5 * (1.0 + p.abs().max_element())
}

/// Shoot. `transfer` holds the patches' direct transfer (patch-major, `nc` coefficients each)
/// and returns their total. `progress(done shots)` returning false cancels
/// (`BakeError::Cancelled`).
pub fn shoot(
    accel: &Accel,
    patches: &[ShootPatch],
    transfer: &mut [f32],
    nc: usize,
    s: &ShootSettings,
    progress: &(dyn Fn(u64) -> bool + Sync),
) -> Result<ShootStats, crate::BakeError> {
    if !(1..=8).contains(&s.block_size) {
        return Err(crate::BakeError::Settings(format!(
            "shooting block size must be 1 to 8, not {}",
            s.block_size
        )));
    }
    if !(s.stop > 0.0 && s.stop < 1.0) {
        return Err(crate::BakeError::Settings(format!(
            "shooting stop must be in (0, 1), not {}",
            s.stop
        )));
    }
    let np = patches.len();
    assert_eq!(transfer.len(), np * nc, "one transfer vector per patch");
    let mut stats = ShootStats {
        patches: np,
        ..Default::default()
    };
    let mut blocks = make_blocks(patches, transfer, nc, s.block_size);
    for b in &mut blocks {
        b.power = b.power(patches, nc);
    }
    let initial_total: f64 = blocks.iter().map(|b| b.power).sum();
    let initial_max = blocks.iter().map(|b| b.power).fold(0.0, f64::max);
    if initial_max <= 0.0 {
        return Ok(stats);
    }
    let threshold = s.stop as f64 * initial_max;
    loop {
        let (bi, bp) =
            blocks
                .iter()
                .map(|b| b.power)
                .enumerate()
                .fold(
                    (usize::MAX, 0.0),
                    |a, (i, v)| if v > a.1 { (i, v) } else { a },
                );
        if bi == usize::MAX || bp < threshold {
            break;
        }
        // `power` is an upper bound (|·|₁ of a sum ≤ the sum of |·|₁): recount the chosen
        // block, and choose again when the bound was loose.
        let real = blocks[bi].power(patches, nc);
        if real < 0.999 * bp {
            blocks[bi].power = real;
            continue;
        }
        if stats.shots >= s.max_shots {
            stats.hit_shot_limit = true;
            break;
        }
        if stats.shots.is_multiple_of(64) && !progress(stats.shots) {
            return Err(crate::BakeError::Cancelled);
        }
        stats.shots += 1;
        let shot = take_shot(&mut blocks[bi], patches, nc);
        blocks
            .par_iter_mut()
            .enumerate()
            .filter(|(i, _)| *i != bi)
            .for_each(|(_, b)| receive(accel, &shot, b, patches, nc));
    }
    let left: f64 = blocks.iter().map(|b| b.power(patches, nc)).sum();
    stats.unshot_fraction = if initial_total > 0.0 {
        left / initial_total
    } else {
        0.0
    };
    for b in &blocks {
        for (&k, t) in b.members.iter().zip(b.total.chunks_exact(nc)) {
            let k = k as usize;
            transfer[k * nc..(k + 1) * nc].copy_from_slice(t);
        }
    }
    Ok(stats)
}

/// Group the patches into blocks of n×n patches of one instance and page with similar normals
/// (members in patch order), each holding its members' transfer: total = `transfer`,
/// unshot = ρ·`transfer`.
fn make_blocks(patches: &[ShootPatch], transfer: &[f32], nc: usize, n: u32) -> Vec<Block> {
    let mut blocks: Vec<Block> = vec![];
    let mut map: std::collections::HashMap<(u32, u32, u32, u32), Vec<usize>> = Default::default();
    for (k, p) in patches.iter().enumerate() {
        let key = (p.page, p.x / n, p.y / n, p.instance);
        let list = map.entry(key).or_default();
        let found = list.iter().copied().find(|&b| blocks[b].ng.dot(p.ng) > 0.9);
        let b = found.unwrap_or_else(|| {
            blocks.push(Block {
                members: vec![],
                centre: Vec3::ZERO,
                n: Vec3::ZERO,
                ng: p.ng,
                area: 0.0,
                total: vec![],
                unshot: vec![],
                power: 0.0,
            });
            list.push(blocks.len() - 1);
            blocks.len() - 1
        });
        let bl = &mut blocks[b];
        let t = &transfer[k * nc..(k + 1) * nc];
        bl.members.push(k as u32);
        bl.total.extend_from_slice(t);
        bl.unshot.extend(t.iter().map(|v| v * p.rho));
        bl.centre += p.p;
        bl.n += p.n;
        bl.area += p.area;
    }
    for b in &mut blocks {
        b.centre /= b.members.len() as f32;
        b.n = b.n.normalize_or(b.ng);
    }
    blocks
}

/// Empty block `b`'s unshot transfer into a shot.
fn take_shot(b: &mut Block, patches: &[ShootPatch], nc: usize) -> Shot {
    let mut phi = vec![0.0f32; nc];
    let members = b
        .members
        .iter()
        .zip(b.unshot.chunks_exact(nc))
        .map(|(&k, u)| {
            let q = patches[k as usize];
            for (a, v) in phi.iter_mut().zip(u) {
                *a += v * q.area;
            }
            (q, u.to_vec())
        })
        .collect();
    b.unshot.fill(0.0);
    b.power = 0.0;
    Shot {
        c: b.centre,
        n: b.n,
        ng: b.ng,
        area: b.area,
        phi,
        members,
    }
}

/// The form factor F from a source (centre `c`, normals, area) to patch `q`, if it faces the
/// source and sees it (Wallace's disc form factor times the area: A cosθ_I cosθ_j/(πr² + A)).
fn form_factor(
    accel: &Accel,
    q: &ShootPatch,
    c: Vec3,
    nrm: Vec3,
    ng: Vec3,
    area: f32,
) -> Option<f32> {
    let r = q.p - c;
    let d2 = r.length_squared();
    if d2 <= 0.0 {
        return None;
    }
    let d = r / d2.sqrt();
    let (ci, cj) = (nrm.dot(d), -q.n.dot(d));
    if ci <= 0.0 || cj <= 0.0 || ng.dot(d) <= 0.0 || -q.ng.dot(d) <= 0.0 {
        return None;
    }
    let o = c + ng * ray_eps(c);
    let t = q.p + q.ng * ray_eps(q.p);
    if accel.occluded(o, t - o, 1.0 - 1e-4) {
        return None;
    }
    Some(area * ci * cj / (std::f32::consts::PI * d2 + area))
}

/// Receive `shot` into every member of block `b`: ΔT = (Φ/A_I)·F from the block as one source,
/// or Σ U_m·F_m from its members one by one within the near field; T += ΔT, U += ρΔT, and the
/// block's power bound grows by |ρΔT|₁·A.
fn receive(accel: &Accel, shot: &Shot, b: &mut Block, patches: &[ShootPatch], nc: usize) {
    let near2 = NEAR * NEAR * shot.area;
    let single = shot.members.len() == 1;
    let mut dt = vec![0.0f32; nc];
    for (i, &k) in b.members.iter().enumerate() {
        let q = &patches[k as usize];
        if single || (q.p - shot.c).length_squared() >= near2 {
            let Some(f) = form_factor(accel, q, shot.c, shot.n, shot.ng, shot.area) else {
                continue;
            };
            let w = f / shot.area;
            for (a, v) in dt.iter_mut().zip(&shot.phi) {
                *a = v * w;
            }
        } else {
            dt.fill(0.0);
            let mut any = false;
            for (m, u) in &shot.members {
                if let Some(f) = form_factor(accel, q, m.p, m.n, m.ng, m.area) {
                    any = true;
                    for (a, v) in dt.iter_mut().zip(u) {
                        *a += v * f;
                    }
                }
            }
            if !any {
                continue;
            }
        }
        let mut added = 0.0f64;
        let (t, u) = (
            &mut b.total[i * nc..(i + 1) * nc],
            &mut b.unshot[i * nc..(i + 1) * nc],
        );
        for ((t, u), v) in t.iter_mut().zip(u.iter_mut()).zip(&dt) {
            *t += v;
            *u += q.rho * v;
            added += (q.rho * v).abs() as f64;
        }
        b.power += added * q.area as f64;
    }
}
