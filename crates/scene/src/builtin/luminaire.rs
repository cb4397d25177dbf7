//! The built-in `luminaire` scene: a small closed room lit by measured lamps (Heidrich 1999
//! ch. 7's theme: real luminaires do not behave like a point light with a cone).
//!
//! Three goniometric lights, their distributions made here from formulas (vendors' files are
//! not free to copy) on webs like real files':
//! - a recessed **batwing downlight** over the table (type C, quadrant symmetry, 5° × 15°
//!   steps, no light above the horizon): its peak at 35° from nadir spreads light sideways;
//! - an asymmetric **wall washer** near the back wall (type C, 0–360° in 15° steps, γ to 180°
//!   with a little up-light), its C0 axis turned towards the wall;
//! - a **floodlight** on the left wall aimed across the room (type B, elliptical beam, wider
//!   in H than in V, −90…90° in 5° steps).
//!
//! The room (4 × 2.8 × 5 m, walls 0.7, floor 0.45) holds a table and a sphere that cast
//! shadows. Nothing emits: every light in the room comes from the lamps.

use super::geom::*;
use crate::model::*;
use crate::photometry::{Goniometric, PhotometryType};
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::sync::Arc;

/// The candela of each (horizontal, vertical) angle pair, horizontal plane by plane.
fn web(
    kind: PhotometryType,
    horizontal: Vec<f32>,
    vertical: Vec<f32>,
    f: impl Fn(f32, f32) -> f32,
) -> Goniometric {
    let candela = horizontal
        .iter()
        .flat_map(|&h| vertical.iter().map(move |&v| (h, v)))
        .map(|(h, v)| f(h.to_radians(), v.to_radians()).max(0.0))
        .collect();
    Goniometric {
        kind,
        vertical,
        horizontal,
        candela,
        tilt: vec![],
        opening: Vec3::new(0.15, 0.15, 0.0),
    }
}

fn steps(from: f32, to: f32, step: f32) -> Vec<f32> {
    let n = ((to - from) / step).round() as usize;
    (0..=n).map(|i| from + i as f32 * step).collect()
}

/// Recessed batwing downlight: quadrant symmetry, peak near γ = 35°, dark above 90°.
pub fn batwing() -> Goniometric {
    web(
        PhotometryType::C,
        steps(0.0, 90.0, 15.0),
        steps(0.0, 90.0, 5.0),
        |c, g| {
            let lobe = g.cos().max(0.0).powf(0.7) * (1.0 + 1.6 * (2.0 * g).sin().powi(2));
            900.0 * lobe * (1.0 + 0.25 * (2.0 * c).cos())
        },
    )
}

/// Asymmetric wall washer: throws towards C0 (the wall), a little up-light all round.
pub fn wall_washer() -> Goniometric {
    web(
        PhotometryType::C,
        steps(0.0, 345.0, 15.0),
        steps(0.0, 180.0, 10.0),
        |c, g| {
            let down = g.cos().max(0.0).powf(0.4) * (1.0 + 0.85 * c.cos()) * (1.0 + g.sin());
            500.0 * down + 25.0 * (-g.cos()).max(0.0)
        },
    )
}

/// Type B floodlight: an elliptical beam, σ 28° in H and 14° in V, on a 40 cd spill.
pub fn floodlight() -> Goniometric {
    web(
        PhotometryType::B,
        steps(-90.0, 90.0, 5.0),
        steps(-90.0, 90.0, 5.0),
        |h, v| {
            let (sh, sv) = (28f32.to_radians(), 14f32.to_radians());
            let beam = (-(h * h) / (2.0 * sh * sh) - (v * v) / (2.0 * sv * sv)).exp();
            (1500.0 * beam + 40.0) * h.cos().max(0.0)
        },
    )
}

/// Focal length of the reflector lamp's paraboloid (m).
pub const REFLECTOR_FOCUS: f32 = 0.04;
/// Radius of the reflector's opening (m).
pub const REFLECTOR_RADIUS: f32 = 0.11;

/// The canned lamp of Heidrich's Fig 7.4: a small emitting sphere at the focal point of a
/// mirror paraboloid, behind a grille that splits the opening into 3 × 3 cells. Local frame:
/// the lamp emits along +Z; the grille lies just inside the rim. Marked luminaire
/// "reflector", placed at `position` aimed along `aim`.
fn reflector_lamp(s: &mut Scene, position: Vec3, aim: Vec3) {
    let mirror = s.add_material(Material {
        name: "reflector_chrome".into(),
        base_color: Vec4::ONE,
        metallic: 1.0,
        roughness: 0.0,
        conductor: crate::model::Conductor::preset("chrome"),
        double_sided: true,
        ..Default::default()
    });
    let bulb = s.add_material(Material {
        name: "bulb".into(),
        base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive: Vec3::new(1.0, 0.85, 0.65),
        emissive_strength: 1200.0,
        double_sided: true,
        ..Material::diffuse("bulb", Vec3::ZERO)
    });
    let grille = s.add_material(Material {
        double_sided: true,
        ..Material::diffuse("grille", Vec3::splat(0.08))
    });
    let (f, r) = (REFLECTOR_FOCUS, REFLECTOR_RADIUS);
    let rim = r * r / (4.0 * f);
    let reflector = parametric("reflector", 48, 16, mirror, Vec2::ONE, |a, b| {
        let (phi, rad) = (a * std::f32::consts::TAU, b * r);
        Vec3::new(rad * phi.cos(), rad * phi.sin(), rad * rad / (4.0 * f))
    });
    let frame = Mat4::from_rotation_translation(
        glam::Quat::from_rotation_arc(Vec3::Z, aim.normalize()),
        position,
    );
    let mut put = |mesh: Mesh, local: Mat4| {
        let name = mesh.name.clone();
        let id = s.meshes.len();
        s.meshes.push(mesh);
        s.instances.push(Instance {
            name,
            mesh: id,
            transform: frame * local,
            nodes: vec!["reflector_lamp".into()],
            luminaire: Some("reflector".into()),
        });
    };
    put(reflector, Mat4::IDENTITY);
    put(
        sphere("bulb", 0.01, 24, 12, bulb),
        Mat4::from_translation(Vec3::new(0.0, 0.0, f)),
    );
    // Two bars each way across the opening: 3 × 3 cells.
    let (w, z) = (0.006, rim - 0.004);
    let mut bars = vec![];
    for k in [-1.0f32, 1.0] {
        let o = k * r / 3.0;
        bars.push(aabb_box(
            "bar",
            Vec3::new(o - w, -r, z - w),
            Vec3::new(o + w, r, z + w),
            grille,
        ));
        bars.push(aabb_box(
            "bar",
            Vec3::new(-r, o - w, z - w),
            Vec3::new(r, o + w, z + w),
            grille,
        ));
    }
    put(merge("grille", &bars), Mat4::IDENTITY);
}

