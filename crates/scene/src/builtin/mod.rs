//! Built-in procedural scenes: no assets in the repository, each with a default camera.
//!
//! | name | what it exercises |
//! |---|---|
//! | `cornell` | the Cornell box as published by the Cornell Program of Computer Graphics |
//! | `room` | an indoor room lit by sun and sky through a window; bounce light dominates |
//! | `shadows` | floor, pillars and boxes (closed meshes) under several point and spot lights |
//! | `bush` | ≈20,000 alpha-tested translucent leaf triangles on branches, lit by the sun |
//! | `prt` | a ridged torus knot (≈86k triangles, deep self-occlusion) and a coarse copy, env-lit |
//! | `spheres` | spheres and a torus of different materials under an environment map |
//! | `atrium` | a two-storey colonnade around a sunlit courtyard, with coloured banners |
//! | `prt-dynamic` | three objects moving near each other over a tiled ground (animated) |
//! | `luminaire` | a small room lit by measured lamps (goniometric: batwing, wall washer, flood) |

pub mod brdfs;
pub mod bumps;
mod dynamic;
pub mod geom;
pub mod glass;
pub mod luminaire;
pub mod mirror;

use crate::model::*;
use geom::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use lightlab_core::image::Image;
use lightlab_core::sampling::{Rng, uniform_sphere};

/// Names of the built-in scenes, in the order `lightlab scenes` lists them.
pub const NAMES: [&str; 12] = [
    "cornell",
    "room",
    "shadows",
    "bush",
    "prt",
    "spheres",
    "atrium",
    "prt-dynamic",
    "luminaire",
    "mirror",
    "glass",
    "brdfs",
];

/// One-line description of a built-in scene.
pub fn describe(name: &str) -> Option<&'static str> {
    Some(match name {
        "cornell" => "Cornell box (published geometry and reflectances), ceiling area light",
        "room" => "room lit by sun and sky through a window, with pillars; bounce light dominates",
        "shadows" => "floor, pillars and boxes (closed meshes) under point and spot lights",
        "bush" => "procedural bush of ~20k alpha-tested translucent leaf triangles, sunlit",
        "prt" => "ridged torus knot (~86k tris) and a coarse copy on a plane, environment-lit",
        "spheres" => "spheres and a torus with different materials under an environment map",
        "atrium" => {
            "two-storey colonnade around a sunlit courtyard, coloured banners (Sponza-like)"
        }
        "prt-dynamic" => {
            "a sphere, a ball and a ring moving near each other over tiled ground (48 frames)"
        }
        "luminaire" => "small room lit by measured lamps: batwing downlight, wall washer, flood",
        "mirror" => "a wall mirror beside a ball, a box and a pillar: planar reflections",
        "glass" => "a solid glass torus in a striped studio environment: refraction",
        "brdfs" => {
            "Heidrich's Figs 5.2, 5.3 and 9.1: Torrance–Sparrow tori, Ward and Banks disks and \
             spheres, Perlin-bumped sphere and torus"
        }
        _ => return None,
    })
}

/// Build a built-in scene by name.
pub fn builtin(name: &str) -> Option<Scene> {
    let mut s = match name {
        "cornell" => cornell(),
        "room" => room(),
        "shadows" => shadows(),
        "bush" => bush(),
        "prt" => prt(),
        "spheres" => spheres(),
        "atrium" => atrium(),
        "prt-dynamic" => dynamic::prt_dynamic(),
        "luminaire" => luminaire::luminaire(),
        "mirror" => mirror::mirror(),
        "glass" => glass::glass(),
        "brdfs" => brdfs::brdfs(),
        _ => return None,
    };
    s.name = name.into();
    for m in &mut s.meshes {
        if m.tangents.is_empty() {
            m.compute_tangents();
        }
    }
    Some(s)
}

