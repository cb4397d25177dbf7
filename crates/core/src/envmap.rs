//! Prefiltered environment maps (Heidrich 1999, ch. 8) and the split-sum table of GGX: what the
//! GPU's specular environment term samples, computed once on the CPU.
//!
//! A map is a set of *levels*, one per roughness the scene's materials use (Heidrich prefilters
//! one map per Phong exponent in use, §8.3.2), each level in one of the sphere
//! parameterisations of [`crate::param`] (dual paraboloid, cube or sphere map, §8.1–8.2), with
//! its own minification mip chain whose texels are averaged by solid angle (§8.2.3).
//!
//! Each level holds the environment's radiance averaged over a lobe around the texel's
//! direction `r`:
//! - [`Lobe::Phong`]: the normalised Phong lobe cosⁿ(r·l) with n = `phong_exponent(roughness)`
//!   (Heidrich's glossy prefilter). With the normalised Phong BRDF (n+2)/2π·cosⁿ the reflected
//!   radiance is then f0·⟨n,r⟩·map(r), up to the variation of ⟨n,l⟩ across the lobe.
//! - [`Lobe::Ggx`]: the GGX lobe of roughness r seen along its normal (n = v = r), weighted by
//!   ⟨n,l⟩ (Karis 2013, the "split sum"); the reflected radiance is map(r)·(f0·A + B) with A, B
//!   from [`split_sum_lut`], the BRDF's directional albedo integrated with the GPU's exact model
//!   (α = roughness², height-correlated Smith G2, Schlick Fresnel).
//!
//! Lobe averages are computed by filtered importance sampling (Křivánek & Colbert 2008): a
//! Hammersley set of lobe directions, each read from a solid-angle-weighted pyramid of the
//! lat-long source at the level whose texels match the sample's share of the lobe. Level 0
//! (roughness 0) is the mirror map: the source averaged over each texel's footprint.
//!
//! Directions are turned into the map's frame by [`EnvMaps::frame`] before the
//! parameterisation: for the view-independent maps (dual paraboloid, cube) world +Y becomes the
//! map's +z, so the paraboloids split at the horizon; the sphere map is made for one viewing
//! direction (its frame is the camera's view rotation, viewer on +z).
//!
//! Written here rather than taken from a crate: no Rust crate prefilters into these
//! parameterisations (the ones that exist produce cube maps for one engine's layout).

use crate::image::Image;
use crate::param::Param;
use crate::sampling::hammersley;
use glam::{DVec2, DVec3, Mat3, Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;

/// The lobe a level is prefiltered with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    Ggx,
    Phong,
}

/// The Phong exponent of a roughness, as the renderers map it (`BrdfModel::exponent`):
/// n = 2/α² − 2 with α = roughness², clamped to [1, 10⁴].
pub fn phong_exponent(roughness: f32) -> f32 {
    let a2 = (roughness * roughness).powi(2).max(1e-6);
    (2.0 / a2 - 2.0).clamp(1.0, 1e4)
}

/// The roughness whose [`phong_exponent`] is `n` (n ≥ 1).
pub fn roughness_of_exponent(n: f32) -> f32 {
    (2.0 / (n.max(1.0) + 2.0)).powf(0.25)
}

/// World direction → the view-independent maps' frame (world +Y = map +z).
pub const WORLD_TO_MAP: Mat3 = Mat3::from_cols(
    Vec3::new(1.0, 0.0, 0.0),
    Vec3::new(0.0, 0.0, 1.0),
    Vec3::new(0.0, -1.0, 0.0),
);

/// What to prefilter.
#[derive(Clone, Debug)]
pub struct EnvSettings {
    pub param: Param,
    /// World → map rotation ([`WORLD_TO_MAP`], or the camera's view rotation for the sphere map).
    pub frame: Mat3,
    /// Face size in texels (square faces).
    pub size: u32,
    /// The levels' roughness values, ascending; the first should be 0 (the mirror map).
    pub roughness: Vec<f32>,
    /// One set of levels per lobe.
    pub lobes: Vec<Lobe>,
    /// Lobe samples per texel.
    pub samples: u32,
    /// Also an irradiance map (Heidrich Eq 8.13): the cosine-weighted mean radiance E/π
    /// around each direction, stored after the lobe sets (`faces` layers).
    pub irradiance: bool,
}

