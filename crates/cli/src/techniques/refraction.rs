//! Geometry light fields (Heidrich §10.2) in the techniques: the field of `--refraction-field
//! DIR`, or of the scene's largest solid glass object baked first (`lightfield-refraction`),
//! through which the Phong techniques refract that object.

use crate::options::{FieldArgs, TechniqueArgs};
use crate::technique::Technique;
use anyhow::{Context, Result, bail};
use lightlab_core::refraction_field::RefractionField;
use lightlab_gpu::raster::GlassField;
use lightlab_scene::Scene;
use lightlab_trace::refraction_field::{bake as bake_field, glass_instances};
use std::sync::Arc;

/// The glass instance `a.glass` names (or the scene's largest) and its field, baked now.
pub fn bake(scene: &Scene, a: &FieldArgs) -> Result<(usize, RefractionField)> {
    for (n, what) in [(a.field_uv, "--field-uv"), (a.field_st, "--field-st")] {
        anyhow::ensure!((2..=256).contains(&n), "{what} must be 2 to 256 (got {n})");
    }
    let glass = glass_instances(scene);
    let instance = match &a.glass {
        Some(name) => *glass
            .iter()
            .find(|&&i| scene.instances[i].name == *name)
            .with_context(|| {
                let names: Vec<&str> = glass
                    .iter()
                    .map(|&i| scene.instances[i].name.as_str())
                    .collect();
                format!(
                    "{} has no solid glass instance '{name}' (it has: {})",
                    scene.name,
                    if names.is_empty() {
                        "none".into()
                    } else {
                        names.join(", ")
                    }
                )
            })?,
        None => *glass.first().with_context(|| {
            format!(
                "{} has no solid glass object to bake a refraction field for: one needs a \
                 material with KHR_materials_transmission, KHR_materials_volume (thickness > 0) \
                 and roughness under 0.05 (built-in: `glass`, `spheres`)",
                scene.name
            )
        })?,
    };
    let field = bake_field(scene, instance, a.field_uv, a.field_st)
        .with_context(|| format!("glass instance {instance} has no geometry"))?;
    Ok((instance, field))
}

/// The glass instance of `scene` whose box is the field's (a field is baked for one object).
fn instance_of(scene: &Scene, field: &RefractionField) -> Option<usize> {
    let size = (field.max - field.min).max_element();
    glass_instances(scene).into_iter().find(|&i| {
        scene.instance_bounds(i).is_some_and(|(lo, hi)| {
            let pad = (hi - lo).max_element() * 1e-3;
            (lo - pad - field.min).abs().max_element() <= 1e-3 * size
                && (hi + pad - field.max).abs().max_element() <= 1e-3 * size
        })
    })
}

/// The field a GPU technique refracts through: `--refraction-field DIR`, or for
/// `lightfield-refraction` the scene's glass baked now; None for other techniques without it.
pub fn field(scene: &Scene, technique: Technique, a: &TechniqueArgs) -> Result<Option<GlassField>> {
    if let Some(dir) = &a.refraction_field {
        let field = RefractionField::read(dir)
            .with_context(|| format!("reading the refraction field in {}", dir.display()))?;
        let Some(instance) = instance_of(scene, &field) else {
            bail!(
                "the refraction field in {} was baked for an object with the box {:.3} … {:.3}; \
                 no solid glass instance of {} has that box (bake it again for this scene)",
                dir.display(),
                field.min,
                field.max,
                scene.name
            );
        };
        return Ok(Some(GlassField {
            instance,
            field: Arc::new(field),
        }));
    }
    if technique != Technique::LightfieldRefraction {
        return Ok(None);
    }
    let f = &a.bake.field;
    eprintln!(
        "no --refraction-field folder: baking {}'s glass into a 6 × {}² × {}² refraction field \
         now",
        scene.name, f.field_uv, f.field_st
    );
    let (instance, field) = bake(scene, f)?;
    Ok(Some(GlassField {
        instance,
        field: Arc::new(field),
    }))
}
