//! # lightlab-viewer
//!
//! `lightlab view`: a window (winit 0.30) that renders a scene with the GPU techniques of
//! `lightlab-gpu` continuously, with an orbit camera and an egui panel to switch technique,
//! set exposure and tone operator, and read the frame's GPU pass times.
//!
//! The viewer does not know how a technique name becomes a renderer: the caller passes a
//! [`MakeRenderer`] (the CLI maps names to settings and bakes or loads light-maps), so
//! `lightlab render` and the viewer draw the same thing. The window shows the renderer's HDR
//! target through [`display::Display`], which applies the tone operators of
//! `lightlab_core::color` exactly as `lightlab render` writes PNGs.
//!
//! Controls: left drag orbits around the target, right or middle drag pans, the wheel dollies;
//! W/A/S/D/Q/E move, Shift moves faster; 1–9 choose a technique, R resets the camera, H hides
//! the panel, P writes a screenshot (`lightlab-view.png`), M sets the mirror-like objects
//! moving or stops them ([`motion`]), Esc quits.

pub mod camera;
pub mod display;
pub mod lens;
pub mod motion;

use camera::OrbitCamera;
use display::{Display, display_to_rgb8};
use glam::Vec3;
use lightlab_core::color::ToneMap;
use lightlab_gpu::GpuContext;
use lightlab_gpu::raster::{FrameTimes, Renderer};
use lightlab_scene::Scene;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Builds the renderer of technique `name` at `width`×`height` (the viewer then sets its
/// camera), and the camera lens's views in steps (None: a pinhole; see [`lens`]). Errors are
/// shown in the panel; the previous renderer stays.
pub type MakeRenderer<'a> =
    Box<dyn FnMut(&GpuContext, &str, u32, u32) -> Result<Made, MakeError> + 'a>;

/// A camera lens's views, in the steps the viewer renders one per frame.
pub type LensSteps = Vec<Vec<lightlab_gpu::lens_morph::LensView>>;

/// What [`MakeRenderer`] makes: the renderer, the lens's views (None: a pinhole) and, for an
/// animated scene, what poses its frames.
pub type Made = (Renderer, Option<LensSteps>, Option<Box<dyn Animation>>);

/// Plays an animated scene in a technique's renderer.
pub trait Animation {
    /// Frames per second, and frames in one loop.
    fn rate(&self) -> (f32, u32);
    /// Pose frame `frame`: the moving objects, and whatever the technique relights for them.
    fn pose(&mut self, ctx: &GpuContext, r: &mut Renderer, frame: u32) -> Result<(), MakeError>;
}

/// Why a technique's renderer could not be built (shown in the panel).
pub type MakeError = Box<dyn std::error::Error + Send + Sync>;

/// What the viewer opens.
pub struct ViewerConfig {
    pub scene: Scene,
    /// Technique names offered in the panel.
    pub techniques: Vec<String>,
    /// Index into `techniques` of the first one shown.
    pub technique: usize,
    /// Scene camera the view starts from.
    pub camera: usize,
    pub width: u32,
    pub height: u32,
    pub exposure: f32,
    pub tone: ToneMap,
    /// Close after this many presented frames (for scripts and tests).
    pub frames: Option<u64>,
    /// Where P (and the end of a `frames` run) writes the displayed 3D view as PNG.
    pub screenshot: PathBuf,
    /// Write the screenshot when a `frames` run ends.
    pub screenshot_at_end: bool,
    /// Start with the mirror-like objects moving (`motion`); the panel toggles it.
    pub animate: bool,
}

/// Errors of the viewer.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error(
        "cannot open a window: {0}. The viewer needs a display (X11 or Wayland; DISPLAY or \
         WAYLAND_DISPLAY); on a headless machine run it under Xvfb (`xvfb-run lightlab view ...`) \
         or use `lightlab render`"
    )]
    Window(String),
    #[error(transparent)]
    Gpu(#[from] lightlab_gpu::GpuError),
    #[error("the window surface failed: {0}")]
    Surface(String),
    #[error("technique '{technique}': {message}")]
    Renderer { technique: String, message: String },
    #[error("writing the screenshot {path}: {source}")]
    Screenshot {
        path: PathBuf,
        source: ScreenshotError,
    },
    #[error("the scene has no camera {0}")]
    NoCamera(usize),
}

