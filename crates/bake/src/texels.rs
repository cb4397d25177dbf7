//! Light-map texels as surface samples: Fuchs's "one patch per texel" (§3.3.2).
//!
//! Every instance's triangles are rasterised into their page with 4×4 sub-samples per texel.
//! A texel's sample point is the centroid of the sub-samples of the triangle that covers most of
//! it (CaLight clips the patch square against the polygon and takes the clipped polygon's vertex
//! average; the sub-sample centroid is the same idea, and always lies inside the triangle, so
//! partly covered border texels get a point on the surface rather than beyond its edge). Its
//! area is the world area of everything the texel covers. Texels no triangle touches stay empty
//! and are filled afterwards ([`crate::repair`]).

use crate::layout::Layout;
use glam::{Vec2, Vec3};
use lightlab_scene::Scene;
use lightlab_trace::Accel;
use lightlab_trace::lights::emission;

/// Sub-samples per texel side.
const SUB: u32 = 4;

/// What a texel sees of the surface.
#[derive(Clone, Copy, Debug)]
pub struct TexelSample {
    /// Sample point (world).
    pub p: Vec3,
    /// Geometric normal of the front side.
    pub ng: Vec3,
    /// Interpolated shading normal, on the front side.
    pub ns: Vec3,
    /// Diffuse reflectance (1−metallic)·base colour.
    pub albedo: Vec3,
    /// Emitted radiance (front side).
    pub emission: Vec3,
    /// World-space step of one texel in x and y (for jittering inside the texel).
    pub dpdx: Vec3,
    pub dpdy: Vec3,
    /// World area the texel covers (m²).
    pub area: f32,
    /// Fraction of the texel square covered by surface.
    pub coverage: f32,
    pub instance: u32,
    /// Whether the material is double-sided (its back faces are legitimate surfaces).
    pub double_sided: bool,
    /// The mesh triangle the sample lies on, its barycentric weights of the second and third
    /// vertices, and their change per texel step in x and y (the texel's footprint on it).
    pub triangle: u32,
    pub bary: Vec2,
    pub dbdx: Vec2,
    pub dbdy: Vec2,
}

/// The texels of one page; `None` where no surface lies.
#[derive(Clone, Debug)]
pub struct PageTexels {
    pub width: u32,
    pub height: u32,
    pub samples: Vec<Option<TexelSample>>,
}

/// All texels of a layout.
#[derive(Clone, Debug)]
pub struct Texels {
    pub pages: Vec<PageTexels>,
}

impl Texels {
    /// Number of texels with a surface sample.
    pub fn count(&self) -> usize {
        self.pages
            .iter()
            .map(|p| p.samples.iter().filter(|s| s.is_some()).count())
            .sum()
    }
}

#[derive(Clone, Copy, Default)]
struct Acc {
    area: f32,
    coverage: f32,
    best_count: u32,
    best: Option<(u32, u32, Vec2)>, // instance, triangle, barycentric sum (b1, b2)
}

/// Rasterise every instance into its page.
pub fn rasterize(scene: &Scene, layout: &Layout) -> Texels {
    let mut acc: Vec<Vec<Acc>> = layout
        .pages
        .iter()
        .map(|p| vec![Acc::default(); (p[0] * p[1]) as usize])
        .collect();
    for pl in layout.placed(scene) {
        let (ii, inst, mesh, rect, uv1) = (pl.index, pl.instance, pl.mesh, pl.rect, pl.uv1);
        let size = layout.page_size(rect.page);
        let w = size.x as u32;
        let page = &mut acc[rect.page as usize];
        for (ti, t) in mesh.indices.chunks_exact(3).enumerate() {
            let idx = [t[0], t[1], t[2]].map(|i| i as usize);
            let q = idx.map(|i| rect.page_uv(uv1[i]) * size);
            let pw = idx.map(|i| inst.transform.transform_point3(mesh.positions[i]));
            let world_area = 0.5 * (pw[1] - pw[0]).cross(pw[2] - pw[0]).length();
            let det = (q[1] - q[0]).perp_dot(q[2] - q[0]);
            if det.abs() < 1e-12 || world_area <= 0.0 {
                continue;
            }
            // World area per texel² of this triangle.
            let jac = world_area / (0.5 * det.abs());
            let lo = q[0].min(q[1]).min(q[2]).floor().max(Vec2::ZERO);
            let hi = q[0].max(q[1]).max(q[2]).ceil().min(size);
            for y in lo.y as u32..hi.y as u32 {
                for x in lo.x as u32..hi.x as u32 {
                    let mut count = 0u32;
                    let mut bsum = Vec2::ZERO;
                    for sy in 0..SUB {
                        for sx in 0..SUB {
                            let c = Vec2::new(
                                x as f32 + (sx as f32 + 0.5) / SUB as f32,
                                y as f32 + (sy as f32 + 0.5) / SUB as f32,
                            );
                            let b1 = (c - q[0]).perp_dot(q[2] - q[0]) / det;
                            let b2 = (q[1] - q[0]).perp_dot(c - q[0]) / det;
                            if b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 {
                                count += 1;
                                bsum += Vec2::new(b1, b2);
                            }
                        }
                    }
                    if count == 0 {
                        continue;
                    }
                    let a = &mut page[(y * w + x) as usize];
                    let frac = count as f32 / (SUB * SUB) as f32;
                    a.coverage += frac;
                    a.area += frac * jac;
                    if count > a.best_count {
                        a.best_count = count;
                        a.best = Some((ii as u32, ti as u32, bsum / count as f32));
                    }
                }
            }
        }
    }
    let pages = acc
        .into_iter()
        .zip(&layout.pages)
        .map(|(acc, &[w, h])| PageTexels {
            width: w,
            height: h,
            samples: acc
                .into_iter()
                .map(|a| {
                    let (ii, ti, b) = a.best?;
                    Some(sample(
                        scene,
                        layout,
                        ii,
                        ti,
                        b,
                        a.area,
                        a.coverage.min(1.0),
                    ))
                })
                .collect(),
        })
        .collect();
    Texels { pages }
}

