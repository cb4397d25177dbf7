//! The built-in `glass` scene: a solid glass torus floating in a patterned studio environment,
//! nothing else near it — the setting of Heidrich 1999 §10.2's geometry light field, where
//! what the glass shows is the environment seen through its refractions.
//!
//! The environment has structure at every scale the refraction can bend: coloured vertical
//! stripes every 20° of azimuth above the horizon, two bright soft boxes, and a checkered floor
//! below. [`studio`] makes it for any stripe colours, so that tests can swap it.

use super::geom::*;
use crate::model::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use lightlab_core::image::Image;

/// A studio environment (equirectangular, `width` × `width/2`): stripes of colours `a` and `b`
/// above the horizon over a gradient, soft boxes, a checkered floor of `floor` and its half.
pub fn studio(width: u32, a: Vec3, b: Vec3, floor: Vec3) -> Environment {
    let height = width / 2;
    let image = Image::from_fn(width, height, |x, y| {
        let uv = Vec2::new(
            (x as f32 + 0.5) / width as f32,
            (y as f32 + 0.5) / height as f32,
        );
        let d = Environment::uv_to_dir(uv);
        let azimuth = d.x.atan2(-d.z).to_degrees() + 180.0;
        if d.y >= 0.0 {
            let stripe = if (azimuth / 20.0) as i32 % 2 == 0 {
                a
            } else {
                b
            };
            let mut c = stripe * (0.35 + 0.65 * (1.0 - d.y));
            for (dir, power) in [
                (Vec3::new(0.6, 0.7, 0.4), 6.0),
                (Vec3::new(-0.7, 0.4, -0.6), 3.0),
            ] {
                c += Vec3::splat(power) * d.dot(dir.normalize()).max(0.0).powf(40.0);
            }
            c
        } else {
            // The floor's checker, in the ground plane one unit below the viewer.
            let p = Vec2::new(d.x, d.z) / (-d.y).max(1e-3);
            let check = ((p.x * 2.0).floor() as i32 + (p.y * 2.0).floor() as i32) & 1 == 0;
            if check { floor } else { floor * 0.5 }
        }
    });
    Environment {
        image,
        intensity: 1.0,
    }
}

pub fn glass() -> Scene {
    let mut s = Scene::default();
    let glass = s.add_material(Material {
        name: "glass_clear".into(),
        base_color: Vec4::ONE,
        roughness: 0.0,
        specular_transmission: 1.0,
        ior: 1.5,
        thickness: 0.4,
        ..Default::default()
    });
    s.add_mesh(
        torus("torus", 0.45, 0.2, 128, 48, glass),
        Mat4::from_rotation_translation(Quat::from_rotation_x(1.1), Vec3::new(0.0, 0.0, 0.0)),
    );
    s.environment = Some(studio(
        512,
        Vec3::new(0.9, 0.45, 0.15),
        Vec3::new(0.15, 0.35, 0.8),
        Vec3::new(0.6, 0.6, 0.55),
    ));
    s.cameras.push(Camera::look_at(
        "glass_camera",
        Vec3::new(0.4, 0.5, 2.2),
        Vec3::ZERO,
        Vec3::Y,
        40f32.to_radians(),
    ));
    s
}
