//! glTF round trips of every built-in scene, and the bad-input cases of the loader.

use glam::{Vec3, Vec4};
use lightlab_scene::{
    BrdfModel, Conductor, LightKind, LoadOptions, Scene, SceneError, builtin, gltf_io, load,
};
use std::path::Path;

fn world_triangles(s: &Scene) -> Vec<[Vec3; 3]> {
    let mut out = vec![];
    for inst in &s.instances {
        let m = &s.meshes[inst.mesh];
        for t in m.indices.chunks_exact(3) {
            out.push(
                [t[0], t[1], t[2]]
                    .map(|i| inst.transform.transform_point3(m.positions[i as usize])),
            );
        }
    }
    out
}

fn assert_same_scene(a: &Scene, b: &Scene) {
    let (ta, tb) = (world_triangles(a), world_triangles(b));
    assert_eq!(ta.len(), tb.len(), "{}: triangle count", a.name);
    for (x, y) in ta.iter().zip(&tb) {
        for k in 0..3 {
            assert!((x[k] - y[k]).length() < 1e-5, "{}: triangle moved", a.name);
        }
    }
    assert_eq!(a.materials.len(), b.materials.len());
    for (x, y) in a.materials.iter().zip(&b.materials) {
        assert_eq!(x.name, y.name);
        assert_eq!(x.base_color, y.base_color);
        assert!((x.emission() - y.emission()).length() < 1e-5 * x.emission().length().max(1.0));
        assert_eq!(
            (x.metallic, x.roughness, x.specular),
            (y.metallic, y.roughness, y.specular)
        );
        assert_eq!(x.alpha_mode, y.alpha_mode);
        assert_eq!(x.double_sided, y.double_sided);
        assert_eq!(x.transmission, y.transmission);
        assert_eq!(x.transmission_texture, y.transmission_texture);
        assert_eq!(x.sway, y.sway);
        assert_eq!(x.brdf, y.brdf);
        assert_eq!(x.conductor, y.conductor);
        assert_eq!(
            (x.anisotropy, x.anisotropy_rotation, x.lafortune),
            (y.anisotropy, y.anisotropy_rotation, y.lafortune)
        );
        assert_eq!(
            (x.specular_transmission, x.ior, x.thickness),
            (y.specular_transmission, y.ior, y.thickness)
        );
        assert_eq!(x.base_color_texture, y.base_color_texture);
        assert_eq!(x.normal_texture, y.normal_texture);
    }
    // Decimated meshes name their high-poly source (by mesh name: indices may differ).
    let detail = |s: &Scene| -> Vec<(String, Option<String>)> {
        s.meshes
            .iter()
            .map(|m| {
                (
                    m.name.clone(),
                    m.detail_source.map(|d| s.meshes[d].name.clone()),
                )
            })
            .collect()
    };
    assert_eq!(detail(a), detail(b), "{}: detail sources", a.name);
    assert_eq!(a.textures.len(), b.textures.len());
    for (x, y) in a.textures.iter().zip(&b.textures) {
        assert_eq!((x.width, x.height), (y.width, y.height));
        for (p, q) in x.to_linear().iter().zip(&y.to_linear()) {
            assert!((*p - *q).abs().max_element() < 0.01, "texel {p} vs {q}");
        }
    }
    assert_eq!(a.lights.len(), b.lights.len());
    for (x, y) in a.lights.iter().zip(&b.lights) {
        assert_eq!(x.name, y.name);
        match (&x.kind, &y.kind) {
            (
                LightKind::Goniometric { profile: p, c0: a },
                LightKind::Goniometric { profile: q, c0: b },
            ) => {
                assert!(p == q, "{}: the profile changed", x.name);
                assert!((*a - *b).length() < 1e-5, "{}: C0 {a} → {b}", x.name);
            }
            (a, b) => assert_eq!(a, b),
        }
        assert_eq!(
            (x.color, x.intensity, x.range),
            (y.color, y.intensity, y.range)
        );
        assert!((x.position - y.position).length() < 1e-5);
        assert!(
            (x.direction - y.direction).length() < 1e-5,
            "{} {}",
            x.direction,
            y.direction
        );
    }
    assert_eq!(a.cameras.len(), b.cameras.len());
    for (x, y) in a.cameras.iter().zip(&b.cameras) {
        assert_eq!(x.yfov, y.yfov);
        assert!(x.transform.abs_diff_eq(y.transform, 1e-5));
    }
    assert_eq!(a.environment.is_some(), b.environment.is_some());
    if let (Some(x), Some(y)) = (&a.environment, &b.environment) {
        assert_eq!(x.image, y.image);
        assert_eq!(x.intensity, y.intensity);
    }
}

