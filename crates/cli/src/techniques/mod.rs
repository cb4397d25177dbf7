//! The one factory of GPU techniques: a technique, a scene and its options become a
//! [`TechniqueRenderer`], with the baked data the technique needs (read from `--baked`, or baked
//! once and shared through [`Bakes`]). `render`, `demo`, `bench frame` and `view` all build
//! through [`build`]; each family's module (`phong`, `lightmap`, `sh`, `lpv`) reads its own
//! options.

pub mod canned;
mod lens;
pub mod lightmap;
mod lpv;
mod normals;
pub mod refraction;
pub mod sh;

use crate::options::{DebugView, TechniqueArgs};
use crate::technique::{Family, Technique};
use anyhow::{Result, bail};
use lightlab_bake::Lightmaps;
use lightlab_bake::prt::VertexTransfer;
use lightlab_core::image::Image;
use lightlab_gpu::GpuContext;
use lightlab_gpu::raster::{FrameTimes, Renderer};
use lightlab_scene::Scene;
use std::collections::HashMap;
use std::time::Instant;

/// What to build: a technique on a scene with its options, at `width`×`height` (before
/// supersampling) from scene camera `camera`. An animated scene comes in its rest pose;
/// `args.frame` poses it.
#[derive(Clone, Copy)]
pub struct Request<'a> {
    pub scene: &'a Scene,
    pub technique: Technique,
    pub args: &'a TechniqueArgs,
    pub width: u32,
    pub height: u32,
    pub camera: usize,
}

/// Baked data made or read so far, keyed by folder or by bake settings, so that techniques
/// built from the same bake share it (the demo and the viewer build many).
#[derive(Default)]
pub struct Bakes {
    lightmaps: HashMap<String, Lightmaps>,
    sh: HashMap<String, sh::StoredSh>,
    vertex: HashMap<String, VertexTransfer>,
}

impl Bakes {
    /// How many bakes (or folder reads) were made.
    pub fn len(&self) -> usize {
        self.lightmaps.len() + self.sh.len() + self.vertex.len()
    }
}

/// A GPU technique's renderer and the per-frame work around it.
pub struct TechniqueRenderer {
    pub technique: Technique,
    pub renderer: Renderer,
    /// What changes from frame to frame: the SH light, an animated scene's pose.
    pub frames: Frames,
    debug_view: DebugView,
    ssaa: u32,
    /// The camera lens's views, in steps (None: the pinhole), and the film they make.
    pub lens: Option<Vec<Vec<lightlab_gpu::lens_morph::LensView>>>,
    film: Option<lightlab_gpu::lens_morph::LensMorph>,
}

/// Build the renderer of a GPU technique.
pub fn build(ctx: &GpuContext, req: &Request, bakes: &mut Bakes) -> Result<TechniqueRenderer> {
    req.technique.check_options(req.args, false)?;
    let frame = req.args.frame;
    if frame.is_some() && req.scene.animation.is_none() {
        bail!(
            "--frame poses an animated scene, and {} has no animation",
            req.scene.name
        );
    }
    // The SH techniques bake the rest pose and move the objects; the others are built on
    // the posed scene (their shadow maps and bakes fitted to it).
    let rest_scene = req.scene;
    let posed;
    let req = &match frame {
        Some(k) if req.technique.family() != Family::Sh => {
            posed = req.scene.posed(k);
            Request {
                scene: &posed,
                ..*req
            }
        }
        _ => *req,
    };
    if !req.args.light_field.is_empty() && req.technique.family() != Family::Phong {
        bail!(
            "--light-field lights the Phong techniques (phong, phong-shadow-volumes, \
             phong-shadow-maps, canned-light), reference and direct; not '{}'",
            req.technique
        );
    }
    if (req.args.refraction_field.is_some() || req.args.radiance_field.is_some())
        && req.technique.family() != Family::Phong
    {
        bail!(
            "--refraction-field and --radiance-field are read by the Phong techniques (phong, \
             phong-shadow-volumes, phong-shadow-maps, canned-light, lightfield-refraction, \
             lightfield-glossy); not '{}'",
            req.technique
        );
    }
    let mut sh_light = None;
    let renderer = match req.technique.family() {
        Family::PathTraced => bail!("'{}' is not a GPU technique", req.technique),
        Family::Phong => {
            let a = &req.args.raster;
            let shadows = req.technique.shadows(a.shadow_variant)?;
            let mut s = a.settings(shadows, req.width, req.height, req.camera)?;
            s.object_field = refraction::field(req.scene, req.technique, req.args)?;
            let slabs = canned::lights(req.scene, req.technique, req.args)?;
            if slabs.is_empty() {
                Renderer::new(ctx, req.scene, s)?
            } else {
                // The slabs replace their luminaires' geometry (and light).
                let room = canned::room(req.scene, &slabs);
                s.light_field = slabs
                    .into_iter()
                    .map(|slab| lightlab_gpu::raster::CannedLight {
                        slab,
                        passes: req.args.light_field_passes,
                    })
                    .collect();
                Renderer::new(ctx, &room, s)?
            }
        }
        Family::Lightmap => {
            let lm = lightmap::lightmaps(req, bakes)?;
            lightmap::renderer(ctx, req, lm)?
        }
        Family::Sh => {
            let data = sh::data(req, bakes)?;
            let (r, state) = sh::renderer(ctx, req, &data)?;
            sh_light = Some(state);
            r
        }
        Family::Lpv => lpv::renderer(ctx, req)?,
        Family::Debug => normals::renderer(ctx, req)?,
    };
    let mut tr = TechniqueRenderer {
        technique: req.technique,
        renderer,
        frames: Frames {
            // The scene the renderer was made from (an SH bake's has its light-map coordinates).
            rest: rest_scene.animation.as_ref().map(|_| match &sh_light {
                Some(state) => state.rest.clone(),
                None => rest_scene.clone(),
            }),
            sh: sh_light,
            start: frame.unwrap_or(0),
        },
        debug_view: req.args.lpv.debug_view,
        ssaa: req.args.raster.ssaa,
        lens: lens::lens_steps(req)?,
        film: None,
    };
    if let (Some(k), Some(_)) = (frame, &tr.frames.sh) {
        tr.pose(ctx, k)?;
    }
    Ok(tr)
}

