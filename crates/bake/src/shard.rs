//! Bakes split over machines: a shard solves a contiguous range of the texels and writes a
//! part folder; a merge checks that the parts belong together and assembles the bake that one
//! machine would have made, bit for bit.
//!
//! Why this is safe: everything before the solver (UV layout, texel rasterisation, the
//! validity probe) is deterministic, so every shard and the merge compute it alike; the path
//! gatherer draws texel i's paths from `Rng::new(seed, i)` alone, so a texel's value does not
//! depend on which machine, thread or range computed it; and what follows the solver (filling,
//! seam stitching) runs once, in the merge, over the assembled pages.
//!
//! **Ranges.** The texel slots are numbered page by page (the gatherer's numbering) and cut into
//! `N` contiguous ranges of equal estimated cost. A slot costs one unit when it is gathered (it
//! has a surface sample and passed the validity probe) and nothing otherwise: every gathered
//! texel traces the same number of paths, so empty page space, which can be most of a page, is
//! not counted as work.
//!
//! **What cannot be sharded.** Radiosity shooting is one global iteration: each shot reads the
//! unshot energy every earlier shot left, so its shots cannot run apart. A shard of a radiosity
//! bake is refused with that reason; bake it on one machine, or use path gathering.
//!
//! A part folder (`lightlab-bake-part`): `manifest.json` ([`PartManifest`], written last with
//! the integrity record of [`crate::folder`]) and `values.bin`, the range's E/π as
//! little-endian f32 RGB triples, followed by the directional ratios when the bake has them.

use crate::folder;
use crate::{BakeError, BakeSettings, Lightmaps, Method, Progress};
use glam::Vec3;
use lightlab_scene::Scene;
use serde::{Deserialize, Serialize};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub const PART_FORMAT: &str = "lightlab-bake-part";
pub const PART_VERSION: u32 = 1;
const VALUES: &str = "values.bin";

