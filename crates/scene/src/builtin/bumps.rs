//! Bump maps made of Perlin noise, and the scenes that measure how a renderer filters them
//! (Heidrich §9.1.1; issue 21).
//!
//! The noise is Perlin's gradient noise written here rather than taken from a crate: a normal
//! map must tile, so the lattice's gradients repeat with the tile (`period`), which the noise
//! crates do not offer for gradient noise; the whole method is a hash, a fade curve and four dot
//! products.
//!
//! [`filter_scene`] is a bump-mapped plane or torus seen from far enough that a pixel of a
//! 128 × 96 image covers ten or more normal-map texels, with a sun whose glossy highlight lies
//! in view: the case where mip-mapped normals go wrong (too shiny, shimmering).

use super::geom::{parametric, torus};
use super::normal_map_from_height;
use crate::model::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

/// A unit gradient of lattice point (`x`, `y`) (taken modulo `period`), from an integer hash.
fn gradient(x: i32, y: i32, period: i32, seed: u32) -> Vec2 {
    let (x, y) = (x.rem_euclid(period) as u32, y.rem_euclid(period) as u32);
    // A 32-bit integer hash (lowbias32 by Chris Wellons) of the folded coordinates.
    let mut h = x
        .wrapping_mul(0x8da6_b343)
        .wrapping_add(y.wrapping_mul(0xd816_3841))
        .wrapping_add(seed.wrapping_mul(0xcb1a_b31f));
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    let a = h as f32 / u32::MAX as f32 * std::f32::consts::TAU;
    Vec2::new(a.cos(), a.sin())
}

/// Perlin's gradient noise at `p` (lattice units), periodic with `period` lattice cells in x
/// and y; values within about ±0.7.
pub fn perlin(p: Vec2, period: i32, seed: u32) -> f32 {
    let (x0, y0) = (p.x.floor(), p.y.floor());
    let f = p - Vec2::new(x0, y0);
    // Perlin's (2002) quintic fade: continuous second derivatives, so normals have no creases.
    let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (i, j) = (x0 as i32, y0 as i32);
    let corner = |dx: i32, dy: i32| {
        gradient(i + dx, j + dy, period, seed).dot(f - Vec2::new(dx as f32, dy as f32))
    };
    let (u, v) = (fade(f.x), fade(f.y));
    let bottom = corner(0, 0) + u * (corner(1, 0) - corner(0, 0));
    let top = corner(0, 1) + u * (corner(1, 1) - corner(0, 1));
    bottom + v * (top - bottom)
}

/// Height over the unit tile: `octaves` octaves of periodic Perlin noise starting at `base`
/// lattice cells per tile, each octave's amplitude halved as its frequency doubles so that every
/// octave adds the same slopes; `slope` scales them (RMS slope ≈ 0.7·slope·√octaves).
pub fn perlin_height(base: u32, octaves: u32, slope: f32, seed: u32) -> impl Fn(f32, f32) -> f32 {
    move |u, v| {
        (0..octaves)
            .map(|o| {
                let f = (base << o) as f32;
                slope / f * perlin(Vec2::new(u, v) * f, f as i32, seed + o)
            })
            .sum()
    }
}

/// An n² tangent-space normal map of [`perlin_height`] (linear; xyz·½ + ½), tiling.
pub fn perlin_normal_map(name: &str, n: u32, base: u32, octaves: u32, slope: f32) -> Texture {
    normal_map_from_height(name, n, perlin_height(base, octaves, slope, 7))
}

/// The shapes of [`filter_scene`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BumpShape {
    /// A 40 × 40 m ground plane under a camera 12 m up, looking down at 56°.
    Plane,
    /// A torus (radii 3 and 1.2 m) 16 m from the camera, on nothing.
    Torus,
}

lightlab_core::named_enum!(BumpShape, "bump shape", {
    Plane => "plane",
    Torus => "torus",
});

/// Normal-map texels per metre of [`filter_scene`]: 256² texels per 2.75 m tile.
pub const FILTER_TEXELS_PER_METRE: f32 = 256.0 / 2.75;

