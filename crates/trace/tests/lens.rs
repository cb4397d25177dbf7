//! The path tracer's thin lens (issue 25): a small lamp far behind the plane of focus images
//! as a disc of the analytic circle of confusion.

use glam::{Mat4, Vec3};
use lightlab_core::lens::{CameraModel, ThinLens};
use lightlab_scene::builtin::geom;
use lightlab_scene::{Camera, Material, Scene};
use lightlab_trace::{Accel, PathTracer, RenderSettings};

#[test]
fn an_out_of_focus_point_blurs_to_its_circle_of_confusion() {
    let (depth, radius, yfov, n) = (10.0f32, 0.1f32, 0.5f32, 128u32);
    let mut scene = Scene::default();
    let mut lamp = Material::diffuse("lamp", Vec3::ZERO);
    lamp.emissive = Vec3::ONE;
    lamp.emissive_strength = 1.0;
    let lamp = scene.add_material(lamp);
    scene.add_mesh(
        geom::sphere("lamp", radius, 48, 24, lamp),
        Mat4::from_translation(Vec3::new(0.0, 0.0, -depth)),
    );
    scene
        .cameras
        .push(Camera::look_at("cam", Vec3::ZERO, -Vec3::Z, Vec3::Y, yfov));
    let lens = ThinLens {
        aperture: 0.4,
        focus_distance: 2.0,
        thickness: 0.0,
    };
    let accel = Accel::new(&scene);
    let img = PathTracer::new(&scene, &accel)
        .render(
            &RenderSettings {
                width: n,
                height: n,
                spp: 1024,
                max_depth: 1,
                seed: 3,
                lens: CameraModel::ThinLens(lens),
                ..Default::default()
            },
            &|_, _| true,
        )
        .unwrap();
    // The image's second moment about its centroid: a uniform disc of radius R has R²/2; the
    // lamp's own disc (radius ρ) and the pixel's box (1/12 per axis) add theirs.
    let (mut w, mut cx, mut cy) = (0.0f64, 0.0f64, 0.0f64);
    for (i, c) in img.data.iter().enumerate() {
        let v = c.x as f64;
        w += v;
        cx += v * ((i as u32 % n) as f64 + 0.5);
        cy += v * ((i as u32 / n) as f64 + 0.5);
    }
    let (cx, cy) = (cx / w, cy / w);
    let m = img
        .data
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (x, y) = (
                (i as u32 % n) as f64 + 0.5 - cx,
                (i as u32 / n) as f64 + 0.5 - cy,
            );
            c.x as f64 * (x * x + y * y)
        })
        .sum::<f64>()
        / w;
    let px_per_unit = n as f64 / (2.0 * (0.5 * yfov as f64).tan());
    let rho = radius as f64 / depth as f64 * px_per_unit;
    let measured = 2.0 * (2.0 * (m - rho * rho / 2.0 - 1.0 / 6.0)).sqrt();
    let analytic = lens.circle_of_confusion(depth, yfov, n) as f64;
    eprintln!("circle of confusion: measured {measured:.3} px, analytic {analytic:.3} px");
    assert!((measured - analytic).abs() <= 0.01 * analytic);
    assert!((cx - n as f64 / 2.0).abs() < 0.2 && (cy - n as f64 / 2.0).abs() < 0.2);
}
