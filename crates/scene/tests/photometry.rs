//! IES LM-63 and EULUMDAT files made here from known distributions (vendors' files are not
//! free to copy): every symmetry type and photometric type reproduces its distribution within
//! 1 % at 200 directions; tilt data, frames and malformed files.

use glam::Vec3;
use lightlab_core::sampling::{Rng, uniform_sphere};
use lightlab_scene::photometry::{Goniometric, PhotometryType, ies, ldt};

/// A distribution: candela at (horizontal, vertical) angles in degrees.
type Dist = dyn Fn(f32, f32) -> f32;

fn range(a: f32, b: f32, step: f32) -> Vec<f32> {
    let n = ((b - a) / step).round() as usize;
    (0..=n).map(|k| a + k as f32 * step).collect()
}

fn join(v: &[f32]) -> String {
    v.iter()
        .map(|x| format!("{x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// An IES file of type `kind` (1 C, 2 B, 3 A) sampling `f(h, v)`, with `tilt` lines.
fn ies_file(kind: u32, hs: &[f32], vs: &[f32], f: &dyn Fn(f32, f32) -> f32, tilt: &str) -> String {
    // Multiplier 2 and ballast factor 0.5 cancel.
    let mut s = format!(
        "IESNA:LM-63-2002\n[TEST] lightlab test\n[MANUFAC] none\n{tilt}\n1 -1 2.0 {} {} {kind} 2 0.1 0.2 0.05\n0.5 1.0 100\n",
        vs.len(),
        hs.len()
    );
    s += &format!("{}\n{}\n", join(vs), join(hs));
    for &h in hs {
        let row: Vec<f32> = vs.iter().map(|&v| f(h, v)).collect();
        s += &format!("{}\n", join(&row));
    }
    s
}

/// A EULUMDAT file of symmetry `isym` with `mc` C-planes and γ every 2.5°, sampling `f(c, γ)`.
fn ldt_file(isym: u32, mc: usize, f: &dyn Fn(f32, f32) -> f32) -> String {
    let dc = 360.0 / mc as f32;
    let gammas = range(0.0, 180.0, 2.5);
    let mut l: Vec<String> = vec![
        "lightlab".into(),
        "1".into(),
        isym.to_string(),
        mc.to_string(),
        dc.to_string(),
        gammas.len().to_string(),
        "2.5".into(),
    ];
    l.extend(["report", "test luminaire", "1", "test.ldt", "today"].map(String::from));
    l.extend(["600", "300", "80", "500", "250", "0", "0", "0", "0"].map(String::from));
    l.extend(["100", "85", "1.0", "0", "1"].map(String::from));
    l.extend(["1", "LED", "2000", "3000", "90", "20"].map(String::from));
    l.extend((0..10).map(|_| "0.5".to_string()));
    let cs: Vec<f32> = (0..mc).map(|k| k as f32 * dc).collect();
    l.extend(cs.iter().map(|c| c.to_string()));
    l.extend(gammas.iter().map(|g| g.to_string()));
    let (first, last) = match isym {
        0 => (0, mc - 1),
        1 => (0, 0),
        2 => (0, mc / 2),
        3 => (mc / 4, mc / 4 + mc / 2),
        _ => (0, mc / 4),
    };
    for c in &cs[first..=last] {
        // cd/klm: the file's 2000 lm make the values half the candela.
        l.extend(gammas.iter().map(|&g| (f(*c, g) / 2.0).to_string()));
    }
    l.join("\r\n") + "\r\n"
}

/// `g`'s intensities against `f` at 200 directions where `f` has data.
fn check(name: &str, g: &Goniometric, f: &dyn Fn(f32, f32) -> Option<f32>) {
    let mut rng = Rng::new(11, 0);
    let mut worst = 0.0f32;
    let mut n = 0;
    while n < 200 {
        let d = uniform_sphere(rng.next_vec2());
        let (h, v) = g.angles(d);
        let got = g.intensity(d);
        match f(h, v) {
            Some(want) => {
                worst = worst.max((got - want).abs() / want);
                n += 1;
            }
            None => assert_eq!(got, 0.0, "{name}: no data at ({h}, {v})"),
        }
    }
    assert!(worst < 0.01, "{name}: worst relative error {worst}");
}

fn g(gamma: f32) -> f32 {
    100.0 + 400.0 * (gamma.to_radians() / 2.0).cos().powi(2)
}

#[test]
fn type_c_symmetries_reproduce_their_distributions() {
    let vs = range(0.0, 180.0, 2.5);
    let cases: Vec<(&str, Vec<f32>, Box<Dist>)> = vec![
        ("rotational", vec![0.0], Box::new(|_, v| g(v))),
        (
            "quadrant",
            range(0.0, 90.0, 5.0),
            Box::new(|h, v| g(v) * (1.0 + 0.4 * (2.0 * h.to_radians()).cos())),
        ),
        (
            "bilateral C0-C180",
            range(0.0, 180.0, 5.0),
            Box::new(|h, v| g(v) * (1.0 + 0.3 * h.to_radians().cos())),
        ),
        (
            "bilateral C90-C270",
            range(90.0, 270.0, 5.0),
            Box::new(|h, v| g(v) * (1.0 + 0.3 * h.to_radians().sin())),
        ),
        (
            "full",
            range(0.0, 360.0, 5.0),
            Box::new(|h, v| {
                g(v) * (1.0 + 0.3 * h.to_radians().cos() + 0.2 * (2.0 * h.to_radians()).sin())
            }),
        ),
        (
            "full, wrapping",
            range(0.0, 355.0, 5.0),
            Box::new(|h, v| g(v) * (1.0 + 0.3 * h.to_radians().cos())),
        ),
    ];
    for (name, hs, f) in &cases {
        let text = ies_file(1, hs, &vs, f, "TILT=NONE");
        let gon = ies::parse(&text, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(gon.kind, PhotometryType::C);
        check(name, &gon, &|h, v| Some(f(h, v)));
    }
}

#[test]
fn eulumdat_symmetries_reproduce_their_distributions() {
    let cases: Vec<(u32, &str, Box<Dist>)> = vec![
        (
            0,
            "none",
            Box::new(|c, v| {
                g(v) * (1.0 + 0.3 * c.to_radians().cos() + 0.2 * (2.0 * c.to_radians()).sin())
            }),
        ),
        (1, "rotational", Box::new(|_, v| g(v))),
        (
            2,
            "C0-C180",
            Box::new(|c, v| g(v) * (1.0 + 0.3 * c.to_radians().cos())),
        ),
        (
            3,
            "C90-C270",
            Box::new(|c, v| g(v) * (1.0 + 0.3 * c.to_radians().sin())),
        ),
        (
            4,
            "C0-C90",
            Box::new(|c, v| g(v) * (1.0 + 0.4 * (2.0 * c.to_radians()).cos())),
        ),
    ];
    for (isym, name, f) in &cases {
        let gon = ldt::parse(&ldt_file(*isym, 72, f)).unwrap_or_else(|e| panic!("{name}: {e}"));
        check(name, &gon, &|h, v| Some(f(h, v)));
        // Dimensions in metres: width 0.3, length 0.6, height 0.08.
        assert!(gon.opening.abs_diff_eq(Vec3::new(0.3, 0.6, 0.08), 1e-6));
    }
}

#[test]
fn types_a_and_b_reproduce_their_distributions() {
    let vs = range(-90.0, 90.0, 2.5);
    let f = |h: f32, v: f32| {
        300.0 + 200.0 * h.to_radians().cos().powi(2) * (1.0 + 0.3 * v.to_radians().sin())
    };
    for (kind, t) in [(2, PhotometryType::B), (3, PhotometryType::A)] {
        // Full horizontal range, then the half an even distribution needs.
        for hs in [range(-90.0, 90.0, 2.5), range(0.0, 90.0, 2.5)] {
            let gon = ies::parse(&ies_file(kind, &hs, &vs, &f, "TILT=NONE"), None).unwrap();
            assert_eq!(gon.kind, t);
            // Directions behind a type B web (|V| > 90°) have no data; type A covers H in ±90°.
            check(&format!("{t:?}"), &gon, &|h, v| {
                (h.abs() <= 90.0 && v.abs() <= 90.0).then(|| f(h, v))
            });
        }
    }
}

#[test]
fn frames_follow_the_documented_axes() {
    let web = |kind| Goniometric {
        kind,
        vertical: vec![0.0, 90.0],
        horizontal: vec![0.0, 90.0],
        candela: vec![1.0; 4],
        tilt: vec![],
        opening: Vec3::ZERO,
    };
    let c = web(PhotometryType::C);
    assert!(
        c.direction(0.0, 0.0).abs_diff_eq(Vec3::NEG_Z, 1e-6),
        "nadir = the light's direction"
    );
    assert!(
        c.direction(90.0, 90.0).abs_diff_eq(Vec3::Y, 1e-6),
        "C90 counterclockwise from C0 = +X"
    );
    let b = web(PhotometryType::B);
    assert!(b.direction(0.0, 90.0).abs_diff_eq(Vec3::Y, 1e-6));
    assert!(
        b.direction(90.0, 30.0).abs_diff_eq(Vec3::X, 1e-6),
        "the planes' common axis"
    );
    let a = web(PhotometryType::A);
    assert!(a.direction(90.0, 0.0).abs_diff_eq(Vec3::X, 1e-6));
    assert!(a.direction(0.0, 90.0).abs_diff_eq(Vec3::Y, 1e-6));
    // Angles and directions invert each other.
    let mut rng = Rng::new(3, 0);
    for w in [&c, &b, &a] {
        for _ in 0..100 {
            let d = uniform_sphere(rng.next_vec2());
            let (h, v) = w.angles(d);
            assert!(w.direction(h, v).abs_diff_eq(d, 1e-4), "{:?} {d}", w.kind);
        }
    }
}

#[test]
fn tilt_data_is_read_inline_and_from_a_file_beside() {
    let vs = range(0.0, 180.0, 10.0);
    let f = |_: f32, v: f32| g(v);
    let inline = "TILT=INCLUDE\n1\n3\n0 45 90\n1.0 0.9 0.7";
    let gon = ies::parse(&ies_file(1, &[0.0], &vs, &f, inline), None).unwrap();
    assert!((gon.tilt_factor(22.5) - 0.95).abs() < 1e-6);
    assert_eq!(gon.tilt_factor(120.0), 0.7);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("lamp.tlt"), "2\n2\n0 90\n1 0.5\n").unwrap();
    let p = dir.path().join("lamp.ies");
    std::fs::write(&p, ies_file(1, &[0.0], &vs, &f, "TILT=lamp.tlt")).unwrap();
    let gon = ies::read(&p).unwrap();
    assert!((gon.tilt_factor(45.0) - 0.75).abs() < 1e-6);
    // Without a way to read it, a tilt file is refused by name.
    let e = ies::parse(&ies_file(1, &[0.0], &vs, &f, "TILT=lamp.tlt"), None).unwrap_err();
    assert!(e.0.contains("lamp.tlt"), "{e}");
    let e = ies::parse(&ies_file(1, &[0.0], &vs, &f, "TILT=../lamp.tlt"), None).unwrap_err();
    assert!(e.0.contains("lamp.tlt"), "{e}");
}

#[test]
fn malformed_files_are_refused_with_the_reason() {
    let vs = range(0.0, 90.0, 10.0);
    let f = |_: f32, v: f32| g(v);
    let good = ies_file(1, &[0.0], &vs, &f, "TILT=NONE");
    assert!(ies::parse(&good, None).is_ok());
    let cases = [
        (good.replace("TILT=NONE\n", ""), "TILT"),
        (good.replace(" 1 2 0.1", " 7 2 0.1"), "photometric type 7"),
        (good.replace(" 1 2 0.1", " 1 5 0.1"), "units type 5"),
        (good.clone() + " 5", "after the candela"),
        (
            good[..good.len() - 8].to_string(),
            "candela values expected",
        ),
        (good.replace("0 10 20", "0 20 10"), "increasing"),
        (
            good.replace("0.5 1.0 100\n", "0.5 1.0 100 x\n"),
            "not a number",
        ),
        (
            ies_file(1, &[45.0, 90.0], &vs, &f, "TILT=NONE"),
            "start at 0",
        ),
        (
            ies_file(1, &[0.0], &vs, &|_, _| -1.0, "TILT=NONE"),
            "not negative",
        ),
    ];
    for (text, want) in cases {
        let e = ies::parse(&text, None).unwrap_err();
        assert!(e.0.contains(want), "{want}: {e}");
    }
    let good = ldt_file(2, 24, &|_, v| g(v));
    assert!(ldt::parse(&good).is_ok());
    let mut lines: Vec<&str> = good.lines().collect();
    lines[2] = "5";
    assert!(
        ldt::parse(&lines.join("\n"))
            .unwrap_err()
            .0
            .contains("symmetry indicator 5")
    );
    let mut lines: Vec<&str> = good.lines().collect();
    lines.truncate(lines.len() - 3);
    assert!(
        ldt::parse(&lines.join("\n"))
            .unwrap_err()
            .0
            .contains("ends before")
    );
    let mut lines: Vec<&str> = good.lines().collect();
    lines[2] = "4";
    lines[3] = "22";
    assert!(ldt::parse(&lines.join("\n")).is_err());
}

/// 200 well-spread unit directions.
fn directions() -> Vec<Vec3> {
    let mut rng = Rng::new(5, 0);
    (0..200)
        .map(|_| uniform_sphere(glam::Vec2::new(rng.next_f32(), rng.next_f32())))
        .collect()
}

/// A glTF made by hand (not by lightlab's exporter) with two measured lamps on turned nodes:
/// an IES file and a EULUMDAT file beside it.
fn lamp_gltf(dir: &std::path::Path, ies_name: &str) -> std::path::PathBuf {
    let f = |c: f32, v: f32| {
        50.0 + 300.0 * v.to_radians().cos().max(0.0) * (1.0 + 0.5 * c.to_radians().cos())
    };
    let ies = ies_file(
        1,
        &range(0.0, 180.0, 22.5),
        &range(0.0, 180.0, 5.0),
        &f,
        "TILT=NONE",
    );
    std::fs::write(dir.join("down.ies"), ies).unwrap();
    std::fs::write(dir.join("flood.ldt"), ldt_file(0, 24, &f)).unwrap();
    // A floor triangle for the scene to hold.
    let tri: Vec<u8> = [-5.0f32, 0.0, -5.0, 5.0, 0.0, -5.0, 0.0, 0.0, 5.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(dir.join("tri.bin"), tri).unwrap();
    // Node 0: −Z turned onto +X (a quarter turn about −Y), so C0 (+X) goes to +Z.
    let (s, c) = (
        std::f32::consts::FRAC_PI_4.sin(),
        std::f32::consts::FRAC_PI_4.cos(),
    );
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1,2]}}],
"buffers":[{{"uri":"tri.bin","byteLength":36}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[-5,0,-5],"max":[5,0,5]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"extensionsUsed":["KHR_lights_punctual"],
"extensions":{{"KHR_lights_punctual":{{"lights":[
 {{"type":"point","intensity":0.5,"color":[1,0.9,0.8],"extras":{{"lightlab":{{"ies":"{ies_name}"}}}}}},
 {{"type":"spot","intensity":2,"spot":{{"outerConeAngle":0.5}},"extras":{{"lightlab":{{"ies":"flood.ldt"}}}}}}]}}}},
"nodes":[
 {{"name":"down","translation":[1,2,3],"rotation":[0,-{s},0,{c}],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}},
 {{"name":"flood","translation":[0,3,0],"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}},
 {{"name":"floor","mesh":0}}]}}"#
    );
    let path = dir.join("lamps.gltf");
    std::fs::write(&path, gltf).unwrap();
    path
}

#[test]
fn gltf_lights_read_their_profiles_in_the_node_frame() {
    use lightlab_scene::{LightKind, gltf_io};
    let dir = tempfile::tempdir().unwrap();
    let path = lamp_gltf(dir.path(), "down.ies");
    let scene = gltf_io::import(&path, Default::default()).unwrap();
    assert_eq!(scene.lights.len(), 2);
    let down = &scene.lights[0];
    let LightKind::Goniometric { profile, c0 } = &down.kind else {
        panic!("{:?}", down.kind)
    };
    assert!(
        (down.direction - Vec3::X).length() < 1e-5,
        "{}",
        down.direction
    );
    assert!((*c0 - Vec3::Z).length() < 1e-5, "{c0}");
    // World direction d is local (d·C0, d·(Z×C0), −d·direction) = (d.z, −d.y, −d.x)... computed
    // from the frame, and each candela equals the file's there, × the glTF intensity.
    let file = ies::read(&dir.path().join("down.ies")).unwrap();
    for d in directions() {
        let local = Vec3::new(d.z, d.y, -d.x);
        let want = file.intensity(local);
        assert!(
            (down.emission(d) - want).abs() <= 1e-3 * want.max(1.0),
            "{d}"
        );
        assert!((profile.intensity(local) - want).abs() <= 1e-3 * want.max(1.0));
    }
    assert_eq!(down.intensity, 0.5);
    // A spot light with a profile is read as the measured lamp, with a warning.
    assert!(matches!(
        scene.lights[1].kind,
        LightKind::Goniometric { .. }
    ));
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("profile on a spot"))
    );
}

