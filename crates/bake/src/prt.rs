//! Precomputed radiance transfer: diffuse transfer vectors per vertex and per point (Sloan,
//! Kautz & Snyder 2002; Fuchs 2005 §5.2–5.4, CaSHL; McKenzie Chapter 2010 ch. 4). Issue 6's
//! first layer: the techniques, compression and the textured/hierarchical variants build on it.
//!
//! **Quantity.** The transfer of a point with normal n is, per SH coefficient i,
//!
//! ```text
//! tᵢ = (1/π) ∫ V(ω) max(n·ω, 0) Yᵢ(ω) dω            (shadowed; V ≡ 1: unshadowed)
//! ```
//!
//! so that under incident radiance L = Σ lᵢ Yᵢ the point receives E/π = Σ lᵢ tᵢ — the same
//! quantity as a light-map texel (white receiver); the radiance leaving it is albedo × that.
//! The unshadowed vector is the clamped cosine rotated to n (`sh::clamped_cosine_zonal`,
//! exact); the others are estimated with `samples` cosine-distributed directions (Hammersley
//! points with a per-point Cranley–Patterson rotation): tᵢ ≈ (1/N) Σ V(ωₖ) Yᵢ(ωₖ).
//!
//! **Inter-reflection** (gathering; Sloan et al. §5's bounce iteration, the gathering
//! counterpart of CaSHL's shooting): bounce b adds, for the occluded directions that reach a
//! front face y, (1/N) Σ ρ(y) T⁽ᵇ⁻¹⁾(y), where T⁽ᵇ⁻¹⁾(y) is the previous bounce's increment
//! interpolated from the vertex transfers of the hit triangle. Transfer at arbitrary points
//! (light-map texels) gathers from the same per-vertex bounces, so the scene's mesh resolution
//! bounds the accuracy of inter-reflected light, as in Sloan's per-vertex PRT.
//!
//! Determinism: point k draws its rotation from `Rng::new(seed, k)`; the results do not depend
//! on the thread count.

use crate::texels::albedo;
use glam::{Vec2, Vec3};
use lightlab_core::sampling::{Frame, Rng, cosine_hemisphere, hammersley};
use lightlab_core::sh;
use lightlab_scene::Scene;
use lightlab_trace::Accel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which transfer to compute.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum TransferKind {
    /// Clamped cosine only (no visibility).
    Unshadowed,
    /// Clamped cosine × visibility.
    Shadowed,
    /// Shadowed plus this many bounces of diffuse inter-reflection, gathered (Sloan et al.).
    Interreflected { bounces: u32 },
    /// Shadowed plus inter-reflection shot between light-map texels to convergence (CaSHL,
    /// [`crate::cashl`]); SH light-maps only.
    Shooting(crate::cashl::ShootSettings),
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TransferSettings {
    /// SH bands (l_max + 1): 4 as Fuchs, 5 as McKenzie Chapter, up to 8.
    pub bands: usize,
    /// Directions per point.
    pub samples: u32,
    pub kind: TransferKind,
    pub seed: u64,
    /// Texels of decimated meshes (those naming a `detail_source`) take position, normal and
    /// occlusion from the source surface (`crate::detail`); None bakes the decimated surface as
    /// it is. No effect on scenes without decimated meshes.
    #[serde(default)]
    pub detail: Option<crate::detail::DetailSettings>,
    /// Texel normals from the materials' normal maps, averaged over each texel (Fuchs §5.7,
    /// `texels::normal_mapped_normal`): the transfer of `shl-normalmapped`.
    #[serde(default)]
    pub normal_mapped: bool,
    /// Each instance occludes only itself (McKenzie Chapter's per-mesh transfer, what
    /// `prt-hierarchical` needs: what objects do to each other is its filters' business).
    /// Without it, the moving instances of an animated scene still get transfer of their own
    /// (`crate::occlusion_groups`).
    #[serde(default)]
    pub self_only: bool,
}

impl Default for TransferSettings {
    fn default() -> Self {
        TransferSettings {
            bands: 4,
            samples: 1024,
            kind: TransferKind::Shadowed,
            seed: 0,
            detail: Some(crate::detail::DetailSettings::default()),
            normal_mapped: false,
            self_only: false,
        }
    }
}

/// Errors of the transfer computation.
#[derive(Debug, thiserror::Error)]
pub enum TransferError {
    #[error("invalid transfer settings: {0}")]
    Settings(String),
}

/// Transfer vectors of every vertex of every instance: `instances[i]` holds the mesh's vertex
/// count × bands² coefficients (vertex-major).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexTransfer {
    pub bands: usize,
    pub instances: Vec<Vec<f32>>,
}

