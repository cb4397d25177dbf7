//! Dynamic environment maps follow moving objects (issue 20): a renderer whose red box moves
//! beside a chrome ball draws the frame a renderer made with the box there draws.

use glam::{Mat4, Vec3, Vec4};
use lightlab_core::image::Image;
use lightlab_gpu::raster::{RasterSettings, Renderer};
use lightlab_gpu::{GpuContext, test_context};
use lightlab_scene::builtin::geom;
use lightlab_scene::{Camera, Material, Scene};

/// A chrome ball on a grey floor under the `spheres` sky, a red box beside it (instance 1).
fn ball_and_box(box_at: Vec3) -> Scene {
    let mut s = Scene {
        environment: lightlab_scene::builtin::builtin("spheres")
            .unwrap()
            .environment,
        ..Default::default()
    };
    let mut chrome = Material::diffuse("chrome", Vec3::ONE);
    chrome.base_color = Vec4::new(0.9, 0.9, 0.9, 1.0);
    chrome.metallic = 1.0;
    chrome.roughness = 0.0;
    let chrome = s.add_material(chrome);
    let red = s.add_material(Material::diffuse("red", Vec3::new(0.8, 0.05, 0.05)));
    let grey = s.add_material(Material::diffuse("grey", Vec3::splat(0.5)));
    s.add_mesh(geom::sphere("ball", 1.0, 48, 24, chrome), Mat4::IDENTITY);
    s.add_mesh(
        geom::aabb_box(
            "box",
            Vec3::new(-0.6, -1.6, -1.0),
            Vec3::new(0.6, 1.2, 1.0),
            red,
        ),
        Mat4::from_translation(box_at),
    );
    s.add_mesh(
        geom::aabb_box(
            "floor",
            Vec3::new(-6.0, -1.8, -6.0),
            Vec3::new(6.0, -1.6, 6.0),
            grey,
        ),
        Mat4::IDENTITY,
    );
    s.cameras.push(Camera::look_at(
        "cam",
        Vec3::new(0.0, 0.8, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        0.75,
    ));
    s
}

fn settings() -> RasterSettings {
    RasterSettings {
        width: 96,
        height: 72,
        dynamic_env: true,
        ..Default::default()
    }
}

fn frame(ctx: &GpuContext, r: &mut Renderer) -> Image {
    r.render(ctx);
    r.read_hdr(ctx).unwrap()
}

fn relmse(a: &Image, b: &Image) -> f64 {
    let (mut e, mut n) = (0.0f64, 0.0f64);
    for (x, y) in a.data.iter().zip(&b.data) {
        e += (*x - *y).length_squared() as f64;
        n += y.length_squared() as f64;
    }
    e / n.max(1e-30)
}

#[test]
fn a_moved_object_is_reflected_where_it_now_stands() {
    let Some(ctx) = test_context() else {
        return;
    };
    let (from, to) = (Vec3::new(2.6, 0.0, -0.5), Vec3::new(-2.4, 0.0, 0.3));
    let before = ball_and_box(from);
    let after = ball_and_box(to);
    let fresh = frame(&ctx, &mut Renderer::new(&ctx, &after, settings()).unwrap());
    // Every frame: the move reaches the maps at the next frame.
    let mut moving = Renderer::new(&ctx, &before, settings()).unwrap();
    let first = frame(&ctx, &mut moving);
    moving.move_instance(&ctx, &after, 1);
    let updated = frame(&ctx, &mut moving);
    // Maps kept from when the renderer was made: the box moves, its reflection does not.
    let mut stale = Renderer::new(&ctx, &before, settings()).unwrap();
    stale.set_dynamic_env_every(0);
    frame(&ctx, &mut stale);
    stale.move_instance(&ctx, &after, 1);
    let kept = frame(&ctx, &mut stale);
    let (e_updated, e_kept, e_first) = (
        relmse(&updated, &fresh),
        relmse(&kept, &fresh),
        relmse(&first, &fresh),
    );
    eprintln!(
        "relMSE against a renderer made with the box moved: updated maps {e_updated:.2e}, \
         maps kept {e_kept:.2e}, before the move {e_first:.2e}"
    );
    assert!(e_first > 1e-2, "the move changes little: {e_first}");
    assert!(e_kept > 1e-3, "the stale reflection is not seen: {e_kept}");
    assert!(e_updated <= 1e-6, "the moved renderer differs: {e_updated}");
}