impl EnvSettings {
    /// The face size that gives `param` about `texels` texels in all (equal-memory comparisons).
    pub fn equal_memory_size(param: Param, texels: u32) -> u32 {
        ((texels as f64 / param.faces() as f64).sqrt().round() as u32).max(4)
    }
}

/// Prefiltered maps: `layers[(set · levels + level) · faces + face]` is a mip chain, `mips[m]`
/// of side `max(size >> m, 1)`, row-major from the face's uv = (0, 0).
#[derive(Clone, Debug)]
pub struct EnvMaps {
    pub param: Param,
    pub frame: Mat3,
    pub size: u32,
    pub roughness: Vec<f32>,
    pub lobes: Vec<Lobe>,
    pub layers: Vec<Vec<Vec<Vec3>>>,
    /// Whether the last `faces` layers are the irradiance map (E/π).
    pub irradiance: bool,
    /// The mean angular size of a level-0 texel, sqrt(4π / texels) (radians): mip selection.
    pub texel_angle: f32,
}

/// A lat-long source with a solid-angle-weighted pyramid (`Param::LatLong` convention).
struct Source {
    levels: Vec<(u32, u32, Vec<Vec3>)>,
}

impl Source {
    fn new(img: &Image, scale: f32) -> Source {
        let mut levels = vec![(
            img.width,
            img.height,
            img.data.iter().map(|&c| c * scale).collect::<Vec<_>>(),
        )];
        while let Some((w, h, d)) = levels.last().filter(|(w, h, _)| *w >= 8 && *h >= 4) {
            let (nw, nh) = (w / 2, h / 2);
            // Rows weighted by their solid angle (∝ sin θ of the row centre).
            let weight = |y: u32| ((y as f32 + 0.5) / *h as f32 * PI).sin().max(1e-6);
            let mut out = Vec::with_capacity((nw * nh) as usize);
            for y in 0..nh {
                for x in 0..nw {
                    let (mut s, mut ws) = (Vec3::ZERO, 0.0);
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                        let wt = weight(sy);
                        s += d[(sy * w + sx) as usize] * wt;
                        ws += wt;
                    }
                    out.push(s / ws);
                }
            }
            levels.push((nw, nh, out));
        }
        Source { levels }
    }

    /// Mean solid angle of a texel of level `l`.
    fn texel_solid_angle(&self, l: usize) -> f32 {
        let (w, h, _) = &self.levels[l];
        4.0 * PI / (*w as f32 * *h as f32)
    }

    /// The level whose texels have solid angle `omega` (fractional).
    fn lod(&self, omega: f32) -> f32 {
        (0.5 * (omega / self.texel_solid_angle(0)).max(1e-12).log2())
            .clamp(0.0, (self.levels.len() - 1) as f32)
    }

    fn bilinear(&self, l: usize, d: Vec3) -> Vec3 {
        let (w, h, data) = &self.levels[l];
        let (w, h) = (*w as i64, *h as i64);
        let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        let (x, y) = (u * w as f32 - 0.5, v * h as f32 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |xi: i64, yi: i64| data[(yi.clamp(0, h - 1) * w + xi.rem_euclid(w)) as usize];
        let (xi, yi) = (x0 as i64, y0 as i64);
        (at(xi, yi) * (1.0 - fx) + at(xi + 1, yi) * fx) * (1.0 - fy)
            + (at(xi, yi + 1) * (1.0 - fx) + at(xi + 1, yi + 1) * fx) * fy
    }

    /// Trilinear read of direction `d` (world) at fractional level `lod`.
    fn sample(&self, d: Vec3, lod: f32) -> Vec3 {
        let l0 = lod.floor() as usize;
        let f = lod - l0 as f32;
        let a = self.bilinear(l0, d);
        if f <= 1e-4 || l0 + 1 >= self.levels.len() {
            return a;
        }
        a * (1.0 - f) + self.bilinear(l0 + 1, d) * f
    }
}