/// A goniometric light at `position` shining along `direction`, its C0 axis towards `c0`
/// (made perpendicular), `scale` × the profile's candela.
fn lamp(name: &str, g: Goniometric, position: Vec3, direction: Vec3, c0: Vec3) -> Light {
    let d = direction.normalize();
    Light {
        name: name.into(),
        kind: LightKind::Goniometric {
            profile: Arc::new(g),
            c0: (c0 - d * c0.dot(d)).normalize(),
        },
        color: Vec3::ONE,
        // The web's candela as W/sr at 1/250: the brightest wall near radiance 1.
        intensity: 0.004,
        position,
        direction: d,
        range: None,
    }
}

pub fn luminaire() -> Scene {
    let mut s = Scene::default();
    let wall = s.add_material(Material::diffuse("wall", Vec3::new(0.72, 0.7, 0.66)));
    let floor = s.add_material(Material::diffuse("floor", Vec3::new(0.45, 0.4, 0.36)));
    let wood = s.add_material(Material {
        name: "wood".into(),
        base_color: Vec4::new(0.5, 0.3, 0.18, 1.0),
        roughness: 0.55,
        specular: 0.5,
        ..Default::default()
    });
    let paint = s.add_material(Material::diffuse("paint", Vec3::new(0.25, 0.4, 0.7)));
    let (x, h, z) = (2.0, 2.8, 2.5);
    let centre = Vec3::new(0.0, h * 0.5, 0.0);
    let c = |px: f32, py: f32, pz: f32| Vec3::new(px, py, pz);
    let faces = [
        (
            "floor",
            [c(-x, 0.0, -z), c(x, 0.0, -z), c(x, 0.0, z), c(-x, 0.0, z)],
            floor,
        ),
        (
            "ceiling",
            [c(-x, h, -z), c(x, h, -z), c(x, h, z), c(-x, h, z)],
            wall,
        ),
        (
            "back_wall",
            [c(-x, 0.0, -z), c(x, 0.0, -z), c(x, h, -z), c(-x, h, -z)],
            wall,
        ),
        (
            "front_wall",
            [c(-x, 0.0, z), c(x, 0.0, z), c(x, h, z), c(-x, h, z)],
            wall,
        ),
        (
            "left_wall",
            [c(-x, 0.0, -z), c(-x, 0.0, z), c(-x, h, z), c(-x, h, -z)],
            wall,
        ),
        (
            "right_wall",
            [c(x, 0.0, -z), c(x, 0.0, z), c(x, h, z), c(x, h, -z)],
            wall,
        ),
    ];
    for (name, p, m) in faces {
        s.add_mesh(quad_facing(name, p, centre, m), Mat4::IDENTITY);
    }
    // A table: top and four legs.
    let top = aabb_box("table_top", c(-0.7, 0.72, -0.45), c(0.7, 0.78, 0.45), wood);
    let legs: Vec<Mesh> = [(-0.62, -0.37), (0.62, -0.37), (-0.62, 0.37), (0.62, 0.37)]
        .iter()
        .map(|&(lx, lz)| {
            aabb_box(
                "leg",
                c(lx - 0.04, 0.0, lz - 0.04),
                c(lx + 0.04, 0.72, lz + 0.04),
                wood,
            )
        })
        .collect();
    let mut parts = vec![top];
    parts.extend(legs);
    s.add_mesh(
        merge("table", &parts),
        Mat4::from_translation(c(0.2, 0.0, -0.6)),
    );
    s.add_mesh(
        sphere("ball", 0.35, 40, 20, paint),
        Mat4::from_translation(c(-1.1, 0.35, 0.6)),
    );
    s.lights.push(lamp(
        "downlight",
        batwing(),
        c(0.2, h - 0.02, -0.6),
        -Vec3::Y,
        Vec3::X,
    ));
    s.lights.push(lamp(
        "wall_washer",
        wall_washer(),
        c(0.9, h - 0.05, -1.7),
        -Vec3::Y,
        -Vec3::Z,
    ));
    s.lights.push(lamp(
        "floodlight",
        floodlight(),
        c(-1.9, 2.2, 1.6),
        c(1.0, -0.45, -1.0),
        c(1.0, 0.0, 1.0),
    ));
    reflector_lamp(&mut s, c(1.5, 2.55, 1.9), c(-0.75, -1.0, -1.2));
    s.cameras.push(Camera::look_at(
        "luminaire_camera",
        c(1.2, 1.6, 2.35),
        c(-0.3, 0.9, -1.5),
        Vec3::Y,
        62f32.to_radians(),
    ));
    s
}
