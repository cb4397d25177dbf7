//! Baking a geometry light field (`lightlab_core::object_field`, Heidrich 1999 §10.2): every
//! sample ray of the six slabs around a glass object traced through it — refracted at each
//! interface by its index, reflected under total internal reflection — to the direction it
//! leaves in, with the product of the Fresnel transmittances it kept.

use crate::accel::Accel;
use crate::render::surface;
use glam::{Vec3, Vec4};
use lightlab_core::object_field::ObjectField;
use lightlab_scene::Scene;
use rayon::prelude::*;

/// Interfaces a sample ray crosses at most; a ray still inside after them is dropped
/// (throughput 0).
pub const MAX_EVENTS: usize = 32;

/// The instances of solid, smooth glass (transmission, a volume, roughness under the path
/// tracer's rough-interface threshold), largest box first: what a geometry light field is for.
pub fn glass_instances(scene: &Scene) -> Vec<usize> {
    let mut found: Vec<(usize, f32)> = scene
        .instances
        .iter()
        .enumerate()
        .filter(|(_, inst)| {
            let m = &scene.materials[scene.meshes[inst.mesh].material];
            m.specular_transmission > 0.0
                && m.thickness > 0.0
                && m.roughness < crate::bsdf::ROUGH_INTERFACE
        })
        .filter_map(|(i, _)| {
            let (lo, hi) = scene.instance_bounds(i)?;
            Some((i, (hi - lo).length()))
        })
        .collect();
    found.sort_by(|a, b| b.1.total_cmp(&a.1));
    found.into_iter().map(|(i, _)| i).collect()
}

/// Where the ray (o, d) leaves the object of `scene` (traced with `accel`) and its
/// throughput.
fn exit(scene: &Scene, accel: &Accel, ior: f32, o: Vec3, d: Vec3, eps: f32) -> Vec4 {
    let (mut o, mut d) = (o, d);
    let mut w = 1.0f32;
    for _ in 0..MAX_EVENTS {
        let Some(hit) = accel.intersect(o, d, f32::INFINITY) else {
            return d.extend(w);
        };
        let sf = surface(scene, accel, &hit);
        let entering = d.dot(sf.ng) < 0.0;
        // The normal on the side the ray comes from; η = n_t / n_i.
        let n = if entering { sf.ns } else { -sf.ns };
        let eta = if entering { ior } else { 1.0 / ior };
        let c = (-d.dot(n)).clamp(0.0, 1.0);
        let f = lightlab_core::brdf::fresnel_dielectric(c as f64, eta as f64) as f32;
        let k = 1.0 - (1.0 - c * c) / (eta * eta);
        d = if k < 0.0 {
            d + 2.0 * c * n
        } else {
            w *= 1.0 - f;
            (d / eta + n * (c / eta - k.sqrt())).normalize()
        };
        // Continue from the side of the surface the ray now travels to.
        let side = if d.dot(sf.ng) > 0.0 { 1.0 } else { -1.0 };
        o = sf.p + sf.ng * (side * eps);
    }
    d.extend(0.0)
}

/// Set every sample of `field` to `value(index, point, direction)` of its ray (a point on the
/// central plane, the unit direction), in parallel over (slab, iv) rows; `index` is the
/// sample's index in `field.data`, for per-sample random streams.
pub(crate) fn fill(field: &mut ObjectField, value: impl Fn(usize, Vec3, Vec3) -> Vec4 + Sync) {
    let (n_uv, n_st) = (field.n_uv, field.n_st);
    let rows: Vec<(usize, usize)> = (0..6)
        .flat_map(|slab| (0..n_uv).map(move |iv| (slab, iv)))
        .collect();
    let f = &*field;
    let values: Vec<Vec<Vec4>> = rows
        .par_iter()
        .map(|&(slab, iv)| {
            let mut row = Vec::with_capacity(n_uv * n_st * n_st);
            for iu in 0..n_uv {
                for it in 0..n_st {
                    for is in 0..n_st {
                        let k = [iu, iv, is, it];
                        let (p, d) = f.ray(slab, k);
                        row.push(value(f.index(slab, k), p, d));
                    }
                }
            }
            row
        })
        .collect();
    // Rows in (slab, iv) order, each (iu, it, is): the field's own layout.
    field.data = values.into_iter().flatten().collect();
}

/// The geometry light field of instance `instance` of `scene`: `n_uv`² × `n_st`² samples per
/// slab, traced through that instance alone with its material's index. None when the instance
/// has no geometry.
pub fn bake(scene: &Scene, instance: usize, n_uv: usize, n_st: usize) -> Option<ObjectField> {
    let mut object = scene.clone();
    object.instances = vec![scene.instances[instance].clone()];
    object.lights.clear();
    let accel = Accel::new(&object);
    let ior = scene.materials[scene.meshes[scene.instances[instance].mesh].material].ior;
    let (lo, hi) = scene.instance_bounds(instance)?;
    let pad = (hi - lo).max_element() * 1e-3;
    // Every sample is traced below: start from a black field, not a straight one.
    let mut field = ObjectField::black(lo - pad, hi + pad, n_uv, n_st);
    field.kind = lightlab_core::object_field::FieldKind::Geometry;
    let reach = 2.0 * (field.max - field.min).length();
    let eps = 1e-4 * (field.max - field.min).max_element();
    fill(&mut field, |_, p, d| {
        exit(&object, &accel, ior, p - d * reach, d, eps)
    });
    Some(field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lightlab_scene::builtin;

    /// A glass ball: the exit direction and throughput of two refractions, in closed form.
    #[test]
    fn a_glass_ball_refracts_as_snell_says() {
        let scene = builtin::builtin("spheres").unwrap();
        let glass = glass_instances(&scene);
        assert_eq!(glass.len(), 1);
        let field = bake(&scene, glass[0], 24, 8).unwrap();
        let (lo, hi) = scene.instance_bounds(glass[0]).unwrap();
        let (c, r) = ((lo + hi) * 0.5, (hi - lo).x * 0.5);
        let ior = 1.5f32;
        // Rays along −Z at offsets b from the centre: deviation 2(θi − θt) towards the axis.
        let mut worst = 0.0f32;
        for b in [0.0f32, 0.1, 0.2, 0.3, 0.35] {
            let o = c + Vec3::new(b * r, 0.0, 3.0);
            let (d, w) = field.lookup(o, Vec3::NEG_Z);
            let ti = (b).asin();
            let tt = (b / ior).asin();
            let dev = 2.0 * (ti - tt);
            let want = Vec3::new(-dev.sin(), 0.0, -dev.cos());
            let f = |c: f32, eta: f32| {
                lightlab_core::brdf::fresnel_dielectric(c as f64, eta as f64) as f32
            };
            let w_want = (1.0 - f(ti.cos(), ior)) * (1.0 - f(tt.cos(), 1.0 / ior));
            worst = worst.max(d.angle_between(want));
            assert!(
                (w - w_want).abs() < 0.02,
                "b {b}: throughput {w} want {w_want}"
            );
        }
        assert!(worst < 0.03, "exit direction off by {worst} rad");
        // A ray that misses the ball goes straight through the field.
        let (d, w) = field.lookup(c + Vec3::new(0.0, 1.2 * r, 3.0), Vec3::NEG_Z);
        assert!(
            d.abs_diff_eq(Vec3::NEG_Z, 1e-3) && (w - 1.0).abs() < 1e-3,
            "{d} {w}"
        );
    }
}
