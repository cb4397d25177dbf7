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
use crate::Texture;
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

/// The slide projector's optics (Heidrich Fig 7.3), in its local frame (+Z forward, origin at
/// the lens's centre).
pub mod projector {
    /// Radius of the lens's clear aperture (m).
    pub const APERTURE: f32 = 0.022;
    /// Radius of curvature of both lens faces (m): a symmetric biconvex lens.
    pub const CURVATURE: f32 = 0.12;
    /// Thickness of the lens at its rim (m).
    pub const EDGE: f32 = 0.002;
    /// Index of refraction of the lens.
    pub const IOR: f32 = 1.5;
    /// Half the slide's picture (a 36 × 24 mm frame).
    pub const SLIDE_HALF: [f32; 2] = [0.018, 0.012];
    /// Half the width of the square housing.
    pub const HOUSING_HALF: f32 = 0.024;

    /// The lens's sag: how far each face bulges beyond its rim.
    pub fn sag() -> f32 {
        CURVATURE - (CURVATURE * CURVATURE - APERTURE * APERTURE).sqrt()
    }

    /// The lens's thickness on its axis.
    pub fn thickness() -> f32 {
        EDGE + 2.0 * sag()
    }

    /// Where the slide sits (its z, negative) for a sharp image at `focus` metres in front of
    /// the lens's centre: the thick lens's paraxial equations (lensmaker's power with the
    /// thickness term; principal planes δ = f (n−1) d / (n R) inside each vertex; Gaussian
    /// 1/s + 1/s' = 1/f between them).
    pub fn slide_z(focus: f32) -> f32 {
        let (n, r, d) = (IOR, CURVATURE, thickness());
        let power = (n - 1.0) * (2.0 / r - (n - 1.0) * d / (n * r * r));
        let f = 1.0 / power;
        let delta = f * (n - 1.0) * d / (n * r);
        let s_image = focus - (d * 0.5 - delta);
        let s_object = 1.0 / (power - 1.0 / s_image);
        -(d * 0.5 - delta) - s_object
    }
}

/// The slide's picture (linear RGB, 96 × 64): sky, sun and hills, in colours that show on a
/// wall. Row 0 is the picture's top.
fn slide_picture() -> Texture {
    let (w, h) = (96u32, 64u32);
    let mut data = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let (x, y) = ((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
            let hill = 0.62 + 0.07 * (x * 9.0).sin() + 0.03 * (x * 23.0 + 1.0).sin();
            let sun = Vec2::new((x - 0.72) * 1.5, y - 0.3).length() < 0.14;
            let c = if y > hill {
                Vec3::new(0.12, 0.55, 0.1) * (1.15 - 0.5 * (y - hill))
            } else if sun {
                Vec3::new(1.0, 0.8, 0.15)
            } else {
                Vec3::new(0.2, 0.42, 0.9).lerp(Vec3::new(0.75, 0.85, 0.95), y / hill)
            };
            data.push(c.extend(1.0));
        }
    }
    Texture {
        name: "slide".into(),
        width: w,
        height: h,
        texels: crate::Texels::Rgba32F(data),
        srgb: true,
    }
}

/// A face of a sphere of radius `r` capping the lens: z = `z0` − `side`·(r − √(r² − ρ²))
/// for ρ ≤ the aperture, facing `side` (±1) along Z, with the sphere's normals.
fn lens_face(side: f32, z0: f32, material: usize) -> Mesh {
    use projector::*;
    let centre_z = z0 - side * CURVATURE;
    let mut m = parametric("lens", 64, 12, material, Vec2::ONE, |a, b| {
        let (phi, rho) = (side * a * std::f32::consts::TAU, b * APERTURE);
        let z = z0 - side * (CURVATURE - (CURVATURE * CURVATURE - rho * rho).sqrt());
        Vec3::new(rho * phi.cos(), rho * phi.sin(), z)
    });
    m.normals = m
        .positions
        .iter()
        .map(|p| (*p - Vec3::new(0.0, 0.0, centre_z)).normalize())
        .collect();
    m
}

