//! Baking a radiance light field around a glossy object (`lightlab_core::object_field`,
//! Heidrich 1999 §10.1): every sample ray of the six slabs that meets the object gets the
//! radiance the object sends back along it, path-traced in the whole scene, less the direct
//! light of the scene's punctual lights — the part a renderer shades per frame (the seed's
//! split: direct on the fly, the rest, which tolerates the field's blur, from the field).
//! Environment light, emitters' light and every bounce stay in the field.

use crate::accel::Accel;
use crate::render::{LightUse, PathTracer, RenderSettings};
use glam::{Vec3, Vec4};
use lightlab_core::object_field::ObjectField;
use lightlab_core::sampling::Rng;
use lightlab_scene::Scene;

/// Glossy instances a radiance field is for: opaque, metallic (≥ 0.5), roughness at least
/// 0.05 (smoother ones are mirrors: environment maps or planar mirrors) — smoothest first,
/// then largest.
pub fn glossy_instances(scene: &Scene) -> Vec<usize> {
    let mut found: Vec<(usize, f32, f32)> = scene
        .instances
        .iter()
        .enumerate()
        .filter_map(|(i, inst)| {
            let m = &scene.materials[scene.meshes[inst.mesh].material];
            let glossy = m.metallic >= 0.5
                && m.roughness >= 0.05
                && m.specular_transmission <= 0.0
                && inst.luminaire.is_none();
            let (lo, hi) = scene.instance_bounds(i)?;
            glossy.then_some((i, m.roughness, (hi - lo).length()))
        })
        .collect();
    found.sort_by(|a, b| a.1.total_cmp(&b.1).then(b.2.total_cmp(&a.2)));
    found.into_iter().map(|(i, _, _)| i).collect()
}

/// The radiance field of instance `instance` of `scene`: `n_uv`² × `n_st`² samples per slab,
/// each the mean of `spp` paths (depth ≤ 16) from just before where the ray meets the object.
pub fn bake(
    scene: &Scene,
    instance: usize,
    [n_uv, n_st]: [usize; 2],
    spp: u32,
    seed: u64,
) -> Option<ObjectField> {
    let (lo, hi) = scene.instance_bounds(instance)?;
    let pad = (hi - lo).max_element() * 1e-3;
    let mut field = ObjectField::black(lo - pad, hi + pad, n_uv, n_st);
    let mut object = scene.clone();
    object.instances = vec![scene.instances[instance].clone()];
    let object_accel = Accel::new(&object);
    let accel = Accel::new(scene);
    let mut pt = PathTracer::new(scene, &accel);
    pt.light_use = vec![
        LightUse {
            direct: false,
            indirect: true,
        };
        scene.lights.len()
    ];
    let settings = RenderSettings {
        spp,
        max_depth: 16,
        seed,
        ..Default::default()
    };
    let reach = 2.0 * (field.max - field.min).length();
    let eps = 1e-4 * (field.max - field.min).max_element();
    crate::refraction_field::fill(&mut field, |item, p, d| {
        let o = p - d * reach;
        let Some(hit) = object_accel.intersect(o, d, f32::INFINITY) else {
            return Vec4::ZERO;
        };
        let start = o + d * (hit.t - eps);
        let mut rng = Rng::new(seed, item as u64);
        let sum: Vec3 = (0..spp)
            .map(|_| pt.radiance(start, d, &settings, &mut rng))
            .sum();
        (sum / spp.max(1) as f32).extend(1.0)
    });
    Some(field)
}
