//! Planar mirrors (Heidrich 1999 ch. 10 intro): the built-in `mirror` scene's wall mirror drawn
//! from the mirrored eye, against the path tracer on the mirror's pixels. Direct light only on
//! both sides (no environment, no ambient term): what the mirror shows is then each visible
//! point's direct light, which the path tracer reaches at depth 2 (the mirror, then the point).

use glam::Vec3;
use lightlab_core::image::Image;
use lightlab_core::metrics::relmse_masked;
use lightlab_gpu::raster::{Ambient, RasterSettings, RenderPath, Renderer, ShadowMethod};
use lightlab_gpu::test_context;
use lightlab_scene::{Camera, Scene, builtin};
use lightlab_trace::render::coverage_mask;
use lightlab_trace::{Accel, PathTracer, RenderSettings};

const W: u32 = 96;
const H: u32 = 72;

fn scene() -> Scene {
    let mut s = builtin::builtin("mirror").unwrap();
    s.environment = None;
    s
}

/// 2 × 2 supersampled, as the demo renders.
fn gpu(scene: &Scene, path: RenderPath, planar_mirrors: bool) -> Image {
    let ctx = test_context().expect("GPU");
    let settings = RasterSettings {
        width: 2 * W,
        height: 2 * H,
        path,
        shadows: ShadowMethod::Map,
        ambient: Ambient::None,
        planar_mirrors,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, scene, settings).unwrap();
    r.render(&ctx);
    r.read_hdr(&ctx).unwrap().downsample(2)
}

fn reference(scene: &Scene) -> Image {
    let accel = Accel::new(scene);
    let pt = PathTracer::new(scene, &accel);
    let s = RenderSettings {
        width: W,
        height: H,
        spp: 256,
        max_depth: 2,
        ..Default::default()
    };
    pt.render(&s, &|_, _| true).unwrap()
}

/// Pixels whose 3 × 3 sub-pixel rays all hit the mirror (its inside, not its edges).
fn mirror_pixels(scene: &Scene) -> Vec<bool> {
    let mirror = scene
        .instances
        .iter()
        .position(|i| i.name == "mirror")
        .unwrap();
    coverage_mask(scene, &scene.cameras[0], W, H, &[mirror])
}

fn check_view(scene: &Scene, label: &str) -> f64 {
    let mask = mirror_pixels(scene);
    let count = mask.iter().filter(|m| **m).count();
    assert!(
        count > 300,
        "{label}: the camera sees the mirror ({count} pixels)"
    );
    let want = reference(scene);
    let mean: f32 = want
        .data
        .iter()
        .zip(&mask)
        .filter(|(_, m)| **m)
        .map(|(p, _)| p.x + p.y + p.z)
        .sum::<f32>()
        / count as f32;
    assert!(mean > 0.05, "{label}: the mirror shows lit things ({mean})");
    let planar = gpu(scene, RenderPath::Forward, true);
    if let Ok(dir) = std::env::var("LIGHTLAB_TEST_IMAGES") {
        let ldr = Default::default();
        let dir = std::path::Path::new(&dir);
        want.write(&dir.join(format!("mirror-{label}-reference.png")), ldr)
            .unwrap();
        planar
            .write(&dir.join(format!("mirror-{label}-gpu.png")), ldr)
            .unwrap();
    }
    let err = relmse_masked(&planar, &want, &mask).unwrap();
    let without = relmse_masked(&gpu(scene, RenderPath::Forward, false), &want, &mask).unwrap();
    eprintln!(
        "{label}: mirror pixels {count}: planar mirror relMSE {err:.5}, without {without:.4}"
    );
    assert!(err <= 0.01, "{label}: planar mirror relMSE {err}");
    assert!(
        without > 0.3,
        "{label}: without the reflection the mirror is wrong: {without}"
    );
    err
}

#[test]
fn a_planar_mirror_shows_the_path_traced_reflection() {
    if test_context().is_none() {
        return;
    }
    let mut scene = scene();
    check_view(&scene, "default camera");
    // From the other side of the room, looking at the mirror across the objects.
    scene.cameras[0] = Camera::look_at(
        "left",
        Vec3::new(-2.2, 1.3, 2.6),
        Vec3::new(0.6, 1.2, -1.9),
        Vec3::Y,
        50f32.to_radians(),
    );
    check_view(&scene, "left camera");
    // The deferred path reads the same reflected view.
    let mask = mirror_pixels(&scene);
    let fwd = gpu(&scene, RenderPath::Forward, true);
    let def = gpu(&scene, RenderPath::Deferred, true);
    let d = relmse_masked(&def, &fwd, &mask).unwrap();
    eprintln!("deferred against forward on the mirror: {d:.6}");
    assert!(d < 1e-3, "deferred {d}");
}