#[test]
fn every_builtin_scene_round_trips_through_glb_and_gltf() {
    let dir = tempfile::tempdir().unwrap();
    for name in builtin::NAMES {
        let s = builtin::builtin(name).unwrap();
        for ext in ["glb", "gltf"] {
            let p = dir.path().join(format!("{name}.{ext}"));
            gltf_io::export(&s, &p).unwrap();
            let back = gltf_io::import(&p, LoadOptions::default()).unwrap();
            assert_same_scene(&s, &back);
        }
    }
    // The reflection model travels in extras.lightlab.brdf, the Lafortune lobe in
    // extras.lightlab.lafortune, anisotropy in KHR_materials_anisotropy.
    let mut s = builtin::builtin("shadows").unwrap();
    let models = [BrdfModel::Lambert, BrdfModel::Banks, BrdfModel::Lafortune];
    for (m, b) in s.materials.iter_mut().zip(models) {
        m.brdf = b;
    }
    s.materials[1].anisotropy = 0.6;
    s.materials[1].anisotropy_rotation = 1.25;
    s.materials[2].lafortune = Vec3::new(-1.1, -0.9, 0.8);
    let p = dir.path().join("brdf.gltf");
    gltf_io::export(&s, &p).unwrap();
    let back = gltf_io::import(&p, LoadOptions::default()).unwrap();
    let got: Vec<BrdfModel> = back.materials.iter().map(|m| m.brdf).collect();
    assert_eq!(got, models);
    assert_same_scene(&s, &back);
    // No temporary files are left behind.
    for e in std::fs::read_dir(dir.path()).unwrap() {
        let n = e.unwrap().file_name().into_string().unwrap();
        assert!(!n.ends_with(".tmp"), "{n}");
    }
}

#[test]
fn builtin_scenes_have_cameras_and_the_specified_sizes() {
    for name in builtin::NAMES {
        let s = builtin::builtin(name).unwrap();
        assert!(s.default_camera().is_some(), "{name}");
        assert!(builtin::describe(name).is_some());
        let mut s2 = s.clone();
        lightlab_scene::validate::validate(&mut s2, Path::new(name), LoadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let bush = builtin::builtin("bush").unwrap();
    let leaves = bush.meshes.iter().find(|m| m.name == "leaves").unwrap();
    assert!((19_000..=21_000).contains(&leaves.triangle_count()));
    let prt = builtin::builtin("prt").unwrap();
    let high = prt.meshes.iter().find(|m| m.name == "knot_high").unwrap();
    assert!((50_000..=200_000).contains(&high.triangle_count()));
    // The decimated knot: meshopt's simplification to ≈2 % that names the high-poly knot.
    let low = prt.meshes.iter().find(|m| m.name == "knot_low").unwrap();
    assert!(
        (1_000..=2_500).contains(&low.triangle_count()),
        "{}",
        low.triangle_count()
    );
    assert_eq!(
        low.detail_source.map(|d| prt.meshes[d].name.as_str()),
        Some("knot_high")
    );
    assert!(prt.materials.iter().any(|m| m.normal_texture.is_some()));
    let cornell = builtin::builtin("cornell").unwrap();
    assert!(cornell.materials.iter().any(|m| m.is_emissive()));
    // brdfs: the Fig 5.2 torus at 200 × 200, and the Fig 5.3 tangent fields as authored
    // (circular: round the centre; radial: away from it), orthogonal to the normals; Fig 9.1's
    // bumped sphere and torus share one normal-mapped material.
    let brdfs = builtin::builtin("brdfs").unwrap();
    assert_eq!(brdfs.triangle_count(), 200_096);
    let bumpy = brdfs
        .materials
        .iter()
        .position(|m| m.normal_texture.is_some());
    let bumped: Vec<&str> = brdfs
        .meshes
        .iter()
        .filter(|m| Some(m.material) == bumpy)
        .map(|m| m.name.as_str())
        .collect();
    assert_eq!(bumped, ["sphere_perlin", "torus_perlin"]);
    let torus = brdfs
        .meshes
        .iter()
        .find(|m| m.name == "torus_ts_0.4")
        .unwrap();
    assert_eq!(torus.triangle_count(), 80_000);
    for (name, radial) in [("disk_banks_circular", false), ("disk_banks_radial", true)] {
        let d = brdfs.meshes.iter().find(|m| m.name == name).unwrap();
        for (p, t) in d
            .positions
            .iter()
            .zip(&d.tangents)
            .filter(|(p, _)| p.length() > 0.01)
        {
            let along = t.truncate().dot(p.normalize()).abs();
            assert!(
                if radial { along > 0.999 } else { along < 1e-3 },
                "{name}: {t} at {p}"
            );
        }
        for (n, t) in d.normals.iter().zip(&d.tangents) {
            assert!(n.dot(t.truncate()).abs() < 1e-5);
        }
    }
}

/// Every triangle of a closed mesh shares each of its edges with exactly one other triangle
/// (after welding coincident positions): the shadow-volume scene needs this.
#[test]
fn shadow_scene_meshes_are_closed() {
    let s = builtin::builtin("shadows").unwrap();
    for m in &s.meshes {
        let key = |p: Vec3| (p * 1e4).round().as_ivec3().to_array();
        let mut edges = std::collections::HashMap::new();
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                let (a, b) = (
                    key(m.positions[t[k] as usize]),
                    key(m.positions[t[(k + 1) % 3] as usize]),
                );
                *edges.entry((a, b)).or_insert(0i32) += 1;
                *edges.entry((b, a)).or_insert(0i32) -= 1;
            }
        }
        // Each directed edge must be matched by its reverse.
        assert!(
            edges.values().all(|&c| c == 0),
            "mesh '{}' is not closed",
            m.name
        );
    }
}

