//! The rasterising renderer of the `phong*` techniques: forward or deferred Phong lighting after
//! Fuchs (2005) §4.1 with one additive pass per light (§4.4), and shadows by stencil shadow
//! volumes (z-fail or z-pass), shadow maps (depth comparison or Heidrich's linear depth, PCF,
//! slope-scaled and normal-offset bias, cascades) or projected planar shadows.
//!
//! Depth is reversed (1 near, 0 at infinity) with an infinite far plane, so shadow-volume
//! vertices at infinity (w = 0) land exactly on the far plane and are never clipped: z-fail
//! needs no depth clamping.
//!
//! Frame structure, each pass timed with GPU timestamps where the adapter has them:
//! 1. `shadow maps`: one depth pass per shadow view (map methods only);
//! 2. `depth+ambient` (forward) or `g-buffer` (deferred): depth, ambient and emission;
//! 3. per light: `volumes` (stencil cleared, volumes or planar projections drawn, scissored to
//!    the light) then `lighting` (additive, where the stencil is 0);
//! 4. `tonemap`: the displayed 8-bit frame.
//!
//! Modules: `settings` (what is drawn), `build` (making a renderer), `light_set` (lights and
//! shadow views), `ambient` (the ambient term's sources: SH irradiance, light-maps, SH
//! transfer, the volume), `bindings` (bind-group layouts by role), `pipelines`, `targets`,
//! `passes` (one function per pass; [`Renderer::render`] lists them in order) and
//! `readback`.

mod ambient;
pub(crate) mod bindings;
mod build;
pub mod env;
pub mod env_dynamic;
mod light_set;
pub mod mirror;
mod passes;
mod pipelines;
mod readback;
mod settings;
mod targets;

pub use ambient::{LightmapInput, SKY_OCCLUSION_DIRECTIONS, SourceKind, sky_lights};
pub use settings::{
    Ambient, BadAmbient, CannedLight, CannedPasses, EnvDiffuse, EnvMapKind, EnvPrefilter,
    FieldObject, FrameTimes, MAX_AREA_LIGHTS, NormalFilter, RasterError, RasterSettings,
    Refraction, RenderPath, ShadowMethod, projection,
};

use crate::GpuContext;
use crate::gpu_scene::GpuScene;
use crate::lights::ShadowProjection;
use crate::shadow_volume::LightPos;
use crate::uniforms::*;
use build::AmbientInput;
use glam::{Mat4, Vec3, Vec4};
use lightlab_scene::{Camera, Scene};
use settings::check_wind;
use std::time::Instant;

/// WGSL of a renderer with ambient source `kind`: common.wgsl, material.wgsl, raster.wgsl and
/// the source's ambient_*.wgsl.
pub fn shader_source(kind: SourceKind) -> &'static str {
    static SOURCES: std::sync::LazyLock<Vec<String>> = std::sync::LazyLock::new(|| {
        SourceKind::ALL
            .iter()
            .map(|k| {
                format!(
                    "{}\n{}\n{}\n{}\n{}",
                    crate::uniforms::COMMON_WGSL,
                    crate::uniforms::MATERIAL_WGSL,
                    include_str!("../shaders/raster.wgsl"),
                    include_str!("../shaders/env.wgsl"),
                    k.wgsl()
                )
            })
            .collect()
    });
    let i = SourceKind::ALL
        .iter()
        .position(|k| *k == kind)
        .expect("a kind");
    &SOURCES[i]
}

/// Bytes between the per-pass uniform slots (the dynamic-offset alignment).
const SLOT: u64 = 256;

