//! # lightlab-bake
//!
//! The CPU bakers. Light-maps: UVs ([`layout`]), texels as surface samples ([`texels`]), two
//! solvers with the same inputs and outputs — radiosity after Fuchs's CaLight ([`radiosity`])
//! and path-traced gathering ([`gather`]) — and border/seam repair ([`repair`], [`seams`]).
//! [`bake_lightmaps`] runs the whole pipeline on a scene snapshot, reports staged progress
//! through a callback that can cancel, and returns typed errors.
//!
//! A light-map stores E/π (incident irradiance over π) in linear RGB: the diffuse radiance of a
//! surface is albedo × light-map, plus its emission.
#![forbid(unsafe_code)]

pub mod cashl;
pub mod detail;
pub mod folder;
pub mod gather;
pub mod hprt;
pub mod layout;
pub mod occlusion_groups;
pub mod output;
pub mod prt;
pub mod radiosity;
pub mod repair;
pub mod seams;
pub mod sh_bake;
pub mod sh_compress;
pub mod sh_cpca;
pub mod sh_folder;
pub mod sh_light;
pub mod shard;
pub mod texels;
pub mod view;

use glam::Vec3;
use lightlab_core::image::Image;
use lightlab_scene::Scene;
use lightlab_trace::{Accel, LightUse, PathTracer};
use serde::{Deserialize, Serialize};
use std::time::Instant;

pub use gather::GatherSettings;
pub use layout::{InstanceRect, Layout, LayoutSettings};
pub use radiosity::{RadiositySettings, RadiosityStats};

/// Progress callback: (stage, done, total; total 0 when unknown). Returning false cancels.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) -> bool + Sync);

/// A progress callback that never cancels.
pub fn no_progress(_: &str, _: usize, _: usize) -> bool {
    true
}

#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error("invalid bake settings: {0}")]
    Settings(String),
    #[error("scene cannot be baked: {0}")]
    Scene(String),
    #[error("light-map UV generation failed: {0}")]
    Unwrap(String),
    #[error("bake cancelled")]
    Cancelled,
    #[error("{0}")]
    Io(String),
}

/// The light-map solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Progressive-refinement radiosity after CaLight.
    Radiosity,
    /// Path-traced gathering per texel.
    Path,
}

lightlab_core::named_enum!(Method, "light-map method", {
    Radiosity => "radiosity",
    Path => "path",
}, aliases { "path-traced" => Path });

/// How a punctual light enters the bake, so baked and dynamic light are never counted twice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum LightMode {
    /// Direct and bounced light are in the light-map.
    #[default]
    Baked,
    /// Only its bounced light is baked; its direct light is rendered in real time.
    IndirectOnly,
    /// Not in the light-map at all.
    Realtime,
}

lightlab_core::named_enum!(LightMode, "light mode", {
    Baked => "baked",
    IndirectOnly => "indirect-only",
    Realtime => "realtime",
}, aliases { "indirect" => IndirectOnly, "dynamic" => Realtime });

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakeSettings {
    pub method: Method,
    pub layout: LayoutSettings,
    pub gather: GatherSettings,
    pub radiosity: RadiositySettings,
    /// One per scene light (missing entries are `Baked`).
    pub light_modes: Vec<LightMode>,
    /// Back-face probe rays per texel, and the fraction of back-face hits that invalidates it.
    pub validity_rays: u32,
    pub max_backface_fraction: f32,
    /// Stitch UV seams and coplanar neighbours.
    pub stitch_seams: bool,
    pub seed: u64,
}

impl Default for BakeSettings {
    fn default() -> Self {
        BakeSettings {
            method: Method::Path,
            layout: LayoutSettings::default(),
            gather: GatherSettings::default(),
            radiosity: RadiositySettings::default(),
            light_modes: vec![],
            validity_rays: 32,
            max_backface_fraction: 0.25,
            stitch_seams: true,
            seed: 0,
        }
    }
}

/// What a bake measured.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BakeStats {
    pub pages: usize,
    pub page_texels: u64,
    /// Texels with a surface sample, and those of them that were valid.
    pub texels: usize,
    pub valid_texels: usize,
    pub charts: u32,
    pub utilization: f32,
    /// Rays cast during the bake (validity probe and solver), counted by the BVH.
    pub rays: u64,
    pub seconds_layout: f64,
    pub seconds_solve: f64,
    pub seconds_total: f64,
    pub radiosity: Option<RadiosityStats>,
    /// Seam sample pairs stitched, and the largest relative difference left across them.
    pub seam_pairs: usize,
    pub seam_max_difference: f32,
}