/// What a viewer session did.
#[derive(Clone, Debug, Default)]
pub struct ViewerStats {
    pub frames: u64,
    pub adapter: String,
    pub backend: String,
    /// Mean wall time per presented frame (ms).
    pub mean_frame_ms: f64,
    pub screenshots: Vec<PathBuf>,
}

/// Open the window and run until it is closed (or `frames` frames were shown).
pub fn run(config: ViewerConfig, make: MakeRenderer<'_>) -> Result<ViewerStats, ViewerError> {
    let cam = config
        .scene
        .cameras
        .get(config.camera)
        .ok_or(ViewerError::NoCamera(config.camera))?;
    let home = OrbitCamera::for_scene(cam, config.scene.bounds());
    let event_loop = EventLoop::new().map_err(|e| ViewerError::Window(e.to_string()))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    // An animated scene plays its own animation instead of circling its mirrors.
    let motion = match config.scene.animation {
        Some(_) => None,
        None => motion::Motion::new(&config.scene),
    };
    let animate = config.animate;
    let mut app = App {
        technique: config
            .technique
            .min(config.techniques.len().saturating_sub(1)),
        exposure: config.exposure,
        tone: config.tone,
        cfg: config,
        make,
        gfx: None,
        orbit: home.clone(),
        home,
        rebuild: true,
        result: Ok(()),
        message: None,
        stats: ViewerStats::default(),
        times: FrameTimes::default(),
        started: None,
        last: Instant::now(),
        frame_ms: 0.0,
        keys: HashSet::new(),
        drag: None,
        cursor: None,
        show_ui: true,
        want_screenshot: false,
        motion,
        animate,
        clock: 0.0,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewerError::Window(e.to_string()))?;
    app.result?;
    if app.gfx.is_none() && app.stats.frames == 0 {
        return Err(ViewerError::Window("no window was created".into()));
    }
    if let Some(t0) = app.started
        && app.stats.frames > 0
    {
        app.stats.mean_frame_ms = t0.elapsed().as_secs_f64() * 1e3 / app.stats.frames as f64;
    }
    Ok(app.stats)
}

/// What the panel lets the user change in a frame.
struct Choices {
    technique: usize,
    exposure: f32,
    tone: ToneMap,
    animate: bool,
    reset: bool,
    shot: bool,
}

/// The panel's header, technique, exposure, tone, motion and buttons.
fn panel(
    ui: &mut egui::Ui,
    techniques: &[String],
    header: &str,
    c: &mut Choices,
    motion: Option<&str>,
) {
    ui.label(header);
    egui::ComboBox::from_label("technique")
        .selected_text(&techniques[c.technique])
        .show_ui(ui, |ui| {
            for (i, t) in techniques.iter().enumerate() {
                ui.selectable_value(&mut c.technique, i, t);
            }
        });
    ui.add(
        egui::Slider::new(&mut c.exposure, 0.01..=100.0)
            .logarithmic(true)
            .text("exposure"),
    );
    ui.horizontal(|ui| {
        ui.selectable_value(&mut c.tone, ToneMap::Filmic, "filmic");
        ui.selectable_value(&mut c.tone, ToneMap::Reinhard, "Reinhard");
        ui.selectable_value(&mut c.tone, ToneMap::Clamp, "clamp");
    });
    if let Some(label) = motion {
        ui.checkbox(&mut c.animate, label);
    }
    ui.horizontal(|ui| {
        c.reset = ui.button("reset camera (R)").clicked();
        c.shot = ui.button("screenshot (P)").clicked();
    });
}