// ---- bad input -------------------------------------------------------------------------------

/// Write a .gltf with the given JSON and binary buffer (as `<stem>.bin`).
fn write_gltf(dir: &Path, name: &str, json: serde_json::Value, bin: &[u8]) -> std::path::PathBuf {
    let p = dir.join(format!("{name}.gltf"));
    std::fs::write(dir.join(format!("{name}.bin")), bin).unwrap();
    std::fs::write(&p, serde_json::to_vec(&json).unwrap()).unwrap();
    p
}

/// One triangle (positions, optional normals), with indices.
fn triangle_file(
    dir: &Path,
    name: &str,
    positions: [[f32; 3]; 3],
    normals: bool,
    extra: impl FnOnce(&mut serde_json::Value),
) -> std::path::PathBuf {
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let mut attrs = serde_json::json!({ "POSITION": 0 });
    let mut views = vec![serde_json::json!({ "buffer": 0, "byteOffset": 0, "byteLength": 36 })];
    let mut accessors = vec![
        serde_json::json!({ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
        "min": [-10.0, -10.0, -10.0], "max": [10.0, 10.0, 10.0] }),
    ];
    if normals {
        bin.extend(
            [0f32, 0.0, 1.0]
                .repeat(3)
                .iter()
                .flat_map(|f| f.to_le_bytes()),
        );
        views.push(serde_json::json!({ "buffer": 0, "byteOffset": 36, "byteLength": 36 }));
        accessors.push(serde_json::json!({ "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3" }));
        attrs["NORMAL"] = serde_json::json!(1);
    }
    let mut json = serde_json::json!({
        "asset": { "version": "2.0" },
        "scene": 0, "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "name": "tri", "primitives": [{ "attributes": attrs }] }],
        "buffers": [{ "uri": format!("{name}.bin"), "byteLength": bin.len() }],
        "bufferViews": views,
        "accessors": accessors,
    });
    extra(&mut json);
    write_gltf(dir, name, json, &bin)
}

const GOOD: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

fn load_err(p: &Path) -> String {
    let e = load(p.to_str().unwrap(), LoadOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains(p.file_name().unwrap().to_str().unwrap()),
        "error does not name the file: {msg}"
    );
    msg
}

#[test]
fn a_good_minimal_file_loads_and_gets_a_framing_camera() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(dir.path(), "good", GOOD, true, |_| {});
    let s = load(p.to_str().unwrap(), LoadOptions::default()).unwrap();
    assert_eq!(s.triangle_count(), 1);
    // The file has no camera: one framing the triangle is added, looking at its centre.
    let cam = s.default_camera().unwrap();
    let centre = Vec3::new(0.5, 0.5, 0.0);
    let d = cam.ray_direction(glam::Vec2::ZERO, 1.0);
    assert!((d - (centre - cam.position()).normalize()).length() < 1e-5);
}

