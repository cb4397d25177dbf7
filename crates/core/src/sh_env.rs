//! Projection of environment maps onto spherical harmonics, and irradiance maps from them (the
//! user job of Ramamoorthi–Hanrahan's `prefilter`).
//!
//! Formats:
//! - **lat-long (equirectangular)**, lightlab's environment convention: for a direction d,
//!   u = 0.5 + atan2(d.x, −d.z)/2π, v = acos(d.y)/π (v = 0 is +Y). Texel (x, y) covers
//!   Δφ = 2π/W and θ ∈ [πy/H, π(y+1)/H]: solid angle (2π/W)(cos θ₀ − cos θ₁), exact.
//! - **angular (light probe)**, as in Ramamoorthi–Hanrahan's `prefilter.c`: u, v ∈ [−1, 1]
//!   (v up), r = √(u²+v²) ≤ 1, θ = π·r, φ = atan2(v, u),
//!   d = (sin θ cos φ, sin θ sin φ, cos θ); solid angle (2π/W)(2π/H)·sinθ/θ.
//!   Coefficients of an angular probe are in the probe's own frame, as in their paper.
//!
//! - **cube strip**: six square faces side by side (+X, −X, +Y, −Y, +Z, −Z), exact texel solid
//!   angles (`param::Param::Cube`).
//!
//! Texel values are taken at texel centres, weighted by the texel's solid angle.

use crate::image::Image;
use crate::param::Param;
use crate::sh::{eval_f64, irradiance_from_radiance, num_coeffs};
use glam::{DVec2, DVec3, Vec2, Vec3};
use std::f64::consts::PI;

/// Layout of an environment image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvFormat {
    LatLong,
    Angular,
    /// Six square cube faces side by side (+X, −X, +Y, −Y, +Z, −Z; OpenGL/Vulkan face
    /// orientation, see `param::Param::Cube`).
    CubeStrip,
}

/// An image that cannot be an environment map of the layout it was given.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EnvError {
    #[error("a {width}×{height} image is not a cube strip (six square faces side by side: 6:1)")]
    NotCubeStrip { width: u32, height: u32 },
    #[error(
        "a {width}×{height} image is not an angular map (square, at least {MIN_ANGULAR}×{MIN_ANGULAR}: \
         smaller discs have no usable solid angles)"
    )]
    NotAngular { width: u32, height: u32 },
    #[error("an environment map needs at least one texel")]
    Empty,
}

/// The smallest angular map whose centre-sample solid angles sum to within 5 % of 4π.
pub const MIN_ANGULAR: u32 = 8;

impl EnvFormat {
    /// Guess from the aspect ratio: 2:1 is lat-long, 1:1 angular (from 8×8), 6:1 a cube strip.
    pub fn guess(width: u32, height: u32) -> Option<EnvFormat> {
        let f = if width == 2 * height {
            EnvFormat::LatLong
        } else if width == height {
            EnvFormat::Angular
        } else if width == 6 * height {
            EnvFormat::CubeStrip
        } else {
            return None;
        };
        f.check(width, height).ok().map(|()| f)
    }

    /// Whether a `width`×`height` image can be a map of this layout.
    pub fn check(self, width: u32, height: u32) -> Result<(), EnvError> {
        if width == 0 || height == 0 {
            return Err(EnvError::Empty);
        }
        match self {
            EnvFormat::LatLong => Ok(()),
            EnvFormat::CubeStrip if width == 6 * height => Ok(()),
            EnvFormat::CubeStrip => Err(EnvError::NotCubeStrip { width, height }),
            EnvFormat::Angular if width == height && width >= MIN_ANGULAR => Ok(()),
            EnvFormat::Angular => Err(EnvError::NotAngular { width, height }),
        }
    }
}

/// Lat-long: direction → uv in [0,1]² (`param::Param::LatLong`'s mapping, computed in f32 for
/// the renderers: the path tracer converts every environment sample and every escaped ray, and
/// libm's f64 `atan2` and `acos` were 5 % of a path-traced `prt`). Agrees with `Param` within
/// 1e-6 away from the poles (tested).
pub fn latlong_dir_to_uv(d: Vec3) -> Vec2 {
    let u = (0.5 + d.x.atan2(-d.z) * (0.5 / std::f32::consts::PI)).rem_euclid(1.0);
    Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI)
}

