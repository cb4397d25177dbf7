//! glTF files as other tools write them: the reference and the GPU read them alike.

use glam::{Vec2, Vec3, Vec4};
use lightlab_scene::{Scene, Texture, TextureRef};
use std::path::Path;

mod common;

use common::{lightlab, ok};

/// `lightlab render --scene SCENE --technique T --width W [extra] -o OUT`, which must succeed;
/// returns its stderr.
fn render(scene: &str, technique: &str, width: u32, extra: &[&str], out: &Path) -> String {
    let w = width.to_string();
    let mut args = vec![
        "render",
        "--scene",
        scene,
        "--technique",
        technique,
        "--width",
        &w,
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", out.to_str().unwrap()]);
    ok(&lightlab(&args))
}

fn relmse(a: &Path, b: &Path) -> f64 {
    let o = lightlab(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
    ]);
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(out.lines().last().unwrap()).unwrap();
    v["relmse"].as_f64().unwrap()
}

/// `shadows` with a checker on the floor read through TEXCOORD_1, while TEXCOORD_0 is all
/// zeros (a single texel): a reader that ignores `texCoord` sees a plain floor.
fn checker_on_uv1() -> Scene {
    let mut s = lightlab_scene::builtin::builtin("shadows").unwrap();
    let checker = Texture {
        name: "checker".into(),
        width: 8,
        height: 8,
        texels: lightlab_scene::Texels::Rgba32F(
            (0..64)
                .map(|i| {
                    let c = if (i % 8 + i / 8) % 2 == 0 { 0.9 } else { 0.05 };
                    Vec4::new(c, c * 0.8, c * 0.6, 1.0)
                })
                .collect(),
        ),
        srgb: true,
    };
    s.textures.push(checker);
    let floor = s.meshes.iter().position(|m| m.name == "floor").unwrap();
    let mesh = &mut s.meshes[floor];
    mesh.uv1 = Some(
        mesh.positions
            .iter()
            .map(|p| Vec2::new(p.x, p.z) / 7.0 + Vec2::splat(0.5))
            .collect(),
    );
    mesh.uv0 = vec![Vec2::ZERO; mesh.positions.len()];
    let m = mesh.material;
    s.materials[m].base_color = Vec4::ONE;
    s.materials[m].base_color_texture = Some(TextureRef::new(s.textures.len() - 1, 1));
    s
}

#[test]
fn a_texture_on_texcoord_1_renders_alike_in_the_reference_and_on_the_gpu() {
    let tmp = tempfile::tempdir().unwrap();
    let glb = tmp.path().join("checker.glb");
    lightlab_scene::gltf_io::export(&checker_on_uv1(), &glb).unwrap();
    let (direct, gpu) = (tmp.path().join("direct.exr"), tmp.path().join("gpu.exr"));
    let g = glb.to_str().unwrap();
    render(g, "direct", 96, &["--spp", "64"], &direct);
    render(g, "phong-shadow-maps", 96, &[], &gpu);
    let e = relmse(&gpu, &direct);
    eprintln!("checker on TEXCOORD_1: phong-shadow-maps against direct, relMSE {e:.4}");
    assert!(e <= 0.01, "relMSE {e}");
    // The checker is there: the floor's pixels vary far more than a plain floor's.
    let img = lightlab_core::image::Image::read(&direct).unwrap();
    let lum: Vec<f32> = img
        .data
        .iter()
        .map(|v| v.dot(Vec3::splat(1.0 / 3.0)))
        .collect();
    let bottom = &lum[lum.len() * 3 / 4..];
    let mean = bottom.iter().sum::<f32>() / bottom.len() as f32;
    let var = bottom.iter().map(|l| (l - mean).powi(2)).sum::<f32>() / bottom.len() as f32;
    assert!(
        var.sqrt() > 0.3 * mean,
        "no checker in the reference: σ {} mean {mean}",
        var.sqrt()
    );
}

/// `checker_on_uv1` with vertex colours on every mesh and, with `transformed`, a
/// KHR_texture_transform on the checker; without it, the floor's TEXCOORD_1 carries the same
/// transform baked into its coordinates.
fn transformed_and_coloured(transformed: bool) -> Scene {
    use lightlab_scene::UvTransform;
    let mut s = checker_on_uv1();
    let t = UvTransform::new(Vec2::new(0.3, -0.2), 0.5, Vec2::new(2.0, 1.5));
    let floor = s.meshes.iter().position(|m| m.name == "floor").unwrap();
    let m = s.meshes[floor].material;
    if transformed {
        s.materials[m]
            .base_color_texture
            .as_mut()
            .unwrap()
            .transform = t;
    } else {
        let uv1 = s.meshes[floor].uv1.as_mut().unwrap();
        uv1.iter_mut().for_each(|u| *u = t.apply(*u));
    }
    for mesh in &mut s.meshes {
        mesh.colors = mesh
            .positions
            .iter()
            .map(|p| Vec4::new(0.6 + 0.4 * p.x.sin(), 0.7, 0.6 + 0.4 * p.z.cos(), 1.0))
            .collect();
    }
    s
}