/// The Cornell box. Geometry: the measured data of the Cornell Program of Computer Graphics
/// (graphics.cornell.edu/online/box/data.html), converted from millimetres to metres; the
/// camera is theirs (35 mm lens on a 25 mm film: yfov = 2·atan(12.5/35) = 39.3°). Reflectances
/// are the usual RGB reductions of the measured spectra (white 0.725/0.71/0.68, red
/// 0.63/0.065/0.05, green 0.14/0.45/0.091) and the light emits radiance (17, 12, 4).
fn cornell() -> Scene {
    let mut s = Scene::default();
    let mm = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * 0.001;
    let white = s.add_material(Material::diffuse("white", Vec3::new(0.725, 0.71, 0.68)));
    let red = s.add_material(Material::diffuse("red", Vec3::new(0.63, 0.065, 0.05)));
    let green = s.add_material(Material::diffuse("green", Vec3::new(0.14, 0.45, 0.091)));
    let light = s.add_material(Material {
        name: "light".into(),
        base_color: Vec4::new(0.78, 0.78, 0.78, 1.0),
        specular: 0.0,
        emissive: Vec3::new(1.0, 12.0 / 17.0, 4.0 / 17.0),
        emissive_strength: 17.0,
        ..Default::default()
    });
    let inside = mm(278.0, 274.4, 279.6);
    let walls: [(&str, [Vec3; 4], usize); 5] = [
        (
            "floor",
            [
                mm(552.8, 0.0, 0.0),
                mm(0.0, 0.0, 0.0),
                mm(0.0, 0.0, 559.2),
                mm(549.6, 0.0, 559.2),
            ],
            white,
        ),
        (
            "ceiling",
            [
                mm(556.0, 548.8, 0.0),
                mm(556.0, 548.8, 559.2),
                mm(0.0, 548.8, 559.2),
                mm(0.0, 548.8, 0.0),
            ],
            white,
        ),
        (
            "back_wall",
            [
                mm(549.6, 0.0, 559.2),
                mm(0.0, 0.0, 559.2),
                mm(0.0, 548.8, 559.2),
                mm(556.0, 548.8, 559.2),
            ],
            white,
        ),
        (
            "right_wall",
            [
                mm(0.0, 0.0, 559.2),
                mm(0.0, 0.0, 0.0),
                mm(0.0, 548.8, 0.0),
                mm(0.0, 548.8, 559.2),
            ],
            green,
        ),
        (
            "left_wall",
            [
                mm(552.8, 0.0, 0.0),
                mm(549.6, 0.0, 559.2),
                mm(556.0, 548.8, 559.2),
                mm(556.0, 548.8, 0.0),
            ],
            red,
        ),
    ];
    for (name, p, mat) in walls {
        s.add_mesh(quad_facing(name, p, inside, mat), Mat4::IDENTITY);
    }
    // The light sits 0.1 mm below the ceiling, facing down.
    let lp = [
        mm(343.0, 548.7, 227.0),
        mm(343.0, 548.7, 332.0),
        mm(213.0, 548.7, 332.0),
        mm(213.0, 548.7, 227.0),
    ];
    s.add_mesh(quad_facing("light", lp, inside, light), Mat4::IDENTITY);
    let short_top = [
        mm(130.0, 165.0, 65.0),
        mm(82.0, 165.0, 225.0),
        mm(240.0, 165.0, 272.0),
        mm(290.0, 165.0, 114.0),
    ];
    let tall_top = [
        mm(423.0, 330.0, 247.0),
        mm(265.0, 330.0, 296.0),
        mm(314.0, 330.0, 456.0),
        mm(472.0, 330.0, 406.0),
    ];
    for (name, top) in [("short_block", short_top), ("tall_block", tall_top)] {
        let bottom = top.map(|p| Vec3::new(p.x, 0.0, p.z));
        s.add_mesh(hexahedron(name, bottom, top, white), Mat4::IDENTITY);
    }
    s.cameras.push(Camera::look_at(
        "cornell_camera",
        mm(278.0, 273.0, -800.0),
        mm(278.0, 273.0, 0.0),
        Vec3::Y,
        2.0 * (12.5f32 / 35.0).atan(),
    ));
    s
}

/// An equirectangular sky: a smooth gradient from `horizon` to `zenith` above and `ground` below,
/// plus broad lobes (direction, colour, cosine exponent) for low-frequency structure.
fn sky_env(
    width: u32,
    zenith: Vec3,
    horizon: Vec3,
    ground: Vec3,
    lobes: &[(Vec3, Vec3, f32)],
) -> Environment {
    let height = width / 2;
    let image = Image::from_fn(width, height, |x, y| {
        let uv = Vec2::new(
            (x as f32 + 0.5) / width as f32,
            (y as f32 + 0.5) / height as f32,
        );
        let d = Environment::uv_to_dir(uv);
        let mut c = if d.y >= 0.0 {
            horizon.lerp(zenith, d.y.sqrt())
        } else {
            horizon.lerp(ground, (-d.y).sqrt().min(1.0) * 0.9 + 0.1)
        };
        for &(dir, col, k) in lobes {
            c += col * d.dot(dir.normalize()).max(0.0).powf(k);
        }
        c
    });
    Environment {
        image,
        intensity: 1.0,
    }
}

/// The clear day of `room` and `atrium`: a sun of 8 W/m² shining along `direction`, and a blue
/// sky over a brown ground as the environment.
fn add_clear_day(s: &mut Scene, direction: Vec3) {
    s.lights
        .push(sun(direction, 8.0, Vec3::new(1.0, 0.95, 0.85)));
    s.environment = Some(sky_env(
        256,
        Vec3::new(0.25, 0.45, 0.9),
        Vec3::new(0.7, 0.8, 0.95),
        Vec3::new(0.25, 0.22, 0.18),
        &[],
    ));
}

fn sun(direction: Vec3, irradiance: f32, color: Vec3) -> Light {
    Light {
        name: "sun".into(),
        kind: LightKind::Directional {
            angular_diameter: 0.0093,
        },
        color,
        intensity: irradiance,
        position: Vec3::ZERO,
        direction: direction.normalize(),
        range: None,
    }
}