/// The panel's frame and pass times, and the last error.
fn timings(ui: &mut egui::Ui, frame_ms: f64, times: &FrameTimes, message: Option<&String>) {
    ui.label(format!("frame {:.2} ms (wall, smoothed)", frame_ms));
    if times.gpu_ms.is_empty() {
        ui.label("no GPU timestamps on this adapter");
    } else {
        let total: f64 = times.gpu_ms.values().sum();
        ui.label(format!("GPU {total:.3} ms"));
        for (k, v) in &times.gpu_ms {
            ui.label(format!("  {k}: {v:.3} ms"));
        }
    }
    if times.cpu_volumes_ms > 0.0 {
        ui.label(format!("CPU volumes {:.3} ms", times.cpu_volumes_ms));
    }
    if let Some(m) = message {
        ui.colored_label(egui::Color32::LIGHT_RED, m);
    }
}

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    display: Display,
    egui: egui_winit::State,
    overlay: Overlay,
    renderer: Option<Renderer>,
    /// The camera lens's film, when the camera has a lens.
    lens: Option<lens::LensState>,
    /// An animated scene's player and the frame it last posed.
    animation: Option<(Box<dyn Animation>, Option<u32>)>,
}

/// The panel's renderer and the texture updates waiting for the next drawn frame.
struct Overlay {
    renderer: egui_wgpu::Renderer,
    pending: egui::TexturesDelta,
}

impl Drop for Overlay {
    fn drop(&mut self) {
        // Updates of a frame that was never drawn are dropped with the window.
        self.pending.clear();
    }
}

struct App<'a> {
    cfg: ViewerConfig,
    make: MakeRenderer<'a>,
    gfx: Option<Gfx>,
    orbit: OrbitCamera,
    home: OrbitCamera,
    technique: usize,
    exposure: f32,
    tone: ToneMap,
    rebuild: bool,
    result: Result<(), ViewerError>,
    message: Option<String>,
    stats: ViewerStats,
    times: FrameTimes,
    started: Option<Instant>,
    last: Instant,
    frame_ms: f64,
    keys: HashSet<KeyCode>,
    drag: Option<MouseButton>,
    cursor: Option<(f64, f64)>,
    show_ui: bool,
    want_screenshot: bool,
    /// The moving objects, if the scene has any, whether they move, and their clock (s).
    motion: Option<motion::Motion>,
    animate: bool,
    clock: f32,
}