impl VertexTransfer {
    /// The transfer vector of vertex `v` of instance `i`.
    pub fn vertex(&self, i: usize, v: usize) -> &[f32] {
        let n = sh::num_coeffs(self.bands);
        &self.instances[i][v * n..(v + 1) * n]
    }

    /// Transfer at a hit: the barycentric blend of its triangle's vertices.
    pub fn at_hit(
        &self,
        scene: &Scene,
        instance: usize,
        triangle: usize,
        bary: Vec2,
        out: &mut [f32],
    ) {
        let mesh = &scene.meshes[scene.instances[instance].mesh];
        let w = [1.0 - bary.x - bary.y, bary.x, bary.y];
        out.fill(0.0);
        for (k, wk) in w.iter().enumerate() {
            let v = mesh.indices[triangle * 3 + k] as usize;
            for (o, t) in out.iter_mut().zip(self.vertex(instance, v)) {
                *o += wk * t;
            }
        }
    }
}

/// E/π under incident radiance `light` (SH coefficients, RGB) for a transfer vector.
pub fn shade(transfer: &[f32], light: &[glam::DVec3]) -> Vec3 {
    transfer
        .iter()
        .zip(light)
        .map(|(t, l)| *l * *t as f64)
        .sum::<glam::DVec3>()
        .as_vec3()
}

pub(crate) fn check(s: &TransferSettings) -> Result<(), TransferError> {
    if !(1..=8).contains(&s.bands) {
        return Err(TransferError::Settings(format!(
            "bands must be 1 to 8, not {}",
            s.bands
        )));
    }
    if s.samples == 0 && s.kind != TransferKind::Unshadowed {
        return Err(TransferError::Settings("samples must be at least 1".into()));
    }
    Ok(())
}

pub(crate) fn ray_eps(p: Vec3) -> f32 {
    2e-5 * (1.0 + p.abs().max_element())
}

/// Fraction of the way from a vertex to the centroid of one of its triangles where its
/// transfer is sampled. A vertex on the line where a wall meets a floor would otherwise cast
/// rays along the other surface's plane, slip past it and see the sky behind it, and its (too
/// bright) transfer would be interpolated over the whole triangle and gathered by every bounce.
const VERTEX_INSET: f32 = 0.02;

/// World-space (position, normal) of every vertex, per instance. The position is moved
/// [`VERTEX_INSET`] towards the centroid of the vertex's triangle that best faces its normal,
/// so it lies *on* that triangle (and is lifted off it like a texel): a point between the
/// vertex and the mean centroid of all its triangles would lie under a convex surface and
/// see only the mesh's inside.
fn world_vertices(scene: &Scene) -> Vec<Vec<(Vec3, Vec3)>> {
    scene
        .instances
        .iter()
        .map(|inst| {
            let m = &scene.meshes[inst.mesh];
            let nm = inst.normal_matrix();
            let world: Vec<Vec3> = m
                .positions
                .iter()
                .map(|p| inst.transform.transform_point3(*p))
                .collect();
            let normal = |v: usize| {
                m.normals
                    .get(v)
                    .map_or(Vec3::Y, |n| (nm * *n).normalize_or(Vec3::Y))
            };
            // Per vertex: (best alignment, triangle centroid, face normal).
            let mut best = vec![(f32::NEG_INFINITY, Vec3::ZERO, Vec3::ZERO); world.len()];
            for t in m.indices.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| world[i as usize]);
                let ng = (b - a).cross(c - a);
                if ng.length_squared() <= 0.0 {
                    continue;
                }
                let ng = ng.normalize();
                let centroid = (a + b + c) / 3.0;
                for &v in t {
                    let al = ng.dot(normal(v as usize));
                    // A face whose winding disagrees with the normal still works turned over.
                    let (al, ngo) = if al < 0.0 { (-al, -ng) } else { (al, ng) };
                    if al > best[v as usize].0 {
                        best[v as usize] = (al, centroid, ngo);
                    }
                }
            }
            (0..world.len())
                .map(|v| {
                    let n = normal(v);
                    let (al, centroid, ng) = best[v];
                    let p = if al.is_finite() {
                        let q = world[v].lerp(centroid, VERTEX_INSET);
                        q + ng * ray_eps(q)
                    } else {
                        world[v]
                    };
                    (p, n)
                })
                .collect()
        })
        .collect()
}

