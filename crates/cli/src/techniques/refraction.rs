//! Object light fields (Heidrich ch. 10) in the techniques: a glass object's geometry light
//! field (§10.2; `--refraction-field DIR`, or baked first by `lightfield-refraction`) or a
//! glossy object's radiance light field (§10.1; `--radiance-field DIR`, or baked first by
//! `lightfield-glossy`), which the Phong techniques read for that object.

use crate::options::{FieldArgs, TechniqueArgs};
use crate::technique::Technique;
use anyhow::{Context, Result, bail};
use lightlab_core::object_field::{FieldKind, ObjectField};
use lightlab_gpu::raster::FieldObject;
use lightlab_scene::Scene;
use lightlab_trace::radiance_field::glossy_instances;
use lightlab_trace::refraction_field::glass_instances;
use std::path::Path;
use std::sync::Arc;

/// The instances a field of `kind` is for, in the order the default picks.
fn candidates(scene: &Scene, kind: FieldKind) -> Vec<usize> {
    match kind {
        FieldKind::Geometry => glass_instances(scene),
        FieldKind::Radiance => glossy_instances(scene),
    }
}

/// The object `a.field_object` names (or the default of `kind`).
fn object(scene: &Scene, kind: FieldKind, a: &FieldArgs) -> Result<usize> {
    let found = candidates(scene, kind);
    let what = match kind {
        FieldKind::Geometry => "solid glass",
        FieldKind::Radiance => "glossy",
    };
    match &a.field_object {
        Some(name) => found
            .iter()
            .copied()
            .find(|&i| scene.instances[i].name == *name)
            .with_context(|| {
                let names: Vec<&str> = found
                    .iter()
                    .map(|&i| scene.instances[i].name.as_str())
                    .collect();
                format!(
                    "{} has no {what} instance '{name}' (it has: {})",
                    scene.name,
                    if names.is_empty() {
                        "none".into()
                    } else {
                        names.join(", ")
                    }
                )
            }),
        None => found.first().copied().with_context(|| match kind {
            FieldKind::Geometry => format!(
                "{} has no solid glass object to bake a refraction field for: one needs a \
                 material with KHR_materials_transmission, KHR_materials_volume (thickness > 0) \
                 and roughness under 0.05 (built-in: `glass`, `spheres`)",
                scene.name
            ),
            FieldKind::Radiance => format!(
                "{} has no glossy object to bake a radiance field for: one needs an opaque \
                 material with metallic ≥ 0.5 and roughness ≥ 0.05 (built-in: `spheres`)",
                scene.name
            ),
        }),
    }
}

/// The field of `kind` for the object `a` names (or the default), baked now.
pub fn bake(
    scene: &Scene,
    kind: FieldKind,
    a: &FieldArgs,
    seed: u64,
) -> Result<(usize, ObjectField)> {
    let [n_uv, n_st] = a.sizes(kind);
    for (n, what) in [(n_uv, "--field-uv"), (n_st, "--field-st")] {
        anyhow::ensure!((2..=256).contains(&n), "{what} must be 2 to 256 (got {n})");
    }
    anyhow::ensure!(
        (1..=65536).contains(&a.field_spp),
        "--field-spp must be 1 to 65536"
    );
    let instance = object(scene, kind, a)?;
    let field = match kind {
        FieldKind::Geometry => lightlab_trace::refraction_field::bake(scene, instance, n_uv, n_st),
        FieldKind::Radiance => {
            lightlab_trace::radiance_field::bake(scene, instance, [n_uv, n_st], a.field_spp, seed)
        }
    }
    .with_context(|| format!("instance {instance} has no geometry"))?;
    Ok((instance, field))
}

/// The instance of `scene` whose box is the field's (a field is baked for one object).
fn instance_of(scene: &Scene, field: &ObjectField) -> Option<usize> {
    let size = (field.max - field.min).max_element();
    candidates(scene, field.kind).into_iter().find(|&i| {
        scene.instance_bounds(i).is_some_and(|(lo, hi)| {
            let pad = (hi - lo).max_element() * 1e-3;
            (lo - pad - field.min).abs().max_element() <= 1e-3 * size
                && (hi + pad - field.max).abs().max_element() <= 1e-3 * size
        })
    })
}

/// A field folder of `kind` for `scene`.
fn read(scene: &Scene, dir: &Path, kind: FieldKind) -> Result<FieldObject> {
    let field = ObjectField::read(dir)
        .with_context(|| format!("reading the light field in {}", dir.display()))?;
    let option = match kind {
        FieldKind::Geometry => "--refraction-field",
        FieldKind::Radiance => "--radiance-field",
    };
    anyhow::ensure!(
        field.kind == kind,
        "{option} {}: this folder holds a {} field",
        dir.display(),
        match field.kind {
            FieldKind::Geometry => "refraction (geometry)",
            FieldKind::Radiance => "radiance",
        }
    );
    let Some(instance) = instance_of(scene, &field) else {
        bail!(
            "the light field in {} was baked for an object with the box {:.3} … {:.3}; no \
             such object of {} has that box (bake it again for this scene)",
            dir.display(),
            field.min,
            field.max,
            scene.name
        );
    };
    Ok(FieldObject {
        instance,
        field: Arc::new(field),
    })
}

/// The field a GPU technique reads: `--refraction-field DIR` or `--radiance-field DIR`, or for
/// `lightfield-refraction` and `lightfield-glossy` the scene's object baked now; None for other
/// techniques without one.
pub fn field(
    scene: &Scene,
    technique: Technique,
    a: &TechniqueArgs,
) -> Result<Option<FieldObject>> {
    match (&a.refraction_field, &a.radiance_field) {
        (Some(_), Some(_)) => {
            bail!("a renderer reads one object light field: --refraction-field or --radiance-field")
        }
        (Some(dir), None) => return read(scene, dir, FieldKind::Geometry).map(Some),
        (None, Some(dir)) => return read(scene, dir, FieldKind::Radiance).map(Some),
        (None, None) => {}
    }
    let kind = match technique {
        Technique::LightfieldRefraction => FieldKind::Geometry,
        Technique::LightfieldGlossy => FieldKind::Radiance,
        _ => return Ok(None),
    };
    let f = &a.bake.field;
    let [n_uv, n_st] = f.sizes(kind);
    eprintln!(
        "no field folder: baking a 6 × {n_uv}² × {n_st}² {} light field of {} now",
        if kind == FieldKind::Geometry {
            "refraction"
        } else {
            "radiance"
        },
        scene.name
    );
    let (instance, field) = bake(scene, kind, f, a.bake.bake_seed)?;
    Ok(Some(FieldObject {
        instance,
        field: Arc::new(field),
    }))
}