/// Measured metals (extras.lightlab.conductor: a preset or an explicit complex index) and
/// KHR_materials_volume load; bad ones are named.
#[test]
fn conductors_and_volumes_load_and_bad_ones_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let with = |name: &str, conductor: serde_json::Value| {
        triangle_file(dir.path(), name, GOOD, true, |j| {
            j["materials"] = serde_json::json!([{
                "name": "m",
                "extras": { "lightlab": { "conductor": conductor } },
                "extensions": {
                    "KHR_materials_transmission": { "transmissionFactor": 0.5 },
                    "KHR_materials_volume": { "thicknessFactor": 0.25 }
                }
            }]);
            j["meshes"][0]["primitives"][0]["material"] = serde_json::json!(0);
            j["extensionsUsed"] =
                serde_json::json!(["KHR_materials_transmission", "KHR_materials_volume"]);
            j["extensionsRequired"] = serde_json::json!(["KHR_materials_volume"]);
        })
    };
    let s = load(
        with("gold", serde_json::json!("gold")).to_str().unwrap(),
        LoadOptions::default(),
    )
    .unwrap();
    let m = &s.materials[0];
    assert_eq!(m.conductor, Conductor::preset("gold"));
    assert_eq!((m.specular_transmission, m.thickness), (0.5, 0.25));
    let explicit = serde_json::json!({ "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.1] });
    let s = load(
        with("explicit", explicit).to_str().unwrap(),
        LoadOptions::default(),
    )
    .unwrap();
    let c = s.materials[0].conductor.unwrap();
    assert_eq!(
        (c.eta, c.k),
        (Vec3::new(0.2, 0.9, 1.1), Vec3::new(3.9, 2.4, 2.1))
    );
    for (name, bad, says) in [
        (
            "tin",
            serde_json::json!("tin"),
            "'tin' is not a known metal",
        ),
        (
            "short",
            serde_json::json!({ "eta": [1, 2], "k": [1, 2, 3] }),
            "'eta' as three numbers",
        ),
        (
            "neg",
            serde_json::json!({ "eta": [1, 2, 3], "k": [1, -2, 3] }),
            "k >= 0",
        ),
        ("num", serde_json::json!(3), "must be a metal's name"),
    ] {
        let msg = load_err(&with(name, bad));
        assert!(
            msg.contains("conductor") && msg.contains(says),
            "{name}: {msg}"
        );
    }
}

/// KHR_materials_anisotropy (required by the file) and extras.lightlab.lafortune load; a bad
/// lobe is named.
#[test]
fn anisotropy_and_lafortune_lobes_load() {
    let dir = tempfile::tempdir().unwrap();
    let with = |name: &str, lobe: serde_json::Value| {
        triangle_file(dir.path(), name, GOOD, true, |j| {
            j["materials"] = serde_json::json!([{
                "name": "brushed",
                "extras": { "lightlab": { "brdf": "lafortune", "lafortune": lobe } },
                "extensions": {
                    "KHR_materials_anisotropy": {
                        "anisotropyStrength": 0.6,
                        "anisotropyRotation": 0.5
                    }
                }
            }]);
            j["meshes"][0]["primitives"][0]["material"] = serde_json::json!(0);
            j["extensionsUsed"] = serde_json::json!(["KHR_materials_anisotropy"]);
            j["extensionsRequired"] = serde_json::json!(["KHR_materials_anisotropy"]);
        })
    };
    let s = load(
        with("good", serde_json::json!([-1.2, -0.8, 1.0]))
            .to_str()
            .unwrap(),
        LoadOptions::default(),
    )
    .unwrap();
    let m = &s.materials[0];
    assert_eq!(m.brdf, BrdfModel::Lafortune);
    assert_eq!((m.anisotropy, m.anisotropy_rotation), (0.6, 0.5));
    assert_eq!(m.lafortune, Vec3::new(-1.2, -0.8, 1.0));
    for (name, bad) in [
        ("two", serde_json::json!([1, 2])),
        ("text", serde_json::json!("phong")),
    ] {
        let msg = load_err(&with(name, bad));
        assert!(
            msg.contains("lafortune") && msg.contains("[Cx, Cy, Cz]"),
            "{name}: {msg}"
        );
    }
}

#[test]
fn malformed_and_truncated_files_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.gltf");
    std::fs::write(&p, b"{ \"asset\": { \"version\": ").unwrap();
    load_err(&p);
    let p = dir.path().join("short.glb");
    std::fs::write(&p, b"glTF\x02\x00\x00\x00").unwrap();
    load_err(&p);
    // A real GLB cut in half.
    let full = dir.path().join("full.glb");
    gltf_io::export(&builtin::builtin("cornell").unwrap(), &full).unwrap();
    let bytes = std::fs::read(&full).unwrap();
    let p = dir.path().join("half.glb");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    load_err(&p);
    let p = dir.path().join("missing.glb");
    assert!(matches!(
        load(p.to_str().unwrap(), LoadOptions::default()),
        Err(SceneError::Io { .. })
    ));
}

