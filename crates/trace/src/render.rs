//! The reference path tracer: unidirectional, next-event estimation with multiple importance
//! sampling (power heuristic) for area and environment lights, every punctual light and the sun
//! sampled at each vertex, Russian roulette after three bounces.
//!
//! Path depth counts scattering events: emission seen directly has depth 0, direct lighting
//! depth 1. A contribution of depth d is kept when `min_depth ≤ d ≤ max_depth`; technique
//! `direct` is `max_depth = 1`.
//!
//! Surfaces shade two-sided (the shading normal is turned towards the viewer), emitters emit
//! from their front side only unless double-sided, and thin translucent materials transmit a
//! fraction of their diffuse light to the back (foliage).
//!
//! Determinism: pixel (x, y) draws from `Rng::new(seed, y·width + x)` for all its samples, so the
//! image does not depend on the thread count or scheduling.

use crate::accel::{Accel, Hit};
use crate::bsdf::Bsdf;
use crate::lights::{LightSet, emission, sample_punctual};
use glam::{Mat3, Vec2, Vec3};
use lightlab_core::image::Image;
use lightlab_core::lens::CameraModel;
use lightlab_core::sampling::{Frame, Rng, power_heuristic};
use lightlab_scene::{Attrs, Camera, Scene};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Largest accepted image side and sample count; beyond these a request is a mistake.
pub const MAX_SIDE: u32 = 16_384;
pub const MAX_SPP: u32 = 1 << 20;

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Largest number of scattering events on a path.
    pub max_depth: u32,
    /// Smallest number of scattering events a contribution must have (0 = everything).
    pub min_depth: u32,
    pub seed: u64,
    /// Index of the scene camera to use (0 = default camera).
    pub camera: usize,
    /// How the camera forms its image (a pinhole, or a thin lens that blurs what is off its
    /// plane of focus).
    pub lens: lightlab_core::lens::CameraModel,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 256,
            height: 256,
            spp: 64,
            max_depth: 16,
            min_depth: 0,
            seed: 0,
            camera: 0,
            lens: Default::default(),
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RenderError {
    #[error("invalid render settings: {0}")]
    InvalidSettings(String),
    #[error("the scene has no camera {0}")]
    NoCamera(usize),
    #[error("cancelled")]
    Cancelled,
}

impl RenderSettings {
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |m: String| Err(RenderError::InvalidSettings(m));
        if self.width == 0 || self.height == 0 {
            return bad(format!(
                "image size {}×{} must be at least 1×1",
                self.width, self.height
            ));
        }
        if self.width > MAX_SIDE || self.height > MAX_SIDE {
            return bad(format!(
                "image size {}×{} exceeds the limit of {MAX_SIDE} per side",
                self.width, self.height
            ));
        }
        if self.spp == 0 || self.spp > MAX_SPP {
            return bad(format!(
                "samples per pixel {} must be in 1..={MAX_SPP}",
                self.spp
            ));
        }
        if self.max_depth == 0 || self.max_depth > 1024 {
            return bad(format!("max depth {} must be in 1..=1024", self.max_depth));
        }
        if self.min_depth > self.max_depth {
            return bad(format!(
                "min depth {} exceeds max depth {}",
                self.min_depth, self.max_depth
            ));
        }
        if let CameraModel::ThinLens(l) = &self.lens {
            l.validate().or_else(|e| bad(e.to_string()))?;
        }
        Ok(())
    }
}