/// Shard `index` of `count` (0-based: index < count).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// Parse `I/N` (0 ≤ I < N). `auto/N` is the caller's: it reads the index from a
    /// scheduler's environment ([`Shard::from_env`]).
    pub fn parse(s: &str) -> Result<Shard, BakeError> {
        let bad = |why: &str| BakeError::Settings(format!("--shard '{s}': {why}"));
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| bad("expected I/N, shard I of N counted from 0 (e.g. 0/4)"))?;
        let count: u32 = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        let index: u32 = if i.trim() == "auto" {
            Shard::index_from_env(|k| std::env::var(k).ok()).map_err(|e| bad(&e))?
        } else {
            i.trim()
                .parse()
                .map_err(|_| bad("I is not a whole number or `auto`"))?
        };
        Shard::new(index, count).map_err(|e| bad(&e))
    }

    pub fn new(index: u32, count: u32) -> Result<Shard, String> {
        if count == 0 {
            return Err("N must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "I must be below N (shards are numbered 0 to {})",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }

    /// The shard index a scheduler gives its task: `JOB_COMPLETION_INDEX` (Kubernetes Indexed
    /// Jobs), else `SLURM_ARRAY_TASK_ID` (Slurm job arrays), both counted from 0 here (a Slurm
    /// array should be declared `--array=0-(N-1)`).
    pub fn index_from_env(var: impl Fn(&str) -> Option<String>) -> Result<u32, String> {
        for key in ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"] {
            if let Some(v) = var(key) {
                return v
                    .trim()
                    .parse()
                    .map_err(|_| format!("{key}={v} is not a whole number"));
            }
        }
        Err(
            "`auto` needs JOB_COMPLETION_INDEX (Kubernetes Indexed Job) or \
             SLURM_ARRAY_TASK_ID (Slurm array) in the environment"
                .into(),
        )
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Cut slots with costs `cost` into `count` contiguous ranges of nearly equal total cost
/// (range k ends at the first slot where the running cost reaches ⌈k·C/N⌉); together they
/// cover every slot once.
pub fn balanced_ranges(cost: &[u32], count: u32) -> Vec<Range<u64>> {
    let total: u64 = cost.iter().map(|&c| c as u64).sum();
    let n = count.max(1) as u64;
    let mut ends = Vec::with_capacity(n as usize);
    let mut run = 0u64;
    let mut slot = 0usize;
    for k in 1..n {
        let target = (k * total).div_ceil(n);
        while slot < cost.len() && run < target {
            run += cost[slot] as u64;
            slot += 1;
        }
        ends.push(slot as u64);
    }
    ends.push(cost.len() as u64);
    let mut start = 0;
    ends.into_iter()
        .map(|e| {
            let r = start..e;
            start = e;
            r
        })
        .collect()
}

/// What a part folder's manifest records.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartManifest {
    pub format: String,
    pub version: u32,
    /// What was baked: `lightmaps` (path gathering) or `sh` (SH light-maps).
    pub kind: String,
    /// The scene as the command line named it (a built-in name or a file).
    pub scene: String,
    /// [`Scene::fingerprint`] in hex: the merge refuses a scene with another.
    pub scene_fingerprint: String,
    /// The bake's settings: `BakeSettings` (lightmaps) or [`ShBakeSettings`] (sh).
    pub settings: serde_json::Value,
    pub shard: Shard,
    /// The slot range this part solved, of `slots` in all.
    pub start: u64,
    pub end: u64,
    pub slots: u64,
    /// How many f32 values `values.bin` holds.
    pub values: u64,
    /// Rays the solver cast for this range (the merge adds its own validity probe's).
    pub solve_rays: u64,
    pub seconds: f64,
    /// The outputs the bake asked for (PNG pages, glTF), which the merge writes.
    #[serde(default)]
    pub png: bool,
    #[serde(default)]
    pub gltf: bool,
    /// SH bakes: the k-means compressed copy's representatives (`--compress N`).
    #[serde(default)]
    pub compress: Option<usize>,
}

/// The settings of a sharded SH light-map bake.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShBakeSettings {
    pub layout: crate::layout::LayoutSettings,
    pub transfer: crate::prt::TransferSettings,
}

/// A part: its manifest and its range's values. Light-maps: RGB E/π per slot of the range,
/// then the directional ratios; SH: per gathered texel of the range, its transfer
/// coefficients and its ambient occlusion.
#[derive(Clone, Debug)]
pub struct Part {
    pub manifest: PartManifest,
    pub values: Vec<f32>,
}

/// The cost of each slot, page by page: 1 where the solver works (a sample that passed the
/// validity probe).
fn slot_costs(texels: &crate::texels::Texels, valid: &[Vec<bool>]) -> Vec<u32> {
    texels
        .pages
        .iter()
        .zip(valid)
        .flat_map(|(p, v)| {
            p.samples
                .iter()
                .zip(v)
                .map(|(s, &ok)| u32::from(s.is_some() && ok))
        })
        .collect()
}

fn hex(f: u64) -> String {
    format!("{f:016x}")
}

fn settings_value<T: Serialize>(t: &T) -> serde_json::Value {
    serde_json::to_value(t).expect("settings serialise")
}

/// A part manifest with what every kind shares; the caller fills in the range and values.
fn part_manifest(
    kind: &str,
    scene: (&Scene, &str),
    settings: serde_json::Value,
    shard: Shard,
) -> PartManifest {
    PartManifest {
        format: PART_FORMAT.into(),
        version: PART_VERSION,
        kind: kind.into(),
        scene: scene.1.into(),
        scene_fingerprint: hex(scene.0.fingerprint()),
        settings,
        shard,
        start: 0,
        end: 0,
        slots: 0,
        values: 0,
        solve_rays: 0,
        seconds: 0.0,
        png: false,
        gltf: false,
        compress: None,
    }
}

/// Bake shard `shard` of the light-maps of `scene` (`scene_name` as the command line named
/// it): the path gatherer over its range of slots.
pub fn bake_part(
    scene: &Scene,
    scene_name: &str,
    settings: &BakeSettings,
    shard: Shard,
    progress: Progress,
) -> Result<Part, BakeError> {
    if settings.method == Method::Radiosity {
        return Err(BakeError::Settings(
            "radiosity cannot be sharded: its shooting is one global iteration in which every \
             shot reads the energy all earlier shots left; bake it on one machine, or shard a \
             path-gathered bake (--method path)"
                .into(),
        ));
    }
    let t = Instant::now();
    let mut prep = crate::prepare(scene, settings, progress)?;
    let costs = slot_costs(&prep.texels, &prep.valid);
    let range = balanced_ranges(&costs, shard.count)[shard.index as usize].clone();
    // Only the range's texels are gathered: the others are masked out as if invalid.
    let mut mask = prep.valid.clone();
    let mut slot = 0u64;
    for page in &mut mask {
        for v in page.iter_mut() {
            *v &= range.contains(&slot);
            slot += 1;
        }
    }
    let before = prep.accel.rays_cast();
    let (values, directional) = crate::solve(&mut prep, settings, &mask, progress)?;
    let mut out = vec![];
    for pages in std::iter::once(&values).chain(directional.as_ref()) {
        let run = pages
            .iter()
            .flatten()
            .skip(range.start as usize)
            .take((range.end - range.start) as usize);
        out.extend(run.flat_map(|v| v.to_array()));
    }
    let scene_ids = (scene, scene_name);
    Ok(Part {
        manifest: PartManifest {
            start: range.start,
            end: range.end,
            slots: slot,
            values: out.len() as u64,
            solve_rays: prep.accel.rays_cast() - before,
            seconds: t.elapsed().as_secs_f64(),
            ..part_manifest("lightmaps", scene_ids, settings_value(settings), shard)
        },
        values: out,
    })
}

/// Bake shard `shard` of the SH light-maps of `scene`: the transfer of its range of slots.
/// CaSHL shooting is refused (one global iteration, as radiosity).
pub fn bake_sh_part(
    scene: &Scene,
    scene_name: &str,
    settings: &ShBakeSettings,
    shard: Shard,
    progress: Progress,
) -> Result<Part, BakeError> {
    use crate::sh_bake;
    let s = &settings.transfer;
    if matches!(s.kind, crate::prt::TransferKind::Shooting(_)) {
        return Err(BakeError::Settings(
            "SH shooting (CaSHL) cannot be sharded: it is one global iteration between all \
             texels; bake it on one machine, or shard gathered transfer (--transfer \
             interreflected|shadowed|unshadowed)"
                .into(),
        ));
    }
    let t = Instant::now();
    let prep = sh_bake::prepare(scene, &settings.layout, s, true, progress)?;
    let costs = slot_costs(&prep.texels, &prep.valid);
    let range = balanced_ranges(&costs, shard.count)[shard.index as usize].clone();
    let mut stats = None;
    let mut out = vec![];
    let mut first_slot = 0u64;
    let nc = lightlab_core::sh::num_coeffs(s.bands);
    for k in 0..prep.texels.pages.len() {
        let (idx, surface) = sh_bake::page_surface(&prep, s, k, &mut stats);
        // The page's gathered texels inside the range: a run of idx.
        let inside = |&i: &usize| range.contains(&(first_slot + i as u64));
        let a = idx.iter().position(inside).unwrap_or(idx.len());
        let b = a + idx[a..].iter().take_while(|&i| inside(i)).count();
        let inst = sh_bake::page_instances(&prep, k, &idx[a..b]);
        let (tr, ao) = sh_bake::page_transfer(&prep, s, &surface[a..b], &inst, a as u64)?;
        for j in 0..b - a {
            out.extend_from_slice(&tr[j * nc..(j + 1) * nc]);
            out.push(ao[j]);
        }
        first_slot += prep.texels.pages[k].samples.len() as u64;
    }
    Ok(Part {
        manifest: PartManifest {
            start: range.start,
            end: range.end,
            slots: first_slot,
            values: out.len() as u64,
            seconds: t.elapsed().as_secs_f64(),
            ..part_manifest("sh", (scene, scene_name), settings_value(settings), shard)
        },
        values: out,
    })
}

/// Write a part folder (atomically, as every bake folder).
pub fn write_part(part: &Part, dir: &Path) -> Result<PartManifest, BakeError> {
    folder::write(dir, |stage| {
        write_f32(&stage.join(VALUES), &part.values)?;
        Ok(part.manifest.clone())
    })
}

/// Read and verify a part folder.
pub fn read_part(dir: &Path) -> Result<Part, BakeError> {
    let (checked, value) = folder::read_manifest(dir, PART_FORMAT, PART_VERSION, "path --shard")?;
    let manifest: PartManifest = checked.parse(value)?;
    if manifest.end < manifest.start || manifest.end > manifest.slots {
        return Err(BakeError::Io(format!(
            "{}: the range {}..{} of {} slots is not a range",
            dir.display(),
            manifest.start,
            manifest.end,
            manifest.slots
        )));
    }
    let values = read_f32(&checked.file(VALUES)?, manifest.values as usize)?;
    Ok(Part { manifest, values })
}

/// Mark `shard`'s part (from `dir`) as seen; an error when it was given already.
fn mark_seen<'a>(
    seen: &mut [Option<&'a Path>],
    shard: Shard,
    dir: &'a Path,
) -> Result<(), BakeError> {
    let i = shard.index as usize;
    if let Some(other) = seen.get(i).copied().flatten() {
        return Err(BakeError::Settings(format!(
            "part {shard} is given twice: {} and {}",
            other.display(),
            dir.display()
        )));
    }
    if let Some(slot) = seen.get_mut(i) {
        *slot = Some(dir);
    }
    Ok(())
}

/// An error naming the parts not seen, if any.
fn none_missing(seen: &[Option<&Path>]) -> Result<(), BakeError> {
    let missing: Vec<String> = (0..seen.len())
        .filter(|&i| seen[i].is_none())
        .map(|i| format!("{i}/{}", seen.len()))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(BakeError::Settings(format!(
        "part{} {} missing",
        if missing.len() > 1 { "s" } else { "" },
        missing.join(", ")
    )))
}

/// Check that `parts` (with the folders they were read from) make one whole bake: the same
/// kind, scene, settings and shard count, every index once. Errors name the part at fault.
fn check_parts(parts: &[(PathBuf, Part)]) -> Result<&PartManifest, BakeError> {
    let Some((first_dir, first)) = parts.first() else {
        return Err(BakeError::Settings("no parts to merge".into()));
    };
    let m0 = &first.manifest;
    let mut seen: Vec<Option<&Path>> = vec![None; m0.shard.count as usize];
    for (dir, p) in parts {
        let m = &p.manifest;
        let foreign = |what: &str| {
            BakeError::Settings(format!(
                "{} belongs to another bake than {}: its {what} differs",
                dir.display(),
                first_dir.display()
            ))
        };
        if m.kind != m0.kind {
            return Err(foreign("kind of bake"));
        }
        if m.scene_fingerprint != m0.scene_fingerprint {
            return Err(foreign("scene"));
        }
        if m.settings != m0.settings {
            return Err(foreign("bake settings"));
        }
        if m.shard.count != m0.shard.count || m.slots != m0.slots {
            return Err(foreign("shard count"));
        }
        mark_seen(&mut seen, m.shard, dir)?;
    }
    none_missing(&seen)?;
    Ok(m0)
}

/// The settings a part records, parsed; an error names the part.
fn parse_settings<T: serde::de::DeserializeOwned>(
    dir: &Path,
    m: &PartManifest,
) -> Result<T, BakeError> {
    serde_json::from_value(m.settings.clone())
        .map_err(|e| BakeError::Io(format!("{}: its settings: {e}", dir.display())))
}

/// What every merge does first: the parts make one whole of `kind`, for `scene`.
fn check_merge<'a>(
    scene: &Scene,
    parts: &'a [(PathBuf, Part)],
    kind: &str,
) -> Result<&'a PartManifest, BakeError> {
    let m0 = check_parts(parts)?;
    if m0.kind != kind {
        return Err(BakeError::Settings(format!(
            "{} is a part of a '{}' bake, not '{kind}'",
            parts[0].0.display(),
            m0.kind
        )));
    }
    if hex(scene.fingerprint()) != m0.scene_fingerprint {
        return Err(BakeError::Scene(format!(
            "the scene loaded as '{}' is not the one the parts were baked from (fingerprint {} \
             against {}): give the merge the same scene and scene options as the bake",
            m0.scene,
            hex(scene.fingerprint()),
            m0.scene_fingerprint
        )));
    }
    Ok(m0)
}