#[test]
fn missing_buffer_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(dir.path(), "nobin", GOOD, true, |j| {
        j["buffers"][0]["uri"] = "absent.bin".into()
    });
    let msg = load_err(&p);
    assert!(msg.contains("buffer"), "{msg}");
}

#[test]
fn unsupported_required_extension_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(dir.path(), "draco", GOOD, true, |j| {
        j["extensionsUsed"] = serde_json::json!(["KHR_draco_mesh_compression"]);
        j["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
    });
    let msg = load_err(&p);
    assert!(msg.contains("KHR_draco_mesh_compression"), "{msg}");
}

#[test]
fn nan_positions_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(
        dir.path(),
        "nan",
        [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
        true,
        |_| {},
    );
    let msg = load_err(&p);
    assert!(msg.contains("NaN"), "{msg}");
    let p = triangle_file(
        dir.path(),
        "inf",
        [[0.0, 0.0, 0.0], [f32::INFINITY, 0.0, 0.0], [0.0, 1.0, 0.0]],
        true,
        |_| {},
    );
    load_err(&p);
}

/// Node cycles, self-cycles and very deep chains are errors naming the node, not stack
/// overflows (exit 134).
#[test]
fn node_cycles_and_deep_chains_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let chain = |n: usize| -> Vec<serde_json::Value> {
        (0..n)
            .map(|i| {
                if i + 1 < n {
                    serde_json::json!({ "children": [i + 1] })
                } else {
                    serde_json::json!({ "mesh": 0 })
                }
            })
            .collect()
    };
    let cases: Vec<(&str, serde_json::Value, &str)> = vec![
        (
            "self",
            serde_json::json!([{ "mesh": 0, "children": [0] }]),
            "reached twice",
        ),
        (
            "pair",
            serde_json::json!([{ "mesh": 0, "children": [1] }, { "children": [0] }]),
            "reached twice",
        ),
        ("deep", serde_json::json!(chain(10_000)), "deeper than"),
    ];
    for (name, nodes, needle) in cases {
        let p = triangle_file(dir.path(), name, GOOD, true, |j| {
            j["nodes"] = nodes.clone();
        });
        let msg = load_err(&p);
        assert!(
            msg.contains(needle) || msg.contains("invalid"),
            "{name}: {msg}"
        );
    }
    // A chain of 100 levels is fine.
    let p = triangle_file(dir.path(), "ok", GOOD, true, |j| {
        j["nodes"] = serde_json::json!(chain(100));
    });
    assert_eq!(
        load(p.to_str().unwrap(), LoadOptions::default())
            .unwrap()
            .triangle_count(),
        1
    );
}

/// World coordinates beyond ±1e15 m (a huge node scale, or huge positions) are refused at load
/// instead of overflowing the BVH build; the scale's determinant is checked in f64.
#[test]
fn coordinates_too_far_from_the_origin_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    for (name, scale) in [("scale19", 1e19f32), ("scale30", 1e30)] {
        let p = triangle_file(dir.path(), name, GOOD, true, |j| {
            j["nodes"][0]["scale"] = serde_json::json!([scale, scale, scale]);
        });
        let msg = load_err(&p);
        assert!(msg.contains("1e15") || msg.contains("singular"), "{msg}");
    }
    let p = triangle_file(
        dir.path(),
        "far",
        [[0.0, 0.0, 0.0], [1e30, 0.0, 0.0], [0.0, 1.0, 0.0]],
        true,
        |_| {},
    );
    assert!(load_err(&p).contains("1e15"));
    // Large but sane: a kilometre-scale scene loads.
    let p = triangle_file(dir.path(), "km", GOOD, true, |j| {
        j["nodes"][0]["scale"] = serde_json::json!([1000.0, 1000.0, 1000.0]);
    });
    load(p.to_str().unwrap(), LoadOptions::default()).unwrap();
}

#[test]
fn degenerate_triangles_are_dropped_or_refused_with_strict() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(
        dir.path(),
        "degen",
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
        true,
        |_| {},
    );
    // Dropping (the default) leaves nothing here, which is an error.
    let msg = load_err(&p);
    assert!(msg.contains("zero area") && msg.contains("'tri'"), "{msg}");
    let e = load(
        p.to_str().unwrap(),
        LoadOptions {
            strict: true,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("--strict"), "{e}");
}