impl App<'_> {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: ViewerError) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        event_loop.exit();
    }

    fn create(&mut self, event_loop: &ActiveEventLoop) -> Result<Gfx, ViewerError> {
        let attrs = Window::default_attributes()
            .with_title(format!("lightlab view: {}", self.cfg.scene.name))
            .with_inner_size(PhysicalSize::new(self.cfg.width, self.cfg.height));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| ViewerError::Window(e.to_string()))?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| ViewerError::Surface(e.to_string()))?;
        let ctx = GpuContext::windowed(instance, &surface)?;
        let caps = surface.get_capabilities(&ctx.adapter);
        // An sRGB-encoding 8-bit format where offered (the display pass then writes linear
        // values); otherwise the first, with the transfer function applied in the shader.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb() && f.components() == 4)
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| ViewerError::Surface("the surface offers no format".into()))?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or_default(),
            view_formats: vec![],
        };
        surface.configure(&ctx.device, &config);
        let display = Display::new(&ctx.device, format);
        let egui_ctx = egui::Context::default();
        let egui = egui_winit::State::new(
            egui_ctx,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let overlay = Overlay {
            renderer: egui_wgpu::Renderer::new(&ctx.device, format, Default::default()),
            pending: Default::default(),
        };
        self.stats.adapter = ctx.info.name.clone();
        self.stats.backend = format!("{:?}", ctx.info.backend);
        Ok(Gfx {
            window,
            surface,
            config,
            ctx,
            display,
            egui,
            overlay,
            renderer: None,
            lens: None,
            animation: None,
        })
    }

    /// Move the camera by the held keys over `dt` seconds.
    fn fly(&mut self, dt: f32) {
        let mut d = Vec3::ZERO;
        for (k, v) in [
            (KeyCode::KeyD, Vec3::X),
            (KeyCode::KeyA, -Vec3::X),
            (KeyCode::KeyE, Vec3::Y),
            (KeyCode::KeyQ, -Vec3::Y),
            (KeyCode::KeyW, Vec3::Z),
            (KeyCode::KeyS, -Vec3::Z),
        ] {
            if self.keys.contains(&k) {
                d += v;
            }
        }
        if d != Vec3::ZERO {
            let fast =
                self.keys.contains(&KeyCode::ShiftLeft) || self.keys.contains(&KeyCode::ShiftRight);
            let speed = self.orbit.distance * if fast { 2.0 } else { 0.5 };
            self.orbit.translate(d.normalize() * speed * dt.min(0.1));
        }
    }

    /// Build the chosen technique's renderer; false when the viewer must exit (the first
    /// renderer failed).
    fn rebuild_renderer(&mut self, event_loop: &ActiveEventLoop) -> bool {
        let Some(gfx) = self.gfx.as_mut() else {
            return false;
        };
        self.rebuild = false;
        let (w, h) = (gfx.config.width, gfx.config.height);
        let name = self.cfg.techniques[self.technique].clone();
        match (self.make)(&gfx.ctx, &name, w, h) {
            Ok((r, steps, animation)) => {
                let (rw, rh) = r.size();
                gfx.lens = steps.map(|s| lens::LensState::new(&gfx.ctx, s, rw, rh));
                gfx.animation = animation.map(|a| (a, None));
                gfx.renderer = Some(r);
                self.message = None;
            }
            Err(message) if gfx.renderer.is_none() => {
                self.result = Err(ViewerError::Renderer {
                    technique: name,
                    message: message.to_string(),
                });
                event_loop.exit();
                return false;
            }
            Err(message) => self.message = Some(format!("{name}: {message}")),
        }
        true
    }

    /// One frame: advance the clock, render the technique, run the panel, present, and keep
    /// the statistics (screenshots, the frame limit).
    fn frame(&mut self, event_loop: &ActiveEventLoop) {
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f32();
        self.last = now;
        self.fly(dt);
        if self.rebuild && !self.rebuild_renderer(event_loop) {
            return;
        }
        if !self.render_scene(dt) {
            return;
        }
        let Some(full) = self.run_panel() else {
            return;
        };
        if !self.present(event_loop, full) {
            return;
        }
        self.finish_frame(event_loop, now, dt);
    }

    /// Advance the animation clock and motion, set the orbit camera and render the technique
    /// (or the lens's next aperture samples); false when there is nothing to draw.
    fn render_scene(&mut self, dt: f32) -> bool {
        let Some(gfx) = self.gfx.as_mut() else {
            return false;
        };
        if self.animate {
            self.clock += dt;
        }
        if let Some(m) = play(gfx, &mut self.motion, self.clock) {
            self.message = Some(m);
        }
        let Some(renderer) = gfx.renderer.as_mut() else {
            return false;
        };
        let camera = self.orbit.camera();
        let transform = camera.transform;
        renderer.set_camera(&gfx.ctx, camera);
        match gfx.lens.as_mut() {
            Some(l) => {
                let moving = self.animate && (self.motion.is_some() || gfx.animation.is_some());
                if let Some(t) = l.step(&gfx.ctx, renderer, transform, moving) {
                    self.times = t;
                }
            }
            None => self.times = renderer.render(&gfx.ctx),
        }
        true
    }

    /// Run the panel (when shown) and apply what was chosen in it; egui's output to draw.
    fn run_panel(&mut self) -> Option<egui::FullOutput> {
        let gfx = self.gfx.as_mut()?;
        let renderer = gfx.renderer.as_ref()?;
        let (rw, rh) = (renderer.settings.width, renderer.settings.height);
        let raw = gfx.egui.take_egui_input(&gfx.window);
        let mut c = Choices {
            technique: self.technique,
            exposure: self.exposure,
            tone: self.tone,
            animate: self.animate,
            reset: false,
            shot: false,
        };
        let mut header = format!(
            "{}  ·  {rw}×{rh}\n{} ({:?})",
            self.cfg.scene.name, gfx.ctx.info.name, gfx.ctx.info.backend
        );
        if let Some((done, all)) = gfx.lens.as_ref().map(|l| l.progress()) {
            header += &format!("\nlens: {done} of {all} aperture samples");
        }
        let show_ui = self.show_ui;
        let mut full = gfx.egui.egui_ctx().run_pass(raw, |ctx| {
            if !show_ui {
                return;
            }
            egui::Window::new("lightlab")
                .default_pos([10.0, 10.0])
                .show(ctx, |ui| {
                    let motion = match (&self.motion, &gfx.animation) {
                        (_, Some(_)) => Some("play the scene's animation (M)"),
                        (Some(_), None) => Some("move the mirror-like objects (M)"),
                        (None, None) => None,
                    };
                    panel(ui, &self.cfg.techniques, &header, &mut c, motion);
                    ui.separator();
                    timings(ui, self.frame_ms, &self.times, self.message.as_ref());
                    ui.separator();
                    ui.small("drag: orbit · right/middle drag: pan · wheel: dolly");
                    ui.small("WASD QE: move (Shift: fast) · 1–9 technique · H panel · M motion · Esc quit");
                });
        });
        gfx.egui
            .handle_platform_output(&gfx.window, std::mem::take(&mut full.platform_output));
        // Texture updates wait in `pending` until a frame is actually drawn.
        gfx.overlay
            .pending
            .append(std::mem::take(&mut full.textures_delta));
        if c.technique != self.technique {
            self.technique = c.technique;
            self.rebuild = true;
        }
        self.exposure = c.exposure;
        self.tone = c.tone;
        self.animate = c.animate;
        if c.reset {
            self.orbit = self.home.clone();
        }
        self.want_screenshot |= c.shot;
        Some(full)
    }

    /// Draw the image (tone-mapped) and the panel into the window's next texture and present
    /// it; false when no frame was drawn (the surface was outdated, lost or busy: a redraw is
    /// requested; or it failed).
    fn present(&mut self, event_loop: &ActiveEventLoop, full: egui::FullOutput) -> bool {
        let Some(gfx) = self.gfx.as_mut() else {
            return false;
        };
        let frame = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gfx.surface.configure(&gfx.ctx.device, &gfx.config);
                gfx.window.request_redraw();
                return false;
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                gfx.window.request_redraw();
                return false;
            }
            other => {
                let e = ViewerError::Surface(format!("{other:?}"));
                self.fail(event_loop, e);
                return false;
            }
        };
        let (w, h) = (gfx.config.width, gfx.config.height);
        let view = frame.texture.create_view(&Default::default());
        let mut enc = gfx.ctx.device.create_command_encoder(&Default::default());
        let (shown, scale) = shown_image(gfx);
        gfx.display.draw(
            &gfx.ctx,
            &mut enc,
            shown,
            &view,
            self.exposure * scale,
            self.tone,
        );
        let egui_ctx = gfx.egui.egui_ctx();
        let extra = gfx
            .overlay
            .draw(&gfx.ctx, egui_ctx, &mut enc, &view, full, [w, h]);
        gfx.ctx
            .queue
            .submit(extra.into_iter().chain(std::iter::once(enc.finish())));
        gfx.window.pre_present_notify();
        gfx.ctx.queue.present(frame);
        true
    }

    /// After a presented frame: count it, smooth the frame time, take a screenshot when asked
    /// (or at the end), and exit after the configured number of frames.
    fn finish_frame(&mut self, event_loop: &ActiveEventLoop, now: Instant, dt: f32) {
        self.stats.frames += 1;
        self.started.get_or_insert(now);
        self.frame_ms = if self.stats.frames == 1 {
            dt as f64 * 1e3
        } else {
            0.9 * self.frame_ms + 0.1 * dt as f64 * 1e3
        };
        let done = self.cfg.frames.is_some_and(|n| self.stats.frames >= n);
        if self.want_screenshot || (done && self.cfg.screenshot_at_end) {
            self.want_screenshot = false;
            let Some(gfx) = self.gfx.as_ref() else {
                return;
            };
            let Some(renderer) = gfx.renderer.as_ref() else {
                return;
            };
            let (shown, scale) = shown_image(gfx);
            let path = self.cfg.screenshot.clone();
            let size = (renderer.settings.width, renderer.settings.height);
            let exposure = self.exposure * scale;
            let shot = screenshot(&gfx.ctx, shown, size, &path, exposure, self.tone);
            match shot {
                Ok(()) => self.stats.screenshots.push(path),
                Err(source) => {
                    self.fail(event_loop, ViewerError::Screenshot { path, source });
                    return;
                }
            }
        }
        if done {
            event_loop.exit();
            return;
        }
        if let Some(gfx) = self.gfx.as_ref() {
            gfx.window.request_redraw();
        }
    }
}