/// A 6 × 3 × 5 m room with 0.2 m thick closed walls, a window in the +X wall, two pillars, sun
/// and sky. Most of the room sees only bounce light.
fn room() -> Scene {
    let mut s = Scene::default();
    let wall = s.add_material(Material::diffuse("plaster", Vec3::splat(0.75)));
    let floor = s.add_material(Material::diffuse("wood", Vec3::new(0.5, 0.35, 0.2)));
    let ceiling = s.add_material(Material::diffuse("ceiling", Vec3::splat(0.8)));
    let pillar = s.add_material(Material::diffuse("pillar", Vec3::new(0.45, 0.5, 0.6)));
    let t = 0.2;
    let (x0, x1, y1, z0, z1) = (-3.0, 3.0, 3.0, -2.5, 2.5);
    let b = |name: &str, min: Vec3, max: Vec3, m| aabb_box(name, min, max, m);
    let parts = [
        b(
            "floor",
            Vec3::new(x0 - t, -t, z0 - t),
            Vec3::new(x1 + t, 0.0, z1 + t),
            floor,
        ),
        b(
            "ceiling",
            Vec3::new(x0 - t, y1, z0 - t),
            Vec3::new(x1 + t, y1 + t, z1 + t),
            ceiling,
        ),
        b(
            "wall_west",
            Vec3::new(x0 - t, 0.0, z0 - t),
            Vec3::new(x0, y1, z1 + t),
            wall,
        ),
        b(
            "wall_north",
            Vec3::new(x0, 0.0, z0 - t),
            Vec3::new(x1, y1, z0),
            wall,
        ),
        b(
            "wall_south",
            Vec3::new(x0, 0.0, z1),
            Vec3::new(x1, y1, z1 + t),
            wall,
        ),
        // The east wall, around a window opening y ∈ [0.8, 2.4], z ∈ [−1.2, 1.2].
        b(
            "wall_east_low",
            Vec3::new(x1, 0.0, z0 - t),
            Vec3::new(x1 + t, 0.8, z1 + t),
            wall,
        ),
        b(
            "wall_east_high",
            Vec3::new(x1, 2.4, z0 - t),
            Vec3::new(x1 + t, y1, z1 + t),
            wall,
        ),
        b(
            "wall_east_north",
            Vec3::new(x1, 0.8, z0 - t),
            Vec3::new(x1 + t, 2.4, -1.2),
            wall,
        ),
        b(
            "wall_east_south",
            Vec3::new(x1, 0.8, 1.2),
            Vec3::new(x1 + t, 2.4, z1 + t),
            wall,
        ),
    ];
    for p in parts {
        s.add_mesh(p, Mat4::IDENTITY);
    }
    let pillar_mesh = s.add_mesh(
        b(
            "pillar",
            Vec3::new(-0.2, 0.0, -0.2),
            Vec3::new(0.2, y1, 0.2),
            pillar,
        ),
        Mat4::from_translation(Vec3::new(0.9, 0.0, -1.1)),
    );
    s.instances.push(Instance {
        name: "pillar_2".into(),
        mesh: pillar_mesh,
        transform: Mat4::from_translation(Vec3::new(0.9, 0.0, 1.1)),
        nodes: vec![],
        luminaire: None,
    });
    add_clear_day(&mut s, Vec3::new(-0.75, -0.55, -0.25));
    s.cameras.push(Camera::look_at(
        "room_camera",
        Vec3::new(-2.6, 1.7, 2.2),
        Vec3::new(1.5, 0.9, -0.8),
        Vec3::Y,
        60f32.to_radians(),
    ));
    s
}

/// A Sponza-like atrium (issue 22): a 16 × 8 m courtyard open to the sky, ringed by a
/// two-storey gallery 2 m deep (columns every 2 m, lintels, floor slabs, outer walls, a
/// roof), with four coloured banners hanging in the upper gallery. The sun (elevation 53°)
/// lights half the courtyard and reaches into the north gallery; everything else is lit by
/// the sky and by bounces, so indirect light and sky occlusion dominate.
// The atrium's courtyard x ∈ [−8, 8], z ∈ [−4, 4]; galleries out to |x| = 10, |z| = 6;
// storeys at 0–3.3 m (slab 3.3–3.6) and 3.6–7 m (roof 7–7.3).
const ATRIUM_COURT: (f32, f32) = (8.0, 4.0);
const ATRIUM_OUTER: (f32, f32) = (10.0, 6.0);

fn atrium() -> Scene {
    let mut s = Scene::default();
    let stone = s.add_material(Material::diffuse("stone", Vec3::new(0.62, 0.57, 0.47)));
    let paving = s.add_material(Material::diffuse("paving", Vec3::new(0.5, 0.46, 0.4)));
    let plaster = s.add_material(Material::diffuse("plaster", Vec3::splat(0.72)));
    let mut parts = atrium_shell(paving, plaster);
    parts.extend(atrium_storeys(stone));
    for p in parts {
        s.add_mesh(p, Mat4::IDENTITY);
    }
    atrium_columns(&mut s, stone);
    atrium_banners(&mut s);
    add_clear_day(&mut s, Vec3::new(-0.35, -0.8, 0.45));
    s.cameras.push(Camera::look_at(
        "atrium_camera",
        Vec3::new(-7.4, 1.7, -3.3),
        Vec3::new(6.0, 3.4, 3.2),
        Vec3::Y,
        70f32.to_radians(),
    ));
    s
}

/// The atrium's ground and its four outer walls.
fn atrium_shell(paving: usize, plaster: usize) -> Vec<Mesh> {
    let b = |name: &str, min: Vec3, max: Vec3, m| aabb_box(name, min, max, m);
    let (ox, oz) = ATRIUM_OUTER;
    let t = 0.3;
    vec![
        b(
            "ground",
            Vec3::new(-ox - t, -0.2, -oz - t),
            Vec3::new(ox + t, 0.0, oz + t),
            paving,
        ),
        b(
            "wall_west",
            Vec3::new(-ox - t, 0.0, -oz - t),
            Vec3::new(-ox, 7.3, oz + t),
            plaster,
        ),
        b(
            "wall_east",
            Vec3::new(ox, 0.0, -oz - t),
            Vec3::new(ox + t, 7.3, oz + t),
            plaster,
        ),
        b(
            "wall_north",
            Vec3::new(-ox, 0.0, oz),
            Vec3::new(ox, 7.3, oz + t),
            plaster,
        ),
        b(
            "wall_south",
            Vec3::new(-ox, 0.0, -oz - t),
            Vec3::new(ox, 7.3, -oz),
            plaster,
        ),
    ]
}