/// Each part's range, checked against the ranges this scene's slots give: `(part, range)`.
fn checked_ranges<'a>(
    parts: &'a [(PathBuf, Part)],
    costs: &[u32],
) -> Result<Vec<(&'a Part, Range<u64>)>, BakeError> {
    let ranges = balanced_ranges(costs, parts[0].1.manifest.shard.count);
    parts
        .iter()
        .map(|(dir, p)| {
            let m = &p.manifest;
            let r = ranges[m.shard.index as usize].clone();
            if (m.start, m.end, m.slots) != (r.start, r.end, costs.len() as u64) {
                return Err(BakeError::Settings(format!(
                    "{}: covers slots {}..{} of {}, where this scene's shard {} is {}..{} of {}",
                    dir.display(),
                    m.start,
                    m.end,
                    m.slots,
                    m.shard,
                    r.start,
                    r.end,
                    costs.len()
                )));
            }
            Ok((p, r))
        })
        .collect()
}

/// Assemble the light-maps of `scene` from its parts: the bake [`crate::bake_lightmaps`] makes
/// on one machine with the parts' settings, apart from its timings.
pub fn merge(
    scene: &Scene,
    parts: &[(PathBuf, Part)],
    progress: Progress,
) -> Result<Lightmaps, BakeError> {
    let m0 = check_merge(scene, parts, "lightmaps")?;
    let settings: BakeSettings = parse_settings(&parts[0].0, m0)?;
    let mut prep = crate::prepare(scene, &settings, progress)?;
    let costs = slot_costs(&prep.texels, &prep.valid);
    let slots = costs.len();
    let per = 3 * if settings.gather.directional { 2 } else { 1 };
    let mut flat = vec![Vec3::ZERO; slots];
    let mut flat_dir = settings.gather.directional.then(|| vec![Vec3::ONE; slots]);
    let (mut rays, mut seconds) = (0u64, 0f64);
    for (p, r) in checked_ranges(parts, &costs)? {
        let (a, b) = (r.start as usize, r.end as usize);
        if p.values.len() != (b - a) * per {
            return Err(BakeError::Settings(format!(
                "part {} holds {} values for {} slots",
                p.manifest.shard,
                p.values.len(),
                b - a
            )));
        }
        let mut v = p.values.chunks_exact(3).map(Vec3::from_slice);
        flat[a..b]
            .iter_mut()
            .for_each(|x| *x = v.next().expect("counted"));
        if let Some(all) = flat_dir.as_mut() {
            all[a..b]
                .iter_mut()
                .for_each(|x| *x = v.next().expect("counted"));
        }
        rays += p.manifest.solve_rays;
        seconds += p.manifest.seconds;
    }
    let split = |flat: Vec<Vec3>| -> Vec<Vec<Vec3>> {
        let mut it = flat.into_iter();
        prep.texels
            .pages
            .iter()
            .map(|p| it.by_ref().take(p.samples.len()).collect())
            .collect()
    };
    let (values, directional) = (split(flat), flat_dir.map(split));
    prep.stats.rays = prep.accel.rays_cast() + rays;
    prep.stats.seconds_solve = seconds;
    Ok(crate::finish(
        prep,
        &settings,
        values,
        directional,
        progress,
    ))
}