/// What a technique's renderer changes from frame to frame: the SH techniques' light
/// (re-projected, filtered by hierarchical PRT) and an animated scene's pose.
pub struct Frames {
    /// An animated scene in its rest pose (what [`Frames::pose`] poses).
    rest: Option<Scene>,
    sh: Option<sh::ShState>,
    /// The frame the renderer was made at (`--frame`): the viewer plays on from it.
    start: u32,
}

impl Frames {
    /// Relight an SH technique; its time in milliseconds (None for other techniques).
    pub fn update(&mut self, ctx: &GpuContext, r: &mut Renderer) -> Result<Option<f64>> {
        let Some(state) = &mut self.sh else {
            return Ok(None);
        };
        let t0 = Instant::now();
        let light = state.light();
        sh::set_light(ctx, r, &light)?;
        Ok(Some(t0.elapsed().as_secs_f64() * 1e3))
    }

    /// Pose an animated scene at frame `k`: its moving instances move (baked data moves with
    /// them) and the SH techniques relight. Nothing for a still scene.
    pub fn pose(&mut self, ctx: &GpuContext, r: &mut Renderer, k: u32) -> Result<()> {
        let Some(rest) = &self.rest else {
            return Ok(());
        };
        let posed = rest.posed(k);
        for t in rest.animation.iter().flat_map(|a| &a.tracks) {
            r.move_instance(ctx, &posed, t.instance);
        }
        if let Some(state) = &mut self.sh {
            state.posed = posed;
            self.update(ctx, r)?;
        }
        Ok(())
    }

    /// Whether the scene is animated.
    pub fn animated(&self) -> bool {
        self.rest.is_some()
    }

    /// Hierarchical PRT's counters of the last frame (None for other techniques).
    pub fn hprt_stats(&self) -> Option<lightlab_bake::hprt::FilterStats> {
        Some(self.sh.as_ref()?.hierarchy.as_ref()?.stats)
    }
}

impl lightlab_viewer::Animation for Frames {
    fn rate(&self) -> (f32, u32) {
        let a = self.rest.as_ref().and_then(|s| s.animation.as_ref());
        a.map_or((24.0, 1), |a| (a.fps, a.frames))
    }

    fn pose(
        &mut self,
        ctx: &GpuContext,
        r: &mut Renderer,
        frame: u32,
    ) -> Result<(), lightlab_viewer::MakeError> {
        Frames::pose(self, ctx, r, self.start + frame).map_err(|e| format!("{e:#}").into())
    }
}

impl TechniqueRenderer {
    /// The CPU work of a frame before it is drawn: SH techniques re-project the scene's lights.
    /// Returns its time in milliseconds, None for techniques without such work.
    pub fn update(&mut self, ctx: &GpuContext) -> Result<Option<f64>> {
        self.frames.update(ctx, &mut self.renderer)
    }

    /// Pose an animated scene at frame `k` ([`Frames::pose`]).
    pub fn pose(&mut self, ctx: &GpuContext, k: u32) -> Result<()> {
        self.frames.pose(ctx, &mut self.renderer, k)
    }

    /// Render two frames (the first compiles pipelines and uploads) and return the second's
    /// image, downsampled by the supersampling factor (or the `--debug-view` layer), and its
    /// times.
    pub fn image(&mut self, ctx: &GpuContext) -> Result<(Image, FrameTimes)> {
        let r = &mut self.renderer;
        // A still image: the dynamic maps made with the renderer see this very scene.
        r.set_dynamic_env_every(0);
        r.render(ctx);
        let times = r.render(ctx);
        if let Some(steps) = &self.lens {
            // The frame's times are the whole lens image's (every view and morph).
            let (img, times) = lens::image(ctx, r, steps, &mut self.film)?;
            return Ok((img.downsample(self.ssaa), times));
        }
        // A debug view's layer replaces the frame, which is then not read back.
        if self.technique.family() == Family::Lpv
            && let Some(layer) = lpv::debug_image(ctx, r, self.debug_view, self.ssaa)?
        {
            return Ok((layer, times));
        }
        Ok((r.read_hdr(ctx)?.downsample(self.ssaa), times))
    }
}