/// Heidrich's Fig 7.3: a slide projector. A diffuser at the back of a square black housing
/// lights a slide (thin glass tinted by its picture) in a gate; a solid biconvex glass lens in
/// the housing's front plate focuses the slide at `focus` metres. Local frame: +Z forward
/// along `aim`, +Y towards `up`; luminaire "projector", its focus recorded in the scene.
fn projector_lamp(s: &mut Scene, position: Vec3, aim: Vec3, up: Vec3, focus: f32) {
    use projector::*;
    let black = s.add_material(Material {
        double_sided: true,
        ..Material::diffuse("housing", Vec3::splat(0.02))
    });
    let glass = s.add_material(Material {
        name: "lens_glass".into(),
        base_color: Vec4::ONE,
        roughness: 0.0,
        specular_transmission: 1.0,
        ior: IOR,
        thickness: thickness(),
        ..Default::default()
    });
    let texture = s.textures.len();
    s.textures.push(slide_picture());
    let slide_glass = s.add_material(Material {
        name: "slide".into(),
        base_color: Vec4::ONE,
        base_color_texture: Some(TextureRef::new(texture, 0)),
        roughness: 0.0,
        specular_transmission: 1.0,
        thickness: 0.0,
        double_sided: true,
        ..Default::default()
    });
    let diffuser = s.add_material(Material {
        emissive: Vec3::new(1.0, 0.95, 0.85),
        emissive_strength: 30000.0,
        ..Material::diffuse("diffuser", Vec3::ZERO)
    });
    let (h, [sx, sy]) = (HOUSING_HALF, SLIDE_HALF);
    let z_slide = slide_z(focus);
    let z_back = z_slide - 0.008;
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let inside = c(0.0, 0.0, z_slide);
    let mut housing = vec![];
    for (a, b) in [
        (c(-h, -h, 0.0), c(h, -h, 0.0)),
        (c(h, -h, 0.0), c(h, h, 0.0)),
    ]
    .into_iter()
    .chain([
        (c(h, h, 0.0), c(-h, h, 0.0)),
        (c(-h, h, 0.0), c(-h, -h, 0.0)),
    ]) {
        let back = Vec3::Z * z_back;
        housing.push(quad_facing(
            "wall",
            [a + back, b + back, b, a],
            inside,
            black,
        ));
    }
    // The gate: the slide's frame in a plate across the housing.
    let z = z_slide;
    for (lo, hi) in [
        (c(-h, -h, z), c(h, -sy, z)),
        (c(-h, sy, z), c(h, h, z)),
        (c(-h, -sy, z), c(-sx, sy, z)),
        (c(sx, -sy, z), c(h, sy, z)),
    ] {
        let p = [lo, c(hi.x, lo.y, z), hi, c(lo.x, hi.y, z)];
        housing.push(quad_facing("gate", p, Vec3::Z, black));
    }
    // The front plate: from the lens's rim out to the square (64 steps put points on the
    // corners, so the plate closes).
    housing.push(parametric("front", 64, 1, black, Vec2::ONE, |a, b| {
        let phi = a * std::f32::consts::TAU;
        let edge = h / phi.cos().abs().max(phi.sin().abs());
        let rho = APERTURE + b * (edge - APERTURE);
        c(rho * phi.cos(), rho * phi.sin(), 0.0)
    }));
    let mut slide = quad_facing(
        "slide",
        [c(-sx, -sy, z), c(sx, -sy, z), c(sx, sy, z), c(-sx, sy, z)],
        Vec3::Z,
        slide_glass,
    );
    // The lens inverts the image: the picture's top (v = 0) goes at −Y, its left at −X.
    slide.uv0 = slide
        .positions
        .iter()
        .map(|p| Vec2::new(p.x / (2.0 * sx) + 0.5, p.y / (2.0 * sy) + 0.5))
        .collect();
    let lamp_house = quad_facing(
        "diffuser",
        [
            c(-h, -h, z_back),
            c(h, -h, z_back),
            c(h, h, z_back),
            c(-h, h, z_back),
        ],
        Vec3::Z,
        diffuser,
    );
    let t = thickness() * 0.5;
    let rim = parametric("lens_rim", 64, 1, glass, Vec2::ONE, |a, b| {
        let phi = -a * std::f32::consts::TAU;
        c(
            APERTURE * phi.cos(),
            APERTURE * phi.sin(),
            -EDGE * 0.5 + b * EDGE,
        )
    });
    let lens = merge(
        "lens",
        &[lens_face(1.0, t, glass), lens_face(-1.0, -t, glass), rim],
    );
    let z_axis = aim.normalize();
    let x_axis = up.cross(z_axis).normalize();
    let y_axis = z_axis.cross(x_axis);
    let frame = Mat4::from_cols(
        x_axis.extend(0.0),
        y_axis.extend(0.0),
        z_axis.extend(0.0),
        position.extend(1.0),
    );
    // The first instance carries the frame the window and the focus are measured in.
    for mesh in [lens, slide, merge("housing", &housing), lamp_house] {
        let id = s.meshes.len();
        s.instances.push(Instance {
            name: mesh.name.clone(),
            mesh: id,
            transform: frame,
            nodes: vec!["projector".into()],
            luminaire: Some("projector".into()),
        });
        s.meshes.push(mesh);
    }
    s.luminaire_focus.insert("projector".into(), focus);
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
    // The projector's screen on the back wall, and the projector focused on it.
    let screen = s.add_material(Material::diffuse("screen", Vec3::splat(0.85)));
    let zs = -z + 0.01;
    s.add_mesh(
        quad_facing(
            "screen",
            [
                c(-1.6, 1.3, zs),
                c(-0.4, 1.3, zs),
                c(-0.4, 2.15, zs),
                c(-1.6, 2.15, zs),
            ],
            centre,
            screen,
        ),
        Mat4::IDENTITY,
    );
    let at = c(-1.0, 1.72, 0.9);
    projector_lamp(&mut s, at, -Vec3::Z, Vec3::Y, at.z - zs);
    s.cameras.push(Camera::look_at(
        "luminaire_camera",
        c(1.2, 1.6, 2.35),
        c(-0.3, 0.9, -1.5),
        Vec3::Y,
        62f32.to_radians(),
    ));
    // Camera 1: the projector's screen, from just in front of the projector.
    s.cameras.push(Camera::look_at(
        "screen_camera",
        c(-1.0, 1.72, 0.4),
        c(-1.0, 1.72, -z),
        Vec3::Y,
        40f32.to_radians(),
    ));
    s
}