/// Each storey's slab over the gallery ring, and its lintels along the courtyard's edge.
fn atrium_storeys(stone: usize) -> Vec<Mesh> {
    let b = |name: &str, min: Vec3, max: Vec3, m| aabb_box(name, min, max, m);
    let ((cx, cz), (ox, oz)) = (ATRIUM_COURT, ATRIUM_OUTER);
    let mut parts = vec![];
    for (level, (y0, y1)) in [(3.3, 3.6), (7.0, 7.3)].into_iter().enumerate() {
        let name = |what: &str| format!("{what}_{level}");
        parts.extend([
            b(
                &name("slab_north"),
                Vec3::new(-ox, y0, cz),
                Vec3::new(ox, y1, oz),
                stone,
            ),
            b(
                &name("slab_south"),
                Vec3::new(-ox, y0, -oz),
                Vec3::new(ox, y1, -cz),
                stone,
            ),
            b(
                &name("slab_east"),
                Vec3::new(cx, y0, -cz),
                Vec3::new(ox, y1, cz),
                stone,
            ),
            b(
                &name("slab_west"),
                Vec3::new(-ox, y0, -cz),
                Vec3::new(-cx, y1, cz),
                stone,
            ),
        ]);
        let (l0, l1) = (y0 - 0.5, y0);
        let w = 0.2;
        parts.extend([
            b(
                &name("lintel_north"),
                Vec3::new(-cx - w, l0, cz - w),
                Vec3::new(cx + w, l1, cz + w),
                stone,
            ),
            b(
                &name("lintel_south"),
                Vec3::new(-cx - w, l0, -cz - w),
                Vec3::new(cx + w, l1, -cz + w),
                stone,
            ),
            b(
                &name("lintel_east"),
                Vec3::new(cx - w, l0, -cz + w),
                Vec3::new(cx + w, l1, cz - w),
                stone,
            ),
            b(
                &name("lintel_west"),
                Vec3::new(-cx - w, l0, -cz + w),
                Vec3::new(-cx + w, l1, cz - w),
                stone,
            ),
        ]);
    }
    parts
}

/// Columns every 2 m along the courtyard's edge, on both storeys.
fn atrium_columns(s: &mut Scene, stone: usize) {
    let (cx, cz) = ATRIUM_COURT;
    let ground_column = s.add_mesh(cylinder("column_0", 0.22, 2.8, 24, stone), Mat4::IDENTITY);
    let upper_column = s.add_mesh(cylinder("column_1", 0.2, 2.9, 24, stone), Mat4::IDENTITY);
    // One instance per column position instead of each mesh's instance at the origin.
    s.instances
        .retain(|i| i.mesh != ground_column && i.mesh != upper_column);
    let mut spots = vec![];
    for i in -4..=4 {
        spots.push(Vec2::new(2.0 * i as f32, cz));
        spots.push(Vec2::new(2.0 * i as f32, -cz));
    }
    for i in -1..=1 {
        spots.push(Vec2::new(cx, 2.0 * i as f32));
        spots.push(Vec2::new(-cx, 2.0 * i as f32));
    }
    for (k, p) in spots.iter().enumerate() {
        for (mesh, y) in [(ground_column, 0.0), (upper_column, 3.6)] {
            s.instances.push(Instance {
                name: format!("column_{k}_{}", y > 0.0),
                mesh,
                transform: Mat4::from_translation(Vec3::new(p.x, y, p.y)),
                nodes: vec![],
                luminaire: None,
            });
        }
    }
}

/// Banners between the upper columns, hanging from the lintel.
fn atrium_banners(s: &mut Scene) {
    let b = |name: &str, min: Vec3, max: Vec3, m| aabb_box(name, min, max, m);
    let cz = ATRIUM_COURT.1;
    for (name, colour, x, z) in [
        ("banner_red", Vec3::new(0.7, 0.08, 0.06), -5.0, cz),
        ("banner_blue", Vec3::new(0.08, 0.15, 0.6), 3.0, cz),
        ("banner_green", Vec3::new(0.1, 0.5, 0.12), -1.0, -cz),
        ("banner_yellow", Vec3::new(0.75, 0.6, 0.1), 5.0, -cz),
    ] {
        let m = s.add_material(Material::diffuse(name, colour));
        s.add_mesh(
            b(
                name,
                Vec3::new(x - 0.6, 4.2, z - 0.03),
                Vec3::new(x + 0.6, 6.5, z + 0.03),
                m,
            ),
            Mat4::IDENTITY,
        );
    }
}