fn sample(
    scene: &Scene,
    layout: &Layout,
    ii: u32,
    ti: u32,
    b: Vec2,
    area: f32,
    coverage: f32,
) -> TexelSample {
    let inst = &scene.instances[ii as usize];
    let mesh = &scene.meshes[inst.mesh];
    let t = ti as usize * 3;
    let idx = [mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]].map(|i| i as usize);
    let bw = [1.0 - b.x - b.y, b.x, b.y];
    let rect = layout.instances[ii as usize].expect("rasterised instances have a rect");
    let uv1 = mesh.uv1.as_ref().expect("rasterised meshes have UV1");
    let q = idx.map(|i| rect.page_uv(uv1[i]) * layout.page_size(rect.page));
    let pw = idx.map(|i| inst.transform.transform_point3(mesh.positions[i]));
    let p = pw[0] * bw[0] + pw[1] * bw[1] + pw[2] * bw[2];
    let ng = (pw[1] - pw[0]).cross(pw[2] - pw[0]).normalize_or(Vec3::Y);
    let (e1w, e2w) = (pw[1] - pw[0], pw[2] - pw[0]);
    let (e1q, e2q) = (q[1] - q[0], q[2] - q[0]);
    let det = e1q.perp_dot(e2q);
    let dpdx = (e1w * e2q.y - e2w * e1q.y) / det;
    let dpdy = (e2w * e1q.x - e1w * e2q.x) / det;
    let ns = shading_normal(mesh, inst.normal_matrix(), idx, bw, ng);
    let uv = mesh.uv_at(idx, bw);
    let mat = &scene.materials[mesh.material];
    TexelSample {
        p,
        ng,
        ns,
        albedo: albedo(scene, mesh.material, uv),
        emission: if mat.is_emissive() {
            emission(scene, mesh.material, uv)
        } else {
            Vec3::ZERO
        },
        dpdx,
        dpdy,
        area,
        coverage,
        instance: ii,
        double_sided: mat.double_sided,
        triangle: ti,
        bary: b,
        dbdx: Vec2::new(e2q.y, -e1q.y) / det,
        dbdy: Vec2::new(-e2q.x, e1q.x) / det,
    }
}

/// The interpolated vertex normal of triangle `idx` at weights `bw` (world space through the
/// normal matrix `nm`), turned to the front side of the geometric normal `ng`; `ng` for meshes
/// without normals.
fn shading_normal(
    mesh: &lightlab_scene::Mesh,
    nm: glam::Mat3,
    idx: [usize; 3],
    bw: [f32; 3],
    ng: Vec3,
) -> Vec3 {
    let ns = if mesh.normals.len() == mesh.positions.len() {
        (nm * (mesh.normals[idx[0]] * bw[0]
            + mesh.normals[idx[1]] * bw[1]
            + mesh.normals[idx[2]] * bw[2]))
            .normalize_or(ng)
    } else {
        ng
    };
    if ns.dot(ng) < 0.0 { -ns } else { ns }
}