/// Per pixel of a `width` × `height` image from `camera`, whether all of its 3 × 3 sub-pixel
/// rays first hit one of `instances` (its inside, not its edges): the pixels on which
/// techniques are compared for one object.
pub fn coverage_mask(
    scene: &Scene,
    camera: &lightlab_scene::Camera,
    width: u32,
    height: u32,
    instances: &[usize],
) -> Vec<bool> {
    let accel = Accel::new(scene);
    let aspect = width as f32 / height as f32;
    (0..width * height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % width, i / width);
            (0..9).all(|k| {
                let fx = x as f32 + 0.1 + 0.4 * (k % 3) as f32;
                let fy = y as f32 + 0.1 + 0.4 * (k / 3) as f32;
                let ndc = glam::Vec2::new(
                    2.0 * fx / width as f32 - 1.0,
                    1.0 - 2.0 * fy / height as f32,
                );
                accel
                    .intersect(
                        camera.position(),
                        camera.ray_direction(ndc, aspect),
                        f32::INFINITY,
                    )
                    .is_some_and(|h| instances.contains(&(h.prim.instance as usize)))
            })
        })
        .collect()
}

/// Shading information at a hit.
pub struct Surface {
    pub p: Vec3,
    /// Geometric normal of the authored front side.
    pub ng: Vec3,
    /// Interpolated (and normal-mapped) shading normal, on the front side.
    pub ns: Vec3,
    /// Both texture-coordinate sets (each texture read picks its own).
    pub uv: Attrs,
    pub material: usize,
    /// The anisotropy direction (unit, orthogonal to `ns`) for the models that read one
    /// ([`lightlab_scene::BrdfModel::uses_tangent`]); zero otherwise.
    pub tangent: Vec3,
}

impl Surface {
    /// The local shading frame around `ns` (on the viewer's side): x along the anisotropy
    /// direction where the material has one, else any.
    pub fn frame(&self, ns: Vec3) -> Frame {
        let t = self.tangent - ns * ns.dot(self.tangent);
        if t.length_squared() < 1e-12 {
            return Frame::from_normal(ns);
        }
        let t = t.normalize();
        Frame {
            t,
            b: ns.cross(t),
            n: ns,
        }
    }
}

/// Reconstruct the surface at a hit (`accel` built from `scene`).
pub fn surface(scene: &Scene, accel: &Accel, hit: &Hit) -> Surface {
    let inst = &scene.instances[hit.prim.instance as usize];
    let mesh = &scene.meshes[inst.mesh];
    let t = hit.prim.triangle as usize * 3;
    let idx = [mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]].map(|i| i as usize);
    let (b1, b2) = (hit.bary.x, hit.bary.y);
    let b0 = 1.0 - b1 - b2;
    // World-space vertices straight from the BVH's triangle array (no re-transform).
    let pw = accel.world_triangle(hit.slot);
    let p = pw[0] * b0 + pw[1] * b1 + pw[2] * b2;
    let ng = (pw[1] - pw[0]).cross(pw[2] - pw[0]).normalize_or(Vec3::Y);
    let nm: Mat3 = accel.normal_matrices[hit.prim.instance as usize];
    let n_interp =
        mesh.normals[idx[0]] * b0 + mesh.normals[idx[1]] * b1 + mesh.normals[idx[2]] * b2;
    let mut ns = (nm * n_interp).normalize_or(ng);
    if ns.dot(ng) < 0.0 {
        // Mirrored transforms or inconsistent authored normals: follow the geometry.
        ns = -ns;
    }
    let uv = mesh.uv_at(idx, [b0, b1, b2]);
    let material = mesh.material;
    let m = &scene.materials[material];
    // (The test before the call saves passing its arguments where there is no normal map.)
    let ns = if m.normal_texture.is_some() {
        normal_mapped(scene, inst, mesh, idx, [b0, b1, b2], uv, ns, ng)
    } else {
        ns
    };
    let tangent = if m.brdf.uses_tangent() && mesh.tangents.len() == mesh.positions.len() {
        let tg =
            mesh.tangents[idx[0]] * b0 + mesh.tangents[idx[1]] * b1 + mesh.tangents[idx[2]] * b2;
        anisotropy_direction(
            Mat3::from_mat4(inst.transform) * tg.truncate(),
            tg.w,
            ns,
            m.anisotropy_rotation,
        )
    } else {
        Vec3::ZERO
    };
    Surface {
        p,
        ng,
        ns,
        uv,
        material,
        tangent,
    }
}