/// One bounce (or the direct visibility term when `previous` is None) at a point: the sum over
/// the point's directions of V·Y (direct) or ρ(y)·T(y) over occluded front-face hits (bounce).
#[allow(clippy::too_many_arguments)]
fn gather_point(
    scene: &Scene,
    accel: &Accel,
    p: Vec3,
    n: Vec3,
    ng: Vec3,
    s: &TransferSettings,
    point: u64,
    previous: Option<&VertexTransfer>,
    out: &mut [f32],
) {
    let nc = out.len();
    let mut y = vec![0.0f32; nc];
    let mut t = vec![0.0f32; nc];
    let mut rng = Rng::new(s.seed, point);
    let rot = rng.next_vec2();
    let frame = Frame::from_normal(n);
    let o = p + n * ray_eps(p);
    out.fill(0.0);
    for k in 0..s.samples {
        let u = (hammersley(k, s.samples) + rot).fract_gl();
        let d = frame.to_world(cosine_hemisphere(u));
        // Fuchs §5.7's second cosine test: a direction below the surface's geometric plane
        // carries nothing, whatever the (normal-mapped or interpolated) normal says.
        if d.dot(ng) <= 0.0 {
            continue;
        }
        match previous {
            None => {
                if !accel.occluded(o, d, f32::INFINITY) {
                    sh::eval_f32(s.bands, d.x, d.y, d.z, &mut y);
                    for (a, b) in out.iter_mut().zip(&y) {
                        *a += b;
                    }
                }
            }
            Some(prev) => {
                let Some(h) = accel.intersect(o, d, f32::INFINITY) else {
                    continue;
                };
                let (ii, tri) = (h.prim.instance as usize, h.prim.triangle as usize);
                let mesh = &scene.meshes[scene.instances[ii].mesh];
                let mat = &scene.materials[mesh.material];
                let w = accel.world_triangle(h.slot);
                let front = (w[1] - w[0]).cross(w[2] - w[0]).dot(d) < 0.0;
                if !front && !mat.double_sided {
                    continue;
                }
                let uv0 = crate::view::hit_uv(mesh, tri, h.bary);
                // Luminance-free: a scalar transfer carries the albedo's mean (the RGB split is
                // left to the albedo applied at shading time of the receiver).
                let rho = albedo(scene, mesh.material, uv0).element_sum() / 3.0;
                prev.at_hit(scene, ii, tri, h.bary, &mut t);
                for (a, b) in out.iter_mut().zip(&t) {
                    *a += rho * b;
                }
            }
        }
    }
    let inv = 1.0 / s.samples as f32;
    out.iter_mut().for_each(|a| *a *= inv);
}

/// Transfer of arbitrary points (position, normal), e.g. light-map texels. Inter-reflected
/// transfer needs the scene's per-vertex bounces (`vertex_bounces`).
pub fn point_transfer(
    scene: &Scene,
    accel: &Accel,
    points: &[(Vec3, Vec3)],
    s: &TransferSettings,
    bounces: &[VertexTransfer],
) -> Result<Vec<f32>, TransferError> {
    let pts: Vec<(Vec3, Vec3, Vec3)> = points.iter().map(|&(p, n)| (p, n, n)).collect();
    surface_transfer(scene, accel, &pts, s, bounces)
}

/// [`point_transfer`] of points (position, shading normal, geometric normal) whose shading
/// normal may differ from the surface's (normal maps, interpolated normals): directions below
/// the geometric plane count as blocked (Fuchs §5.7's two cosine tests). Unshadowed transfer
/// stays the exact clamped cosine about the shading normal.
pub fn surface_transfer(
    scene: &Scene,
    accel: &Accel,
    points: &[(Vec3, Vec3, Vec3)],
    s: &TransferSettings,
    bounces: &[VertexTransfer],
) -> Result<Vec<f32>, TransferError> {
    Ok(surface_transfer_ao(scene, accel, points, s, bounces)?.0)
}

/// [`surface_transfer`] and each point's ambient occlusion: the visible fraction of the
/// cosine-weighted hemisphere, t₀/Y₀ of the direct (shadowed) term (1 for unshadowed transfer).
pub fn surface_transfer_ao(
    scene: &Scene,
    accel: &Accel,
    points: &[(Vec3, Vec3, Vec3)],
    s: &TransferSettings,
    bounces: &[VertexTransfer],
) -> Result<(Vec<f32>, Vec<f32>), TransferError> {
    transfer_ao_from(scene, accel, points, s, bounces, 0)
}

/// [`surface_transfer_ao`] of points that are the run of a longer list from index `first`:
/// point k draws its directions as point `first + k` of the whole list would, so runs computed
/// apart (shards) give the values of the whole.
pub(crate) fn transfer_ao_from(
    scene: &Scene,
    accel: &Accel,
    points: &[(Vec3, Vec3, Vec3)],
    s: &TransferSettings,
    bounces: &[VertexTransfer],
    first: u64,
) -> Result<(Vec<f32>, Vec<f32>), TransferError> {
    transfer_ao_seeded(scene, accel, points, s, bounces, &|k| first + k as u64)
}