/// Assemble SH light-maps from their parts: what [`crate::prt::bake_sh_lightmaps`] makes on one
/// machine. Returns them and the parts' summed seconds.
pub fn merge_sh(
    scene: &Scene,
    parts: &[(PathBuf, Part)],
    progress: Progress,
) -> Result<(crate::prt::ShLightmaps, f64), BakeError> {
    use crate::sh_bake;
    let m0 = check_merge(scene, parts, "sh")?;
    let settings: ShBakeSettings = parse_settings(&parts[0].0, m0)?;
    let s = &settings.transfer;
    let prep = sh_bake::prepare(scene, &settings.layout, s, false, progress)?;
    let costs = slot_costs(&prep.texels, &prep.valid);
    let nc = lightlab_core::sh::num_coeffs(s.bands);
    // Every gathered texel's (transfer, occlusion), by slot.
    let mut per_slot: Vec<Option<&[f32]>> = vec![None; costs.len()];
    let mut seconds = 0.0;
    for (p, r) in checked_ranges(parts, &costs)? {
        let gathered: Vec<usize> = (r.start as usize..r.end as usize)
            .filter(|&i| costs[i] > 0)
            .collect();
        if p.values.len() != gathered.len() * (nc + 1) {
            return Err(BakeError::Settings(format!(
                "part {} holds {} values for {} texels",
                p.manifest.shard,
                p.values.len(),
                gathered.len()
            )));
        }
        for (slot, v) in gathered.into_iter().zip(p.values.chunks_exact(nc + 1)) {
            per_slot[slot] = Some(v);
        }
        seconds += p.manifest.seconds;
    }
    let mut stats = sh_bake::detail_stats(&prep);
    let mut computed = vec![];
    let mut first = 0usize;
    for k in 0..prep.texels.pages.len() {
        let (idx, surface) = sh_bake::page_surface(&prep, s, k, &mut stats);
        let (mut tr, mut ao) = (Vec::with_capacity(idx.len() * nc), vec![]);
        for &i in &idx {
            let v = per_slot[first + i].expect("every gathered slot is in a checked range");
            tr.extend_from_slice(&v[..nc]);
            ao.push(v[nc]);
        }
        first += prep.texels.pages[k].samples.len();
        computed.push((idx, surface, tr, ao));
    }
    Ok((sh_bake::finish(prep, s, &computed, stats, None), seconds))
}