/// The anisotropy direction: the world tangent `tw` made orthogonal to `ns`, turned by
/// `rotation` towards the bitangent (glTF: ns × t · handedness); zero where `tw` is degenerate.
/// The GPU's `surface()` (raster.wgsl) computes the same.
pub fn anisotropy_direction(tw: Vec3, handedness: f32, ns: Vec3, rotation: f32) -> Vec3 {
    let t = (tw - ns * ns.dot(tw)).normalize_or_zero();
    if t == Vec3::ZERO {
        return t;
    }
    let b = ns.cross(t) * if handedness < 0.0 { -1.0 } else { 1.0 };
    t * rotation.cos() + b * rotation.sin()
}

/// The shading normal perturbed by the material's tangent-space normal map (glTF: xy scaled by
/// `normal_scale`) at `uv`, in the frame of the triangle `idx`'s interpolated tangent (weights
/// `bw`) around `ns`; `ns` itself where the mesh has no tangents, the material no normal map, or
/// the mapped normal would face away from the geometric normal `ng`. Shared by the path tracer
/// and the bakers (normal-mapped SH light-maps), so both read normal maps the same way.
#[allow(clippy::too_many_arguments)]
pub fn normal_mapped(
    scene: &Scene,
    inst: &lightlab_scene::Instance,
    mesh: &lightlab_scene::Mesh,
    idx: [usize; 3],
    bw: [f32; 3],
    uv: Attrs,
    ns: Vec3,
    ng: Vec3,
) -> Vec3 {
    let mat = &scene.materials[mesh.material];
    let Some(r) = mat.normal_texture else {
        return ns;
    };
    if mesh.tangents.len() != mesh.positions.len() {
        return ns;
    }
    let tg = mesh.tangents[idx[0]] * bw[0]
        + mesh.tangents[idx[1]] * bw[1]
        + mesh.tangents[idx[2]] * bw[2];
    let tw = Mat3::from_mat4(inst.transform) * tg.truncate();
    let tw = (tw - ns * ns.dot(tw)).normalize_or_zero();
    if tw == Vec3::ZERO {
        return ns;
    }
    let bw = ns.cross(tw) * if tg.w < 0.0 { -1.0 } else { 1.0 };
    let s = scene.sample(r, uv).truncate() * 2.0 - Vec3::ONE;
    let s = Vec3::new(s.x * mat.normal_scale, s.y * mat.normal_scale, s.z);
    let mapped = (tw * s.x + bw * s.y + ns * s.z).normalize_or(ns);
    if mapped.dot(ng) > 0.0 { mapped } else { ns }
}

/// Offset a ray origin off the surface, to the side of `dir`.
#[inline]
fn offset(p: Vec3, ng: Vec3, dir: Vec3) -> Vec3 {
    // ≈ 300 ulp of the coordinate: clear of the surface's own intersection error, small next to
    // real geometry (the Cornell light hangs 0.1 mm below its ceiling).
    let eps = 2e-5 * (1.0 + p.abs().max_element());
    if dir.dot(ng) >= 0.0 {
        p + ng * eps
    } else {
        p - ng * eps
    }
}

/// Which scattering depths a punctual light contributes to (per-light bake modes: a light whose
/// direct part is rendered in real time contributes only to depths ≥ 2 of a bake).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightUse {
    /// Direct light (next-event estimation at the first scattering event).
    pub direct: bool,
    /// Light reaching the first surface after one or more bounces.
    pub indirect: bool,
}

impl LightUse {
    pub const ALL: LightUse = LightUse {
        direct: true,
        indirect: true,
    };
}

/// Where a path starts.
enum Start {
    /// A camera ray.
    Ray(Vec3, Vec3),
    /// A surface point with its own BSDF (a light-map texel), seen from along `ns`.
    Surface {
        p: Vec3,
        ng: Vec3,
        ns: Vec3,
        bsdf: Bsdf,
    },
}