/// A bump-mapped `shape` of reflection model `brdf` at `roughness` (glossy, with a dielectric's
/// specular), its normal map two octaves of Perlin noise (32 and 64 cells per tile, RMS slope
/// ≈ 0.35) tiled every 2.75 m, lit by a sun placed so that the highlight lies in view. A pixel of a 128 × 96 image
/// covers 9 to 24 texels of the plane, about 11 of the torus; a pixel of the image 8 × 8
/// supersampled, at most 3 (so the supersampled reference resolves the bumps).
pub fn filter_scene(shape: BumpShape, brdf: BrdfModel, roughness: f32) -> Scene {
    let mut s = Scene {
        name: format!(
            "bumps-{}",
            if shape == BumpShape::Plane {
                "plane"
            } else {
                "torus"
            }
        ),
        ..Default::default()
    };
    let tex = s.textures.len();
    s.textures
        .push(perlin_normal_map("perlin_normal", 256, 32, 2, 0.35));
    let tile = 256.0 / FILTER_TEXELS_PER_METRE;
    let mat = s.add_material(Material {
        name: "bumpy_glossy".into(),
        base_color: Vec4::new(0.35, 0.3, 0.25, 1.0),
        roughness,
        specular: 1.0,
        brdf,
        normal_texture: Some(TextureRef::new(tex, 0)),
        ..Default::default()
    });
    // Each shape with its camera and a sun whose glossy highlight lies in view.
    let (mut mesh, transform, eye, target, sun) = match shape {
        BumpShape::Plane => {
            let size = 40.0;
            let m = parametric("plane", 8, 8, mat, Vec2::splat(size / tile), |u, v| {
                Vec3::new(size * (u - 0.5), 0.0, size * (v - 0.75))
            });
            let eye = Vec3::new(0.0, 12.0, 0.0);
            let sun = Vec3::new(0.2, -0.77, 0.64);
            (m, Mat4::IDENTITY, eye, Vec3::new(0.0, 0.0, -8.0), sun)
        }
        BumpShape::Torus => {
            // 2π·R / tile repeats around, 2π·r / tile across (whole numbers, so the map tiles).
            let (big, small) = (3.0, 1.2);
            let mut m = torus("torus", big, small, 128, 48, mat);
            let reps = Vec2::new(
                (std::f32::consts::TAU * big / tile).round(),
                (std::f32::consts::TAU * small / tile).round(),
            );
            for uv in &mut m.uv0 {
                *uv = *uv / Vec2::new(8.0, 2.0) * reps;
            }
            let at = Mat4::from_rotation_translation(Quat::from_rotation_x(0.9), Vec3::ZERO);
            let sun = Vec3::new(-0.3, -0.5, -1.0);
            (m, at, Vec3::new(0.0, 1.0, 16.0), Vec3::ZERO, sun)
        }
    };
    mesh.compute_tangents();
    s.add_mesh(mesh, transform);
    s.lights
        .push(super::sun(sun, 3.0, Vec3::new(1.0, 0.95, 0.9)));
    s.cameras.push(Camera::look_at(
        "bumps_camera",
        eye,
        target,
        Vec3::Y,
        40f32.to_radians(),
    ));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perlin_noise_tiles_and_vanishes_on_the_lattice() {
        for k in 0..50 {
            let p = Vec2::new(0.37 * k as f32, 1.91 * k as f32 % 8.0);
            let a = perlin(p, 8, 3);
            assert!((a - perlin(p + Vec2::new(8.0, 0.0), 8, 3)).abs() < 1e-5);
            assert!((a - perlin(p + Vec2::new(0.0, -16.0), 8, 3)).abs() < 1e-5);
            assert!(a.abs() < 1.0);
        }
        assert_eq!(perlin(Vec2::new(3.0, 5.0), 8, 1), 0.0);
    }

    #[test]
    fn perlin_height_has_the_slopes_it_promises() {
        let h = perlin_height(8, 3, 0.35, 7);
        let (n, e) = (200, 1e-3);
        let mut sum = 0.0;
        for k in 0..n * n {
            let (u, v) = ((k % n) as f32 / n as f32, (k / n) as f32 / n as f32);
            let du = (h(u + e, v) - h(u - e, v)) / (2.0 * e);
            sum += du * du;
        }
        let rms = (sum / (n * n) as f32).sqrt();
        // ≈ 0.7·0.35·√3 / √2 per axis ≈ 0.30 (a loose band: the noise is random).
        assert!((0.2..0.45).contains(&rms), "RMS slope along u {rms}");
    }
}