/// The direction of texel centre `uv` of `face`, extended past the discs of the paraboloid
/// (into the other hemisphere, continuously) and the sphere map (clamped to its rim), so that
/// bilinear reads near a rim blend meaningful values.
pub fn texel_direction(param: Param, face: usize, uv: Vec2) -> Vec3 {
    let q = uv.as_dvec2() * 2.0 - DVec2::ONE;
    let d = match param {
        Param::DualParaboloid => {
            let r2 = q.length_squared();
            let z = (1.0 - r2) / (1.0 + r2);
            let s = if face == 0 { 1.0 } else { -1.0 };
            DVec3::new(2.0 * q.x / (1.0 + r2), 2.0 * q.y / (1.0 + r2), s * z)
        }
        Param::SphereMap => {
            let q = if q.length() > 0.999 {
                q.normalize() * 0.999
            } else {
                q
            };
            param
                .uv_to_dir(face, (q + DVec2::ONE) * 0.5)
                .unwrap_or(DVec3::Z)
        }
        _ => param.uv_to_dir(face, uv.as_dvec2()).unwrap_or(DVec3::Z),
    };
    d.as_vec3().normalize()
}

/// Lobe-averaged radiance around map direction `r` (world `rw`).
fn lobe_average(src: &Source, lobe: Lobe, roughness: f32, rw: Vec3, samples: u32) -> Vec3 {
    let axis = rw.as_dvec3();
    let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
    let (t, b) = crate::sampling::orthonormal_basis(rw);
    for i in 0..samples {
        let u = hammersley(i, samples);
        let (l, pdf, w) = match lobe {
            Lobe::Phong => {
                let n = phong_exponent(roughness) as f64;
                let l = crate::brdf::sample_cos_lobe(axis, n, u.as_dvec2()).as_vec3();
                let c = l.dot(rw).max(0.0) as f64;
                let pdf = (n + 1.0) / (2.0 * std::f64::consts::PI) * c.powf(n);
                (l, pdf as f32, 1.0)
            }
            Lobe::Ggx => {
                let alpha = (roughness * roughness).max(1e-3) as f64;
                let ggx = crate::brdf::Distribution::Ggx { alpha };
                let hl = ggx.sample_h(u.as_dvec2()).as_vec3();
                let h = t * hl.x + b * hl.y + rw * hl.z;
                let l = 2.0 * h.dot(rw) * h - rw;
                let nl = l.dot(rw);
                if nl <= 0.0 {
                    continue;
                }
                // p(l) = D(h)·⟨n,h⟩ / (4⟨v,h⟩) = D/4 with n = v.
                (l, ggx.d(hl.z as f64) as f32 / 4.0, nl)
            }
        };
        let omega = 1.0 / (samples as f32 * pdf.max(1e-12));
        // One level coarser than the sample's solid angle: smooth with few samples (with
        // many, the extra blur would bias wide lobes across sharp edges such as a horizon).
        let lod = src.lod(omega) + if samples >= 1024 { 0.0 } else { 1.0 };
        sum += src.sample(l, lod.min((src.levels.len() - 1) as f32)) * w;
        wsum += w;
    }
    if wsum > 0.0 { sum / wsum } else { Vec3::ZERO }
}

/// The angular width of a lobe (radians, about its standard deviation).
fn lobe_width(lobe: Lobe, roughness: f32) -> f32 {
    match lobe {
        Lobe::Phong => 1.0 / phong_exponent(roughness).sqrt(),
        Lobe::Ggx => 2.0 * roughness * roughness,
    }
}

/// Samples a lobe needs over a source whose texels have solid angle `texel_solid_angle`: a
/// lobe a few source texels wide is averaged well by few (each read is filtered), up to `max`
/// for wide ones.
pub fn lobe_samples(texel_solid_angle: f32, lobe: Lobe, roughness: f32, max: u32) -> u32 {
    let texel = texel_solid_angle.sqrt();
    let ratio = lobe_width(lobe, roughness) / texel;
    ((16.0 * ratio * ratio).ceil() as u32).clamp(16.min(max), max)
}

/// The face size at which a level is computed before it is upsampled to `settings.size`: the
/// full size for the mirror level, else the size that resolves the lobe (a texel under a
/// third of its width).
pub fn level_size(settings: &EnvSettings, lobe: Lobe, roughness: f32) -> u32 {
    let size = settings.size.max(1);
    if roughness <= 0.0 {
        return size;
    }
    let width = lobe_width(lobe, roughness);
    let per_face = (4.0 * PI / settings.param.faces() as f32).sqrt();
    let need = (3.0 * per_face / width.max(1e-6)).ceil() as u32;
    need.next_power_of_two().clamp(16, size).min(size)
}