#[test]
fn missing_normals_are_computed_as_the_spec_requires() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(dir.path(), "nonormals", GOOD, false, |_| {});
    let s = load(p.to_str().unwrap(), LoadOptions::default()).unwrap();
    assert!(
        s.meshes[0]
            .normals
            .iter()
            .all(|n| (*n - Vec3::Z).length() < 1e-6)
    );
}

#[test]
fn textured_mesh_without_uvs_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    // A 1×1 PNG as the texture.
    let mut png = vec![];
    image::RgbaImage::from_raw(1, 1, vec![255, 0, 0, 255])
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(dir.path().join("t.png"), &png).unwrap();
    let p = triangle_file(dir.path(), "nouv", GOOD, true, |j| {
        j["images"] = serde_json::json!([{ "uri": "t.png" }]);
        j["textures"] = serde_json::json!([{ "source": 0 }]);
        j["materials"] =
            serde_json::json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
        j["meshes"][0]["primitives"][0]["material"] = 0.into();
    });
    let msg = load_err(&p);
    assert!(msg.contains("TEXCOORD_0"), "{msg}");
}

#[test]
fn missing_and_empty_images_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(dir.path(), "noimg", GOOD, true, |j| {
        j["images"] = serde_json::json!([{ "uri": "absent.png" }]);
        j["textures"] = serde_json::json!([{ "source": 0 }]);
    });
    let msg = load_err(&p);
    assert!(msg.contains("image"), "{msg}");
    std::fs::write(dir.path().join("empty.png"), b"").unwrap();
    let p = triangle_file(dir.path(), "emptyimg", GOOD, true, |j| {
        j["images"] = serde_json::json!([{ "uri": "empty.png" }]);
        j["textures"] = serde_json::json!([{ "source": 0 }]);
    });
    load_err(&p);
}

#[test]
fn unknown_scene_names_are_explained() {
    let e = load("no-such-scene", LoadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("lightlab scenes"), "{e}");
}

#[test]
fn export_refuses_other_extensions_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let s = builtin::builtin("cornell").unwrap();
    assert!(gltf_io::export(&s, &dir.path().join("x.obj")).is_err());
    assert!(gltf_io::export(&s, &dir.path().join("nodir/x.glb")).is_err());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    let _ = Vec4::ZERO;
}

/// A decimated mesh's high-poly source travels in `extras.lightlab.detailSource` and is loaded
/// even when no node shows it; a source index that names no other mesh is an error.
#[test]
fn detail_sources_load_without_an_instance_and_bad_ones_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = builtin::builtin("prt").unwrap();
    // Only the decimated knot (and the ground) are shown; the high-poly knot is only its source.
    s.instances.retain(|i| i.name != "knot_high");
    let p = dir.path().join("decimated.gltf");
    gltf_io::export(&s, &p).unwrap();
    let back = gltf_io::import(&p, LoadOptions::default()).unwrap();
    let low = back.meshes.iter().find(|m| m.name == "knot_low").unwrap();
    let src = low.detail_source.expect("the source link survives");
    assert_eq!(back.meshes[src].name, "knot_high");
    assert_eq!(back.meshes[src].triangle_count(), 86_400);
    assert!(!back.instances.iter().any(|i| i.mesh == src));
    // A source that names the mesh itself.
    let text = std::fs::read_to_string(&p).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let meshes = json["meshes"].as_array_mut().unwrap();
    let k = meshes.iter().position(|m| m["name"] == "knot_low").unwrap();
    meshes[k]["extras"]["lightlab"]["detailSource"] = serde_json::json!(k);
    std::fs::write(&p, serde_json::to_string(&json).unwrap()).unwrap();
    let msg = load_err(&p);
    assert!(msg.contains("detailSource"), "{msg}");
}

/// Little-endian bytes of floats.
fn f32_bytes<const N: usize>(v: &[[f32; N]]) -> Vec<u8> {
    v.iter().flatten().flat_map(|f| f.to_le_bytes()).collect()
}

