//! `prt-dynamic`: objects moving near each other over a ground, for hierarchical PRT
//! (McKenzie Chapter ch. 5; his tests A and B): a sphere sliding to and fro, a ball orbiting
//! it and a spinning ring orbiting the other way, over a ground of 6 × 6 tiles, under a sky
//! and a sun. 48 frames at 24 fps; frames 0, 12 and 24 are the measured ones.
//!
//! The ground is tiled so that each tile is a node of its own in a shadowing hierarchy, with
//! its own light sample points (one point per 6 m ground would give it one shadow value).
//! The tiles sit under the nodes `ground` / `block_I_J` (3 × 3 tiles each: `Instance::nodes`,
//! glTF group nodes when exported), so a tile's siblings are few.

use super::geom::*;
use super::{sky_env, sun};
use crate::model::*;
use crate::{Animation, Track};
use glam::{Mat4, Quat, Vec3};
use std::f32::consts::TAU;

const FPS: f32 = 24.0;
const FRAMES: u32 = 48;
/// Tiles per side of the 6 m ground, grouped in blocks of `BLOCK` × `BLOCK` tiles.
const TILES: usize = 12;
const BLOCK: usize = 3;

pub(super) fn prt_dynamic() -> Scene {
    let mut s = Scene::default();
    let ground = s.add_material(Material::diffuse("ground", Vec3::new(0.55, 0.53, 0.5)));
    let tile = 6.0 / TILES as f32;
    // Block by block, so that the instances come in the order of the glTF hierarchy.
    let blocks = TILES / BLOCK;
    for (br, bc) in (0..blocks).flat_map(|a| (0..blocks).map(move |b| (a, b))) {
        for (r, c) in
            (0..BLOCK).flat_map(|a| (0..BLOCK).map(move |b| (br * BLOCK + a, bc * BLOCK + b)))
        {
            let (x0, z0) = (-3.0 + c as f32 * tile, -3.0 + r as f32 * tile);
            let q = quad(
                &format!("tile_{r}_{c}"),
                [
                    Vec3::new(x0, 0.0, z0 + tile),
                    Vec3::new(x0 + tile, 0.0, z0 + tile),
                    Vec3::new(x0 + tile, 0.0, z0),
                    Vec3::new(x0, 0.0, z0),
                ],
                ground,
            );
            s.add_mesh(q, Mat4::IDENTITY);
            let block = format!("block_{br}_{bc}");
            s.instances.last_mut().expect("added").nodes = vec!["ground".into(), block];
        }
    }
    let warm = s.add_material(Material::diffuse("sphere", Vec3::new(0.75, 0.7, 0.62)));
    let red = s.add_material(Material::diffuse("ball", Vec3::new(0.7, 0.2, 0.15)));
    let blue = s.add_material(Material::diffuse("ring", Vec3::new(0.2, 0.35, 0.7)));
    let mut tracks = vec![];
    // The sphere slides along x by ±0.3 m over the loop.
    let sphere_i = s.instances.len();
    s.add_mesh(
        sphere("sphere", 0.55, 48, 24, warm),
        Mat4::from_translation(Vec3::new(0.0, 0.55, 0.0)),
    );
    tracks.push(keyed(sphere_i, |f| {
        (Vec3::new(0.3 * (f * TAU).sin(), 0.0, 0.0), Quat::IDENTITY)
    }));
    // The ball rolls round the sphere on the ground, radius 1.05 m, once per loop.
    let ball_i = s.instances.len();
    let ball_rest = Vec3::new(1.05, 0.28, 0.0);
    s.add_mesh(
        sphere("ball", 0.28, 32, 16, red),
        Mat4::from_translation(ball_rest),
    );
    // M(t) = the orbit's rotation about the world's y axis: the ball rolls round.
    tracks.push(keyed(ball_i, |f| {
        (Vec3::ZERO, Quat::from_rotation_y(f * TAU))
    }));
    // The ring orbits the other way at 1.5 m, 0.5 m up, tilted and spinning about its axis.
    let ring_i = s.instances.len();
    let ring_rest = Vec3::new(-1.5, 0.5, 0.0);
    let tilt = Quat::from_rotation_z(1.1);
    s.add_mesh(
        torus("ring", 0.32, 0.11, 48, 16, blue),
        Mat4::from_rotation_translation(tilt, ring_rest),
    );
    tracks.push(keyed(ring_i, |f| {
        let orbit = Quat::from_rotation_y(-f * TAU);
        let spin = tilt * Quat::from_rotation_y(2.0 * f * TAU) * tilt.inverse();
        // M(t)·rest: rotate the rest pose about its centre by the spin, then carry the centre
        // round the orbit.
        let q = orbit * spin;
        (orbit * ring_rest - q * ring_rest, q)
    }));
    s.animation = Some(Animation {
        fps: FPS,
        frames: FRAMES,
        tracks,
    });
    s.lights.push(sun(
        Vec3::new(-0.55, -0.75, -0.35),
        3.0,
        Vec3::new(1.0, 0.95, 0.85),
    ));
    s.environment = Some(sky_env(
        128,
        Vec3::new(0.25, 0.4, 0.75),
        Vec3::new(0.6, 0.65, 0.7),
        Vec3::new(0.2, 0.18, 0.15),
        &[],
    ));
    s.cameras.push(Camera::look_at(
        "prt_dynamic_camera",
        Vec3::new(0.3, 2.5, 3.3),
        Vec3::new(0.0, 0.35, 0.0),
        Vec3::Y,
        45f32.to_radians(),
    ));
    s
}

/// A track keyed at every frame of the loop (and its end) from `motion(fraction of the loop)`.
fn keyed(instance: usize, motion: impl Fn(f32) -> (Vec3, Quat)) -> Track {
    let mut t = Track {
        instance,
        times: vec![],
        translations: vec![],
        rotations: vec![],
    };
    for k in 0..=FRAMES {
        let (tr, q) = motion(k as f32 / FRAMES as f32);
        t.times.push(k as f32 / FPS);
        t.translations.push(tr);
        t.rotations.push(q.normalize());
    }
    t
}