/// The sides of a face's mip chain, as the GPU halves them (⌊n/2⌋ down to 1).
pub fn mip_sizes(size: u32) -> Vec<u32> {
    let mut sizes = vec![size.max(1)];
    while let Some(&n) = sizes.last().filter(|n| **n > 1) {
        sizes.push(n / 2);
    }
    sizes
}

/// The texels' solid angles of every level of a face's mip chain but the last, one level
/// after the other (row-major): the weights of [`mip_chain`]'s 2×2 steps, for a GPU port.
pub fn mip_weights(param: Param, size: u32) -> Vec<f32> {
    level_solid_angles(param, size)
        .iter()
        .flatten()
        .map(|&w| w as f32)
        .collect()
}

/// The texels' solid angles of every level of a face's mip chain but the last (row-major,
/// one table per level). They are the same for every layer of a map, so [`prefilter`] computes
/// them once: each rim texel of the disc maps costs a quadrature, and recomputing them per
/// layer was a tenth of a `phong-shadow-maps` render of a small image on lavapipe.
fn level_solid_angles(param: Param, size: u32) -> Vec<Vec<f64>> {
    let sizes = mip_sizes(size);
    sizes[..sizes.len() - 1]
        .iter()
        .map(|&n| {
            (0..n * n)
                .map(|i| param.texel_solid_angle(i % n, i / n, n, n))
                .collect()
        })
        .collect()
}

/// One face of one level at face size `n`.
fn level_face(
    src: &Source,
    s: &EnvSettings,
    lobe: Lobe,
    roughness: f32,
    face: usize,
    n: u32,
) -> Vec<Vec3> {
    let to_world = s.frame.transpose();
    (0..n * n)
        .into_par_iter()
        .map(|i| {
            let uv = Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) / n as f32;
            let d = to_world * texel_direction(s.param, face, uv);
            if roughness <= 0.0 {
                // The mirror map: the source over the texel's footprint.
                let omega = 4.0 * PI / (s.param.faces() as f32 * (n * n) as f32);
                src.sample(d, src.lod(omega))
            } else {
                lobe_average(src, lobe, roughness, d, s.samples)
            }
        })
        .collect()
}

/// Bilinear upsampling of a face from `n` to `m` texels a side (texel centres aligned).
fn upsample(data: &[Vec3], n: u32, m: u32) -> Vec<Vec3> {
    if n == m {
        return data.to_vec();
    }
    let at = |x: i64, y: i64| {
        let c = |v: i64| v.clamp(0, n as i64 - 1);
        data[(c(y) * n as i64 + c(x)) as usize]
    };
    (0..m * m)
        .map(|i| {
            let p = (Vec2::new((i % m) as f32, (i / m) as f32) + 0.5) * (n as f32 / m as f32) - 0.5;
            let (p0, f) = (p.floor(), p - p.floor());
            let (x, y) = (p0.x as i64, p0.y as i64);
            (at(x, y) * (1.0 - f.x) + at(x + 1, y) * f.x) * (1.0 - f.y)
                + (at(x, y + 1) * (1.0 - f.x) + at(x + 1, y + 1) * f.x) * f.y
        })
        .collect()
}

/// The minification chain of a face: 2×2 averages weighted by the texels' solid angles
/// (§8.2.3); texels outside a disc weigh nothing unless all four are outside.
fn mip_chain(level0: Vec<Vec3>, size: u32, angles: &[Vec<f64>]) -> Vec<Vec<Vec3>> {
    // Sizes halve as the GPU's do (⌊n/2⌋); an odd row or column is read twice. `angles` is
    // `level_solid_angles` of the map's parameterisation and `size`.
    let mut mips = vec![level0];
    let mut n = size;
    while n > 1 {
        let prev = mips.last().unwrap();
        let omega = &angles[mips.len() - 1];
        let m = n / 2;
        let mut out = Vec::with_capacity((m * m) as usize);
        for y in 0..m {
            for x in 0..m {
                let (mut s, mut ws, mut plain) = (Vec3::ZERO, 0.0f64, Vec3::ZERO);
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (cx, cy) = ((2 * x + dx).min(n - 1), (2 * y + dy).min(n - 1));
                    let v = prev[(cy * n + cx) as usize];
                    let w = omega[(cy * n + cx) as usize];
                    s += v * w as f32;
                    ws += w;
                    plain += v * 0.25;
                }
                out.push(if ws > 0.0 { s / ws as f32 } else { plain });
            }
        }
        mips.push(out);
        n = m;
    }
    mips
}