/// The path tracer over a prepared scene.
pub struct PathTracer<'a> {
    pub scene: &'a Scene,
    pub accel: &'a Accel,
    pub lights: std::sync::Arc<LightSet>,
    /// Per punctual light (index into `scene.lights`): which depths it lights. Empty = all.
    pub light_use: Vec<LightUse>,
    /// Lights that are not scene geometry, sampled at every vertex (next-event estimation
    /// only): light slabs and luminaires seen through their windows (`luminaire.rs`).
    pub windows: Vec<std::sync::Arc<dyn WindowEmitter>>,
}

/// A light leaving through a window that rays do not hit (a light slab, or a luminaire's
/// geometry traced through its window): sampled by next-event estimation only.
pub trait WindowEmitter: Send + Sync {
    /// A point on the window and the radiance it sends to `x` × cos θ' / (r² · pdf), pdf per
    /// unit area; None where nothing reaches x.
    fn sample(&self, x: Vec3, rng: &mut Rng) -> Option<(Vec3, Vec3)>;
}

impl WindowEmitter for lightlab_core::light_slab::SlabEmitter {
    fn sample(&self, x: Vec3, rng: &mut Rng) -> Option<(Vec3, Vec3)> {
        let (pick, u) = (rng.next_f32(), rng.next_vec2());
        lightlab_core::light_slab::SlabEmitter::sample(self, x, pick, u).map(|s| (s.point, s.value))
    }
}

impl<'a> PathTracer<'a> {
    pub fn new(scene: &'a Scene, accel: &'a Accel) -> Self {
        PathTracer {
            scene,
            accel,
            lights: std::sync::Arc::new(LightSet::new(scene)),
            light_use: Vec::new(),
            windows: Vec::new(),
        }
    }

    /// Radiance along one camera ray. As a rasteriser culls them, the back faces of
    /// single-sided materials are invisible to it (glTF `doubleSided: false`); the ray passes
    /// through them. Later bounces see every face.
    pub fn radiance(&self, origin: Vec3, dir: Vec3, s: &RenderSettings, rng: &mut Rng) -> Vec3 {
        self.trace(Start::Ray(origin, dir), s, rng)
    }

    /// Radiance leaving a surface point `p` (geometric normal `ng`, shading normal `ns`, both on
    /// the lit side) along `ns`, through the Lambertian BSDF of reflectance `albedo`. With
    /// `albedo = 1` this is irradiance/π, the quantity a light-map stores. Depth counts from
    /// this point: its direct light has depth 1.
    pub fn surface_radiance(
        &self,
        p: Vec3,
        ng: Vec3,
        ns: Vec3,
        albedo: Vec3,
        s: &RenderSettings,
        rng: &mut Rng,
    ) -> Vec3 {
        let bsdf = Bsdf::lambert(albedo);
        self.trace(Start::Surface { p, ng, ns, bsdf }, s, rng)
    }