#[test]
fn goniometric_lights_survive_an_export_round_trip() {
    use lightlab_scene::{builtin, gltf_io};
    let scene = builtin::builtin("luminaire").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("room.gltf");
    gltf_io::export(&scene, &out).unwrap();
    assert!(dir.path().join("room.light0.ies").exists());
    let back = gltf_io::import(&out, Default::default()).unwrap();
    assert_eq!(back.lights.len(), scene.lights.len());
    // The reflector lamp's geometry stays marked as its luminaire.
    let marked = |s: &lightlab_scene::Scene| {
        s.instances
            .iter()
            .filter(|i| i.luminaire.as_deref() == Some("reflector"))
            .count()
    };
    assert_eq!(marked(&back), marked(&scene));
    assert_eq!(marked(&scene), 3);
    // The projector's focus (its slab's (s,t) plane) survives too.
    let focus = scene.luminaire_focus["projector"];
    assert!((back.luminaire_focus["projector"] - focus).abs() < 1e-6);
    // A focus that is no distance is refused, naming the node.
    let text = std::fs::read_to_string(&out).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    for node in doc["nodes"].as_array_mut().unwrap() {
        if node["extras"]["lightlab"]["luminaireFocus"].is_number() {
            node["extras"]["lightlab"]["luminaireFocus"] = serde_json::json!(-1.0);
        }
    }
    std::fs::write(&out, serde_json::to_string(&doc).unwrap()).unwrap();
    let e = gltf_io::import(&out, Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("luminaireFocus") && e.contains("node"), "{e}");
    for (a, b) in scene.lights.iter().zip(&back.lights) {
        for d in directions() {
            let (x, y) = (a.emission(d), b.emission(d));
            assert!(
                (x - y).abs() <= 1e-3 * x.max(1.0),
                "{}: {d}: {x} → {y}",
                a.name
            );
        }
        assert_eq!(a.intensity, b.intensity);
    }
}

#[test]
fn a_missing_or_broken_profile_names_the_light_and_the_file() {
    use lightlab_scene::gltf_io;
    let dir = tempfile::tempdir().unwrap();
    let path = lamp_gltf(dir.path(), "nowhere.ies");
    let e = gltf_io::import(&path, Default::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("extras.lightlab.ies") && e.contains("nowhere.ies"),
        "{e}"
    );
    let path = lamp_gltf(dir.path(), "down.ies");
    std::fs::write(
        dir.path().join("down.ies"),
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2",
    )
    .unwrap();
    let e = gltf_io::import(&path, Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("light 0") && e.contains("down.ies"), "{e}");
}
