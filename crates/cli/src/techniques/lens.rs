//! A GPU technique's still image through a camera lens (Heidrich ch. 11): a thin or thick
//! lens by Haeberli & Akeley's accumulation of off-axis projections, a traced lens by the
//! image-based model (perspective renders morphed onto the film, `lightlab_gpu::lens_morph`).

use super::Request;
use anyhow::Result;
use lightlab_core::image::Image;
use lightlab_core::lens::image_model::{self, ImageModel};
use lightlab_core::lens::{CameraModel, ThinLens};
use lightlab_gpu::GpuContext;
use lightlab_gpu::lens_morph::LensMorph;
use lightlab_gpu::raster::Renderer;

/// How a technique's still image goes through the camera's lens.
pub enum LensPlan {
    /// A thin or thick lens and its aperture points: one frame per point, averaged.
    Accumulate(ThinLens, Vec<glam::Vec2>),
    /// A traced lens's image-based model; the film is made on first use.
    ImageBased {
        model: ImageModel,
        yfov: f32,
        film: Option<LensMorph>,
    },
}

impl LensPlan {
    /// The plan for `req`'s lens options; None for a pinhole.
    pub fn new(req: &Request) -> Result<Option<LensPlan>> {
        let lens = &req.args.lens;
        let aspect = req.width as f32 / req.height as f32;
        Ok(match lens.model(req.scene, req.camera, aspect)? {
            CameraModel::Pinhole => None,
            CameraModel::ThinLens(l) => Some(LensPlan::Accumulate(
                l,
                l.samples(lens.lens_samples.unwrap_or(64)),
            )),
            CameraModel::Traced(system) => {
                let model = image_model::build(&system, &lens.image_model()?);
                anyhow::ensure!(
                    !model.projections.is_empty(),
                    "no light passes the lens: check --aperture and --lens-scale"
                );
                Some(LensPlan::ImageBased {
                    model,
                    yfov: req.scene.cameras[req.camera].yfov,
                    film: None,
                })
            }
        })
    }

    /// The image through the lens (at the renderer's resolution).
    pub fn image(&mut self, ctx: &GpuContext, r: &mut Renderer) -> Result<Image> {
        let img = match self {
            LensPlan::Accumulate(lens, points) => accumulate(ctx, r, lens, points)?,
            LensPlan::ImageBased { model, yfov, film } => {
                let (w, h) = r.size();
                let film = film.get_or_insert_with(|| LensMorph::new(ctx, w, h));
                film.clear();
                for p in &model.projections {
                    r.set_lens_view(ctx, Some((p.view(*yfov, w as f32 / h as f32), p.eye())));
                    r.render(ctx);
                    film.add(ctx, r.hdr_view(), &p.vertices, &p.indices());
                }
                film.read(ctx)?
            }
        };
        r.set_lens_view(ctx, None);
        Ok(img)
    }
}

/// The average of one frame per aperture point of `lens` (Haeberli & Akeley's accumulation).
fn accumulate(
    ctx: &GpuContext,
    r: &mut Renderer,
    lens: &ThinLens,
    points: &[glam::Vec2],
) -> Result<Image> {
    let mut sum: Option<Image> = None;
    for p in points {
        r.set_lens_view(ctx, Some((lens.lens_view(*p), lens.eye(*p))));
        r.render(ctx);
        let img = r.read_hdr(ctx)?;
        match &mut sum {
            None => sum = Some(img),
            Some(s) => s.data.iter_mut().zip(&img.data).for_each(|(a, b)| *a += *b),
        }
    }
    let mut img = sum.expect("at least one aperture point");
    let k = 1.0 / points.len() as f32;
    img.data.iter_mut().for_each(|c| *c *= k);
    Ok(img)
}