/// Prefilter the lat-long image `img` (radiance × `scale`) into `settings.param`.
pub fn prefilter(img: &Image, scale: f32, settings: &EnvSettings) -> EnvMaps {
    let src = Source::new(img, scale);
    let faces = settings.param.faces();
    let size = settings.size.max(1);
    let angles = level_solid_angles(settings.param, size);
    let mut layers = vec![];
    for &lobe in &settings.lobes {
        for &r in &settings.roughness {
            let n = level_size(settings, lobe, r);
            let level = EnvSettings {
                samples: lobe_samples(src.texel_solid_angle(0), lobe, r, settings.samples),
                ..settings.clone()
            };
            for face in 0..faces {
                let data = level_face(&src, &level, lobe, r, face, n);
                layers.push(mip_chain(upsample(&data, n, size), size, &angles));
            }
        }
    }
    if settings.irradiance {
        // The clamped cosine is the Phong lobe of exponent 1; its map is smooth: 32² a face.
        let cosine = EnvSettings {
            samples: 2048,
            ..settings.clone()
        };
        let n = size.min(32);
        for face in 0..faces {
            let data = level_face(
                &src,
                &cosine,
                Lobe::Phong,
                roughness_of_exponent(1.0),
                face,
                n,
            );
            layers.push(mip_chain(upsample(&data, n, size), size, &angles));
        }
    }
    EnvMaps {
        param: settings.param,
        frame: settings.frame,
        size,
        roughness: settings.roughness.clone(),
        lobes: settings.lobes.clone(),
        irradiance: settings.irradiance,
        layers,
        texel_angle: (4.0 * PI / (faces as f32 * (size * size) as f32)).sqrt(),
    }
}

impl EnvMaps {
    /// The maps of a black environment in `settings`' layout (what dynamic maps sit beside
    /// when a scene has no environment).
    pub fn black(settings: &EnvSettings) -> EnvMaps {
        let size = settings.size.max(1);
        let faces = settings.param.faces();
        let count = settings.lobes.len() * settings.roughness.len() * faces
            + if settings.irradiance { faces } else { 0 };
        let mut chain = vec![];
        let mut n = size;
        loop {
            chain.push(vec![Vec3::ZERO; (n * n) as usize]);
            if n == 1 {
                break;
            }
            n /= 2;
        }
        EnvMaps {
            param: settings.param,
            frame: settings.frame,
            size,
            roughness: settings.roughness.clone(),
            lobes: settings.lobes.clone(),
            irradiance: settings.irradiance,
            layers: vec![chain; count],
            texel_angle: (4.0 * PI / (faces as f32 * (size * size) as f32)).sqrt(),
        }
    }

    pub fn faces(&self) -> usize {
        self.param.faces()
    }

    /// The levels around `roughness` and the weight of the upper one.
    pub fn bracket(&self, roughness: f32) -> (usize, usize, f32) {
        let r = &self.roughness;
        let last = r.len() - 1;
        if roughness <= r[0] {
            return (0, 0, 0.0);
        }
        if roughness >= r[last] {
            return (last, last, 0.0);
        }
        let hi = r.iter().position(|&x| x >= roughness).unwrap_or(last);
        let lo = hi - 1;
        let t = (roughness - r[lo]) / (r[hi] - r[lo]).max(1e-9);
        (lo, hi, t)
    }

    /// Bilinear read of mip 0 of one layer at map direction `m` (the shader's lookup).
    fn read(&self, layer_base: usize, m: Vec3) -> Vec3 {
        let (face, uv) = self.param.dir_to_uv(m.as_dvec3());
        let data = &self.layers[layer_base + face][0];
        let n = self.size as i64;
        let p = uv.as_vec2() * self.size as f32 - 0.5;
        let (p0, f) = (p.floor(), p - p.floor());
        let at = |x: i64, y: i64| data[(y.clamp(0, n - 1) * n + x.clamp(0, n - 1)) as usize];
        let (x, y) = (p0.x as i64, p0.y as i64);
        (at(x, y) * (1.0 - f.x) + at(x + 1, y) * f.x) * (1.0 - f.y)
            + (at(x, y + 1) * (1.0 - f.x) + at(x + 1, y + 1) * f.x) * f.y
    }

