//! Canned light sources (Heidrich ch. 7) in the techniques: the light slabs of `--light-field
//! DIR` (repeatable), or of the scene's luminaires baked first (`canned-light`), drawn by the
//! Phong techniques in place of those luminaires' geometry.

use crate::options::{SlabArgs, TechniqueArgs};
use crate::technique::Technique;
use anyhow::{Context, Result, bail};
use lightlab_core::light_slab::LightSlab;
use lightlab_scene::Scene;
use lightlab_trace::luminaire::{self, LampEmitter};
use std::sync::Arc;

/// Paths inside a lamp scatter at most this many times (reflectors, lenses).
pub const LAMP_DEPTH: u32 = 16;

/// The luminaires `a` names (`--luminaire`), or all of the scene's when `all`, else its first.
pub fn chosen(scene: &Scene, a: &SlabArgs, all: bool) -> Result<Vec<String>> {
    let names = luminaire::names(scene);
    match &a.luminaire {
        Some(n) if names.contains(n) => Ok(vec![n.clone()]),
        Some(n) => bail!(
            "{} has no luminaire '{n}' (it has: {})",
            scene.name,
            if names.is_empty() {
                "none".into()
            } else {
                names.join(", ")
            }
        ),
        None if names.is_empty() => bail!(
            "{} has no luminaire to bake: mark a lamp's nodes with glTF \
             extras.lightlab.luminaire = \"NAME\" (built-in: `luminaire`)",
            scene.name
        ),
        None if all => Ok(names),
        None => Ok(names[..1].to_vec()),
    }
}

/// Luminaire `name` baked into a light slab: its (s,t) window at `--slab-far` (default its
/// focus, else infinity), `--slab-far-half` wide (default fitted to its beam).
pub fn bake(scene: &Scene, name: &str, a: &SlabArgs, seed: u64) -> Result<LightSlab> {
    let lamp = LampEmitter::new(scene, name, LAMP_DEPTH)
        .with_context(|| format!("luminaire '{name}' has no geometry"))?;
    let far = a.far(luminaire::default_far(scene, name, &lamp.window))?;
    let far_half = match a.slab_far_half {
        Some(h) if h.is_finite() && h > 0.0 => glam::Vec2::splat(h),
        Some(h) => bail!("--slab-far-half {h} must be a positive number"),
        None => luminaire::fit_far_half(&lamp, far, seed).with_context(|| {
            format!("luminaire '{name}' sends no light through its window: nothing to bake")
        })?,
    };
    Ok(luminaire::bake_slab(
        &lamp,
        a.slab_uv,
        far,
        far_half,
        a.slab_st,
        a.slab_samples,
        seed,
    ))
}

/// The canned lights a GPU technique draws: the `--light-field` folders, or for
/// `canned-light` the scene's luminaires (`--luminaire`: that one) baked now; none for other
/// techniques without `--light-field`.
pub fn lights(
    scene: &Scene,
    technique: Technique,
    a: &TechniqueArgs,
) -> Result<Vec<Arc<LightSlab>>> {
    if !a.light_field.is_empty() {
        return read(&a.light_field);
    }
    if technique != Technique::CannedLight {
        return Ok(vec![]);
    }
    let s = &a.bake.slab;
    chosen(scene, s, true)?
        .iter()
        .map(|name| {
            eprintln!(
                "no --light-field folder: baking {}'s luminaire '{name}' into a {}×{}×{}×{} \
                 light slab now ({} paths per sample)",
                scene.name, s.slab_uv[0], s.slab_uv[1], s.slab_st[0], s.slab_st[1], s.slab_samples
            );
            Ok(Arc::new(bake(scene, name, s, a.bake.bake_seed)?))
        })
        .collect()
}

/// The light slabs in the folders `dirs` (`--light-field`).
pub fn read(dirs: &[std::path::PathBuf]) -> Result<Vec<Arc<LightSlab>>> {
    dirs.iter()
        .map(|dir| {
            LightSlab::read(dir)
                .map(Arc::new)
                .with_context(|| format!("reading the light slab in {}", dir.display()))
        })
        .collect()
}

/// The names of the luminaires `slabs` replace (a slab without one replaces all).
pub fn replaced<'a>(scene: &'a Scene, slabs: &'a [Arc<LightSlab>]) -> Vec<String> {
    if slabs.iter().any(|s| s.luminaire.is_none()) {
        return luminaire::names(scene);
    }
    slabs.iter().filter_map(|s| s.luminaire.clone()).collect()
}

/// `scene` without the geometry of the luminaires `slabs` replace.
pub fn room(scene: &Scene, slabs: &[Arc<LightSlab>]) -> Scene {
    let names = replaced(scene, slabs);
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    luminaire::without(scene, &names)
}