#[test]
fn texture_transforms_and_vertex_colours_render_alike_in_the_reference_and_on_the_gpu() {
    let tmp = tempfile::tempdir().unwrap();
    let path = |name: &str| tmp.path().join(name);
    let mut files = vec![];
    for (name, scene) in [
        ("transformed", transformed_and_coloured(true)),
        ("baked", transformed_and_coloured(false)),
        ("plain", checker_on_uv1()),
    ] {
        let glb = path(&format!("{name}.glb"));
        lightlab_scene::gltf_io::export(&scene, &glb).unwrap();
        let exr = path(&format!("{name}.exr"));
        render(glb.to_str().unwrap(), "direct", 96, &["--spp", "32"], &exr);
        files.push((glb, exr));
    }
    // The transform applied at sampling equals the same transform baked into the UVs.
    let same = relmse(&files[0].1, &files[1].1);
    // Transform and colours change the image.
    let changed = relmse(&files[0].1, &files[2].1);
    let gpu = path("gpu.exr");
    render(
        files[0].0.to_str().unwrap(),
        "phong-shadow-maps",
        96,
        &[],
        &gpu,
    );
    let e = relmse(&gpu, &files[0].1);
    eprintln!(
        "texture transform + COLOR_0: sampled vs baked UVs {same:.2e}, vs plain {changed:.3}, \
         phong-shadow-maps vs direct {e:.4}"
    );
    if let Ok(keep) = std::env::var("LIGHTLAB_KEEP") {
        for (from, to) in [
            (&files[0].1, "tt-direct.exr"),
            (&gpu, "tt-gpu.exr"),
            (&files[0].0, "tt.glb"),
        ] {
            let _ = std::fs::copy(from, Path::new(&keep).join(to));
        }
    }
    assert!(
        same < 1e-4,
        "transform at sampling vs baked UVs: relMSE {same}"
    );
    assert!(
        changed > 0.02,
        "transform and colours change nothing: {changed}"
    );
    assert!(e <= 0.01, "phong-shadow-maps against direct: relMSE {e}");
}

#[test]
fn a_file_without_lights_is_lit_by_daylight_with_a_notice_everywhere() {
    let tmp = tempfile::tempdir().unwrap();
    let mut s = lightlab_scene::builtin::builtin("shadows").unwrap();
    s.lights.clear();
    s.environment = None;
    assert!(s.is_unlit());
    let glb = tmp.path().join("unlit.glb");
    lightlab_scene::gltf_io::export(&s, &glb).unwrap();
    let g = glb.to_str().unwrap();
    let notice = "has no lights";
    for technique in ["reference", "phong-shadow-maps"] {
        let out = tmp.path().join(format!("{technique}.exr"));
        let e = render(g, technique, 48, &["--spp", "16"], &out);
        assert!(
            e.contains(notice) && e.contains("Preetham"),
            "{technique}: {e}"
        );
        let img = lightlab_core::image::Image::read(&out).unwrap();
        assert!(
            img.mean().element_sum() / 3.0 > 0.2,
            "{technique}: mean {}",
            img.mean()
        );
    }
    let baked = tmp.path().join("baked");
    let e = ok(&lightlab(&[
        "bake",
        "--scene",
        g,
        "--method",
        "path",
        "--gather-samples",
        "8",
        "--texels-per-metre",
        "4",
        "--out",
        baked.to_str().unwrap(),
    ]));
    assert!(e.contains(notice), "bake: {e}");
    let page = lightlab_core::image::Image::read(&baked.join("lightmap-0.exr")).unwrap();
    assert!(
        page.mean().element_sum() > 0.1,
        "bake: mean {}",
        page.mean()
    );
    // --env sky and --sun light a scene that has lights of its own too, and bad suns are
    // refused before any work.
    let out = tmp.path().join("sky.exr");
    let o = out.to_str().unwrap();
    let sun = ["--env", "sky", "--sun", "30,90,5", "--spp", "4"];
    render("cornell", "direct", 16, &sun, &out);
    for bad in ["90", "-5,10", "45,x", "45,10,-1"] {
        let r = lightlab(&[
            "render",
            "--scene",
            "cornell",
            "--technique",
            "direct",
            "--sun",
            bad,
            "-o",
            o,
        ]);
        let e = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "--sun {bad}: {e}");
        assert!(e.contains("--sun"), "--sun {bad}: {e}");
    }
}

