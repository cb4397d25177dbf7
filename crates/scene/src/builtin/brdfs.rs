//! The built-in `brdfs` scene: Heidrich's reflection-model figures side by side (seed 004 ch. 5).
//!
//! - Back row, Fig 5.2: three copper tori on Torrance–Sparrow (Beckmann D, separable Smith G) at
//!   roughness 0.25, 0.4 and 0.6; the middle one tessellated 200 × 200 as the figure's.
//! - Middle row, Fig 5.3: brushed metal disks, tilted towards the camera; front row: spheres
//!   of the same materials. Columns, left to right: isotropic Ward; Banks with circular
//!   features (tangents round the disk's centre, along the sphere's parallels); Banks with
//!   radial features (tangents away from the centre, along the meridians); anisotropic Ward
//!   (KHR_materials_anisotropy strength 0.8) on the circular field, brushed metal as glTF
//!   writes it.
//!
//! - Back corners, Fig 9.1: a Blinn-Phong sphere and torus with Perlin-noise normal maps.
//!
//! The Fig 5.3 tangent fields are the meshes' own TANGENT (so the scene round-trips through
//! glTF), not MikkTSpace's. A point light and a low sun light the scene; a grey ground receives
//! shadows.

use super::geom::*;
use crate::model::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::f32::consts::TAU;

/// The Fig 5.3 tangent fields.
#[derive(Clone, Copy, PartialEq)]
enum Field {
    /// Whatever MikkTSpace gives (the isotropic column does not read it).
    Any,
    /// Round the disk's centre; the sphere's parallels.
    Circular,
    /// Away from the disk's centre; the sphere's meridians.
    Radial,
}

/// A disk of radius `r` in the XZ plane facing +Y (polar grid: `nu` around, `nv` out), with the
/// tangent field `field`.
fn disk(name: &str, r: f32, nu: u32, nv: u32, material: usize, field: Field) -> Mesh {
    let mut m = parametric(name, nu, nv, material, Vec2::splat(2.0 * r), |u, v| {
        let phi = u * TAU;
        Vec3::new(phi.cos(), 0.0, -phi.sin()) * (r * v)
    });
    m.normals = vec![Vec3::Y; m.positions.len()];
    // Planar UVs: the disk seen from above.
    m.uv0 = m
        .positions
        .iter()
        .map(|p| Vec2::new(p.x / (2.0 * r) + 0.5, 0.5 - p.z / (2.0 * r)))
        .collect();
    m.tangents = m
        .positions
        .iter()
        .map(|p| {
            let radial = Vec3::new(p.x, 0.0, p.z).normalize_or(Vec3::X);
            let t = match field {
                Field::Radial => radial,
                Field::Circular | Field::Any => Vec3::Y.cross(radial),
            };
            t.extend(1.0)
        })
        .collect();
    m
}

/// A UV sphere with the tangent field `field` (parallels or meridians).
fn sphere_with(name: &str, r: f32, material: usize, field: Field) -> Mesh {
    let mut m = sphere(name, r, 96, 48, material);
    m.tangents = m
        .normals
        .iter()
        .map(|n| {
            // Parallels: round the Y axis; meridians: from the north pole to the south.
            let around = Vec3::Y.cross(*n).normalize_or(Vec3::X);
            let t = match field {
                Field::Radial => n.cross(around),
                Field::Circular | Field::Any => around,
            };
            t.extend(1.0)
        })
        .collect();
    m
}