/// A renderer for one scene at one resolution.
pub struct Renderer {
    pub settings: RasterSettings,
    /// The specular environment term's maps, for reports (None: off).
    pub env_summary: Option<String>,
    pub scene: GpuScene,
    camera: Camera,
    lights: Vec<GpuLight>,
    light_pos: Vec<LightPos>,
    light_radius: Vec<Option<f32>>,
    views: Vec<ShadowProjection>,
    /// (light, view) of every shadow view.
    view_light: Vec<usize>,
    planar: Vec<Option<Mat4>>,
    plane: Option<Vec4>,
    pipelines: pipelines::Pipelines,
    targets: targets::Targets,
    shadow: targets::ShadowMaps,
    frame_buf: wgpu::Buffer,
    _pass_buf: wgpu::Buffer,
    group0: wgpu::BindGroup,
    group2: wgpu::BindGroup,
    group3: wgpu::BindGroup,
    tonemap_group: wgpu::BindGroup,
    /// The environment map (Rgba32Float, read texel by texel as the CPU's `radiance`), when
    /// the scene has one and a background is drawn.
    sky_group: Option<wgpu::BindGroup>,
    volume_buf: Option<wgpu::Buffer>,
    volume_ranges: Vec<std::ops::Range<u32>>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    frame: FrameUniforms,
    ambient: ambient::AmbientSource,
    env: env::EnvResources,
    /// An instance the camera passes leave out (a dynamic map's own object, seen from its
    /// centre); it still casts shadows.
    hidden: Option<usize>,
    /// Objects moved since the last frame (the sky occlusion is drawn again).
    moved: bool,
    /// The thin lens and the aperture point the frame is seen from (None: the pinhole).
    /// Camera space → the space the camera's projection applies to, and the eye in camera
    /// space (a lens's view of the scene); None: the pinhole.
    lens: Option<(Mat4, Vec3)>,
    /// The planar mirrors and the renderers of their reflected views (`mirror`).
    mirrors: Vec<mirror::Mirror>,
    /// The pixels the camera passes draw (a mirror's reflected view: the mirror's screen
    /// rectangle); None: all.
    clip_rect: Option<(u32, u32, u32, u32)>,
}