/// [`transfer_ao_from`] with point k drawing its directions from seed index `seed(k)`.
pub(crate) fn transfer_ao_seeded(
    scene: &Scene,
    accel: &Accel,
    points: &[(Vec3, Vec3, Vec3)],
    s: &TransferSettings,
    bounces: &[VertexTransfer],
    seed: &(dyn Fn(usize) -> u64 + Sync),
) -> Result<(Vec<f32>, Vec<f32>), TransferError> {
    check(s)?;
    let nc = sh::num_coeffs(s.bands);
    let zonal = sh::clamped_cosine_zonal(s.bands);
    let y0 = 0.5 / std::f32::consts::PI.sqrt();
    let mut out = vec![0.0f32; points.len() * nc];
    let mut ao = vec![1.0f32; points.len()];
    out.par_chunks_mut(nc)
        .zip(ao.par_iter_mut())
        .zip(points.par_iter())
        .enumerate()
        .for_each(|(k, ((o, ao), &(p, n, ng)))| {
            if s.kind == TransferKind::Unshadowed {
                let c = sh::zonal_to_axis(&zonal, n.as_dvec3());
                for (a, b) in o.iter_mut().zip(c) {
                    *a = (b / std::f64::consts::PI) as f32;
                }
                return;
            }
            let k = seed(k);
            gather_point(scene, accel, p, n, ng, s, k, None, o);
            *ao = o[0] / y0;
            let mut add = vec![0.0f32; nc];
            for prev in bounces {
                gather_point(scene, accel, p, n, ng, s, k, Some(prev), &mut add);
                for (a, b) in o.iter_mut().zip(&add) {
                    *a += b;
                }
            }
        });
    Ok((out, ao))
}

/// Per-vertex transfer of the whole scene and, for inter-reflection, what each bounce gathers
/// from (the direct term, then each bounce's increment): pass that list to [`point_transfer`]
/// to give points the same number of bounces.
pub fn vertex_transfer(
    scene: &Scene,
    accel: &Accel,
    s: &TransferSettings,
) -> Result<(VertexTransfer, Vec<VertexTransfer>), TransferError> {
    check(s)?;
    if matches!(s.kind, TransferKind::Shooting(_)) {
        return Err(TransferError::Settings(
            "shooting (CaSHL) runs between light-map texels; per-vertex transfer gathers its \
             bounces (use interreflected)"
                .into(),
        ));
    }
    let verts = world_vertices(scene);
    let flat: Vec<(Vec3, Vec3)> = verts.iter().flatten().copied().collect();
    let nc = sh::num_coeffs(s.bands);
    let split = |v: Vec<f32>| -> VertexTransfer {
        let mut it = v.into_iter();
        VertexTransfer {
            bands: s.bands,
            instances: verts
                .iter()
                .map(|vs| it.by_ref().take(vs.len() * nc).collect())
                .collect(),
        }
    };
    let direct = TransferSettings {
        kind: if s.kind == TransferKind::Unshadowed {
            TransferKind::Unshadowed
        } else {
            TransferKind::Shadowed
        },
        ..*s
    };
    let mut total = point_transfer(scene, accel, &flat, &direct, &[])?;
    let mut increments = vec![];
    if let TransferKind::Interreflected { bounces } = s.kind {
        let mut prev = split(total.clone());
        for _ in 0..bounces {
            // What this bounce gathers from: the direct term, then each bounce's increment.
            increments.push(prev.clone());
            let mut inc = vec![0.0f32; total.len()];
            inc.par_chunks_mut(nc)
                .zip(flat.par_iter())
                .enumerate()
                .for_each(|(k, (o, &(p, n)))| {
                    gather_point(scene, accel, p, n, n, s, k as u64, Some(&prev), o)
                });
            for (a, b) in total.iter_mut().zip(&inc) {
                *a += b;
            }
            prev = split(inc);
        }
    }
    Ok((split(total), increments))
}

/// Normal-map samples averaged per texel for normal-mapped transfer (Fuchs's CaSHL: 20).
pub const NORMAL_MAP_SAMPLES: u32 = 20;