/// A single-sided quad (facing +Y) over a lit box, seen from below through the quad, with a
/// near plane that cuts a second quad close to the camera.
fn faces_and_near_plane(double_sided: bool) -> Scene {
    use lightlab_scene::builtin::geom::{aabb_box, quad_facing};
    use lightlab_scene::{Camera, Light, LightKind, Material};
    let mut s = Scene::default();
    let mut m = Material::diffuse("white", Vec3::splat(0.7));
    m.double_sided = double_sided;
    let mat = s.add_material(m);
    let grey = s.add_material(Material::diffuse("grey", Vec3::splat(0.5)));
    let q = |y: f32, h: f32| {
        [
            Vec3::new(-h, y, -h),
            Vec3::new(h, y, -h),
            Vec3::new(h, y, h),
            Vec3::new(-h, y, h),
        ]
    };
    s.add_mesh(
        quad_facing("sheet", q(1.0, 1.0), Vec3::Y * 9.0, mat),
        glam::Mat4::IDENTITY,
    );
    // 5 cm in front of the camera, inside a 0.2 m near plane: clipped by both.
    s.add_mesh(
        quad_facing("near", q(-0.95, 0.3), -Vec3::Y * 9.0, grey),
        glam::Mat4::IDENTITY,
    );
    s.add_mesh(
        aabb_box(
            "box",
            Vec3::new(-0.4, 1.6, -0.4),
            Vec3::new(0.4, 2.4, 0.4),
            grey,
        ),
        glam::Mat4::IDENTITY,
    );
    s.lights.push(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        color: Vec3::ONE,
        intensity: 2.0,
        position: Vec3::new(0.0, 1.3, 0.6),
        direction: -Vec3::Y,
        range: None,
    });
    let mut cam = Camera::look_at("below", Vec3::new(0.0, -1.0, 0.0), Vec3::ZERO, Vec3::Z, 1.2);
    cam.znear = 0.2;
    s.cameras.push(cam);
    s
}

#[test]
fn back_faces_and_the_near_plane_mean_the_same_in_the_reference_and_on_the_gpu() {
    let tmp = tempfile::tempdir().unwrap();
    for double_sided in [false, true] {
        let glb = tmp.path().join(format!("faces-{double_sided}.glb"));
        lightlab_scene::gltf_io::export(&faces_and_near_plane(double_sided), &glb).unwrap();
        let g = glb.to_str().unwrap();
        let (direct, gpu) = (tmp.path().join("d.exr"), tmp.path().join("g.exr"));
        render(g, "direct", 64, &["--spp", "64"], &direct);
        render(g, "phong-shadow-maps", 64, &["--ambient", "none"], &gpu);
        let e = relmse(&gpu, &direct);
        eprintln!("double-sided {double_sided}: phong-shadow-maps against direct, relMSE {e:.4}");
        assert!(e < 0.02, "double-sided {double_sided}: relMSE {e}");
        // Single-sided: the camera sees through the sheet to the lit box; double-sided: the
        // sheet's unlit underside fills the middle.
        if let Ok(keep) = std::env::var("LIGHTLAB_KEEP") {
            let _ = std::fs::copy(
                &direct,
                Path::new(&keep).join(format!("d-{double_sided}.exr")),
            );
            let _ = std::fs::copy(&gpu, Path::new(&keep).join(format!("g-{double_sided}.exr")));
            let _ = std::fs::copy(&glb, Path::new(&keep).join(format!("s-{double_sided}.glb")));
        }
        let img = lightlab_core::image::Image::read(&direct).unwrap();
        let centre = img.data[(32 * 64 + 32) as usize].element_sum();
        assert_eq!(centre > 0.01, !double_sided, "centre {centre}");
    }
}

#[test]
fn an_overlapping_texcoord_1_is_replaced_for_light_maps_with_a_warning() {
    let tmp = tempfile::tempdir().unwrap();
    // `shadows` with TEXCOORD_1 = each mesh's TEXCOORD_0 fitted into [0, 1]: a texture set,
    // whose faces overlap (the box's six faces share one square).
    let mut s = lightlab_scene::builtin::builtin("shadows").unwrap();
    for m in &mut s.meshes {
        let (lo, hi) = m
            .uv0
            .iter()
            .fold((Vec2::MAX, Vec2::MIN), |(l, h), u| (l.min(*u), h.max(*u)));
        let size = (hi - lo).max(Vec2::splat(1e-6));
        m.uv1 = Some(m.uv0.iter().map(|u| (*u - lo) / size).collect());
    }
    let glb = tmp.path().join("uv1.glb");
    lightlab_scene::gltf_io::export(&s, &glb).unwrap();
    let g = glb.to_str().unwrap();
    let reference = tmp.path().join("ref.exr");
    render(g, "reference", 48, &["--spp", "64"], &reference);
    let mut errors = vec![];
    for (mode, warned) in [("auto", true), ("authored", false)] {
        let out = tmp.path().join(format!("{mode}.exr"));
        let bake = ["--lightmap-uv", mode, "--gather-samples", "32"];
        let e = render(g, "lightmap", 48, &bake, &out);
        assert_eq!(e.contains("light-map UVs generated"), warned, "{mode}: {e}");
        errors.push(relmse(&out, &reference));
    }
    eprintln!(
        "texture set as TEXCOORD_1: lightmap vs reference relMSE {:.4} (auto) {:.4} (authored)",
        errors[0], errors[1]
    );
    assert!(errors[0] < 0.5 * errors[1], "{errors:?}");
}