/// The image the window shows (the renderer's, or the lens's accumulation) and the exposure
/// scale that goes with it.
fn shown_image(gfx: &Gfx) -> (&wgpu::TextureView, f32) {
    match &gfx.lens {
        Some(l) => l.image(),
        None => (
            gfx.renderer
                .as_ref()
                .expect("a renderer is built before the first frame")
                .hdr_view(),
            1.0,
        ),
    }
}

impl Overlay {
    /// Draw the panel's shapes over `view` (updating and freeing egui's textures); the command
    /// buffers egui's callbacks recorded, to submit before `enc`.
    fn draw(
        &mut self,
        ctx: &GpuContext,
        egui_ctx: &egui::Context,
        enc: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        full: egui::FullOutput,
        size: [u32; 2],
    ) -> Vec<wgpu::CommandBuffer> {
        let ppp = full.pixels_per_point;
        let prims = egui_ctx.tessellate(full.shapes, ppp);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: size,
            pixels_per_point: ppp,
        };
        for (id, deltas) in self.pending.set.drain() {
            for delta in deltas {
                self.renderer
                    .update_texture(&ctx.device, &ctx.queue, id, &delta);
            }
        }
        let extra = self
            .renderer
            .update_buffers(&ctx.device, &ctx.queue, enc, &prims, &screen);
        {
            let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.renderer
                .render(&mut pass.forget_lifetime(), &prims, &screen);
        }
        for id in self.pending.free.drain() {
            self.renderer.free_texture(&id);
        }
        extra
    }
}

