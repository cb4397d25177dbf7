//! Light-maps rendered on the CPU: the `lightmap` technique without a GPU, and the measure the
//! acceptance tests use. A camera ray finds the visible surface; its radiance is
//! albedo × light-map (bilinear or bicubic at its TEXCOORD_1) + emission, as the GPU technique
//! computes it per fragment.

use crate::Lightmaps;
use crate::texels::albedo;
use glam::{Vec2, Vec3};
use lightlab_core::image::Image;
use lightlab_core::sampling::Rng;
use lightlab_trace::Accel;
use lightlab_trace::lights::emission;
use rayon::prelude::*;

/// How a light-map is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    Bilinear,
    Bicubic,
}

impl Filter {
    pub fn parse(s: &str) -> Option<Filter> {
        match s {
            "bilinear" => Some(Filter::Bilinear),
            "bicubic" => Some(Filter::Bicubic),
            _ => None,
        }
    }
}

/// What a surface point reads from the light-maps: page, page UV and the hit's attributes.
pub struct LightmapHit {
    pub page: u32,
    pub uv: Vec2,
    pub p: Vec3,
    pub material: usize,
    pub uv0: Vec2,
    /// Whether the camera sees the front side.
    pub front: bool,
}

/// Trace a ray and return where it lands in the light-maps.
pub fn lightmap_hit(lm: &Lightmaps, accel: &Accel, o: Vec3, d: Vec3) -> Option<LightmapHit> {
    layout_hit(&lm.scene, &lm.layout, accel, o, d)
}

/// [`lightmap_hit`] for any data laid out by `layout` (light-maps, SH light-maps).
pub fn layout_hit(
    scene: &lightlab_scene::Scene,
    layout: &crate::layout::Layout,
    accel: &Accel,
    o: Vec3,
    d: Vec3,
) -> Option<LightmapHit> {
    let hit = accel.intersect(o, d, f32::INFINITY)?;
    let inst = &scene.instances[hit.prim.instance as usize];
    let mesh = &scene.meshes[inst.mesh];
    let rect = layout.instances[hit.prim.instance as usize]?;
    let uv1 = mesh.uv1.as_ref()?;
    let t = hit.prim.triangle as usize * 3;
    let idx = [mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]].map(|i| i as usize);
    let b = [1.0 - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y];
    let u1 = uv1[idx[0]] * b[0] + uv1[idx[1]] * b[1] + uv1[idx[2]] * b[2];
    let uv0 = if mesh.uv0.len() == mesh.positions.len() {
        mesh.uv0[idx[0]] * b[0] + mesh.uv0[idx[1]] * b[1] + mesh.uv0[idx[2]] * b[2]
    } else {
        Vec2::ZERO
    };
    let w = accel.world_triangle(hit.slot);
    let ng = (w[1] - w[0]).cross(w[2] - w[0]);
    Some(LightmapHit {
        page: rect.page,
        uv: rect.page_uv(u1),
        p: o + d * hit.t,
        material: mesh.material,
        uv0,
        front: ng.dot(d) < 0.0,
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
                if let Some(h) = lightmap_hit(lm, &accel, origin, d) {
                    let mat = &scene.materials[h.material];
                    let mut c = albedo(scene, h.material, h.uv0) * sample(lm, h.page, h.uv, filter);
                    if mat.is_emissive() && (h.front || mat.double_sided) {
                        c += emission(scene, h.material, h.uv0);
                    }
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
