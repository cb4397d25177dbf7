//! The built-in `mirror` scene: a large planar wall mirror beside objects close to it, the case
//! where environment maps fail (Heidrich 1999 ch. 10, "environment maps fail for large
//! reflectors close to other geometry") and planar mirrors are drawn from the mirrored eye.
//!
//! A 6 × 6 m room with walls 3 m high and no ceiling (the sky comes in from above), a
//! 2.4 × 1.5 m silver mirror on the back wall in a dark frame, a red ball, a blue box and a
//! yellow pillar in front of it, lit by a point light and the sky. The camera sees the mirror
//! obliquely, so the mirror shows the objects' far sides, the side walls and the wall behind
//! the camera.

use super::geom::*;
use crate::model::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

/// The mirror's centre (on the back wall, 2 cm in front of it) and half extents (x, y).
pub const MIRROR_CENTRE: Vec3 = Vec3::new(0.3, 1.35, -1.98);
pub const MIRROR_HALF: Vec2 = Vec2::new(1.2, 0.75);

pub fn mirror() -> Scene {
    let mut s = Scene::default();
    let floor = s.add_material(Material::diffuse("floor", Vec3::new(0.55, 0.5, 0.45)));
    let wall = s.add_material(Material::diffuse("wall", Vec3::splat(0.7)));
    let green_wall = s.add_material(Material::diffuse("wall_green", Vec3::new(0.3, 0.55, 0.3)));
    let blue_wall = s.add_material(Material::diffuse("wall_blue", Vec3::new(0.35, 0.4, 0.6)));
    let frame = s.add_material(Material::diffuse("frame", Vec3::new(0.12, 0.08, 0.05)));
    let silver = s.add_material(Material {
        name: "mirror_silver".into(),
        base_color: Vec4::new(0.95, 0.93, 0.88, 1.0),
        metallic: 1.0,
        roughness: 0.0,
        ..Default::default()
    });
    let red = s.add_material(Material::diffuse("ball_red", Vec3::new(0.75, 0.12, 0.1)));
    let blue = s.add_material(Material {
        name: "box_blue".into(),
        base_color: Vec4::new(0.1, 0.2, 0.7, 1.0),
        roughness: 0.4,
        ..Default::default()
    });
    let yellow = s.add_material(Material::diffuse(
        "pillar_yellow",
        Vec3::new(0.8, 0.7, 0.15),
    ));
    mirror_room(&mut s, [floor, wall, green_wall, blue_wall]);
    mirror_glass(&mut s, silver, frame);
    mirror_objects(&mut s, red, blue, yellow);
    s.lights.push(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        color: Vec3::new(1.0, 0.95, 0.85),
        intensity: 18.0,
        position: Vec3::new(1.2, 2.7, 0.8),
        direction: Vec3::NEG_Y,
        range: None,
    });
    s.environment = Some(super::sky_env(
        128,
        Vec3::new(0.2, 0.3, 0.55),
        Vec3::new(0.45, 0.5, 0.6),
        Vec3::new(0.2, 0.18, 0.15),
        &[],
    ));
    s.cameras.push(Camera::look_at(
        "mirror_camera",
        Vec3::new(2.3, 1.6, 3.4),
        Vec3::new(-0.2, 1.0, -1.6),
        Vec3::Y,
        55f32.to_radians(),
    ));
    s
}

/// Floor and walls as grids (per-vertex methods hold their shading); a grid faces ∂v × ∂u.
/// Materials: floor, back and right wall, left wall, front wall.
fn mirror_room(s: &mut Scene, [floor, wall, green_wall, blue_wall]: [usize; 4]) {
    s.add_mesh(
        parametric("floor", 24, 24, floor, Vec2::new(6.0, 6.0), |u, v| {
            Vec3::new(-3.0 + 6.0 * u, 0.0, -2.0 + 6.0 * v)
        }),
        Mat4::IDENTITY,
    );
    s.add_mesh(
        parametric("wall_back", 12, 24, wall, Vec2::new(3.0, 6.0), |u, v| {
            Vec3::new(-3.0 + 6.0 * v, 3.0 * u, -2.0)
        }),
        Mat4::IDENTITY,
    );
    s.add_mesh(
        parametric(
            "wall_left",
            24,
            12,
            green_wall,
            Vec2::new(6.0, 3.0),
            |u, v| Vec3::new(-3.0, 3.0 * v, -2.0 + 6.0 * u),
        ),
        Mat4::IDENTITY,
    );
    s.add_mesh(
        parametric("wall_right", 12, 24, wall, Vec2::new(3.0, 6.0), |u, v| {
            Vec3::new(3.0, 3.0 * u, -2.0 + 6.0 * v)
        }),
        Mat4::IDENTITY,
    );
    s.add_mesh(
        parametric(
            "wall_front",
            24,
            12,
            blue_wall,
            Vec2::new(6.0, 3.0),
            |u, v| Vec3::new(-3.0 + 6.0 * u, 3.0 * v, 4.0),
        ),
        Mat4::IDENTITY,
    );
}

/// The silver glass on the back wall and its dark frame.
fn mirror_glass(s: &mut Scene, silver: usize, frame: usize) {
    let (c, h) = (MIRROR_CENTRE, MIRROR_HALF);
    s.add_mesh(
        quad(
            "mirror",
            [
                c + Vec3::new(-h.x, -h.y, 0.0),
                c + Vec3::new(h.x, -h.y, 0.0),
                c + Vec3::new(h.x, h.y, 0.0),
                c + Vec3::new(-h.x, h.y, 0.0),
            ],
            silver,
        ),
        Mat4::IDENTITY,
    );
    // The frame: four bars 8 cm wide, 4 cm deep, around the glass.
    let (w, z0, z1) = (0.08, -2.0, -1.96);
    for (name, lo, hi) in [
        (
            "frame_bottom",
            Vec2::new(-h.x - w, -h.y - w),
            Vec2::new(h.x + w, -h.y),
        ),
        (
            "frame_top",
            Vec2::new(-h.x - w, h.y),
            Vec2::new(h.x + w, h.y + w),
        ),
        (
            "frame_left",
            Vec2::new(-h.x - w, -h.y),
            Vec2::new(-h.x, h.y),
        ),
        ("frame_right", Vec2::new(h.x, -h.y), Vec2::new(h.x + w, h.y)),
    ] {
        s.add_mesh(
            aabb_box(
                name,
                Vec3::new(c.x + lo.x, c.y + lo.y, z0),
                Vec3::new(c.x + hi.x, c.y + hi.y, z1),
                frame,
            ),
            Mat4::IDENTITY,
        );
    }
}

/// The ball, the box and the pillar in front of the mirror.
fn mirror_objects(s: &mut Scene, red: usize, blue: usize, yellow: usize) {
    s.add_mesh(
        sphere("ball", 0.35, 48, 24, red),
        Mat4::from_translation(Vec3::new(-0.7, 0.35, -0.9)),
    );
    s.add_mesh(
        aabb_box("box", Vec3::splat(-0.3), Vec3::splat(0.3), blue),
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(0.9, 0.3, -0.6)),
    );
    s.add_mesh(
        aabb_box(
            "pillar",
            Vec3::new(-0.15, 0.0, -0.15),
            Vec3::new(0.15, 1.6, 0.15),
            yellow,
        ),
        Mat4::from_translation(Vec3::new(-1.9, 0.0, 0.3)),
    );
}