/// Pose the scene for `clock`: an animated scene plays its own animation (frame 0 until M
/// starts the clock), others move their mirror-like objects; returns a posing error to show.
fn play(gfx: &mut Gfx, motion: &mut Option<motion::Motion>, clock: f32) -> Option<String> {
    let renderer = gfx.renderer.as_mut()?;
    let Some((player, last)) = gfx.animation.as_mut() else {
        motion::pose(motion, clock, &gfx.ctx, renderer);
        return None;
    };
    let (fps, frames) = player.rate();
    let k = (clock * fps) as u32 % frames.max(1);
    if *last == Some(k) {
        return None;
    }
    *last = Some(k);
    player
        .pose(&gfx.ctx, renderer, k)
        .err()
        .map(|e| format!("frame {k}: {e}"))
}

/// Write the shown image (the renderer's frame or the lens's film) as the window displays
/// it (without the panel).
fn screenshot(
    ctx: &GpuContext,
    shown: &wgpu::TextureView,
    (w, h): (u32, u32),
    path: &Path,
    exposure: f32,
    tone: ToneMap,
) -> Result<(), ScreenshotError> {
    let px = display_to_rgb8(ctx, shown, w, h, exposure, tone)?;
    let bytes: Vec<u8> = px.iter().flatten().copied().collect();
    lightlab_core::image::write_atomic(
        path,
        |f| -> Result<(), lightlab_core::image::ImageError> {
            use image::ImageEncoder;
            image::codecs::png::PngEncoder::new(std::io::BufWriter::new(f))
                .write_image(&bytes, w, h, image::ExtendedColorType::Rgb8)
                .map_err(|e| lightlab_core::image::ImageError::Encode {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                })
        },
    )?;
    Ok(())
}

