//! Goniometric lights (measured lamps, IES LM-63 / EULUMDAT) on the GPU: each light's
//! candela distribution resampled once onto a regular grid in its own frame, one layer of an
//! `R32Float` texture array per light, read with a bilinear lookup by `profile_candela` in
//! `common.wgsl` (kind 4).
//!
//! The grid: texel (i, j) holds the candela towards C = i·360°/[`WIDTH`], γ = j·180°/([`HEIGHT`]
//! − 1) (type C angles of the light's frame: γ from nadir, the light's direction; C from its
//! C0 axis), so the poles and the C0 plane fall on texels and C wraps. Types A and B are
//! resampled through the same frame ([`Goniometric::intensity`] folds any symmetry). At half a
//! degree a step the resampling error is far below the path tracer's noise for the profiles
//! of real lamps, whose files step by 1°–5° (measured in `tests/photometric.rs`).

use lightlab_scene::photometry::Goniometric;
use std::f32::consts::PI;

/// Texels over C (0 … 360°, wrapping).
pub const WIDTH: u32 = 720;
/// Texels over γ (0 … 180°, both ends included).
pub const HEIGHT: u32 = 361;

/// The local (file frame) direction of texel (i, j).
fn texel_direction(i: u32, j: u32) -> glam::Vec3 {
    let c = i as f32 * 2.0 * PI / WIDTH as f32;
    let g = j as f32 * PI / (HEIGHT - 1) as f32;
    glam::Vec3::new(g.sin() * c.cos(), g.sin() * c.sin(), -g.cos())
}

/// `g` resampled onto the grid, row by row (γ), C along each row.
pub fn table(g: &Goniometric) -> Vec<f32> {
    (0..HEIGHT)
        .flat_map(|j| (0..WIDTH).map(move |i| g.intensity(texel_direction(i, j))))
        .collect()
}

/// The shader's bilinear lookup of [`table`] towards local direction `d` (for tests).
pub fn lookup(table: &[f32], d: glam::Vec3) -> f32 {
    let d = d.normalize_or(glam::Vec3::NEG_Z);
    let gamma = (-d.z).clamp(-1.0, 1.0).acos();
    let c = d.y.atan2(d.x).rem_euclid(2.0 * PI);
    let fu = c / (2.0 * PI) * WIDTH as f32;
    let fv = gamma / PI * (HEIGHT - 1) as f32;
    let u0 = (fu.floor() as u32).min(WIDTH - 1);
    let u1 = (u0 + 1) % WIDTH;
    let tu = (fu - u0 as f32).clamp(0.0, 1.0);
    let v0 = (fv.floor() as u32).min(HEIGHT - 2);
    let tv = (fv - v0 as f32).clamp(0.0, 1.0);
    let at = |u: u32, v: u32| table[(v * WIDTH + u) as usize];
    let a = at(u0, v0) * (1.0 - tu) + at(u1, v0) * tu;
    let b = at(u0, v0 + 1) * (1.0 - tu) + at(u1, v0 + 1) * tu;
    a * (1.0 - tv) + b * tv
}

/// The texture array of `profiles`, one layer each (black layers when there are none, and at
/// least two layers: GL makes a one-layer texture a plain 2D one).
pub fn profile_texture(ctx: &crate::GpuContext, profiles: &[&Goniometric]) -> wgpu::TextureView {
    let layers = (profiles.len() as u32).max(2);
    let tex = crate::resources::texture(
        &ctx.device,
        "light profiles",
        WIDTH,
        HEIGHT,
        layers,
        wgpu::TextureFormat::R32Float,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    let black = vec![0.0f32; (WIDTH * HEIGHT) as usize];
    for layer in 0..layers {
        let data = profiles.get(layer as usize).map(|g| table(g));
        let data = data.as_deref().unwrap_or(&black);
        crate::resources::write_layer(
            ctx,
            &tex,
            layer,
            bytemuck::cast_slice(data),
            WIDTH * 4,
            [WIDTH, HEIGHT],
        );
    }
    crate::resources::array_view(&tex)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lightlab_scene::photometry::PhotometryType;

    #[test]
    fn the_lookup_reproduces_a_smooth_profile() {
        // cos² γ · (1 + 0.5 cos C) on a 5° web: the table's bilinear lookup within 0.5 %.
        let vertical: Vec<f32> = (0..=36).map(|i| i as f32 * 5.0).collect();
        let horizontal: Vec<f32> = (0..72).map(|i| i as f32 * 5.0).collect();
        let mut candela = vec![];
        for h in &horizontal {
            for v in &vertical {
                let (hr, vr) = (h.to_radians(), v.to_radians());
                candela.push(100.0 * vr.cos().max(0.0).powi(2) * (1.0 + 0.5 * hr.cos()) + 1.0);
            }
        }
        let g = Goniometric {
            kind: PhotometryType::C,
            vertical,
            horizontal,
            candela,
            tilt: vec![],
            opening: glam::Vec3::ZERO,
        };
        let t = table(&g);
        let mut worst = 0.0f32;
        for k in 0..500 {
            let a = k as f32 * 2.399;
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / 500.0;
            let r = (1.0 - z * z).sqrt();
            let d = glam::Vec3::new(r * a.cos(), r * a.sin(), z);
            let (want, got) = (g.intensity(d), lookup(&t, d));
            worst = worst.max((got - want).abs() / want.max(1.0));
        }
        assert!(worst < 5e-3, "worst relative error {worst}");
    }
}