/// A floor, four pillars, boxes and a sphere (closed meshes) under three point and two spot
/// lights: the shadow-volume and shadow-map test scene.
fn shadows() -> Scene {
    let mut s = Scene::default();
    let floor = s.add_material(Material::diffuse("floor", Vec3::splat(0.6)));
    let stone = s.add_material(Material {
        name: "stone".into(),
        base_color: Vec4::new(0.7, 0.65, 0.55, 1.0),
        roughness: 0.5,
        specular: 0.5,
        ..Default::default()
    });
    let painted = s.add_material(Material {
        name: "painted".into(),
        base_color: Vec4::new(0.2, 0.35, 0.7, 1.0),
        roughness: 0.35,
        specular: 1.0,
        ..Default::default()
    });
    s.add_mesh(
        aabb_box(
            "floor",
            Vec3::new(-7.0, -0.2, -7.0),
            Vec3::new(7.0, 0.0, 7.0),
            floor,
        ),
        Mat4::IDENTITY,
    );
    let pillar = s.add_mesh(
        cylinder("pillar", 0.3, 2.5, 24, stone),
        Mat4::from_translation(Vec3::new(-2.5, 0.0, -2.5)),
    );
    for (i, p) in [(2.5, -2.5), (-2.5, 2.5), (2.5, 2.5)].iter().enumerate() {
        s.instances.push(Instance {
            name: format!("pillar_{}", i + 2),
            mesh: pillar,
            transform: Mat4::from_translation(Vec3::new(p.0, 0.0, p.1)),
            nodes: vec![],
            luminaire: None,
        });
    }
    let cube = s.add_mesh(
        aabb_box("box", Vec3::splat(-0.5), Vec3::splat(0.5), painted),
        Mat4::from_scale_rotation_translation(
            Vec3::new(1.2, 1.0, 1.2),
            Quat::from_rotation_y(0.5),
            Vec3::new(0.0, 0.5, 0.0),
        ),
    );
    s.instances.push(Instance {
        name: "box_2".into(),
        mesh: cube,
        transform: Mat4::from_scale_rotation_translation(
            Vec3::new(0.6, 1.6, 0.6),
            Quat::from_rotation_y(-0.3),
            Vec3::new(1.4, 0.8, 1.2),
        ),
        nodes: vec![],
        luminaire: None,
    });
    s.instances.push(Instance {
        name: "box_3".into(),
        mesh: cube,
        transform: Mat4::from_scale_rotation_translation(
            Vec3::splat(0.7),
            Quat::from_rotation_y(0.9),
            Vec3::new(-1.5, 0.35, 0.8),
        ),
        nodes: vec![],
        luminaire: None,
    });
    s.add_mesh(
        sphere("ball", 0.5, 48, 24, stone),
        Mat4::from_translation(Vec3::new(0.6, 0.5, -1.6)),
    );
    let point = |name: &str, pos: Vec3, color: Vec3, intensity: f32| Light {
        name: name.into(),
        kind: LightKind::Point,
        color,
        intensity,
        position: pos,
        direction: -Vec3::Y,
        range: None,
    };
    s.lights.push(point(
        "point_warm",
        Vec3::new(-1.5, 3.2, -1.0),
        Vec3::new(1.0, 0.8, 0.6),
        6.0,
    ));
    s.lights.push(point(
        "point_cool",
        Vec3::new(2.0, 2.8, 0.5),
        Vec3::new(0.6, 0.75, 1.0),
        5.0,
    ));
    s.lights.push(point(
        "point_white",
        Vec3::new(0.0, 4.0, 2.8),
        Vec3::ONE,
        4.0,
    ));
    for (name, pos, target, color) in [
        (
            "spot_a",
            Vec3::new(-4.0, 4.5, 3.0),
            Vec3::new(-0.5, 0.0, 0.0),
            Vec3::new(1.0, 0.95, 0.8),
        ),
        (
            "spot_b",
            Vec3::new(4.0, 5.0, -3.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(0.85, 1.0, 0.85),
        ),
    ] {
        s.lights.push(Light {
            name: name.into(),
            kind: LightKind::Spot {
                inner_cone: 0.3,
                outer_cone: 0.45,
            },
            color,
            intensity: 40.0,
            position: pos,
            direction: (target - pos).normalize(),
            range: None,
        });
    }
    s.cameras.push(Camera::look_at(
        "shadows_camera",
        Vec3::new(0.0, 6.0, 8.5),
        Vec3::new(0.0, 0.6, 0.0),
        Vec3::Y,
        45f32.to_radians(),
    ));
    s
}

/// A 64×64 leaf texture: per texel whether it lies inside the leaf (a pointed ellipse), on the
/// midrib or on a vein, mapped to a texel by `texel`.
fn leaf_map(texel: impl Fn(bool, bool, bool) -> Vec4) -> Vec<Vec4> {
    let n = 64u32;
    let mut data = Vec::with_capacity((n * n) as usize);
    for y in 0..n {
        for x in 0..n {
            let s = (x as f32 + 0.5) / n as f32 - 0.5;
            let t = (y as f32 + 0.5) / n as f32;
            let half_width = 0.42 * (std::f32::consts::PI * t).sin().powf(0.8);
            let inside = s.abs() < half_width;
            let rib = s.abs() < 0.03;
            let vein = ((t * 14.0 - s.abs() * 10.0).fract() - 0.5).abs() < 0.06;
            data.push(texel(inside, rib, vein));
        }
    }
    data
}

/// A procedural 64×64 leaf texture (linear RGBA): a pointed ellipse with a midrib; alpha 0
/// outside the leaf for alpha testing.
fn leaf_texture() -> Texture {
    let data = leaf_map(|inside, rib, vein| {
        let c = if rib {
            Vec3::new(0.22, 0.38, 0.08)
        } else if vein {
            Vec3::new(0.16, 0.34, 0.07)
        } else {
            Vec3::new(0.10, 0.30, 0.05)
        };
        c.extend(if inside { 1.0 } else { 0.0 })
    });
    Texture {
        name: "leaf".into(),
        width: 64,
        height: 64,
        texels: crate::Texels::Rgba32F(data),
        srgb: true,
    }
}

/// The leaf's translucency map (linear; alpha scales the diffuse transmission): the thin lamina
/// lets light through, the veins less and the midrib least, as in the WPI report's leaves.
fn leaf_translucency() -> Texture {
    let data = leaf_map(|_, rib, vein| {
        let a = if rib {
            0.25
        } else if vein {
            0.6
        } else {
            1.0
        };
        Vec4::new(1.0, 1.0, 1.0, a)
    });
    Texture {
        name: "leaf_translucency".into(),
        width: 64,
        height: 64,
        texels: crate::Texels::Rgba32F(data),
        srgb: false,
    }
}

/// A bush of about 20,000 leaf triangles (10,000 alpha-tested, double-sided, translucent quads)
/// on a trunk and branches, over a ground plane, lit by the sun and a dim sky.
fn bush() -> Scene {
    let mut s = Scene::default();
    let ground = s.add_material(Material::diffuse("ground", Vec3::new(0.3, 0.28, 0.18)));
    let bark = s.add_material(Material {
        // Branches move a little in the wind, the leaves fully.
        sway: 0.2,
        ..Material::diffuse("bark", Vec3::new(0.25, 0.17, 0.1))
    });
    s.textures.push(leaf_texture());
    s.textures.push(leaf_translucency());
    let leaf = s.add_material(Material {
        name: "leaf".into(),
        base_color: Vec4::ONE,
        base_color_texture: Some(TextureRef::new(0, 0)),
        roughness: 0.6,
        specular: 0.3,
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        double_sided: true,
        transmission: 0.45,
        sway: 1.0,
        transmission_texture: Some(TextureRef::new(1, 0)),
        ..Default::default()
    });
    s.add_mesh(
        quad(
            "ground",
            [
                Vec3::new(-5.0, 0.0, 5.0),
                Vec3::new(5.0, 0.0, 5.0),
                Vec3::new(5.0, 0.0, -5.0),
                Vec3::new(-5.0, 0.0, -5.0),
            ],
            ground,
        ),
        Mat4::IDENTITY,
    );
    let mut rng = Rng::new(2011, 0);
    let trunk_top = Vec3::new(0.0, 0.9, 0.0);
    let branch_mesh = s.add_mesh(cylinder("trunk", 0.07, 0.9, 12, bark), Mat4::IDENTITY);
    let crown_centre = Vec3::new(0.0, 1.45, 0.0);
    let crown_radii = Vec3::new(0.95, 0.65, 0.95);
    let mut tips = Vec::new();
    for i in 0..14 {
        // Branch tips spread over the upper crown.
        let mut d = uniform_sphere(rng.next_vec2());
        d.y = d.y.abs() * 0.8 + 0.1;
        let tip = crown_centre + d.normalize() * crown_radii * 0.75;
        let axis = tip - trunk_top;
        let len = axis.length();
        let rot = Quat::from_rotation_arc(Vec3::Y, axis / len);
        // The branch mesh is the trunk cylinder (height 0.9, radius 0.07) rescaled.
        s.instances.push(Instance {
            name: format!("branch_{i}"),
            mesh: branch_mesh,
            transform: Mat4::from_scale_rotation_translation(
                Vec3::new(0.35, len / 0.9, 0.35),
                rot,
                trunk_top,
            ),
            nodes: vec![],
            luminaire: None,
        });
        tips.push(tip);
    }
    // 10,000 leaves: 70 % clustered around branch tips, 30 % on the crown's outer shell.
    let mut leaves = Mesh {
        name: "leaves".into(),
        material: leaf,
        ..Default::default()
    };
    for i in 0..10_000 {
        let centre = if i % 10 < 7 {
            let tip = tips[i % tips.len()];
            tip + uniform_sphere(rng.next_vec2()) * 0.35 * rng.next_f32().cbrt()
        } else {
            let d = uniform_sphere(rng.next_vec2());
            crown_centre + d * crown_radii * (0.8 + 0.2 * rng.next_f32())
        };
        let normal = uniform_sphere(rng.next_vec2());
        let (t, b) = lightlab_core::sampling::orthonormal_basis(normal);
        let angle = rng.next_f32() * std::f32::consts::TAU;
        let along = t * angle.cos() + b * angle.sin();
        let across = normal.cross(along);
        let (len, wid) = (0.13 + 0.04 * rng.next_f32(), 0.09);
        let base = centre - along * len * 0.5;
        let corners = [
            base - across * wid * 0.5,
            base + across * wid * 0.5,
            base + across * wid * 0.5 + along * len,
            base - across * wid * 0.5 + along * len,
        ];
        let first = leaves.positions.len() as u32;
        let uvs = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ];
        let n = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize();
        for (p, uv) in corners.iter().zip(uvs) {
            leaves.positions.push(*p);
            leaves.normals.push(n);
            leaves.uv0.push(uv);
        }
        leaves
            .indices
            .extend([first, first + 1, first + 2, first, first + 2, first + 3]);
    }
    s.add_mesh(leaves, Mat4::IDENTITY);
    s.lights.push(sun(
        Vec3::new(-0.4, -0.8, -0.45),
        6.0,
        Vec3::new(1.0, 0.96, 0.88),
    ));
    s.environment = Some(sky_env(
        256,
        Vec3::new(0.15, 0.25, 0.5),
        Vec3::new(0.4, 0.45, 0.55),
        Vec3::new(0.12, 0.1, 0.08),
        &[],
    ));
    s.cameras.push(Camera::look_at(
        "bush_camera",
        Vec3::new(2.7, 1.5, 3.1),
        Vec3::new(0.0, 1.05, 0.0),
        Vec3::Y,
        40f32.to_radians(),
    ));
    s
}