/// Why a screenshot failed: the GPU readback or the PNG file.
#[derive(Debug, thiserror::Error)]
pub enum ScreenshotError {
    #[error(transparent)]
    Readback(#[from] lightlab_gpu::resources::ReadbackError),
    #[error(transparent)]
    Write(#[from] lightlab_core::image::ImageError),
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        match self.create(event_loop) {
            Ok(g) => {
                g.window.request_redraw();
                self.gfx = Some(g);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gfx) = self.gfx.as_mut() else {
            return;
        };
        let consumed = gfx.egui.on_window_event(&gfx.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                gfx.config.width = size.width;
                gfx.config.height = size.height;
                gfx.surface.configure(&gfx.ctx.device, &gfx.config);
                self.rebuild = true;
            }
            WindowEvent::RedrawRequested => self.frame(event_loop),
            WindowEvent::KeyboardInput { event, .. } if !consumed => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                if event.state == ElementState::Released {
                    self.keys.remove(&code);
                    return;
                }
                self.keys.insert(code);
                if event.repeat {
                    return;
                }
                let digit = [
                    KeyCode::Digit1,
                    KeyCode::Digit2,
                    KeyCode::Digit3,
                    KeyCode::Digit4,
                    KeyCode::Digit5,
                    KeyCode::Digit6,
                    KeyCode::Digit7,
                    KeyCode::Digit8,
                    KeyCode::Digit9,
                ]
                .iter()
                .position(|k| *k == code);
                match code {
                    KeyCode::Escape => event_loop.exit(),
                    KeyCode::KeyR => self.orbit = self.home.clone(),
                    KeyCode::KeyM => self.animate = !self.animate,
                    KeyCode::KeyH => self.show_ui = !self.show_ui,
                    KeyCode::KeyP => self.want_screenshot = true,
                    _ => {
                        if let Some(i) = digit
                            && i < self.cfg.techniques.len()
                            && i != self.technique
                        {
                            self.technique = i;
                            self.rebuild = true;
                        }
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                if state == ElementState::Pressed && !consumed {
                    self.drag = Some(button);
                } else if state == ElementState::Released {
                    self.drag = None;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = (position.x, position.y);
                if let (Some(b), Some(last)) = (self.drag, self.cursor) {
                    let (dx, dy) = ((p.0 - last.0) as f32, (p.1 - last.1) as f32);
                    if b == MouseButton::Left {
                        self.orbit.orbit(dx, dy);
                    } else {
                        // Pan: one window height of drag moves the view by its height at
                        // the target's distance.
                        let s = 2.0 * self.orbit.distance * (self.orbit.yfov * 0.5).tan()
                            / gfx.config.height as f32;
                        self.orbit.translate(Vec3::new(-dx * s, dy * s, 0.0));
                    }
                }
                self.cursor = Some(p);
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 50.0,
                };
                self.orbit.dolly(steps);
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(g) = &self.gfx
            && !self.keys.is_empty()
        {
            g.window.request_redraw();
        }
    }
}
