//! Canned light sources (Heidrich ch. 7) in the techniques: the light slab of `--light-field
//! DIR`, or of the scene's luminaire baked first (`canned-light`), drawn by the Phong
//! techniques in place of the luminaire's geometry.

use crate::options::{SlabArgs, TechniqueArgs};
use crate::technique::Technique;
use anyhow::{Context, Result, bail};
use lightlab_core::light_slab::LightSlab;
use lightlab_scene::Scene;
use lightlab_trace::luminaire::{self, LampEmitter};
use std::sync::Arc;

/// Paths inside a lamp scatter at most this many times (reflectors, lenses).
pub const LAMP_DEPTH: u32 = 16;

/// The luminaire `a.luminaire` (or the scene's first) baked into a light slab.
pub fn bake(scene: &Scene, a: &SlabArgs, seed: u64) -> Result<(String, LightSlab)> {
    let names = luminaire::names(scene);
    let name = match &a.luminaire {
        Some(n) if names.contains(n) => n.clone(),
        Some(n) => bail!(
            "{} has no luminaire '{n}' (it has: {})",
            scene.name,
            if names.is_empty() {
                "none".into()
            } else {
                names.join(", ")
            }
        ),
        None => names.first().cloned().with_context(|| {
            format!(
                "{} has no luminaire to bake: mark a lamp's nodes with glTF \
                 extras.lightlab.luminaire = \"NAME\" (built-in: `luminaire`)",
                scene.name
            )
        })?,
    };
    let lamp = LampEmitter::new(scene, &name, LAMP_DEPTH)
        .with_context(|| format!("luminaire '{name}' has no geometry"))?;
    let slab = luminaire::bake_slab(
        &lamp,
        a.slab_uv,
        a.far()?,
        glam::Vec2::splat(a.slab_far_half),
        a.slab_st,
        a.slab_samples,
        seed,
    );
    Ok((name, slab))
}

/// The canned light a GPU technique draws: `--light-field DIR`, or for `canned-light` the
/// scene's luminaire baked now; None for other techniques without `--light-field`.
pub fn light(
    scene: &Scene,
    technique: Technique,
    a: &TechniqueArgs,
) -> Result<Option<Arc<LightSlab>>> {
    if let Some(dir) = &a.light_field {
        let slab = LightSlab::read(dir)
            .with_context(|| format!("reading the light slab in {}", dir.display()))?;
        return Ok(Some(Arc::new(slab)));
    }
    if technique != Technique::CannedLight {
        return Ok(None);
    }
    let s = &a.bake.slab;
    eprintln!(
        "no --light-field folder: baking {}'s luminaire into a {}×{}×{}×{} light slab now \
         ({} paths per sample)",
        scene.name, s.slab_uv[0], s.slab_uv[1], s.slab_st[0], s.slab_st[1], s.slab_samples
    );
    let (_, slab) = bake(scene, s, a.bake.bake_seed)?;
    Ok(Some(Arc::new(slab)))
}