/// Transfer per light-map texel (Fuchs §5's SH light-maps, the texels of CaSHL): the scene's
/// light-map layout, and per page the coefficients packed three to an RGB image
/// (`ceil(bands²/3)` images per page, coefficient c in image c/3, channel c%3).
#[derive(Clone, Debug)]
pub struct ShLightmaps {
    /// The scene with its light-map UVs.
    pub scene: Scene,
    pub layout: crate::layout::Layout,
    pub bands: usize,
    pub pages: Vec<Vec<lightlab_core::image::Image>>,
    pub settings: TransferSettings,
    /// Texels projected onto detail sources (None: no detail baked).
    pub detail: Option<crate::detail::DetailStats>,
    /// What CaSHL's shooting did (None: no shooting).
    pub shooting: Option<crate::cashl::ShootStats>,
    /// Per page, the baked normal and ambient occlusion (empty when read from a folder).
    pub detail_pages: Vec<DetailPage>,
}

/// What a bake learnt of the surface at each texel, for other techniques: with detail from a
/// high-poly source these are its normal map and occlusion map, on the decimated mesh's atlas.
#[derive(Clone, Debug)]
pub struct DetailPage {
    /// Unit shading normal in the instance's object space (xyz, signed, not packed).
    pub normal: lightlab_core::image::Image,
    /// Visible fraction of the cosine-weighted hemisphere (all three channels).
    pub occlusion: lightlab_core::image::Image,
}

impl ShLightmaps {
    /// The transfer vector at page coordinates `uv` of `page`, bilinearly filtered.
    pub fn sample(&self, page: u32, uv: Vec2, out: &mut [f32]) {
        for (k, img) in self.pages[page as usize].iter().enumerate() {
            let v = crate::sample_bilinear(img, uv);
            for c in 0..3 {
                if let Some(o) = out.get_mut(3 * k + c) {
                    *o = v[c];
                }
            }
        }
    }
}

impl From<TransferError> for crate::BakeError {
    fn from(e: TransferError) -> Self {
        match e {
            TransferError::Settings(m) => crate::BakeError::Settings(m),
        }
    }
}

pub use crate::sh_bake::bake_sh_lightmaps;

/// Render SH light-maps on the CPU under the incident radiance of `light` (SH, RGB, blended
/// from its sample points at each hit): radiance = albedo × Σ lᵢ tᵢ, the environment where rays
/// escape. The reference view of the `shl` techniques.
pub fn render_sh_lightmaps(
    sl: &ShLightmaps,
    light: &crate::sh_light::ShLighting,
    width: u32,
    height: u32,
    camera: usize,
    spp: u32,
) -> Option<lightlab_core::image::Image> {
    let scene = &sl.scene;
    let nc = sh::num_coeffs(sl.bands);
    crate::view::render_camera(scene, width, height, camera, spp, |accel, o, d| {
        let h = crate::view::layout_hit(scene, &sl.layout, accel, o, d)?;
        let mut t = vec![0.0f32; nc];
        sl.sample(h.page, h.uv, &mut t);
        let l = light.at(h.instance, h.p);
        Some(albedo(scene, h.material, h.tex_uv) * shade(&t, &l).max(Vec3::ZERO))
    })
}

/// Render per-vertex transfer on the CPU under the incident radiance of `light`: each vertex of
/// the hit triangle is shaded (E/π = Σ lᵢ tᵢ, the light blended at the vertex) and the results
/// interpolated (Gouraud, as `prt-vertex` on the GPU), radiance = albedo × max(E/π, 0); the
/// environment where rays escape.
pub fn render_vertex_transfer(
    scene: &Scene,
    vt: &VertexTransfer,
    light: &crate::sh_light::ShLighting,
    width: u32,
    height: u32,
    camera: usize,
    spp: u32,
) -> Option<lightlab_core::image::Image> {
    let nc = sh::num_coeffs(vt.bands);
    crate::view::render_camera(scene, width, height, camera, spp, |accel, o, d| {
        let h = accel.intersect(o, d, f32::INFINITY)?;
        let (ii, tri) = (h.prim.instance as usize, h.prim.triangle as usize);
        let inst = &scene.instances[ii];
        let mesh = &scene.meshes[inst.mesh];
        // Shaded per vertex (light blended at the vertex), then interpolated.
        let w = [1.0 - h.bary.x - h.bary.y, h.bary.x, h.bary.y];
        let mut e = Vec3::ZERO;
        for (k, wk) in w.iter().enumerate() {
            let v = mesh.indices[tri * 3 + k] as usize;
            let p = inst.transform.transform_point3(mesh.positions[v]);
            e += *wk * shade(&vt.instances[ii][v * nc..(v + 1) * nc], &light.at(ii, p));
        }
        let uv0 = crate::view::hit_uv(mesh, tri, h.bary);
        Some(albedo(scene, mesh.material, uv0) * e.max(Vec3::ZERO))
    })
}