    fn trace(&self, start: Start, s: &RenderSettings, rng: &mut Rng) -> Vec3 {
        let scene = self.scene;
        let keep = |depth: u32| depth >= s.min_depth && depth <= s.max_depth;
        let mut l = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        let (mut o, mut d, mut first) = match start {
            Start::Ray(o, d) => (o, d, None),
            Start::Surface { p, ng, ns, bsdf } => (p, -ns, Some((p, ng, ns, bsdf))),
        };
        // pdf of the BSDF sample that produced `d` (0 for the camera ray: no MIS).
        let mut prev_pdf = 0.0f32;
        let mut prev_p = o;
        // Scattering events so far.
        let mut depth = 0u32;
        // Back faces a camera ray passed through (bounded: a ray cannot be culled forever).
        let mut culled = 0u32;
        loop {
            if let Some((p, ng, ns, bsdf)) = first.take() {
                // The texel itself: no emission, straight to scattering.
                let frame = Frame::from_normal(ns);
                let sf = Surface {
                    p,
                    ng,
                    ns,
                    uv: Attrs::default(),
                    material: usize::MAX,
                    tangent: Vec3::ZERO,
                };
                let wo_l = Vec3::Z;
                depth += 1;
                if keep(depth) {
                    l += beta * self.direct(&sf, ng, &frame, wo_l, &bsdf, depth, rng);
                }
                if depth >= s.max_depth
                    && !(self.lights.has_emitters() || scene.environment.is_some())
                {
                    break;
                }
                let Some((wi_l, f, pdf)) = bsdf.sample(wo_l, rng.next_f32(), rng.next_vec2())
                else {
                    break;
                };
                let wi = frame.to_world(wi_l);
                if wi.dot(ng) <= 0.0 {
                    break;
                }
                beta *= f * wi_l.z / pdf;
                prev_pdf = pdf;
                prev_p = p;
                o = offset(p, ng, wi);
                d = wi;
                continue;
            }
            let Some(hit) = self.accel.intersect(o, d, f32::INFINITY) else {
                if let Some(env) = &scene.environment
                    && keep(depth)
                {
                    let (le, env_pdf) = self.lights.env_lookup(env, d);
                    let w = if prev_pdf > 0.0 {
                        power_heuristic(prev_pdf, env_pdf)
                    } else {
                        1.0
                    };
                    l += beta * le * w;
                }
                break;
            };
            let sf = surface(scene, self.accel, &hit);
            let wo = -d;
            let mat = &scene.materials[sf.material];
            if depth == 0 && !mat.double_sided && wo.dot(sf.ng) < 0.0 && culled < 64 {
                culled += 1;
                o = offset(sf.p, sf.ng, d);
                continue;
            }
            // Emission, seen from the front (or either side if double-sided).
            if mat.is_emissive() && keep(depth) && (wo.dot(sf.ng) > 0.0 || mat.double_sided) {
                let le = emission(scene, sf.material, sf.uv);
                let w = if prev_pdf > 0.0 {
                    let idx = self
                        .lights
                        .emitter_index(hit.prim.instance, hit.prim.triangle)
                        .expect("emissive instance is registered");
                    let dist = (sf.p - prev_p).length();
                    power_heuristic(prev_pdf, self.lights.emitter_pdf(idx, dist, wo.dot(sf.ng)))
                } else {
                    1.0
                };
                l += beta * le * w;
            }
            if depth >= s.max_depth {
                break;
            }
            // Shading frame on the viewer's side.
            let side = if wo.dot(sf.ng) >= 0.0 { 1.0 } else { -1.0 };
            let ng = sf.ng * side;
            // Where the viewer is below the interpolated normal (grazing views of coarse
            // meshes) shade with the geometric normal rather than returning black.
            let ns = if (sf.ns * side).dot(wo) > 1e-4 {
                sf.ns * side
            } else {
                ng
            };
            let frame = sf.frame(ns);
            let wo_l = frame.to_local(wo);
            if wo_l.z <= 0.0 {
                break;
            }
            let mut bsdf = Bsdf::new(scene, mat, sf.uv, wo_l.z);
            // A dielectric refracts from outside (the authored front side) inwards.
            bsdf.entering = side > 0.0;
            depth += 1;
            // Next-event estimation.
            if keep(depth) {
                l += beta * self.direct(&sf, ng, &frame, wo_l, &bsdf, depth, rng);
            }
            if depth >= s.max_depth {
                // Only emission reached by a BSDF sample can still count (MIS partner of the
                // light samples above).
                if !(self.lights.has_emitters() || scene.environment.is_some()) {
                    break;
                }
            }
            // Continue the path.
            let Some((wi_l, f, pdf)) = bsdf.sample(wo_l, rng.next_f32(), rng.next_vec2()) else {
                break;
            };
            let wi = frame.to_world(wi_l);
            if wi.dot(ng) * wi_l.z <= 0.0 {
                // Shading and geometric normals disagree about the side: drop the sample.
                break;
            }
            beta *= f * wi_l.z.abs() / pdf;
            if depth >= 3 {
                let q = beta.max_element().min(0.95);
                if rng.next_f32() >= q {
                    break;
                }
                beta /= q;
            }
            if !beta.is_finite() || beta == Vec3::ZERO {
                break;
            }
            prev_pdf = pdf;
            prev_p = sf.p;
            o = offset(sf.p, ng, wi);
            d = wi;
        }
        l
    }