/// Fuchs §5.7: the texel's normal as the mean of `samples` normal-map normals at uniformly
/// random points of its footprint (±½ texel along the texel's axes, extrapolated on the
/// triangle's plane), each through the triangle's interpolated tangent frame
/// (`lightlab_trace::render::normal_mapped`, as the path tracer reads it). Fuchs's CaSHL uses
/// 20 samples and nearest-texel reads; ours are bilinear. None when the material has no normal
/// map or the mesh no tangents.
pub fn normal_mapped_normal(
    scene: &Scene,
    t: &TexelSample,
    samples: u32,
    rng: &mut lightlab_core::sampling::Rng,
) -> Option<Vec3> {
    let inst = &scene.instances[t.instance as usize];
    let mesh = &scene.meshes[inst.mesh];
    let mat = &scene.materials[mesh.material];
    if mat.normal_texture.is_none()
        || mesh.tangents.len() != mesh.positions.len()
        || mesh.uv0.len() != mesh.positions.len()
        || samples == 0
    {
        return None;
    }
    let k = t.triangle as usize * 3;
    let idx = [mesh.indices[k], mesh.indices[k + 1], mesh.indices[k + 2]].map(|i| i as usize);
    let nm = inst.normal_matrix();
    let mut sum = Vec3::ZERO;
    for _ in 0..samples {
        let u = rng.next_vec2() - Vec2::splat(0.5);
        let b = t.bary + t.dbdx * u.x + t.dbdy * u.y;
        let bw = [1.0 - b.x - b.y, b.x, b.y];
        let uv = mesh.uv_at(idx, bw);
        let ns = shading_normal(mesh, nm, idx, bw, t.ng);
        sum += lightlab_trace::render::normal_mapped(scene, inst, mesh, idx, bw, uv, ns, t.ng);
    }
    Some(sum.normalize_or(t.ns))
}

/// Diffuse reflectance of a material at a surface point: (1−metallic)·base colour (× vertex
/// colour × textures), less the glass part of a transmissive material (its diffuse layer is
/// 1 − t of it, as in the path tracer's BSDF).
pub fn albedo(scene: &Scene, material: usize, uv: lightlab_scene::Attrs) -> Vec3 {
    let m = &scene.materials[material];
    let mut base = m.base_color * uv.color;
    if let Some(r) = m.base_color_texture {
        base *= scene.sample(r, uv);
    }
    let mut metallic = m.metallic;
    if let Some(r) = m.metallic_roughness_texture {
        metallic *= scene.sample(r, uv).z;
    }
    let glass = if m.brdf == lightlab_scene::BrdfModel::Pbr {
        m.specular_transmission * (1.0 - metallic)
    } else {
        0.0
    };
    base.truncate() * (1.0 - metallic) * (1.0 - glass)
}

/// Mark texels whose sample point sees back faces (it lies inside or under geometry, as where a
/// floor continues under a wall): `rays` cosine-distributed probes, invalid when more than
/// `max_fraction` of them hit the back of a single-sided surface. Such texels must not gather
/// or shoot light (Fuchs §3.3.6's bleeding, handled at the sample rather than afterwards);
/// they are filled from valid neighbours. Returns one flag per texel and page.
pub fn probe_validity(
    texels: &Texels,
    scene: &Scene,
    accel: &Accel,
    rays: u32,
    max_fraction: f32,
    seed: u64,
) -> Vec<Vec<bool>> {
    use lightlab_core::sampling::{Frame, Rng, cosine_hemisphere, hammersley};
    use rayon::prelude::*;
    let mut base = 0u64;
    texels
        .pages
        .iter()
        .map(|page| {
            let start = base;
            base += page.samples.len() as u64;
            page.samples
                .par_iter()
                .enumerate()
                .map(|(i, s)| {
                    let Some(s) = s else { return false };
                    let mut rng = Rng::new(seed ^ 0x5eed_0bac, start + i as u64);
                    let off = rng.next_vec2();
                    let frame = Frame::from_normal(s.ng);
                    let eps = 2e-5 * (1.0 + s.p.abs().max_element());
                    let o = s.p + s.ng * eps;
                    let mut back = 0u32;
                    for k in 0..rays {
                        let u = (hammersley(k, rays) + off).fract_gl();
                        let d = frame.to_world(cosine_hemisphere(u));
                        if let Some(hit) = accel.intersect(o, d, f32::INFINITY) {
                            let t = accel.world_triangle(hit.slot);
                            let n = (t[1] - t[0]).cross(t[2] - t[0]);
                            if n.dot(d) > 0.0 {
                                let inst = &scene.instances[hit.prim.instance as usize];
                                let mat = &scene.materials[scene.meshes[inst.mesh].material];
                                if !mat.double_sided {
                                    back += 1;
                                }
                            }
                        }
                    }
                    back as f32 <= max_fraction * rays as f32
                })
                .collect()
        })
        .collect()
}