/// The manifest format of a part folder (`PART_FORMAT` or `RENDER_PART_FORMAT`), to tell
/// which merge it needs; the folder is verified by the reader of that kind.
pub fn part_format(dir: &Path) -> Result<String, BakeError> {
    let path = dir.join(folder::MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        BakeError::Io(format!(
            "{}: {e} (is this a part folder written by `bake --shard` or `render --shard`?)",
            path.display()
        ))
    })?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| BakeError::Io(format!("{}: {e}", path.display())))?;
    Ok(v.get("format")
        .and_then(|f| f.as_str())
        .unwrap_or_default()
        .to_string())
}

// ---- reference renders -------------------------------------------------------------------

pub const RENDER_PART_FORMAT: &str = "lightlab-render-part";
const PIXELS: &str = "pixels.bin";

/// What a path-traced render is, as its parts record it: two parts belong to one render when
/// these and the scene's fingerprint agree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderSpec {
    /// `reference` or `direct`.
    pub technique: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub min_depth: u32,
    pub seed: u64,
    pub camera: usize,
    /// PNG output: exposure and tone operator (by name).
    pub exposure: f32,
    pub tonemap: String,
    /// The camera's lens (`CameraModel::describe`; parts written before lenses: a pinhole).
    #[serde(default = "pinhole")]
    pub camera_model: String,
}

