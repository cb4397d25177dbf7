//! How well a normal-map filter (`raster::NormalFilter`, Heidrich §9.1.1) lights a surface whose
//! bumps are smaller than a pixel: its error against a supersampled render of the finest normals
//! and its flicker under a sub-pixel camera move. Shared by `lightlab bench normal-filter` and
//! the GPU tests.
//!
//! Every render lights the scene's punctual lights only (no ambient, no shadows), so the figures
//! are the filters' and nothing else's.

use crate::GpuContext;
use crate::raster::{Ambient, NormalFilter, RasterError, RasterSettings, Renderer, ShadowMethod};
use glam::Mat4;
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse;
use lightlab_scene::{Camera, Scene};

/// One filter's figures.
#[derive(Clone, Copy, Debug)]
pub struct FilterFigures {
    pub filter: NormalFilter,
    /// relMSE against the reference.
    pub relmse: f64,
    /// Shimmer when the camera turns by `shift` pixels: [`change`] away from silhouettes
    /// ([`interior`]).
    pub flicker: f64,
    /// Milliseconds of the (not supersampled) frame: the fastest of three.
    pub frame_ms: f64,
}

/// What [`measure`] renders.
#[derive(Clone, Copy, Debug)]
pub struct FilterStudy {
    pub width: u32,
    pub height: u32,
    /// The reference's supersampling per axis (8: 64 samples per pixel).
    pub supersample: u32,
    /// The camera's turn between the two frames of the flicker figure, in pixels.
    pub shift: f32,
}

impl Default for FilterStudy {
    fn default() -> Self {
        FilterStudy {
            width: 128,
            height: 96,
            supersample: 8,
            shift: 0.25,
        }
    }
}

/// `camera` turned about its up axis by `pixels` pixels of a `height`-pixel
/// image (at the image centre).
fn turned(camera: &Camera, pixels: f32, height: u32) -> Camera {
    Camera {
        transform: camera.transform * Mat4::from_rotation_y(turn_angle(camera, pixels, height)),
        ..camera.clone()
    }
}

/// The turn (to the left) that moves the image centre by `pixels` pixels.
fn turn_angle(camera: &Camera, pixels: f32, height: u32) -> f32 {
    (pixels * 2.0 * (camera.yfov * 0.5).tan() / height as f32).atan()
}

/// The image of `filter` at `scale`× the study's size (box-downsampled back), camera turned
/// by `shift` pixels, and the fastest of three frames' milliseconds.
fn render(
    ctx: &GpuContext,
    (scene, camera): (&Scene, &Camera),
    study: &FilterStudy,
    filter: NormalFilter,
    scale: u32,
    shift: f32,
) -> Result<(Image, f64), RasterError> {
    let settings = RasterSettings {
        width: study.width * scale,
        height: study.height * scale,
        shadows: ShadowMethod::None,
        ambient: Ambient::None,
        background: false,
        normal_filter: filter,
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, scene, settings)?;
    r.set_camera(ctx, turned(camera, shift, study.height));
    let mut best = f64::MAX;
    let mut img = None;
    for _ in 0..if scale == 1 { 3 } else { 1 } {
        let t = std::time::Instant::now();
        r.render(ctx);
        img = Some(r.read_hdr(ctx)?);
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    Ok((img.expect("a frame").downsample(scale), best))
}

/// Shimmer: how much `b` (the camera turned left by `angle` from `a`, vertical field of view
/// `yfov`) differs from `a` moved as the turn moves it, over mean `a`, all channels, over the
/// pixels of `mask`. The turn moves a pixel at u from the image centre to f·tan(atan(u/f) + δ)
/// (f the focal length in pixels); `a` is read there with linear interpolation along the row.
/// What remains is what a still surface under a moving camera should not show.
pub fn change(a: &Image, b: &Image, mask: &[bool], yfov: f32, angle: f32) -> f64 {
    let (w, h) = (a.width as usize, a.height as usize);
    let f = 0.5 * h as f32 / (0.5 * yfov).tan();
    let (mut d, mut s) = (0.0f64, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let k = y * w + x;
            let u = x as f32 + 0.5 - 0.5 * w as f32;
            let src = f * ((u / f).atan() - angle).tan() + 0.5 * w as f32 - 0.5;
            let (x0, t) = (src.floor(), src - src.floor());
            if !mask[k] || x0 < 0.0 || x0 as usize + 1 >= w {
                continue;
            }
            let row = &a.data[y * w..(y + 1) * w];
            let moved = row[x0 as usize].lerp(row[x0 as usize + 1], t);
            d += (b.data[k] - moved).abs().element_sum() as f64;
            s += a.data[k].element_sum() as f64;
        }
    }
    d / s.max(1e-30)
}

/// The pixels away from silhouettes and shadow terminators: lit, as are their eight
/// neighbours, in each of `images`. There a sub-pixel camera turn moves nothing but shading.
pub fn interior(images: &[&Image]) -> Vec<bool> {
    let (w, h) = (images[0].width as i64, images[0].height as i64);
    let lit = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && x < w
            && y < h
            && images
                .iter()
                .all(|i| i.data[(y * w + x) as usize].max_element() > 0.0)
    };
    (0..w * h)
        .map(|k| {
            let (x, y) = (k % w, k / w);
            (-1..=1).all(|dy| (-1..=1).all(|dx| lit(x + dx, y + dy)))
        })
        .collect()
}

/// The figures of each of `filters` on `scene` seen from `camera`, and the reference's own change under the
/// camera turn (what a perfect filter would show: the image does move).
pub fn measure(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    study: &FilterStudy,
    filters: &[NormalFilter],
) -> Result<(Vec<FilterFigures>, f64), RasterError> {
    let ss = study.supersample;
    let scene = (scene, camera);
    let (reference, _) = render(ctx, scene, study, NormalFilter::None, ss, 0.0)?;
    let (moved, _) = render(ctx, scene, study, NormalFilter::None, ss, study.shift)?;
    let mask = interior(&[&reference, &moved]);
    let (yfov, angle) = (camera.yfov, turn_angle(camera, study.shift, study.height));
    let figures = filters
        .iter()
        .map(|&filter| {
            let (a, frame_ms) = render(ctx, scene, study, filter, 1, 0.0)?;
            let (b, _) = render(ctx, scene, study, filter, 1, study.shift)?;
            Ok(FilterFigures {
                filter,
                relmse: relmse(&a, &reference).unwrap_or(f64::NAN),
                flicker: change(&a, &b, &mask, yfov, angle),
                frame_ms,
            })
        })
        .collect::<Result<_, RasterError>>()?;
    Ok((figures, change(&reference, &moved, &mask, yfov, angle)))
}
