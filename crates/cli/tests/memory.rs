//! Memory grows with the file: a scene with 100 MB of 8-bit textures loads (and renders a
//! tiny image) in under 250 MB peak RSS. Its own test binary, so that the peak of the children
//! this process waited for is this test's command alone.

use std::process::Command;

/// Four 2500 × 2500 RGBA8 textures: 100 MB of texels, on a quad.
fn textured_scene(dir: &std::path::Path) -> std::path::PathBuf {
    use glam::{Vec2, Vec3};
    use lightlab_scene::builtin::geom::quad_facing;
    use lightlab_scene::{Material, Scene, TextureRef};
    let mut s = Scene::default();
    let side = 2500u32;
    let mut refs = vec![];
    for k in 0..4u32 {
        let img = image::RgbaImage::from_fn(side, side, |x, y| {
            image::Rgba([(x ^ y) as u8, (x + k * 40) as u8, (y / 3) as u8, 255])
        });
        let name = format!("t{k}.png");
        img.save(dir.join(&name)).unwrap();
        refs.push(name);
    }
    // The scene is written with placeholder textures, then pointed at the PNG files.
    for (k, _) in refs.iter().enumerate() {
        s.textures.push(lightlab_scene::Texture::linear(
            &format!("t{k}"),
            1,
            1,
            vec![glam::Vec4::ONE],
            true,
        ));
        let mut m = Material::diffuse(&format!("m{k}"), Vec3::ONE);
        m.base_color_texture = Some(TextureRef::new(k, 0));
        let mat = s.add_material(m);
        let x = k as f32 * 2.2;
        let mut mesh = quad_facing(
            &format!("q{k}"),
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 2.0, 0.0, 0.0),
                Vec3::new(x + 2.0, 0.0, 2.0),
                Vec3::new(x, 0.0, 2.0),
            ],
            Vec3::Y,
            mat,
        );
        mesh.uv0 = vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        s.add_mesh(mesh, glam::Mat4::IDENTITY);
    }
    let gltf = dir.join("big.gltf");
    lightlab_scene::gltf_io::export(&s, &gltf).unwrap();
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(&gltf).unwrap()).unwrap();
    for (k, name) in refs.iter().enumerate() {
        v["images"][k] = serde_json::json!({ "uri": name });
    }
    std::fs::write(&gltf, serde_json::to_vec(&v).unwrap()).unwrap();
    gltf
}

#[test]
fn a_scene_with_100_mb_of_8_bit_textures_loads_in_under_250_mb() {
    let tmp = tempfile::tempdir().unwrap();
    let gltf = textured_scene(tmp.path());
    let out = tmp.path().join("o.exr");
    let o = Command::new(env!("CARGO_BIN_EXE_lightlab"))
        .args([
            "render",
            "--scene",
            gltf.to_str().unwrap(),
            "--technique",
            "direct",
        ])
        .args(["--width", "8", "--spp", "1", "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // SAFETY: getrusage fills the zeroed struct it is given; nothing else is touched.
    let usage = unsafe {
        let mut ru: libc::rusage = std::mem::zeroed();
        assert_eq!(libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru), 0);
        ru
    };
    // ru_maxrss is in KiB on Linux.
    let peak_mb = usage.ru_maxrss as f64 * 1024.0 / 1e6;
    eprintln!("100 MB of 8-bit textures: peak RSS {peak_mb:.0} MB");
    assert!(peak_mb < 250.0, "peak RSS {peak_mb:.0} MB");
    assert!(
        peak_mb > 100.0,
        "peak RSS {peak_mb:.0} MB: were the textures loaded?"
    );
}