fn pinhole() -> String {
    "pinhole".into()
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderPartManifest {
    pub format: String,
    pub version: u32,
    pub scene: String,
    pub scene_fingerprint: String,
    pub render: RenderSpec,
    pub shard: Shard,
    pub seconds: f64,
}

/// A render part: its manifest and its rows' pixels (rows in [`shard_rows`] order).
#[derive(Clone, Debug)]
pub struct RenderPart {
    pub manifest: RenderPartManifest,
    pub pixels: Vec<Vec3>,
}

/// The rows shard `shard` renders: every N-th from its index (y ≡ I mod N). Interleaved
/// rows balance the cost without estimating it: sky, floor and objects are spread over all
/// shards alike.
pub fn shard_rows(height: u32, shard: Shard) -> Vec<u32> {
    (shard.index..height)
        .step_by(shard.count as usize)
        .collect()
}

/// Render shard `shard` of `spec` with `tracer` (the scene's, `scene_fingerprint` its hex
/// fingerprint).
pub fn render_part(
    tracer: &lightlab_trace::PathTracer,
    settings: &lightlab_trace::RenderSettings,
    spec: RenderSpec,
    scene: (&str, u64),
    shard: Shard,
    progress: &(dyn Fn(usize, usize) -> bool + Sync),
) -> Result<RenderPart, BakeError> {
    let t = Instant::now();
    let rows = shard_rows(settings.height, shard);
    let pixels = tracer
        .render_rows(settings, &rows, progress)
        .map_err(|e| BakeError::Settings(e.to_string()))?;
    Ok(RenderPart {
        manifest: RenderPartManifest {
            format: RENDER_PART_FORMAT.into(),
            version: PART_VERSION,
            scene: scene.0.into(),
            scene_fingerprint: hex(scene.1),
            render: spec,
            shard,
            seconds: t.elapsed().as_secs_f64(),
        },
        pixels,
    })
}

fn write_f32(path: &Path, v: &[f32]) -> Result<(), BakeError> {
    let bytes: Vec<u8> = v.iter().flat_map(|c| c.to_le_bytes()).collect();
    std::fs::write(path, bytes).map_err(|e| BakeError::Io(format!("{}: {e}", path.display())))
}

fn read_f32(path: &Path, expected: usize) -> Result<Vec<f32>, BakeError> {
    let bytes =
        std::fs::read(path).map_err(|e| BakeError::Io(format!("{}: {e}", path.display())))?;
    if bytes.len() != expected * 4 {
        return Err(BakeError::Io(format!(
            "{}: {} bytes, where its manifest records {} values ({} bytes)",
            path.display(),
            bytes.len(),
            expected,
            expected * 4
        )));
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

pub fn write_render_part(part: &RenderPart, dir: &Path) -> Result<(), BakeError> {
    folder::write(dir, |stage| {
        let flat: Vec<f32> = part.pixels.iter().flat_map(|v| v.to_array()).collect();
        write_f32(&stage.join(PIXELS), &flat)?;
        Ok(part.manifest.clone())
    })
    .map(|_| ())
}

pub fn read_render_part(dir: &Path) -> Result<RenderPart, BakeError> {
    let (checked, value) =
        folder::read_manifest(dir, RENDER_PART_FORMAT, PART_VERSION, "reference --shard")?;
    let manifest: RenderPartManifest = checked.parse(value)?;
    let (w, h) = (manifest.render.width, manifest.render.height);
    let shard = Shard::new(manifest.shard.index, manifest.shard.count)
        .map_err(|e| BakeError::Io(format!("{}: shard {e}", dir.display())))?;
    let n = shard_rows(h, shard).len() * w as usize;
    let flat = read_f32(&checked.file(PIXELS)?, 3 * n)?;
    let pixels = flat.chunks_exact(3).map(Vec3::from_slice).collect();
    Ok(RenderPart { manifest, pixels })
}

/// Check a render's parts belong together and none is missing or doubled (as [`check_parts`]
/// does for bakes), then assemble the image.
pub fn merge_render(
    parts: &[(PathBuf, RenderPart)],
) -> Result<lightlab_core::image::Image, BakeError> {
    let Some((first_dir, first)) = parts.first() else {
        return Err(BakeError::Settings("no parts to merge".into()));
    };
    let m0 = &first.manifest;
    let (w, h) = (m0.render.width, m0.render.height);
    let mut data = vec![Vec3::ZERO; w as usize * h as usize];
    let mut seen: Vec<Option<&Path>> = vec![None; m0.shard.count as usize];
    for (dir, p) in parts {
        let m = &p.manifest;
        let what = if m.scene_fingerprint != m0.scene_fingerprint {
            Some("scene")
        } else if m.render != m0.render {
            Some("render settings")
        } else if m.shard.count != m0.shard.count {
            Some("shard count")
        } else {
            None
        };
        if let Some(what) = what {
            return Err(BakeError::Settings(format!(
                "{} belongs to another render than {}: its {what} differs",
                dir.display(),
                first_dir.display()
            )));
        }
        mark_seen(&mut seen, m.shard, dir)?;
        for (k, y) in shard_rows(h, m.shard).into_iter().enumerate() {
            let (src, dst) = (k * w as usize, y as usize * w as usize);
            data[dst..dst + w as usize].copy_from_slice(&p.pixels[src..src + w as usize]);
        }
    }
    none_missing(&seen)?;
    Ok(lightlab_core::image::Image {
        width: w,
        height: h,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_split_the_cost_evenly_and_cover_every_slot_once() {
        let cost: Vec<u32> = (0..1000)
            .map(|i| u32::from(i % 3 != 0 || i > 700))
            .collect();
        for n in [1, 2, 3, 7, 13] {
            let r = balanced_ranges(&cost, n);
            assert_eq!(r.len(), n as usize);
            assert_eq!(r[0].start, 0);
            assert_eq!(r.last().unwrap().end, 1000);
            for w in r.windows(2) {
                assert_eq!(w[0].end, w[1].start);
            }
            let total: u32 = cost.iter().sum();
            for x in &r {
                let c: u32 = cost[x.start as usize..x.end as usize].iter().sum();
                assert!(c.abs_diff(total / n) <= 1, "{n} shards: {c} of {total}");
            }
        }
        // More shards than work: the extra ranges are empty, still contiguous.
        let r = balanced_ranges(&[1, 0, 1], 5);
        assert_eq!(r.iter().map(|x| x.end - x.start).sum::<u64>(), 3);
    }

    #[test]
    fn shard_specs_parse_and_name_their_faults() {
        assert_eq!(Shard::parse("2/7").unwrap(), Shard { index: 2, count: 7 });
        for bad in ["7/7", "1", "a/3", "0/0", "1/x"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains(bad), "{e}");
        }
        let env = |k: &str| (k == "SLURM_ARRAY_TASK_ID").then(|| "3".to_string());
        assert_eq!(Shard::index_from_env(env), Ok(3));
        let k8s = |k: &str| (k == "JOB_COMPLETION_INDEX").then(|| "1".to_string());
        assert_eq!(Shard::index_from_env(k8s), Ok(1));
        assert!(Shard::index_from_env(|_| None).is_err());
    }
}