impl Renderer {
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
    ) -> Result<Renderer, RasterError> {
        Self::build(ctx, scene, settings, AmbientInput::None)
    }

    /// A renderer whose ambient term is diffuse × light-map (Fuchs §3.4) instead of the SH
    /// ambient: the `lightmap` and `lightmap+phong` techniques.
    pub fn with_lightmap(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        lightmap: Option<&LightmapInput>,
    ) -> Result<Renderer, RasterError> {
        let ambient = lightmap.map_or(AmbientInput::None, AmbientInput::Lightmap);
        Self::build(ctx, scene, settings, ambient)
    }

    /// A renderer whose ambient term is diffuse × SH transfer · SH light (the PRT techniques,
    /// `crate::prt`). The light is black until [`Renderer::set_sh_light`].
    pub fn with_sh(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        sh: &crate::prt::ShInput,
    ) -> Result<Renderer, RasterError> {
        Self::build(ctx, scene, settings, AmbientInput::Sh(sh))
    }

    /// A renderer whose diffuse surfaces also receive the indirect light of a light propagation
    /// volume (`crate::lpv`), recomputed every frame; `indirect_only` renders only that light
    /// (the `--debug-view indirect` of the `lpv` techniques).
    pub fn with_lpv(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
        lpv: &crate::lpv::LpvSettings,
        indirect_only: bool,
    ) -> Result<Renderer, RasterError> {
        Self::build(ctx, scene, settings, AmbientInput::Lpv(lpv, indirect_only))
    }

    /// A renderer that shows the shading normals (after normal maps, turned to the viewer) as
    /// n/2 + ½, unlit: the `normals` debug technique. The scene's lights are not drawn.
    pub fn normals(
        ctx: &GpuContext,
        scene: &Scene,
        settings: RasterSettings,
    ) -> Result<Renderer, RasterError> {
        let mut unlit = scene.clone();
        unlit.lights.clear();
        let settings = RasterSettings {
            shadows: ShadowMethod::None,
            area_lights: false,
            ..settings
        };
        Self::build(ctx, &unlit, settings, AmbientInput::Normals)
    }

    /// The light propagation volume, if this renderer has one.
    pub fn lpv(&self) -> Option<&crate::lpv::Lpv> {
        self.ambient.volume()
    }

    /// The SH light of the next frame: `points` (groups × sample points) and per point its
    /// bands² RGB coefficients (`lightlab_bake::sh_light::ShLighting`, flattened).
    pub fn set_sh_light(
        &mut self,
        ctx: &GpuContext,
        points: &[Vec3],
        coeffs: &[Vec3],
    ) -> Result<(), RasterError> {
        let ambient::AmbientSource::Sh(sh) = &self.ambient else {
            return Err(RasterError::Settings(
                "only a renderer built with SH transfer takes an SH light".into(),
            ));
        };
        let gp = (sh.uniforms.groups * sh.uniforms.points) as usize;
        let nc = sh.bands * sh.bands;
        if points.len() != gp || coeffs.len() != gp * nc {
            return Err(RasterError::Settings(format!(
                "the SH light needs {gp} sample points and {} coefficients (got {} and {})",
                gp * nc,
                points.len(),
                coeffs.len()
            )));
        }
        let data = crate::prt::pack_light(points, coeffs, sh.bands);
        ctx.queue
            .write_buffer(&sh.light, 0, bytemuck::cast_slice(&data));
        for m in &mut self.mirrors {
            m.child.set_sh_light(ctx, points, coeffs)?;
        }
        Ok(())
    }

    /// The linear HDR colour target of the last frame (Rgba16Float, `width`×`height`), for a
    /// viewer's own display pass.
    pub fn hdr_view(&self) -> &wgpu::TextureView {
        &self.targets.hdr_view
    }

    /// The frame's size in pixels (width, height), supersampling included.
    pub fn size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }

    /// The camera-relative positions of the last frame (deferred path; w = 0 where nothing
    /// was drawn).
    pub(crate) fn position_view(&self) -> &wgpu::TextureView {
        &self.targets.gbuffer[3]
    }

    /// Move instance `i` to its transform in `scene` (the scene the renderer was made from,
    /// with that instance's transform changed): its vertices, bounds and shadow volume, and
    /// the environment term's bounding sphere and dynamic maps follow from the next frame.
    /// Baked data (light-maps, SH transfer) and shadow cascades, fitted to the scene's bounds
    /// when the renderer was made, do not.
    pub fn move_instance(&mut self, ctx: &GpuContext, scene: &Scene, i: usize) {
        if i >= self.scene.draws.len() || i >= scene.instances.len() {
            return;
        }
        self.scene.move_instance(&ctx.queue, scene, i);
        self.env.moved(ctx, scene, i);
        self.moved = true;
        for m in &mut self.mirrors {
            m.child.move_instance(ctx, scene, i);
        }
    }

    /// Update the dynamic environment maps every `every` frames from now on (0: keep those
    /// made with the renderer, as a still image needs).
    pub fn set_dynamic_env_every(&mut self, every: u32) {
        if let Some(d) = &mut self.env.dynamic {
            d.set_every(every);
        }
        for m in &mut self.mirrors {
            m.child.set_dynamic_env_every(every);
        }
    }

    /// The camera of the next frame.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Number of lights rendered (the scene's, then its area lights).
    pub fn light_count(&self) -> usize {
        self.light_pos.len()
    }

    /// Set the wind (e.g. its time, for animation): every pass sways from the next frame on.
    pub fn set_wind(
        &mut self,
        ctx: &GpuContext,
        wind: lightlab_core::wind::Wind,
    ) -> Result<(), RasterError> {
        check_wind(&wind, self.settings.shadows)?;
        self.settings.wind = wind;
        [self.frame.wind_a, self.frame.wind_b] = wind.uniform();
        ctx.queue
            .write_buffer(&self.frame_buf, 0, bytemuck::bytes_of(&self.frame));
        if let Some(l) = self.ambient.volume_mut() {
            l.set_wind(ctx, &wind);
        }
        for m in &mut self.mirrors {
            m.child.set_wind(ctx, wind)?;
        }
        Ok(())
    }

    /// See the next frame through a lens's view: `view` maps camera space to the space the
    /// camera's projection applies to, `eye` is where shading sees the viewer (camera space).
    /// A thin lens's aperture point gives the off-axis projection that keeps its plane of
    /// focus where the pinhole sees it (`lightlab_core::lens::ThinLens::lens_view`; the
    /// average of such frames is the thin lens's image, Haeberli & Akeley); a cell of the
    /// image-based lens model gives its COP and window (`Projection::view`). None: the pinhole.
    pub fn set_lens_view(&mut self, ctx: &GpuContext, lens: Option<(Mat4, Vec3)>) {
        self.lens = lens;
        self.set_camera(ctx, self.camera.clone());
    }

    /// Move the camera (the next frame uses it). Cascades follow only on a new renderer.
    pub fn set_camera(&mut self, ctx: &GpuContext, camera: Camera) {
        let aspect = self.settings.width as f32 / self.settings.height as f32;
        let (lens_view, eye) = self.lens.unwrap_or((Mat4::IDENTITY, Vec3::ZERO));
        let view = lens_view * camera.transform.inverse();
        let view_proj = projection(&camera, aspect) * view;
        self.frame.view_proj = view_proj.to_cols_array_2d();
        self.frame.inv_view_proj = view_proj.inverse().to_cols_array_2d();
        self.frame.view = view.to_cols_array_2d();
        let eye_world = camera.transform.transform_point3(eye);
        self.frame.camera_pos = eye_world.to_array();
        for m in &mut self.mirrors {
            m.follow(ctx, &camera, eye_world, self.lens, view_proj);
        }
        self.camera = camera;
        ctx.queue
            .write_buffer(&self.frame_buf, 0, bytemuck::bytes_of(&self.frame));
    }

    /// Record and submit one frame; returns its timings.
    pub fn render(&mut self, ctx: &GpuContext) -> FrameTimes {
        let t0 = Instant::now();
        let mut times = FrameTimes::default();
        if std::mem::take(&mut self.moved) {
            self.ambient.geometry_moved(ctx, &self.scene);
        }
        if let Some(d) = &mut self.env.dynamic {
            d.before_frame(ctx, &mut times);
        }
        if matches!(
            self.settings.shadows,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass
        ) {
            let tv = Instant::now();
            self.build_volumes(ctx);
            times.cpu_volumes_ms = tv.elapsed().as_secs_f64() * 1e3;
        }
        self.render_mirrors(ctx, &mut times);
        let mut labels = vec![];
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        self.copy_mirror_images(&mut enc);
        self.prepasses(&mut enc, &mut labels);
        if self.settings.shadows.map() {
            self.shadow_map_passes(&mut enc, &mut labels);
        }
        self.base_pass(
            &mut enc,
            &mut labels,
            self.settings.path == RenderPath::Deferred,
        );
        if !self.ambient.indirect_only() {
            self.sky_pass(&mut enc, &mut labels);
            if !self.ambient.composite() {
                self.light_passes(&mut enc, &mut labels);
            }
        }
        // Tonemap: the 8-bit frame a viewer would display.
        {
            let ts = self.timestamps(&mut labels, "tonemap");
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("tonemap"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.targets.ldr_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: ts,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(self.pipelines.tonemap.get());
            pass.set_bind_group(0, &self.group0, &[0]);
            pass.set_bind_group(1, &self.scene.materials[0].bind_group, &[]);
            pass.set_bind_group(2, &self.group2, &[]);
            pass.set_bind_group(3, &self.tonemap_group, &[]);
            pass.draw(0..3, 0..1);
        }
        if let Some((set, resolve, read)) = &self.queries
            && !labels.is_empty()
        {
            let count = 2 * labels.len() as u32;
            enc.resolve_query_set(set, 0..count, resolve, 0);
            enc.copy_buffer_to_buffer(resolve, 0, read, 0, count as u64 * 8);
        }
        ctx.queue.submit([enc.finish()]);
        if let Some((_, _, read)) = &self.queries
            && !labels.is_empty()
        {
            let slice = read.slice(..labels.len() as u64 * 16);
            slice.map_async(wgpu::MapMode::Read, |_| {});
            let _ = crate::wait_idle(&ctx.device);
            if let Ok(data) = slice.get_mapped_range() {
                let ticks: &[u64] = bytemuck::cast_slice(&data);
                let period = ctx.queue.get_timestamp_period() as f64;
                for (i, l) in labels.iter().enumerate() {
                    let dt = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period * 1e-6;
                    *times.gpu_ms.entry(l).or_default() += dt;
                }
            }
            read.unmap();
        } else {
            let _ = crate::wait_idle(&ctx.device);
        }
        times.wall_ms = t0.elapsed().as_secs_f64() * 1e3;
        times
    }
}