/// An n² tangent-space normal map (linear; xyz·½ + ½) of a height field over the unit tile,
/// in tile units, by central differences.
fn normal_map_from_height(name: &str, n: u32, height: impl Fn(f32, f32) -> f32) -> Texture {
    let e = 0.5 / n as f32;
    let data = (0..n * n)
        .map(|k| {
            let (x, y) = (k % n, k / n);
            let (u, v) = ((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
            let du = (height(u + e, v) - height(u - e, v)) / (2.0 * e);
            let dv = (height(u, v + e) - height(u, v - e)) / (2.0 * e);
            let nrm = Vec3::new(-du, -dv, 1.0).normalize();
            (nrm * 0.5 + Vec3::splat(0.5)).extend(1.0)
        })
        .collect();
    Texture {
        name: name.into(),
        width: n,
        height: n,
        texels: crate::Texels::Rgba32F(data),
        srgb: false,
    }
}

/// Dune-map repeats per metre on the `prt` ground.
const DUNE_TILES_PER_METRE: f32 = 0.5;

/// A 256² tangent-space normal map of wind-blown sand (linear; xyz·½ + ½): asymmetric ripples
/// crossing two dune ridges, periodic in the tile, slopes up to ≈30° — the ground of the `prt`
/// scene, for normal-mapped SH light-maps (Fuchs §5.7 shows sand dunes).
fn dune_normal_map() -> Texture {
    use std::f32::consts::TAU;
    let n = 256u32;
    // Height in tile units (one tile = 1/DUNE_TILES_PER_METRE metres).
    let height = |u: f32, v: f32| {
        let ridge = (TAU * (u + 0.15 * (TAU * v).sin())).sin();
        let ripple_phase = TAU * (6.0 * u + v + 0.3 * (TAU * 2.0 * v).sin());
        // Ripples steeper on their lee side: sin + a second harmonic.
        let ripple = ripple_phase.sin() + 0.35 * (2.0 * ripple_phase).sin();
        0.045 * ridge + 0.007 * ripple
    };
    normal_map_from_height("dunes_normal", n, height)
}

/// A 128² tangent-space normal map of crossing waves (linear; xyz·½ + ½), periodic in the
/// tile, slopes up to ≈25°: the bumps of the `spheres` torus (Heidrich's Fig 9.1 uses waves).
fn wave_normal_map() -> Texture {
    use std::f32::consts::TAU;
    let n = 128u32;
    let height =
        |u: f32, v: f32| 0.025 * ((TAU * (2.0 * u + v)).sin() + 0.6 * (TAU * 3.0 * v).sin());
    normal_map_from_height("waves_normal", n, height)
}

/// How the `prt` scene's decimated knot is made from the high-poly one.
pub const KNOT_DECIMATION: crate::simplify::SimplifySettings = crate::simplify::SimplifySettings {
    target_triangles: 2000,
    max_error: 0.05,
    weld: 1e-5,
};

/// The PRT scene: a ridged (2,3) torus knot of ≈86k triangles and a meshopt decimation of it
/// beside it, on a plane, under a low-frequency environment.
fn prt() -> Scene {
    let mut s = Scene::default();
    s.textures.push(dune_normal_map());
    let mut ground = Material::diffuse("plane", Vec3::splat(0.6));
    ground.normal_texture = Some(TextureRef::new(0, 0));
    let plane = s.add_material(ground);
    let body = s.add_material(Material::diffuse("knot", Vec3::new(0.75, 0.72, 0.68)));
    let mut ground_mesh = quad(
        "plane",
        [
            Vec3::new(-4.0, 0.0, 4.0),
            Vec3::new(4.0, 0.0, 4.0),
            Vec3::new(4.0, 0.0, -4.0),
            Vec3::new(-4.0, 0.0, -4.0),
        ],
        plane,
    );
    // UV0 in metres: the dune map tiles every 2 m.
    ground_mesh
        .uv0
        .iter_mut()
        .for_each(|uv| *uv *= DUNE_TILES_PER_METRE);
    ground_mesh.compute_tangents();
    s.add_mesh(ground_mesh, Mat4::IDENTITY);
    let high = ridged_torus_knot("knot_high", 2.0, 3.0, 1.0, 0.22, 7.0, 0.35, 900, 48, body);
    let high_id = s.meshes.len();
    // The decimated copy: meshoptimizer's simplification of the high-poly knot to ≈2% of its
    // triangles (the ridges mostly collapse into the tube); it names the high-poly knot as its
    // detail source, so textured PRT bakes the ridges' normals and occlusion onto it.
    let low = crate::simplify::simplify(&high, high_id, &KNOT_DECIMATION)
        .expect("the built-in knot simplifies")
        .mesh;
    s.add_mesh(high, Mat4::from_translation(Vec3::new(-1.3, 0.72, 0.0)));
    s.add_mesh(
        Mesh {
            name: "knot_low".into(),
            ..low
        },
        Mat4::from_translation(Vec3::new(1.3, 0.72, 0.0)),
    );
    s.environment = Some(sky_env(
        128,
        Vec3::new(0.3, 0.4, 0.6),
        Vec3::new(0.5, 0.5, 0.5),
        Vec3::new(0.15, 0.13, 0.1),
        &[
            (Vec3::new(0.6, 0.7, 0.4), Vec3::new(1.6, 1.2, 0.7), 4.0),
            (Vec3::new(-0.7, 0.3, -0.5), Vec3::new(0.2, 0.35, 0.8), 2.0),
        ],
    ));
    s.cameras.push(Camera::look_at(
        "prt_camera",
        Vec3::new(0.0, 2.4, 4.8),
        Vec3::new(0.0, 0.6, 0.0),
        Vec3::Y,
        45f32.to_radians(),
    ));
    s
}

/// Spheres of diffuse, plastic and metal materials and a glossy torus under an environment map.
fn spheres() -> Scene {
    let mut s = Scene::default();
    let ground = s.add_material(Material::diffuse("ground", Vec3::splat(0.5)));
    let mats = [
        Material::diffuse("diffuse_red", Vec3::new(0.7, 0.1, 0.08)),
        Material {
            name: "plastic_blue".into(),
            base_color: Vec4::new(0.1, 0.2, 0.7, 1.0),
            roughness: 0.25,
            specular: 1.0,
            ..Default::default()
        },
        // Measured metals: the exact Fresnel of their complex index (Heidrich §8.3.1).
        Material {
            name: "gold_rough".into(),
            base_color: Vec4::ONE,
            metallic: 1.0,
            roughness: 0.4,
            conductor: Conductor::preset("gold"),
            ..Default::default()
        },
        Material {
            name: "silver_polished".into(),
            base_color: Vec4::ONE,
            metallic: 1.0,
            roughness: 0.08,
            conductor: Conductor::preset("silver"),
            ..Default::default()
        },
    ];
    // The ground is a 80 × 80 grid (12.5 cm cells), not one quad, so that per-vertex methods
    // (per-vertex PRT) hold the spheres' contact shadows.
    s.add_mesh(
        parametric("ground", 80, 80, ground, Vec2::splat(10.0), |u, v| {
            Vec3::new(-5.0 + 10.0 * u, 0.0, -5.0 + 10.0 * v)
        }),
        Mat4::IDENTITY,
    );
    for (i, m) in mats.into_iter().enumerate() {
        let name = format!("sphere_{}", m.name);
        let id = s.add_material(m);
        s.add_mesh(
            sphere(&name, 0.45, 64, 32, id),
            Mat4::from_translation(Vec3::new(-1.65 + 1.1 * i as f32, 0.45, -0.3)),
        );
    }
    // Behind the row: clear glass (KHR_materials_transmission) and a chrome mirror, which
    // reflects its neighbours (Heidrich ch. 8; `--dynamic-env` on the GPU).
    for (name, m, x) in [
        (
            "glass",
            Material {
                name: "glass_clear".into(),
                base_color: Vec4::ONE,
                roughness: 0.0,
                specular_transmission: 1.0,
                ior: 1.5,
                // A solid ball (KHR_materials_volume), not a thin-walled bubble.
                thickness: 0.9,
                ..Default::default()
            },
            -1.1,
        ),
        (
            "mirror",
            Material {
                name: "chrome_mirror".into(),
                base_color: Vec4::ONE,
                metallic: 1.0,
                roughness: 0.0,
                conductor: Conductor::preset("chrome"),
                ..Default::default()
            },
            1.1,
        ),
    ] {
        let id = s.add_material(m);
        s.add_mesh(
            sphere(&format!("sphere_{name}"), 0.45, 64, 32, id),
            Mat4::from_translation(Vec3::new(x, 0.45, -1.5)),
        );
    }
    // A normal-mapped glossy torus: the environment on a bumpy surface (Heidrich §9.3).
    let waves = s.textures.len();
    s.textures.push(wave_normal_map());
    let green = s.add_material(Material {
        name: "plastic_green_waves".into(),
        base_color: Vec4::new(0.15, 0.5, 0.15, 1.0),
        roughness: 0.3,
        specular: 1.0,
        normal_texture: Some(TextureRef::new(waves, 0)),
        ..Default::default()
    });
    let mut torus_mesh = torus("torus", 0.35, 0.12, 64, 24, green);
    torus_mesh.compute_tangents();
    s.add_mesh(
        torus_mesh,
        Mat4::from_rotation_translation(Quat::from_rotation_x(0.4), Vec3::new(0.0, 0.3, 0.9)),
    );
    s.environment = Some(sky_env(
        256,
        Vec3::new(0.35, 0.5, 0.8),
        Vec3::new(0.8, 0.8, 0.8),
        Vec3::new(0.2, 0.18, 0.15),
        &[(Vec3::new(0.5, 0.6, 0.6), Vec3::new(30.0, 27.0, 22.0), 400.0)],
    ));
    s.cameras.push(Camera::look_at(
        "spheres_camera",
        Vec3::new(0.0, 1.5, 4.3),
        Vec3::new(0.0, 0.4, 0.0),
        Vec3::Y,
        40f32.to_radians(),
    ));
    s
}