/// Lat-long: uv → unit direction (`param::Param::LatLong`'s mapping in f32; see
/// [`latlong_dir_to_uv`]).
pub fn latlong_uv_to_dir(uv: Vec2) -> Vec3 {
    latlong_uv_to_dir_sin(uv).0
}

/// [`latlong_uv_to_dir`] and the sine of the polar angle, sin θ, which converts a density
/// over uv into one over solid angle (the environment's importance sampling needs both).
pub fn latlong_uv_to_dir_sin(uv: Vec2) -> (Vec3, f32) {
    let (sp, cp) = ((uv.x - 0.5) * std::f32::consts::TAU).sin_cos();
    let (st, ct) = (uv.y * std::f32::consts::PI).sin_cos();
    (Vec3::new(st * sp, ct, -st * cp), st)
}

/// Visit every texel of an environment image with its direction and solid angle. Directions
/// come from `param::Param`, the one owner of each mapping. An image that does not fit the
/// layout (`EnvFormat::check`) has no texels to visit.
pub fn for_each_texel(img: &Image, format: EnvFormat, mut f: impl FnMut(DVec3, f64, Vec3)) {
    if format.check(img.width, img.height).is_err() {
        return;
    }
    let (w, h) = (img.width as usize, img.height as usize);
    let centre = |x: usize, y: usize, w: usize, h: usize| {
        DVec2::new((x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64)
    };
    match format {
        EnvFormat::LatLong => {
            for y in 0..h {
                // The same for the whole row: computed once.
                let omega = Param::LatLong.texel_solid_angle(0, y as u32, w as u32, h as u32);
                for x in 0..w {
                    let d = Param::LatLong
                        .uv_to_dir(0, centre(x, y, w, h))
                        .expect("total");
                    f(d, omega, img.data[y * w + x]);
                }
            }
        }
        EnvFormat::CubeStrip => {
            let n = h as u32;
            for face in 0..6usize {
                for y in 0..n {
                    for x in 0..n {
                        let uv = centre(x as usize, y as usize, n as usize, n as usize);
                        let d = Param::Cube
                            .uv_to_dir(face, uv)
                            .expect("cube maps are total");
                        let omega = Param::Cube.texel_solid_angle(x, y, n, n);
                        f(
                            d,
                            omega,
                            img.data[y as usize * w + face * n as usize + x as usize],
                        );
                    }
                }
            }
        }
        EnvFormat::Angular => {
            for y in 0..h {
                for x in 0..w {
                    // Outside the disc there is no direction.
                    let Some(d) = Param::Angular.uv_to_dir(0, centre(x, y, w, h)) else {
                        continue;
                    };
                    // Ramamoorthi–Hanrahan's centre-sample solid angle (prefilter.c):
                    // (2π/W)(2π/H)·sinθ/θ. (`Param::Angular::texel_solid_angle` is exact but
                    // integrates every texel, ≈ 10× slower.)
                    let theta = d.z.clamp(-1.0, 1.0).acos();
                    let sinc = if theta > 0.0 {
                        theta.sin() / theta
                    } else {
                        1.0
                    };
                    let omega = (2.0 * PI / w as f64) * (2.0 * PI / h as f64) * sinc;
                    f(d, omega, img.data[y * w + x]);
                }
            }
        }
    }
}

/// RGB SH coefficients of an environment image.
pub fn project_env(img: &Image, format: EnvFormat, bands: usize) -> Vec<DVec3> {
    let mut c = vec![DVec3::ZERO; num_coeffs(bands)];
    let mut y = vec![0.0; num_coeffs(bands)];
    for_each_texel(img, format, |d, omega, v| {
        eval_f64(bands, d.x, d.y, d.z, &mut y);
        let v = v.as_dvec3() * omega;
        for (ci, yi) in c.iter_mut().zip(&y) {
            *ci += v * *yi;
        }
    });
    c
}

/// A lat-long irradiance map (irradiance E, W/m²) of `width × width/2` from radiance
/// coefficients: convolution with the clamped cosine, then evaluation per texel.
pub fn irradiance_map(radiance: &[DVec3], width: u32) -> Image {
    let e = irradiance_from_radiance(radiance);
    let bands = crate::sh::bands_of(e.len());
    let height = (width / 2).max(1);
    let mut y = vec![0.0; num_coeffs(bands)];
    Image::from_fn(width, height, |x, yy| {
        let uv = DVec2::new(
            (x as f64 + 0.5) / width as f64,
            (yy as f64 + 0.5) / height as f64,
        );
        let d = Param::LatLong
            .uv_to_dir(0, uv)
            .expect("lat-long maps are total");
        eval_f64(bands, d.x, d.y, d.z, &mut y);
        let v: DVec3 = e.iter().zip(&y).map(|(c, b)| *c * *b).sum();
        v.as_vec3()
    })
}

/// A sun found in a lat-long environment: the compact bright region around its brightest
/// texel, as a directional light, and the environment without it.
#[derive(Clone, Debug)]
pub struct EnvSun {
    /// Unit direction towards the sun (world).
    pub direction: Vec3,
    /// Irradiance it gives a surface facing it: Σ L·Ω over its texels (RGB, before the
    /// environment's intensity).
    pub irradiance: Vec3,
    /// Angular diameter of the disc of the same solid angle (radians).
    pub angular_diameter: f32,
    /// The environment with the sun's texels replaced by the sky around them.
    pub remainder: Image,
    /// The fraction of the environment's total power (luminance) the sun carries.
    pub share: f32,
}

/// Extract a sun from a lat-long environment (for renderers that shadow a directional light but
/// not their ambient term). The brightest texel must exceed `min_ratio` × the sphere's mean
/// luminance; the sun is then the texels within 20° of it brighter than twice the sky just
/// outside (the mean of a 20–30° ring), less that sky, which stays behind in the remainder.
/// None when no texel is that bright (an overcast sky) or the sun carries under 1 % of the
/// environment's power.
pub fn extract_sun(img: &Image, min_ratio: f32) -> Option<EnvSun> {
    let (w, h) = (img.width as usize, img.height as usize);
    if EnvFormat::LatLong.check(img.width, img.height).is_err() {
        return None;
    }
    let lum = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let mut texels = Vec::with_capacity(w * h);
    for_each_texel(img, EnvFormat::LatLong, |d, omega, c| {
        texels.push((d.as_vec3(), omega as f32, c))
    });
    let total: f64 = texels.iter().map(|t| (lum(t.2) * t.1) as f64).sum();
    let mean = (total / (4.0 * std::f64::consts::PI)) as f32;
    let (peak_i, peak) = texels
        .iter()
        .enumerate()
        .map(|(i, t)| (i, lum(t.2)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    if !(peak > min_ratio * mean && mean > 0.0) {
        return None;
    }
    let centre = texels[peak_i].0;
    let (cos_in, cos_ring) = (20f32.to_radians().cos(), 30f32.to_radians().cos());
    let (mut ring, mut ring_w) = (Vec3::ZERO, 0.0f32);
    for t in &texels {
        let c = t.0.dot(centre);
        if c < cos_in && c >= cos_ring {
            ring += t.2 * t.1;
            ring_w += t.1;
        }
    }
    let background = if ring_w > 0.0 {
        ring / ring_w
    } else {
        Vec3::ZERO
    };
    let threshold = 2.0 * lum(background);
    let is_sun = |t: &(Vec3, f32, Vec3)| t.0.dot(centre) >= cos_in && lum(t.2) > threshold;
    let (mut irradiance, mut dir, mut omega) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
    let mut remainder = img.clone();
    for (i, t) in texels.iter().enumerate() {
        if is_sun(t) {
            // What the sun adds over the sky behind it.
            let excess = (t.2 - background).max(Vec3::ZERO);
            irradiance += excess * t.1;
            dir += t.0 * lum(excess) * t.1;
            omega += t.1;
            remainder.data[i] = t.2 - excess;
        }
    }
    let share = (lum(irradiance) as f64 / total) as f32;
    if share < 0.01 || dir == Vec3::ZERO {
        return None;
    }
    // Ω = 2π(1 − cos r) for a disc of angular radius r.
    let r = (1.0 - omega / std::f32::consts::TAU)
        .clamp(-1.0, 1.0)
        .acos();
    Some(EnvSun {
        direction: dir.normalize(),
        irradiance,
        angular_diameter: 2.0 * r,
        remainder,
        share,
    })
}

#[cfg(test)]
mod small_map_tests {
    use super::*;

    #[test]
    fn the_f32_lat_long_mapping_agrees_with_param() {
        let mut rng = crate::sampling::Rng::new(3, 0);
        for _ in 0..10_000 {
            let uv = rng.next_vec2();
            let want = Param::LatLong.uv_to_dir(0, uv.as_dvec2()).unwrap();
            let d = latlong_uv_to_dir(uv);
            assert!((d.as_dvec3() - want).length() < 1e-6, "{uv} {d} {want}");
            let (_, back) = Param::LatLong.dir_to_uv(d.as_dvec3());
            let got = latlong_dir_to_uv(d).as_dvec2();
            assert!((got.y - back.y).abs() < 1e-6, "{got} {back}");
            // u wraps around at 0 and 1, and is ill-conditioned at the poles.
            let du = (got.x - back.x).abs();
            assert!(
                du.min(1.0 - du) < 1e-6 || want.y.abs() > 0.999,
                "{got} {back}"
            );
        }
    }

    /// A sky of constant radiance 0.5 with a disc of radiance 500 and radius 2° around a
    /// known direction: the sun comes out at that direction with the disc's excess
    /// irradiance, and the remainder is the plain sky.
    #[test]
    fn a_sun_disc_is_extracted_and_the_sky_stays() {
        let sun_dir = Vec3::new(0.4, 0.7, -0.3).normalize();
        let r = 2f32.to_radians();
        let (w, h) = (1024u32, 512u32);
        let mut img = Image::new(w, h);
        let mut disc = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let d = latlong_uv_to_dir(uv);
                let inside = d.dot(sun_dir) >= r.cos();
                img.data[(y * w + x) as usize] = Vec3::splat(if inside { 500.0 } else { 0.5 });
                if inside {
                    disc += Param::LatLong.texel_solid_angle(0, y, w, h);
                }
            }
        }
        let sun = extract_sun(&img, 20.0).expect("a sun");
        assert!(
            sun.direction.dot(sun_dir) > 0.2f32.to_radians().cos(),
            "{}",
            sun.direction
        );
        let expect = 499.5 * disc as f32;
        assert!(
            (sun.irradiance.x - expect).abs() < 0.01 * expect,
            "{} vs {expect}",
            sun.irradiance
        );
        assert!(
            (sun.angular_diameter - 2.0 * r).abs() < 0.1 * r,
            "{}",
            sun.angular_diameter
        );
        assert!(sun.remainder.data.iter().all(|c| (c.x - 0.5).abs() < 1e-4));
        // An overcast sky has no sun.
        let flat = Image {
            width: w,
            height: h,
            data: vec![Vec3::splat(0.5); (w * h) as usize],
        };
        assert!(extract_sun(&flat, 20.0).is_none());
    }

    /// Every (size, format) either is refused by `check` or projects a constant map to its
    /// exact L00 = √(4π) within 5 %: no panic on small or mis-shaped images.
    #[test]
    fn small_and_misshaped_maps_are_refused_or_project_correctly() {
        let sizes = [
            (1, 1),
            (2, 1),
            (3, 1),
            (6, 1),
            (4, 4),
            (8, 8),
            (12, 2),
            (7, 5),
            (64, 32),
            (96, 16),
        ];
        let formats = [EnvFormat::LatLong, EnvFormat::Angular, EnvFormat::CubeStrip];
        let mut accepted = 0;
        for (w, h) in sizes {
            let img = Image::from_fn(w, h, |_, _| Vec3::ONE);
            for f in formats {
                let ok = f.check(w, h);
                let c = std::panic::catch_unwind(|| project_env(&img, f, 2));
                let Ok(()) = ok else {
                    continue;
                };
                accepted += 1;
                let c = c.unwrap_or_else(|_| panic!("{w}×{h} {f:?} panicked"));
                let want = (4.0 * PI).sqrt();
                let got = c[0].x;
                assert!(
                    (got / want - 1.0).abs() < 0.05,
                    "{w}×{h} {f:?}: L00 {got} vs {want}"
                );
            }
        }
        assert!(accepted >= 5, "{accepted}");
        assert!(EnvFormat::CubeStrip.check(12, 3).is_err());
        assert!(EnvFormat::Angular.check(1, 1).is_err());
        assert_eq!(EnvFormat::guess(1, 1), None);
    }
}