/// Baked light-maps with the scene they belong to (its meshes carry the light-map UVs).
#[derive(Clone, Debug)]
pub struct Lightmaps {
    pub scene: Scene,
    pub layout: Layout,
    /// One HDR image per page (E/π, linear RGB).
    pub pages: Vec<Image>,
    /// Directional light-maps: per page, the luminance ratios of the three basis directions
    /// (see `gather`), when baked with `gather.directional`.
    pub directional: Option<Vec<Image>>,
    pub settings: BakeSettings,
    pub stats: BakeStats,
}

/// Bake light-maps for a scene.
pub fn bake_lightmaps(
    scene: &Scene,
    settings: &BakeSettings,
    progress: Progress,
) -> Result<Lightmaps, BakeError> {
    let mut prep = prepare(scene, settings, progress)?;
    let t1 = Instant::now();
    let valid = prep.valid.clone();
    let (values, directional) = solve(&mut prep, settings, &valid, progress)?;
    prep.stats.seconds_solve = t1.elapsed().as_secs_f64();
    prep.stats.rays = prep.accel.rays_cast();
    Ok(finish(prep, settings, values, directional, progress))
}

/// A bake up to its solver: the scene with light-map UVs, its layout, the texels and their
/// validity, and the figures so far ([`bake_lightmaps`] = prepare, solve, finish; a shard
/// solves part of the texels, a merge only prepares and finishes, see [`shard`]).
pub(crate) struct Prepared {
    pub scene: Scene,
    pub layout: Layout,
    pub texels: texels::Texels,
    pub valid: Vec<Vec<bool>>,
    pub accel: Accel,
    pub stats: BakeStats,
    pub t0: Instant,
}

pub(crate) fn prepare(
    scene: &Scene,
    settings: &BakeSettings,
    progress: Progress,
) -> Result<Prepared, BakeError> {
    let t0 = Instant::now();
    if settings.light_modes.len() > scene.lights.len() {
        return Err(BakeError::Settings(format!(
            "{} light modes given for {} lights",
            settings.light_modes.len(),
            scene.lights.len()
        )));
    }
    if settings.gather.directional && settings.method != Method::Path {
        return Err(BakeError::Settings(
            "directional light-maps are gathered by path tracing: use the path method".into(),
        ));
    }
    let mut scene = scene.clone();
    progress("layout", 0, 1);
    let layout = layout::unwrap_scene(&mut scene, &settings.layout)?;
    if !progress("layout", 1, 1) {
        return Err(BakeError::Cancelled);
    }
    let texels = texels::rasterize(&scene, &layout);
    let accel = Accel::new(&scene);
    let valid = texels::probe_validity(
        &texels,
        &scene,
        &accel,
        settings.validity_rays.max(1),
        settings.max_backface_fraction,
        settings.seed,
    );
    let stats = BakeStats {
        pages: layout.pages.len(),
        page_texels: layout.texel_count(),
        texels: texels.count(),
        valid_texels: valid.iter().flatten().filter(|&&b| b).count(),
        charts: layout.charts,
        utilization: layout.utilization,
        seconds_layout: t0.elapsed().as_secs_f64(),
        ..Default::default()
    };
    Ok(Prepared {
        scene,
        layout,
        texels,
        valid,
        accel,
        stats,
        t0,
    })
}

/// The solver over the texels `valid` marks (all of a bake's, or a shard's part of them):
/// per page and texel E/π, and the directional ratios when asked for.
pub(crate) fn solve(
    prep: &mut Prepared,
    settings: &BakeSettings,
    valid: &[Vec<bool>],
    progress: Progress,
) -> Result<gather::Gathered, BakeError> {
    let scene = &prep.scene;
    match settings.method {
        Method::Path => {
            let mut tracer = PathTracer::new(scene, &prep.accel);
            tracer.light_use = (0..scene.lights.len())
                .map(
                    |i| match settings.light_modes.get(i).copied().unwrap_or_default() {
                        LightMode::Baked => LightUse::ALL,
                        LightMode::IndirectOnly => LightUse {
                            direct: false,
                            indirect: true,
                        },
                        LightMode::Realtime => LightUse {
                            direct: false,
                            indirect: false,
                        },
                    },
                )
                .collect();
            gather::gather(
                &tracer,
                &prep.texels,
                valid,
                &settings.gather,
                settings.seed,
                progress,
            )
        }
        Method::Radiosity => {
            let (v, rs) = radiosity::solve(
                scene,
                &prep.accel,
                &prep.texels,
                valid,
                &settings.light_modes,
                &settings.radiosity,
                settings.seed,
                progress,
            )?;
            prep.stats.radiosity = Some(rs);
            Ok((v, None))
        }
    }
}