/// `GOOD` under a node at (0, 0, 1) with EXT_mesh_gpu_instancing: translations (0,0,0),
/// (5,0,0), (0,5,0); the second scaled by 2, the third turned 90° about z. `counts` are the
/// accessor counts of TRANSLATION, ROTATION and SCALE (3 each for a good file).
fn instanced_file(dir: &Path, name: &str, counts: [usize; 3]) -> std::path::PathBuf {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let t = f32_bytes(&[[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 5.0, 0.0]]);
    let r = f32_bytes(&[[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, h, h]]);
    let s = f32_bytes(&[[1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [1.0, 1.0, 1.0]]);
    let bin = [t, r, s].concat();
    std::fs::write(dir.join(format!("{name}-inst.bin")), &bin).unwrap();
    triangle_file(dir, name, GOOD, true, |j| {
        j["extensionsUsed"] = serde_json::json!(["EXT_mesh_gpu_instancing"]);
        // Required, as files without a fallback declare it (the gltf crate alone refuses that).
        j["extensionsRequired"] = serde_json::json!(["EXT_mesh_gpu_instancing"]);
        j["nodes"][0]["translation"] = serde_json::json!([0.0, 0.0, 1.0]);
        j["nodes"][0]["extensions"] = serde_json::json!({ "EXT_mesh_gpu_instancing": {
            "attributes": { "TRANSLATION": 2, "ROTATION": 3, "SCALE": 4 } } });
        let buffers = j["buffers"].as_array_mut().unwrap();
        buffers.push(
            serde_json::json!({ "uri": format!("{name}-inst.bin"), "byteLength": bin.len() }),
        );
        let views = j["bufferViews"].as_array_mut().unwrap();
        for (offset, len) in [(0, 36), (36, 48), (84, 36)] {
            views.push(serde_json::json!({ "buffer": 1, "byteOffset": offset, "byteLength": len }));
        }
        let accessors = j["accessors"].as_array_mut().unwrap();
        for (k, (ty, count)) in [
            ("VEC3", counts[0]),
            ("VEC4", counts[1]),
            ("VEC3", counts[2]),
        ]
        .into_iter()
        .enumerate()
        {
            accessors.push(serde_json::json!({
                "bufferView": 2 + k, "componentType": 5126, "count": count, "type": ty }));
        }
    })
}

#[test]
fn gpu_instancing_draws_the_mesh_once_per_transform() {
    let dir = tempfile::tempdir().unwrap();
    let p = instanced_file(dir.path(), "inst", [3, 3, 3]);
    let s = load(p.to_str().unwrap(), LoadOptions::default()).unwrap();
    assert_eq!(s.instances.len(), 3);
    assert_eq!(s.meshes.len(), 1, "the instances share one mesh");
    let tris = world_triangles(&s);
    let near = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    // Vertex (1, 0, 0) of each instance.
    assert!(near(tris[0][1], Vec3::new(1.0, 0.0, 1.0)), "{:?}", tris[0]);
    assert!(near(tris[1][1], Vec3::new(7.0, 0.0, 1.0)), "{:?}", tris[1]);
    assert!(near(tris[2][1], Vec3::new(0.0, 6.0, 1.0)), "{:?}", tris[2]);
    assert!(
        s.warnings.iter().all(|w| !w.contains("instanc")),
        "{:?}",
        s.warnings
    );
    // A GLB requiring KHR_materials_specular (rebuilt around the relaxed JSON).
    let glb = dir.path().join("inst.glb");
    lightlab_scene::gltf_io::export(&s, &glb).unwrap();
    let mut bytes = std::fs::read(&glb).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut v: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    v["extensionsUsed"] = serde_json::json!(["KHR_materials_specular"]);
    v["extensionsRequired"] = serde_json::json!(["KHR_materials_specular"]);
    let mut text = serde_json::to_vec(&v).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let rest = bytes[(20 + json_len).next_multiple_of(4)..].to_vec();
    bytes.truncate(12);
    bytes[8..12].copy_from_slice(&((20 + text.len() + rest.len()) as u32).to_le_bytes());
    bytes.extend_from_slice(&(text.len() as u32).to_le_bytes());
    bytes.extend_from_slice(b"JSON");
    bytes.extend_from_slice(&text);
    bytes.extend_from_slice(&rest);
    std::fs::write(&glb, &bytes).unwrap();
    let g = load(glb.to_str().unwrap(), LoadOptions::default()).unwrap();
    assert_eq!(g.instances.len(), 3);
    // Attributes of different counts are refused, naming the extension.
    let bad = instanced_file(dir.path(), "bad", [3, 2, 3]);
    let msg = load_err(&bad);
    assert!(
        msg.contains("EXT_mesh_gpu_instancing") && msg.contains("count"),
        "{msg}"
    );
}

#[test]
fn a_camera_node_scale_scales_its_clip_distances() {
    let dir = tempfile::tempdir().unwrap();
    let p = triangle_file(dir.path(), "cam", GOOD, true, |j| {
        j["nodes"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({ "camera": 0, "translation": [0.0, 0.0, 3.0], "scale": [2.0, 2.0, 2.0] }));
        j["scenes"][0]["nodes"] = serde_json::json!([0, 1]);
        j["cameras"] = serde_json::json!([{ "type": "perspective",
            "perspective": { "yfov": 0.8, "znear": 0.1, "zfar": 10.0 } }]);
    });
    let s = load(p.to_str().unwrap(), LoadOptions::default()).unwrap();
    let cam = &s.cameras[0];
    assert!((cam.znear - 0.2).abs() < 1e-6, "znear {}", cam.znear);
    assert!((cam.zfar.unwrap() - 20.0).abs() < 1e-4);
    // The view itself is rigid: the camera sits at the node's position, unscaled.
    assert!((cam.position() - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-6);
    assert!((cam.transform.x_axis.length() - 1.0).abs() < 1e-6);
}

#[test]
fn texture_transforms_and_vertex_colours_round_trip() {
    use lightlab_scene::UvTransform;
    let mut s = lightlab_scene::builtin::builtin("bush").unwrap();
    let t = UvTransform::new(glam::Vec2::new(0.25, -0.5), -2.5, glam::Vec2::new(3.0, 0.5));
    let m = s
        .materials
        .iter()
        .position(|m| m.base_color_texture.is_some())
        .unwrap();
    s.materials[m]
        .base_color_texture
        .as_mut()
        .unwrap()
        .transform = t;
    for mesh in &mut s.meshes {
        mesh.colors = (0..mesh.positions.len())
            .map(|i| glam::Vec4::new((i % 7) as f32 / 6.0, 0.5, 1.0, (i % 3) as f32 / 2.0))
            .collect();
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.glb");
    lightlab_scene::gltf_io::export(&s, &p).unwrap();
    let b = load(p.to_str().unwrap(), LoadOptions::default()).unwrap();
    let got = b.materials[m].base_color_texture.unwrap().transform;
    for (x, y) in got.0.iter().flatten().zip(t.0.iter().flatten()) {
        assert!((x - y).abs() < 1e-5, "{got:?} vs {t:?}");
    }
    for (x, y) in s.meshes.iter().zip(&b.meshes) {
        assert_eq!(x.colors.len(), y.colors.len(), "{}", x.name);
        for (p, q) in x.colors.iter().zip(&y.colors) {
            assert!((*p - *q).abs().max_element() < 1e-6);
        }
    }
    assert!(
        b.warnings
            .iter()
            .all(|w| !w.contains("COLOR_0") && !w.contains("transform"))
    );
}

/// A camera's lens travels in `extras.lightlab.lens`; a prescription file named in it is
/// found beside the glTF file; a malformed lens is refused with the camera's name.
#[test]
fn camera_lenses_round_trip_in_extras() {
    use lightlab_scene::CameraLens;
    let dir = tempfile::tempdir().unwrap();
    let mut s = builtin::builtin("shadows").unwrap();
    s.cameras[0].lens = Some(CameraLens {
        model: "thick-lens".into(),
        aperture: Some(0.2),
        focus_distance: Some(4.5),
        thickness: Some(0.1),
        scale: None,
    });
    let p = dir.path().join("lens.gltf");
    gltf_io::export(&s, &p).unwrap();
    let back = gltf_io::import(&p, LoadOptions::default()).unwrap();
    assert_eq!(back.cameras[0].lens, s.cameras[0].lens);
    // A prescription file is relative to the glTF file.
    s.cameras[0].lens = Some(CameraLens {
        model: "lens:my.lens".into(),
        ..Default::default()
    });
    gltf_io::export(&s, &p).unwrap();
    let back = gltf_io::import(&p, LoadOptions::default()).unwrap();
    let want = format!("lens:{}", dir.path().join("my.lens").display());
    assert_eq!(back.cameras[0].lens.as_ref().unwrap().model, want);
    // Without a model, or with a number that is not one: refused, naming the camera.
    let text = std::fs::read_to_string(&p).unwrap();
    let original = "\"model\": \"lens:my.lens\"";
    assert!(text.contains(original));
    for bad in [
        "\"x\": 1",
        "\"model\": \"thin-lens\", \"aperture\": \"wide\"",
    ] {
        let q = dir.path().join("bad.gltf");
        std::fs::write(&q, text.replace(original, bad)).unwrap();
        let e = gltf_io::import(&q, LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("extras.lightlab.lens"), "{e}");
    }
}