/// Fig 9.1 (bottom): a sphere and a torus with Perlin-noise normal maps, Blinn-Phong, at the
/// back corners. Three octaves of tiling noise, RMS slope ≈ 0.4, repeating three times round
/// the sphere and along the torus's 8 × 2 UV tiles; MikkTSpace tangents.
fn add_fig_9_1(s: &mut Scene) {
    let tex = s.textures.len();
    s.textures.push(super::bumps::perlin_normal_map(
        "perlin_bumps",
        256,
        4,
        3,
        0.45,
    ));
    let m = s.add_material(Material {
        name: "plastic_bumpy".into(),
        base_color: Vec4::new(0.55, 0.5, 0.42, 1.0),
        roughness: 0.3,
        specular: 1.0,
        brdf: BrdfModel::BlinnPhong,
        normal_texture: Some(TextureRef::new(tex, 0)),
        ..Default::default()
    });
    let r = 0.45;
    let mut ball = sphere("sphere_perlin", r, 96, 48, m);
    for uv in &mut ball.uv0 {
        // parametric's UVs are arc lengths (2πr round, πr pole to pole).
        *uv *= Vec2::new(3.0 / (TAU * r), 1.5 / (std::f32::consts::PI * r));
    }
    ball.compute_tangents();
    s.add_mesh(ball, Mat4::from_translation(Vec3::new(-3.0, r, -1.3)));
    let mut ring = torus("torus_perlin", 0.38, 0.16, 128, 64, m);
    ring.compute_tangents();
    s.add_mesh(
        ring,
        Mat4::from_rotation_translation(Quat::from_rotation_x(1.2), Vec3::new(3.0, 0.75, -1.3)),
    );
}

pub fn brdfs() -> Scene {
    let mut s = Scene::default();
    let ground = s.add_material(Material::diffuse("ground", Vec3::splat(0.45)));
    s.add_mesh(
        parametric("ground", 40, 40, ground, Vec2::splat(10.0), |u, v| {
            Vec3::new(-5.0 + 10.0 * u, 0.0, -4.0 + 8.0 * v)
        }),
        Mat4::IDENTITY,
    );
    // Fig 5.2: Torrance–Sparrow tori.
    for (i, roughness) in [0.25f32, 0.4, 0.6].into_iter().enumerate() {
        let m = s.add_material(Material {
            name: format!("copper_ts_{roughness}"),
            base_color: Vec4::new(0.95, 0.64, 0.54, 1.0),
            metallic: 0.6,
            roughness,
            brdf: BrdfModel::TorranceSparrow,
            ..Default::default()
        });
        let n = if i == 1 { 200 } else { 96 };
        s.add_mesh(
            torus(&format!("torus_ts_{roughness}"), 0.38, 0.16, n, n, m),
            Mat4::from_rotation_translation(
                Quat::from_rotation_x(1.2),
                Vec3::new(-1.6 + 1.6 * i as f32, 0.85, -2.0),
            ),
        );
    }
    // Fig 5.3: disks and spheres, one column per model and tangent field.
    let columns = [
        ("ward", BrdfModel::Ward, 0.0, Field::Any),
        ("banks_circular", BrdfModel::Banks, 0.0, Field::Circular),
        ("banks_radial", BrdfModel::Banks, 0.0, Field::Radial),
        ("ward_brushed", BrdfModel::Ward, 0.8, Field::Circular),
    ];
    for (i, (name, brdf, anisotropy, field)) in columns.into_iter().enumerate() {
        let m = s.add_material(Material {
            name: format!("aluminium_{name}"),
            base_color: Vec4::new(0.6, 0.62, 0.66, 1.0),
            metallic: 0.5,
            roughness: 0.35,
            brdf,
            anisotropy,
            ..Default::default()
        });
        let x = -2.1 + 1.4 * i as f32;
        s.add_mesh(
            disk(&format!("disk_{name}"), 0.42, 96, 24, m, field),
            Mat4::from_rotation_translation(Quat::from_rotation_x(0.75), Vec3::new(x, 0.45, -0.2)),
        );
        s.add_mesh(
            sphere_with(&format!("sphere_{name}"), 0.32, m, field),
            Mat4::from_translation(Vec3::new(x, 0.32, 1.1)),
        );
    }
    add_fig_9_1(&mut s);
    s.lights.push(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        color: Vec3::new(1.0, 0.96, 0.9),
        intensity: 25.0,
        position: Vec3::new(-1.8, 3.2, 2.8),
        direction: Vec3::NEG_Y,
        range: None,
    });
    s.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional {
            angular_diameter: 0.0,
        },
        color: Vec3::new(1.0, 0.97, 0.92),
        intensity: 0.8,
        position: Vec3::ZERO,
        direction: Vec3::new(-0.55, -0.5, -0.67).normalize(),
        range: None,
    });
    s.cameras.push(Camera::look_at(
        "brdfs_camera",
        Vec3::new(0.0, 2.3, 5.6),
        Vec3::new(0.0, 0.45, -0.6),
        Vec3::Y,
        45f32.to_radians(),
    ));
    s
}