/// Repair (fill invalid and empty texels, stitch seams) and package the solved values.
pub(crate) fn finish(
    prep: Prepared,
    settings: &BakeSettings,
    values: Vec<Vec<Vec3>>,
    directional: Option<Vec<Vec<Vec3>>>,
    progress: Progress,
) -> Lightmaps {
    let Prepared {
        scene,
        layout,
        texels,
        valid,
        mut stats,
        t0,
        ..
    } = prep;
    let mut pages: Vec<Image> = vec![];
    let mut filled_masks = vec![];
    let mut dir_pages: Vec<Image> = vec![];
    let mut directional = directional.map(|d| d.into_iter());
    for ((page, mut v), valid) in texels.pages.iter().zip(values).zip(valid) {
        let mut ok: Vec<bool> = page
            .samples
            .iter()
            .zip(&valid)
            .map(|(s, &ok)| s.is_some() && ok)
            .collect();
        let inside = ok.clone();
        if let Some(mut d) = directional.as_mut().and_then(|it| it.next()) {
            let mut ok_d = ok.clone();
            repair::dilate(&mut d, &mut ok_d, page.width, page.height, 64);
            // Texels nothing reached stay neutral (ratio 1).
            for (x, o) in d.iter_mut().zip(&ok_d) {
                if !o {
                    *x = Vec3::ONE;
                }
            }
            dir_pages.push(Image {
                width: page.width,
                height: page.height,
                data: d,
            });
        }
        repair::dilate(&mut v, &mut ok, page.width, page.height, 64);
        filled_masks.push(inside);
        pages.push(Image {
            width: page.width,
            height: page.height,
            data: v,
        });
    }
    if settings.stitch_seams {
        let r = seams::stitch(&scene, &layout, &mut pages, &filled_masks);
        stats.seam_pairs = r.pairs;
        stats.seam_max_difference = r.max_difference;
    }
    stats.seconds_total = t0.elapsed().as_secs_f64();
    progress("done", 1, 1);
    Lightmaps {
        scene,
        layout,
        pages,
        directional: (!dir_pages.is_empty()).then_some(dir_pages),
        settings: settings.clone(),
        stats,
    }
}

/// Bilinear sample of a page at page coordinates `uv` ∈ [0, 1]² (texel centres at (i+½)/w),
/// clamped at the edges: how the GPU's linear sampler reads a light-map.
pub fn sample_bilinear(page: &Image, uv: glam::Vec2) -> Vec3 {
    let x = uv.x * page.width as f32 - 0.5;
    let y = uv.y * page.height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |xi: f32, yi: f32| {
        let xi = (xi as i64).clamp(0, page.width as i64 - 1) as u32;
        let yi = (yi as i64).clamp(0, page.height as i64 - 1) as u32;
        page.get(xi, yi)
    };
    let a = at(x0, y0).lerp(at(x0 + 1.0, y0), fx);
    let b = at(x0, y0 + 1.0).lerp(at(x0 + 1.0, y0 + 1.0), fx);
    a.lerp(b, fy)
}

/// Bicubic (cubic B-spline) sample, as Bevy's `bicubic_sampling` and the GPU technique do:
/// smoother than bilinear, reaching two texels out.
pub fn sample_bicubic(page: &Image, uv: glam::Vec2) -> Vec3 {
    let x = uv.x * page.width as f32 - 0.5;
    let y = uv.y * page.height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let wts = |t: f32| {
        let t2 = t * t;
        let t3 = t2 * t;
        [
            (1.0 - t).powi(3) / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ]
    };
    let (wx, wy) = (wts(fx), wts(fy));
    let mut sum = Vec3::ZERO;
    for (j, wyj) in wy.iter().enumerate() {
        for (i, wxi) in wx.iter().enumerate() {
            let xi = (x0 as i64 - 1 + i as i64).clamp(0, page.width as i64 - 1) as u32;
            let yi = (y0 as i64 - 1 + j as i64).clamp(0, page.height as i64 - 1) as u32;
            sum += page.get(xi, yi) * (wxi * wyj);
        }
    }
    sum
}