    /// Direct light at a surface: every punctual light, one emitter sample and one
    /// environment sample, each with MIS where the light is not a delta.
    #[allow(clippy::too_many_arguments)]
    fn direct(
        &self,
        sf: &Surface,
        ng: Vec3,
        frame: &Frame,
        wo_l: Vec3,
        bsdf: &Bsdf,
        depth: u32,
        rng: &mut Rng,
    ) -> Vec3 {
        let scene = self.scene;
        let mut l = Vec3::ZERO;
        let add = |ls: crate::lights::LightSample, l: &mut Vec3| {
            let wi_l = frame.to_local(ls.wi);
            // Transmission only where the material transmits; geometric side must agree.
            if wi_l.z * ls.wi.dot(ng) <= 0.0 {
                return;
            }
            let f = bsdf.eval(wo_l, wi_l);
            if f == Vec3::ZERO {
                return;
            }
            // The shadow ray leaves the offset origin and aims at the sampled point itself:
            // keeping the direction from the un-offset point would reach the light's plane
            // eps/cosθ early and hit the light (a loss of several per cent near lights).
            let o = offset(sf.p, ng, ls.wi);
            let (dir, tmax) = if ls.dist.is_finite() {
                (sf.p + ls.wi * ls.dist - o, 1.0 - 1e-4)
            } else {
                (ls.wi, f32::INFINITY)
            };
            if self.accel.occluded(o, dir, tmax) {
                return;
            }
            let w = if ls.pdf > 0.0 {
                power_heuristic(ls.pdf, bsdf.pdf(wo_l, wi_l))
            } else {
                1.0
            };
            *l += f * ls.value * wi_l.z.abs() * w;
        };
        for i in 0..scene.lights.len() {
            let u = rng.next_vec2();
            let used = self
                .light_use
                .get(i)
                .is_none_or(|u| if depth <= 1 { u.direct } else { u.indirect });
            if !used {
                continue;
            }
            if let Some(ls) = sample_punctual(scene, i, sf.p, u) {
                add(ls, &mut l);
            }
        }
        let (u_sel, u) = (rng.next_f32(), rng.next_vec2());
        if let Some(ls) = self.lights.sample_emitter(scene, sf.p, u_sel, u) {
            add(ls, &mut l);
        }
        let u = rng.next_vec2();
        if let Some(env) = &scene.environment
            && let Some(ls) = self.lights.sample_env(env, u)
        {
            add(ls, &mut l);
        }
        for w in &self.windows {
            if let Some((point, value)) = w.sample(sf.p, rng) {
                let to = point - sf.p;
                let dist = to.length();
                if dist > 1e-9 {
                    let ls = crate::lights::LightSample {
                        wi: to / dist,
                        dist,
                        value,
                        pdf: 0.0,
                    };
                    add(ls, &mut l);
                }
            }
        }
        l
    }

    /// Render an image. `progress(done_rows, total_rows)` is called from worker threads;
    /// returning false cancels the render.
    pub fn render(
        &self,
        s: &RenderSettings,
        progress: &(dyn Fn(usize, usize) -> bool + Sync),
    ) -> Result<Image, RenderError> {
        let rows: Vec<u32> = (0..s.height).collect();
        Ok(Image {
            width: s.width,
            height: s.height,
            data: self.render_rows(s, &rows, progress)?,
        })
    }