    /// The prefiltered radiance of lobe set `set` at `roughness` around world direction `d`.
    pub fn lookup(&self, set: usize, roughness: f32, d: Vec3) -> Vec3 {
        let m = self.frame * d.normalize();
        let levels = self.roughness.len();
        let (lo, hi, t) = self.bracket(roughness);
        let base = |l: usize| (set * levels + l) * self.faces();
        let a = self.read(base(lo), m);
        if t == 0.0 {
            return a;
        }
        a * (1.0 - t) + self.read(base(hi), m) * t
    }

    /// The irradiance map's E/π around world direction `n` (None without one).
    pub fn irradiance(&self, n: Vec3) -> Option<Vec3> {
        self.irradiance.then(|| {
            let base = self.layers.len() - self.faces();
            self.read(base, self.frame * n.normalize())
        })
    }

    /// Bytes of the maps as RGBA16F with their mip chains.
    pub fn bytes(&self) -> usize {
        self.layers
            .iter()
            .map(|l| l.iter().map(|m| m.len() * 8).sum::<usize>())
            .sum()
    }
}

/// How well a mirror map of `texels` texels in `param` holds `img`: the relative squared error
/// of its reads against the source (bilinear at full resolution) over `n` directions spread
/// evenly over the sphere (a mirror sphere's reflected directions, seen from any side, are
/// spread evenly over its image), in bands of the angle from the map's +z axis (the sphere
/// map's viewer): `[0°, 90°)`, `[90°, 150°)`, `[150°, 180°]`, and over all.
pub struct MirrorError {
    pub size: u32,
    pub bands: [f64; 3],
    pub all: f64,
    /// The error of the worst 1 % of directions (relative to the mean squared radiance).
    pub worst_percent: f64,
}

pub fn mirror_error(img: &Image, param: Param, texels: u32, n: u32) -> MirrorError {
    let settings = EnvSettings {
        param,
        frame: WORLD_TO_MAP,
        size: EnvSettings::equal_memory_size(param, texels),
        roughness: vec![0.0],
        lobes: vec![Lobe::Ggx],
        samples: 1,
        irradiance: false,
    };
    let maps = prefilter(img, 1.0, &settings);
    let src = Source::new(img, 1.0);
    let (mut err, mut norm) = ([0.0f64; 3], [0.0f64; 3]);
    let mut each = Vec::with_capacity(n as usize);
    for k in 0..n {
        let d = crate::sampling::uniform_sphere(hammersley(k, n));
        let want = src.bilinear(0, d);
        let e = (maps.lookup(0, 0.0, d) - want).length_squared() as f64;
        let z = (WORLD_TO_MAP * d).z;
        let band = if z > 0.0 {
            0
        } else if z > -(150f32.to_radians().cos().abs()) {
            1
        } else {
            2
        };
        err[band] += e;
        norm[band] += want.length_squared() as f64;
        each.push(e);
    }
    let mean_sq = norm.iter().sum::<f64>() / n as f64;
    each.sort_by(f64::total_cmp);
    let top = (n as usize / 100).max(1);
    let worst = each[each.len() - top..].iter().sum::<f64>() / top as f64;
    MirrorError {
        size: maps.size,
        bands: [0, 1, 2].map(|b| err[b] / norm[b].max(1e-30)),
        all: err.iter().sum::<f64>() / norm.iter().sum::<f64>().max(1e-30),
        worst_percent: worst / mean_sq.max(1e-30),
    }
}

/// The levels' roughness values for materials of roughness `used` (untextured factors) and,
/// when `ladder`, a ladder for textured roughness: 0 first, ascending, at most `max` values
/// (the closest pairs merged).
pub fn level_roughness(used: &[f32], ladder: bool, max: usize) -> Vec<f32> {
    let mut r: Vec<f32> = used
        .iter()
        .map(|x| x.clamp(0.0, 1.0))
        .filter(|x| x.is_finite())
        .collect();
    r.push(0.0);
    if ladder {
        r.extend((1..=10).map(|k| k as f32 / 10.0));
    }
    r.sort_by(f32::total_cmp);
    r.dedup_by(|a, b| (*a - *b).abs() < 1e-3);
    while r.len() > max.max(2) {
        // Merge the closest pair (never dropping 0).
        let i = (1..r.len() - 1)
            .min_by(|&i, &j| (r[i + 1] - r[i]).total_cmp(&(r[j + 1] - r[j])))
            .unwrap_or(1);
        r.remove(i + 1);
    }
    r
}

