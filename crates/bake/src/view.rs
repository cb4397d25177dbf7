//! Light-maps rendered on the CPU: the `lightmap` technique without a GPU, and the measure the
//! acceptance tests use. A camera ray finds the visible surface; its radiance is
//! albedo × light-map (bilinear or bicubic at its TEXCOORD_1) + emission, as the GPU technique
//! computes it per fragment.

use crate::Lightmaps;
use crate::texels::albedo;
use glam::{Vec2, Vec3};
use lightlab_core::image::Image;
use lightlab_core::sampling::Rng;
use lightlab_scene::{Mesh, Scene};
use lightlab_trace::Accel;
use lightlab_trace::lights::emission;
use rayon::prelude::*;

/// How a light-map is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Bilinear,
    Bicubic,
}

lightlab_core::named_enum!(Filter, "light-map filter", {
    Bilinear => "bilinear",
    Bicubic => "bicubic",
});

/// What a surface point reads from the light-maps: page, page UV and the hit's attributes.
pub struct LightmapHit {
    pub instance: usize,
    pub page: u32,
    pub uv: Vec2,
    pub p: Vec3,
    pub material: usize,
    /// The texture coordinates (both sets) at the hit.
    pub tex_uv: lightlab_scene::Attrs,
    /// Whether the camera sees the front side.
    pub front: bool,
}

/// Trace a ray and return where it lands in the light-maps.
pub fn lightmap_hit(lm: &Lightmaps, accel: &Accel, o: Vec3, d: Vec3) -> Option<LightmapHit> {
    layout_hit(&lm.scene, &lm.layout, accel, o, d)
}

/// [`lightmap_hit`] for any data laid out by `layout` (light-maps, SH light-maps).
pub fn layout_hit(
    scene: &Scene,
    layout: &crate::layout::Layout,
    accel: &Accel,
    o: Vec3,
    d: Vec3,
) -> Option<LightmapHit> {
    let hit = accel.intersect(o, d, f32::INFINITY)?;
    let inst = &scene.instances[hit.prim.instance as usize];
    let mesh = &scene.meshes[inst.mesh];
    let rect = layout.instances[hit.prim.instance as usize]?;
    let tri = hit.prim.triangle as usize;
    let u1 = interpolate(mesh.uv1.as_ref()?, mesh, tri, hit.bary);
    let tex_uv = hit_uv(mesh, tri, hit.bary);
    let w = accel.world_triangle(hit.slot);
    let ng = (w[1] - w[0]).cross(w[2] - w[0]);
    Some(LightmapHit {
        instance: hit.prim.instance as usize,
        page: rect.page,
        uv: rect.page_uv(u1),
        p: o + d * hit.t,
        material: mesh.material,
        tex_uv,
        front: ng.dot(d) < 0.0,
    })
}

/// A per-vertex attribute at barycentric `bary` of triangle `tri` (obvhs's weights of the
/// second and third vertices).
pub fn interpolate(values: &[Vec2], mesh: &Mesh, tri: usize, bary: Vec2) -> Vec2 {
    let b = [1.0 - bary.x - bary.y, bary.x, bary.y];
    (0..3)
        .map(|k| values[mesh.indices[tri * 3 + k] as usize] * b[k])
        .sum()
}

/// Both texture-coordinate sets at a hit (zero for meshes without UVs).
pub fn hit_uv(mesh: &Mesh, tri: usize, bary: Vec2) -> lightlab_scene::Attrs {
    let idx = [0, 1, 2].map(|k| mesh.indices[tri * 3 + k] as usize);
    mesh.uv_at(idx, [1.0 - bary.x - bary.y, bary.x, bary.y])
}

/// Render `scene` from camera `camera` with `spp` jittered samples per pixel: `radiance`
/// returns what a camera ray (origin, direction) sees, or None where it escapes (the
/// environment is drawn there). The pixel loop of every CPU view of a baked technique.
pub fn render_camera(
    scene: &Scene,
    width: u32,
    height: u32,
    camera: usize,
    spp: u32,
    radiance: impl Fn(&Accel, Vec3, Vec3) -> Option<Vec3> + Sync,
) -> Option<Image> {
    let cam = scene.cameras.get(camera)?;
    let accel = Accel::new(scene);
    let aspect = width as f32 / height as f32;
    let origin = cam.position();
    let data: Vec<Vec3> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let mut rng = Rng::new(7, i as u64);
            let mut sum = Vec3::ZERO;
            for _ in 0..spp.max(1) {
                let j = if spp > 1 {
                    rng.next_vec2()
                } else {
                    Vec2::splat(0.5)
                };
                let ndc = Vec2::new(
                    (x as f32 + j.x) / width as f32 * 2.0 - 1.0,
                    1.0 - (y as f32 + j.y) / height as f32 * 2.0,
                );
                let d = cam.ray_direction(ndc, aspect);
                if let Some(c) = radiance(&accel, origin, d) {
                    sum += c;
                } else if let Some(env) = &scene.environment {
                    sum += env.radiance(d);
                }
            }
            sum / spp.max(1) as f32
        })
        .collect();
    Some(Image {
        width,
        height,
        data,
    })
}

/// Sample a light-map page.
pub fn sample(lm: &Lightmaps, page: u32, uv: Vec2, filter: Filter) -> Vec3 {
    let img = &lm.pages[page as usize];
    match filter {
        Filter::Bilinear => crate::sample_bilinear(img, uv),
        Filter::Bicubic => crate::sample_bicubic(img, uv),
    }
}

/// Render the light-mapped scene from camera `camera` with `spp` jittered samples per pixel.
pub fn render(
    lm: &Lightmaps,
    width: u32,
    height: u32,
    camera: usize,
    filter: Filter,
    spp: u32,
) -> Option<Image> {
    let scene = &lm.scene;
    render_camera(scene, width, height, camera, spp, |accel, o, d| {
        let h = lightmap_hit(lm, accel, o, d)?;
        let mat = &scene.materials[h.material];
        let mut c = albedo(scene, h.material, h.tex_uv) * sample(lm, h.page, h.uv, filter);
        if mat.is_emissive() && (h.front || mat.double_sided) {
            c += emission(scene, h.material, h.tex_uv);
        }
        Some(c)
    })
}
