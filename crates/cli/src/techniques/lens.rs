//! A GPU technique's image through a camera lens (Heidrich ch. 11), as steps of lens views
//! (`lightlab_gpu::lens_morph`): a thin or thick lens by Haeberli & Akeley's accumulation of
//! off-axis projections (one step per aperture point, the whole frame at weight 1/N), a
//! traced lens by the image-based model (one step per sample point: its projections, each
//! morphed onto its film cell). A still image renders every step; the viewer one per frame.

use super::Request;
use anyhow::Result;
use lightlab_core::image::Image;
use lightlab_core::lens::CameraModel;
use lightlab_core::lens::image_model::{self, ImageModel};
use lightlab_gpu::GpuContext;
use lightlab_gpu::lens_morph::{LensMorph, LensView, full_frame};
use lightlab_gpu::raster::{FrameTimes, Renderer};
use std::time::Instant;

/// The views of the lens of `req` at its size, grouped in steps; None for a pinhole.
pub fn lens_steps(req: &Request) -> Result<Option<Vec<Vec<LensView>>>> {
    let lens = &req.args.lens;
    let aspect = req.width as f32 / req.height as f32;
    Ok(match lens.model(req.scene, req.camera, aspect)? {
        CameraModel::Pinhole => None,
        CameraModel::ThinLens(l) => {
            let points = l.samples(lens.lens_samples.unwrap_or(64));
            let (vertices, indices) = full_frame(1.0 / points.len() as f32);
            let steps = points.iter().map(|p| {
                vec![LensView {
                    view: l.lens_view(*p),
                    eye: l.eye(*p),
                    vertices: vertices.clone(),
                    indices: indices.clone(),
                }]
            });
            Some(steps.collect())
        }
        CameraModel::Traced(system) => {
            let model = image_model::build(&system, &lens.image_model()?);
            anyhow::ensure!(
                !model.projections.is_empty(),
                "no light passes the lens: check --aperture and --lens-scale"
            );
            Some(image_based_steps(
                &model,
                req.scene.cameras[req.camera].yfov,
                aspect,
            ))
        }
    })
}

/// The image-based model's projections, one step per sample point.
fn image_based_steps(model: &ImageModel, yfov: f32, aspect: f32) -> Vec<Vec<LensView>> {
    let mut steps: Vec<Vec<LensView>> = Vec::new();
    let mut last = None;
    for p in &model.projections {
        let view = LensView {
            view: p.view(yfov, aspect),
            eye: p.eye(),
            vertices: p.vertices.clone(),
            indices: p.indices(),
        };
        // Projections come grouped by their sample point.
        match steps.last_mut() {
            Some(step) if last == Some(p.point) => step.push(view),
            _ => steps.push(vec![view]),
        }
        last = Some(p.point);
    }
    steps
}

/// Render every view of `steps` through `r` onto `film` (made on first use) and read it;
/// with the whole lens frame's times (wall: every view and morph until the GPU is idle; GPU:
/// the views' passes summed).
pub fn image(
    ctx: &GpuContext,
    r: &mut Renderer,
    steps: &[Vec<LensView>],
    film: &mut Option<LensMorph>,
) -> Result<(Image, FrameTimes)> {
    let (w, h) = r.size();
    let film = film.get_or_insert_with(|| LensMorph::new(ctx, w, h));
    film.clear();
    let t0 = Instant::now();
    let mut times = FrameTimes::default();
    for v in steps.iter().flatten() {
        r.set_lens_view(ctx, Some((v.view, v.eye)));
        let t = r.render(ctx);
        for (k, ms) in t.gpu_ms {
            *times.gpu_ms.entry(k).or_default() += ms;
        }
        times.cpu_volumes_ms += t.cpu_volumes_ms;
        film.add(ctx, r.hdr_view(), &v.vertices, &v.indices);
    }
    film.wait(ctx);
    times.wall_ms = t0.elapsed().as_secs_f64() * 1e3;
    r.set_lens_view(ctx, None);
    Ok((film.read(ctx)?, times))
}