    /// Render the image rows `rows` (each below `s.height`) of the image `s` describes, their
    /// pixels in the order given: a shard of a render split over machines. A pixel's value
    /// does not depend on which other rows are rendered (see the module doc), so the rows of
    /// several calls assemble the image `render` makes, bit for bit.
    pub fn render_rows(
        &self,
        s: &RenderSettings,
        rows: &[u32],
        progress: &(dyn Fn(usize, usize) -> bool + Sync),
    ) -> Result<Vec<Vec3>, RenderError> {
        s.validate()?;
        let cam: &Camera = self
            .scene
            .cameras
            .get(s.camera)
            .ok_or(RenderError::NoCamera(s.camera))?;
        if let Some(&y) = rows.iter().find(|&&y| y >= s.height) {
            return Err(RenderError::InvalidSettings(format!(
                "row {y} is outside a {}-row image",
                s.height
            )));
        }
        let (w, h) = (s.width, s.height);
        let aspect = w as f32 / h as f32;
        let origin = cam.position();
        let forward = cam.transform.transform_vector3(-Vec3::Z).normalize();
        let t = (cam.yfov * 0.5).tan();
        // The pinhole's camera-space direction through an NDC point (the thin lens's chief ray).
        let pinhole = |ndc: Vec2| Vec3::new(ndc.x * t * aspect, ndc.y * t, -1.0);
        let done = AtomicUsize::new(0);
        let cancelled = AtomicBool::new(false);
        let out: Vec<Vec<Vec3>> = rows
            .par_iter()
            .map(|&y| {
                if cancelled.load(Ordering::Relaxed) {
                    return vec![];
                }
                let row = (0..w)
                    .map(|x| {
                        let mut rng = Rng::new(s.seed, (y as u64) * w as u64 + x as u64);
                        let mut sum = glam::DVec3::ZERO;
                        for _ in 0..s.spp {
                            let j = rng.next_vec2();
                            let ndc = Vec2::new(
                                (x as f32 + j.x) / w as f32 * 2.0 - 1.0,
                                1.0 - (y as f32 + j.y) / h as f32 * 2.0,
                            );
                            let (o, dir, weight) = match &s.lens {
                                CameraModel::Pinhole => {
                                    // `Camera::ray_direction` with its tangent computed once.
                                    let d = cam.transform.transform_vector3(pinhole(ndc));
                                    (origin, d.normalize(), 1.0)
                                }
                                CameraModel::ThinLens(l) => {
                                    let (o, d) = l.ray(pinhole(ndc), rng.next_vec2());
                                    (o, d, 1.0)
                                }
                                CameraModel::Traced(l) => {
                                    let u = rng.next_vec2().as_dvec2();
                                    let Some(r) = l.sample_ray(ndc.as_dvec2(), u) else {
                                        continue;
                                    };
                                    (r.origin.as_vec3(), r.dir.as_vec3(), r.weight as f32)
                                }
                            };
                            let (o, dir) = match &s.lens {
                                CameraModel::Pinhole => (o, dir),
                                _ => (
                                    cam.transform.transform_point3(o),
                                    cam.transform.transform_vector3(dir).normalize(),
                                ),
                            };
                            // Clipped at the near plane, as the rasteriser clips.
                            let near = cam.znear / dir.dot(forward).max(1e-6);
                            let v = self.radiance(o + dir * near, dir, s, &mut rng) * weight;
                            if v.is_finite() {
                                sum += v.as_dvec3();
                            }
                        }
                        (sum / s.spp as f64).as_vec3()
                    })
                    .collect();
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                if !progress(n, rows.len()) {
                    cancelled.store(true, Ordering::Relaxed);
                }
                row
            })
            .collect();
        if cancelled.load(Ordering::Relaxed) {
            return Err(RenderError::Cancelled);
        }
        Ok(out.into_iter().flatten().collect())
    }
}
