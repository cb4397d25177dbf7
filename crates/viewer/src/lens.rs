//! A camera lens in the viewer: the lens's views (`lightlab_gpu::lens_morph::LensView`,
//! grouped in steps: a thin lens's aperture points, the image-based model's sample points)
//! are rendered one step per frame while the camera rests and accumulate on a film, which the
//! window shows scaled by N / steps done; a moved camera, a moving object or a new renderer
//! starts the film again. The first frame after a move is therefore one aperture point's
//! image (sharp, with the lens's distortion), and the blur fills in over the next N − 1.

use glam::Mat4;
use lightlab_gpu::GpuContext;
use lightlab_gpu::lens_morph::{LensMorph, LensView};
use lightlab_gpu::raster::{FrameTimes, Renderer};

/// The film of a lens and how far it is.
pub struct LensState {
    steps: Vec<Vec<LensView>>,
    film: LensMorph,
    done: usize,
    /// The camera the film was started with.
    camera: Option<Mat4>,
}

impl LensState {
    /// A film of `width` × `height` for the views `steps`.
    pub fn new(ctx: &GpuContext, steps: Vec<Vec<LensView>>, width: u32, height: u32) -> LensState {
        LensState {
            steps,
            film: LensMorph::new(ctx, width, height),
            done: 0,
            camera: None,
        }
    }

    /// Render the next step (starting again when `camera` moved or `restart`); returns the
    /// last render's times, None when the film is complete and nothing was drawn.
    pub fn step(
        &mut self,
        ctx: &GpuContext,
        r: &mut Renderer,
        camera: Mat4,
        restart: bool,
    ) -> Option<FrameTimes> {
        if restart || self.camera != Some(camera) {
            self.camera = Some(camera);
            self.done = 0;
            self.film.clear();
        }
        let step = self.steps.get(self.done)?;
        let mut times = None;
        for v in step {
            r.set_lens_view(ctx, Some((v.view, v.eye)));
            times = Some(r.render(ctx));
            self.film.add(ctx, r.hdr_view(), &v.vertices, &v.indices);
        }
        r.set_lens_view(ctx, None);
        self.done += 1;
        times
    }

    /// The film and the factor that scales it to a whole image.
    pub fn image(&self) -> (&wgpu::TextureView, f32) {
        let scale = self.steps.len() as f32 / self.done.max(1) as f32;
        (self.film.film_view(), scale)
    }

    /// Steps done and in all.
    pub fn progress(&self) -> (usize, usize) {
        (self.done, self.steps.len())
    }
}