/// A glTF file written by hand (not by lightlab): a floor, a metallic roughness-0 quad as the
/// mirror, and a red panel behind the camera that only the mirror shows.
fn hand_written_gltf(dir: &std::path::Path) -> std::path::PathBuf {
    let quads: [[[f32; 3]; 4]; 3] = [
        // Floor (+Y), mirror (+Z, at z = −1), red panel (−Z, at z = 3: behind the camera).
        [
            [-3.0, 0.0, 3.5],
            [3.0, 0.0, 3.5],
            [3.0, 0.0, -2.0],
            [-3.0, 0.0, -2.0],
        ],
        [
            [-1.0, 0.2, -1.0],
            [1.0, 0.2, -1.0],
            [1.0, 1.6, -1.0],
            [-1.0, 1.6, -1.0],
        ],
        [
            [0.8, 0.0, 3.0],
            [-0.8, 0.0, 3.0],
            [-0.8, 1.8, 3.0],
            [0.8, 1.8, 3.0],
        ],
    ];
    let normals = [[0.0f32, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    let mut bin: Vec<u8> = vec![];
    for q in &quads {
        for p in q {
            bin.extend(p.iter().flat_map(|v| v.to_le_bytes()));
        }
    }
    for n in &normals {
        for _ in 0..4 {
            bin.extend(n.iter().flat_map(|v| v.to_le_bytes()));
        }
    }
    for k in 0..3u16 {
        for i in [0u16, 1, 2, 0, 2, 3] {
            bin.extend((4 * k + i).to_le_bytes());
        }
    }
    std::fs::write(dir.join("room.bin"), &bin).unwrap();
    let gltf = r#"{"asset":{"version":"2.0","generator":"written by hand"},"scene":0,
"scenes":[{"nodes":[0,1,2,3,4]}],
"buffers":[{"uri":"room.bin","byteLength":324}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":144},{"buffer":0,"byteOffset":144,"byteLength":144},
 {"buffer":0,"byteOffset":288,"byteLength":36}],
"accessors":[
 {"bufferView":0,"componentType":5126,"count":12,"type":"VEC3","min":[-3,0,-2],"max":[3,1.8,3.5]},
 {"bufferView":1,"componentType":5126,"count":12,"type":"VEC3"},
 {"bufferView":2,"byteOffset":0,"componentType":5123,"count":6,"type":"SCALAR"},
 {"bufferView":2,"byteOffset":12,"componentType":5123,"count":6,"type":"SCALAR"},
 {"bufferView":2,"byteOffset":24,"componentType":5123,"count":6,"type":"SCALAR"}],
"materials":[
 {"name":"floor","pbrMetallicRoughness":{"baseColorFactor":[0.6,0.6,0.6,1],"metallicFactor":0,"roughnessFactor":1}},
 {"name":"mirror","pbrMetallicRoughness":{"baseColorFactor":[0.9,0.9,0.9,1],"metallicFactor":1,"roughnessFactor":0}},
 {"name":"red","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.1,0.1,1],"metallicFactor":0,"roughnessFactor":1}}],
"meshes":[
 {"primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"indices":2,"material":0}]},
 {"primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"indices":3,"material":1}]},
 {"primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"indices":4,"material":2}]}],
"cameras":[{"type":"perspective","perspective":{"yfov":0.9,"znear":0.05,"aspectRatio":1.333}}],
"extensionsUsed":["KHR_lights_punctual"],
"extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","intensity":6,"color":[1,1,1]}]}},
"nodes":[
 {"name":"floor","mesh":0},{"name":"mirror","mesh":1},{"name":"panel","mesh":2},
 {"name":"camera","camera":0,"translation":[0.3,1.0,2.2],"rotation":[-0.05,0,0,0.9987]},
 {"name":"lamp","translation":[0,2.2,1.5],"extensions":{"KHR_lights_punctual":{"light":0}}}]}"#;
    let path = dir.join("room.gltf");
    std::fs::write(&path, gltf).unwrap();
    path
}

#[test]
fn a_mirror_in_a_hand_written_gltf_shows_what_is_behind_the_camera() {
    if test_context().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = hand_written_gltf(dir.path());
    let scene = lightlab_scene::load(path.to_str().unwrap(), Default::default()).unwrap();
    let found = lightlab_gpu::raster::mirror::find(&scene);
    assert_eq!(found.len(), 1, "one planar mirror");
    assert_eq!(scene.instances[found[0].instance].name, "mirror");
    let mask = coverage_mask(&scene, &scene.cameras[0], W, H, &[found[0].instance]);
    let count = mask.iter().filter(|m| **m).count();
    assert!(count > 500, "the camera sees the mirror ({count})");
    let want = reference(&scene);
    let planar = gpu(&scene, RenderPath::Forward, true);
    let err = relmse_masked(&planar, &want, &mask).unwrap();
    // The red panel behind the camera, seen in the mirror.
    let red = |img: &Image| {
        img.data
            .iter()
            .zip(&mask)
            .filter(|(p, m)| **m && p.x > 2.0 * p.y && p.x > 0.02)
            .count()
    };
    let (red_ref, red_gpu) = (red(&want), red(&planar));
    eprintln!(
        "hand-written glTF: {count} mirror pixels, relMSE {err:.5}, red pixels {red_gpu} (reference {red_ref})"
    );
    assert!(
        red_ref > 50,
        "the reference shows the panel in the mirror ({red_ref})"
    );
    assert!(err <= 0.01, "relMSE {err}");
}