/// The split-sum table of the GPU's GGX model: `n × n` entries (A, B), column = ⟨n,v⟩ at texel
/// centres, row = roughness at texel centres, such that ∫ f·cos dl = f0·A + B for a constant
/// environment of radiance 1.
pub fn split_sum_lut(n: u32, samples: u32) -> Vec<[f32; 2]> {
    (0..n * n)
        .into_par_iter()
        .map(|i| {
            let nv = ((i % n) as f64 + 0.5) / n as f64;
            let r = ((i / n) as f64 + 0.5) / n as f64;
            let alpha = (r * r).max(1e-3);
            let ggx = crate::brdf::Distribution::Ggx { alpha };
            let v = DVec3::new((1.0 - nv * nv).sqrt(), 0.0, nv);
            let (mut a, mut b) = (0.0, 0.0);
            for k in 0..samples {
                let h = ggx.sample_h(hammersley(k, samples).as_dvec2());
                let vh = v.dot(h);
                let l = 2.0 * vh * h - v;
                if l.z <= 0.0 || vh <= 0.0 {
                    continue;
                }
                let g = 1.0 / (1.0 + ggx.lambda(nv) + ggx.lambda(l.z));
                let g_vis = g * vh / (h.z * nv);
                let fc = (1.0 - vh).powi(5);
                a += (1.0 - fc) * g_vis;
                b += fc * g_vis;
            }
            [(a / samples as f64) as f32, (b / samples as f64) as f32]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A lat-long test environment: a smooth sky gradient, a warm ground and a bright patch.
    fn test_env(w: u32) -> Image {
        let h = w / 2;
        let data = (0..w * h)
            .map(|i| {
                let uv = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5)
                    / Vec2::new(w as f32, h as f32);
                let d = Param::LatLong
                    .uv_to_dir(0, uv.as_dvec2())
                    .unwrap()
                    .as_vec3();
                let sky = Vec3::new(0.3, 0.5, 1.0) * (0.5 + 0.5 * d.y.max(0.0));
                let ground = Vec3::new(0.4, 0.3, 0.2);
                let patch = if d.dot(Vec3::new(0.6, 0.5, -0.6).normalize()) > 0.97 {
                    Vec3::splat(20.0)
                } else {
                    Vec3::ZERO
                };
                (if d.y > 0.0 { sky } else { ground }) + patch
            })
            .collect();
        Image {
            width: w,
            height: h,
            data,
        }
    }

    /// Brute force: the lobe average by many stratified samples of the full-resolution source.
    fn brute(img: &Image, lobe: Lobe, roughness: f32, d: Vec3) -> Vec3 {
        brute_n(img, lobe, roughness, d, 64)
    }

    fn brute_n(img: &Image, lobe: Lobe, roughness: f32, d: Vec3, n: u32) -> Vec3 {
        let src = Source::new(img, 1.0);
        let (t, b) = crate::sampling::orthonormal_basis(d);
        let (mut s, mut ws) = (Vec3::ZERO, 0.0);
        for i in 0..n {
            for j in 0..n {
                let u = DVec2::new((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let (l, w) = match lobe {
                    Lobe::Phong => (
                        crate::brdf::sample_cos_lobe(
                            d.as_dvec3(),
                            phong_exponent(roughness) as f64,
                            u,
                        )
                        .as_vec3(),
                        1.0,
                    ),
                    Lobe::Ggx => {
                        let g = crate::brdf::Distribution::Ggx {
                            alpha: (roughness * roughness).max(1e-3) as f64,
                        };
                        let hl = g.sample_h(u).as_vec3();
                        let h = t * hl.x + b * hl.y + d * hl.z;
                        let l = 2.0 * h.dot(d) * h - d;
                        (l, l.dot(d).max(0.0))
                    }
                };
                s += src.bilinear(0, l) * w;
                ws += w;
            }
        }
        s / ws
    }

    #[test]
    fn prefiltered_levels_match_brute_force_lobe_averages() {
        let img = test_env(256);
        for param in [Param::DualParaboloid, Param::Cube] {
            let s = EnvSettings {
                param,
                frame: WORLD_TO_MAP,
                size: EnvSettings::equal_memory_size(param, 2 * 128 * 128),
                roughness: vec![0.0, 0.3, 0.6],
                lobes: vec![Lobe::Ggx, Lobe::Phong],
                samples: 256,
                irradiance: false,
            };
            let maps = prefilter(&img, 1.0, &s);
            for (set, lobe) in s.lobes.iter().enumerate() {
                for &r in &s.roughness[1..] {
                    let (mut err, mut norm) = (0.0, 0.0);
                    for k in 0..64 {
                        let u = hammersley(k, 64);
                        let d = crate::sampling::uniform_sphere(u);
                        let got = maps.lookup(set, r, d);
                        let want = brute(&img, *lobe, r, d);
                        err += (got - want).length_squared();
                        norm += want.length_squared();
                    }
                    let rel = err / norm;
                    eprintln!("{param:?} {lobe:?} r {r}: relative error {rel:.2e}");
                    assert!(rel < 2e-3, "{param:?} {lobe:?} r {r}: relative error {rel}");
                }
            }
        }
    }

    #[test]
    fn the_mirror_level_reproduces_the_source() {
        let img = test_env(256);
        let src = Source::new(&img, 1.0);
        for param in [Param::DualParaboloid, Param::Cube, Param::SphereMap] {
            let s = EnvSettings {
                param,
                frame: WORLD_TO_MAP,
                size: EnvSettings::equal_memory_size(param, 2 * 256 * 256),
                roughness: vec![0.0],
                lobes: vec![Lobe::Ggx],
                samples: 1,
                irradiance: false,
            };
            let maps = prefilter(&img, 1.0, &s);
            let (mut err, mut norm) = (0.0, 0.0);
            for k in 0..500 {
                let d = crate::sampling::uniform_sphere(hammersley(k, 500));
                // The sphere map is only good facing the viewer (+z in its frame = world +y).
                if param == Param::SphereMap && (WORLD_TO_MAP * d).z < -0.5 {
                    continue;
                }
                let want = src.bilinear(0, d);
                err += (maps.lookup(0, 0.0, d) - want).length_squared();
                norm += want.length_squared();
            }
            eprintln!("mirror {param:?}: {:.2e}", err / norm);
            assert!(err / norm < 1e-3, "{param:?}: {}", err / norm);
        }
    }

    #[test]
    fn the_irradiance_map_matches_cosine_weighted_averages() {
        let img = test_env(256);
        let s = EnvSettings {
            param: Param::DualParaboloid,
            frame: WORLD_TO_MAP,
            size: 64,
            roughness: vec![0.0],
            lobes: vec![Lobe::Ggx],
            samples: 256,
            irradiance: true,
        };
        let maps = prefilter(&img, 1.0, &s);
        let (mut err, mut norm) = (0.0, 0.0);
        for k in 0..64 {
            let d = crate::sampling::uniform_sphere(hammersley(k, 64));
            let want = brute_n(&img, Lobe::Phong, roughness_of_exponent(1.0), d, 256);
            err += (maps.irradiance(d).unwrap() - want).length_squared();
            norm += want.length_squared();
        }
        eprintln!("irradiance map: relative error {:.2e}", err / norm);
        assert!(err / norm < 1e-3, "{}", err / norm);
    }

    #[test]
    fn the_split_sum_table_integrates_the_brdf() {
        // Furnace: with F0 = 1 the GGX lobe reflects A + B ≤ 1, near 1 for smooth surfaces.
        let lut = split_sum_lut(16, 1024);
        for (i, [a, b]) in lut.iter().enumerate() {
            assert!(*a >= 0.0 && *b >= 0.0 && a + b <= 1.001, "{i}: {a} {b}");
        }
        let smooth_normal = lut[15];
        assert!(
            smooth_normal[0] + smooth_normal[1] > 0.97,
            "{smooth_normal:?}"
        );
        // At normal incidence Schlick's Fc is tiny: B ≪ A.
        assert!(smooth_normal[1] < 0.01);
    }

    #[test]
    fn roughness_levels_start_at_zero_and_stay_within_the_cap() {
        let r = level_roughness(&[0.5, 0.5, 0.21, 0.2], false, 16);
        assert_eq!(r, vec![0.0, 0.2, 0.21, 0.5]);
        let r = level_roughness(&[0.35], true, 6);
        assert_eq!(r.len(), 6);
        assert_eq!(r[0], 0.0);
        assert!(r.windows(2).all(|w| w[0] < w[1]));
        assert!((roughness_of_exponent(phong_exponent(0.4)) - 0.4).abs() < 1e-4);
    }
}
