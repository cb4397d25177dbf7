//! Light propagation volumes on the GPU: reflective shadow maps, injection,
//! propagation and the 3D textures the renderer's ambient pass reads (`Renderer::with_lpv`).
//!
//! Per frame, [`Lpv::record`] runs, for every RSM view (directional and spot lights, the six
//! cube faces of a point light, each emissive instance as a Lambertian area light seen from
//! its centre, and the sky's cells as directional lights at a quarter of the side, in targets
//! of their own; at most [`MAX_RSM_LIGHTS`]):
//! 1. the RSM pass: flux, normal (+ diffuse transmission), position (+ texel area ⊥ the light);
//! 2. injection (compute): Kaplanyan scatters every texel as a cosine lobe into fixed-point
//!    atomics (WGSL has no float atomics) and, with occlusion, its blocker into the geometry
//!    volume in the same dispatch; the WPI scheme gathers per voxel.
//!
//! then resolves the atomics, propagates `iterations` times (ping-pong storage buffers, the
//! accumulation in a third) and stores the result into three `Rgba16Float` 3D textures, one per
//! colour, which the ambient pass samples trilinearly. `lightlab_core::lpv` is the CPU reference
//! of each step; `tests/lpv.rs` compares the two.
//!
//! Limits: an emissive instance is seen through a 150° frustum from its centre (light leaving at more than 75° from its
//! normal is not injected) and one that is not roughly planar (|Σ n·A| < ½ΣA) is skipped.

use crate::GpuContext;
use crate::gpu_scene::GpuScene;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use glam::camera::rh::proj::directx;
use glam::camera::rh::view::look_to_mat4;
use lightlab_core::color::luminance;
use lightlab_core::lpv::{self, Grid};
use lightlab_scene::{LightKind, Scene};
use wgpu::util::DeviceExt;

mod setup;

/// WGSL of the LPV passes: common.wgsl, material.wgsl, lpv.wgsl.
pub static LPV_SOURCE: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!(
        "{}\n{}\n{}",
        crate::uniforms::COMMON_WGSL,
        crate::uniforms::MATERIAL_WGSL,
        include_str!("../shaders/lpv.wgsl")
    )
});

/// Which propagation scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LpvScheme {
    /// Kaplanyan & Dachsbacher (2010): flux RSM, scattered cosine lobes, 6-face propagation with
    /// a geometry volume and accumulation; irradiance lookup (`lpv`).
    Kaplanyan,
    /// The WPI report (2011): gathered SH deltas, 18-neighbour additive propagation, point
    /// evaluation at −n (`lpv-faithful`).
    Wpi,
}

#[derive(Clone, Debug)]
pub struct LpvSettings {
    pub scheme: LpvScheme,
    /// Cells per axis.
    pub grid: u32,
    /// Propagation steps; None = 8 (Kaplanyan & Dachsbacher's figure for 32³: the 2-band
    /// transport is diffusive and does not carry light much further, see docs/lpv.md; cascades
    /// reach further) or 2 (WPI, as the report's Fig 6.1).
    pub iterations: Option<u32>,
    /// RSM side in texels.
    pub rsm_size: u32,
    /// Attenuate propagation by the geometry volume (Kaplanyan only).
    pub occlusion: bool,
    /// WPI gather injection: samples per voxel.
    pub wpi_samples: u32,
    /// Empty cells around the scene on each side.
    pub margin: f32,
    /// Damping against self-illumination (Kaplanyan only): the lookup also reads this many
    /// cells further along the normal and keeps the smaller irradiance; 0 = off
    /// (`lightlab_core::lpv::Volume::irradiance_damped`).
    pub damping: f32,
    /// Nested volumes (Kaplanyan only): the coarsest fitted around the scene, each finer one
    /// with half the cell size, following the camera (`lightlab_core::lpv::cascade_grids`).
    pub cascades: u32,
    /// Move the camera-following cascades in whole cells only (against flicker).
    pub snap: bool,
    /// With occlusion, also inject blockers from the camera's view (Kaplanyan: the geometry
    /// volume from the RSM *and* the G-buffer): surfaces no light sees (a ceiling above the
    /// lamp) then stop light too. Where a light and the camera see the same surface, the cell
    /// keeps the larger of the two blockers, not their sum.
    pub camera_blockers: bool,
    /// Place the cascades for this eye position and view direction instead of the render
    /// camera's (e.g. around a player, or to test a moved camera against a fixed view).
    pub anchor: Option<(Vec3, Vec3)>,
    /// How the light crossing a receiving cell's side faces is re-emitted (Kaplanyan only):
    /// `Central` (default) keeps its direction, `FaceNormal` is Kaplanyan & Dachsbacher's
    /// original (see `lightlab_core::lpv::Reemit`).
    pub reemit: lpv::Reemit,
    /// With `Reemit::Central`, the side faces' re-emitted lobe: its band-1 weight relative to
    /// a delta's, ⅔ for Kaplanyan's cosine lobe, more to keep the light's direction
    /// (`lightlab_core::lpv::reemission_lobe`; default `DEFAULT_REEMIT_LOBE`).
    pub reemit_lobe: f32,
    /// Whether light the geometry volume blocks is absorbed (`Single`: one bounce) or
    /// reflected × the blocking surfaces' albedo (`Multiple`, the default; Kaplanyan only,
    /// with `occlusion`; see `lightlab_core::lpv::Bounces`).
    pub bounces: lpv::Bounces,
    /// Keep the volume's light only from the share of the hemisphere whose first surface lies
    /// beyond the lookup's reach (0.5 + `damping` cells of the scene's grid): not from the
    /// open sky, nor from surfaces nearer than the cells resolve. Read from the sky's depth
    /// maps (Kaplanyan only; needs an environment, so none on cornell). See
    /// [`Lpv::near_occlusion_radius`].
    pub near_occlusion: bool,
    /// The near field: the light of the surfaces within the lookup's reach, which near
    /// occlusion takes out of the volume's light, gathered from the last light's RSM when it
    /// is directional (the sun) with this many texels per pixel, occluded through the geometry
    /// volume; on opaque surfaces only (Dachsbacher & Stamminger 2005's RSM gathering). 0 =
    /// none; needs `near_occlusion`.
    pub near_field: u32,
    /// The sky's light injected as this many directional RSM views (the environment split into
    /// cells, `raster::ambient::sky::sky_lights`), so that the volume carries the bounce of sky
    /// light, occluded as the sun's is; 0 = none (the sky then lights only directly).
    pub sky_lights: u32,
}

/// `lpv`'s cells per axis by default. With multiple bounces a coarse grid wins: each step
/// moves light by a cell, so a 16³ volume lets light cross a room in a third of the steps a 32³
/// one needs, and 2-band lobes blur less per metre travelled. Measured (relMSE against
/// `reference`, ratio to the CPU's direct light; docs/lpv.md): room 0.45×, cornell 0.27×,
/// atrium 0.33× at 16³ × 48 steps, against 0.71×, 0.55×, 0.39× at 32³ × 32 steps.
pub const DEFAULT_GRID: u32 = 16;
/// The near field's RSM texels per pixel by default ([`LpvSettings::near_field`]).
pub const DEFAULT_NEAR_FIELD: u32 = 32;
/// The most near-field texels per pixel.
pub const MAX_NEAR_FIELD: u32 = 256;
/// `lpv-faithful`'s grid (the WPI report's 32³).
pub const FAITHFUL_GRID: u32 = 32;
/// `lpv`'s propagation steps per cell of the grid by default: light crosses the volume three
/// times, so a closed room gets its second and third bounces and an open scene's light has
/// left. At 16³ the 48 steps cost fewer cell updates (196 k) than 32³ × 8 did (262 k).
pub const STEPS_PER_CELL: u32 = 3;

impl Default for LpvSettings {
    fn default() -> Self {
        LpvSettings {
            scheme: LpvScheme::Kaplanyan,
            grid: DEFAULT_GRID,
            iterations: None,
            rsm_size: 256,
            occlusion: true,
            wpi_samples: 16,
            margin: 1.0,
            damping: 2.0,
            cascades: 1,
            snap: true,
            camera_blockers: true,
            anchor: None,
            reemit: lpv::Reemit::Central,
            reemit_lobe: lpv::DEFAULT_REEMIT_LOBE,
            bounces: lpv::Bounces::Multiple,
            near_occlusion: true,
            near_field: DEFAULT_NEAR_FIELD,
            sky_lights: DEFAULT_SKY_LIGHTS,
        }
    }
}

/// Errors of the light propagation volume.
#[derive(Debug, thiserror::Error)]
pub enum LpvError {
    #[error("invalid LPV settings: {0}")]
    Settings(String),
    #[error("the volume has no cascade {0}")]
    NoCascade(usize),
    #[error(transparent)]
    Readback(#[from] crate::resources::ReadbackError),
}

impl LpvSettings {
    pub fn iterations(&self) -> u32 {
        self.iterations.unwrap_or(match self.scheme {
            LpvScheme::Kaplanyan => STEPS_PER_CELL * self.grid,
            LpvScheme::Wpi => 2,
        })
    }

    /// Refuse settings out of range or that the scheme does not have.
    pub fn validate(&self) -> Result<(), LpvError> {
        self.problem().map_err(LpvError::Settings)
    }

    fn problem(&self) -> Result<(), String> {
        if !(4..=256).contains(&self.grid) {
            return Err(format!("LPV grid {} must be within 4..=256", self.grid));
        }
        if !(16..=4096).contains(&self.rsm_size) {
            return Err(format!(
                "RSM size {} must be within 16..=4096",
                self.rsm_size
            ));
        }
        if self.iterations() > 1024 {
            return Err(format!(
                "LPV iterations {} must be at most 1024",
                self.iterations()
            ));
        }
        if !(1..=256).contains(&self.wpi_samples) {
            return Err("WPI samples per voxel must be within 1..=256".into());
        }
        if !(self.damping.is_finite() && (0.0..=8.0).contains(&self.damping)) {
            return Err(format!(
                "LPV damping {} must be within 0..=8 cells",
                self.damping
            ));
        }
        if self.near_field > MAX_NEAR_FIELD {
            return Err(format!(
                "LPV near-field samples {} must be at most {MAX_NEAR_FIELD}",
                self.near_field
            ));
        }
        if self.sky_lights as usize > MAX_RSM_LIGHTS {
            return Err(format!(
                "LPV sky lights {} must be at most {MAX_RSM_LIGHTS} (RSM views)",
                self.sky_lights
            ));
        }
        if !(1..=4).contains(&self.cascades) {
            return Err(format!(
                "LPV cascades {} must be within 1..=4",
                self.cascades
            ));
        }
        if self.cascades > 1 && self.scheme == LpvScheme::Wpi {
            return Err(
                "lpv-faithful has a single volume (the report's); cascades need lpv".into(),
            );
        }
        let reemission =
            self.reemit != lpv::Reemit::Central || self.reemit_lobe != lpv::DEFAULT_REEMIT_LOBE;
        if reemission && self.scheme == LpvScheme::Wpi {
            return Err(
                "lpv-faithful propagates with the report's 18-neighbour kernel; the re-emission \
                 of the 6-face scheme applies to lpv"
                    .into(),
            );
        }
        if !(self.reemit_lobe.is_finite() && (0.0..=1.0).contains(&self.reemit_lobe)) {
            return Err(format!(
                "LPV re-emission lobe {} must be within 0..=1 (⅔: a cosine lobe, 1: a delta)",
                self.reemit_lobe
            ));
        }
        if !(self.margin.is_finite() && (0.0..=self.grid as f32 / 4.0).contains(&self.margin)) {
            return Err("LPV margin must be within 0..=grid/4 cells".into());
        }
        Ok(())
    }

    /// The volume's grid around the scene's bounds (the coarsest cascade).
    pub fn grid_for(&self, scene: &Scene) -> Grid {
        let (lo, hi) = scene
            .bounds()
            .unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
        Grid::around(lo, hi, self.grid, self.margin)
    }

    /// The cascades' grids, finest first, for a camera at `eye` looking along `forward`
    /// (`anchor` overrides both).
    pub fn grids_for(&self, scene: &Scene, eye: Vec3, forward: Vec3) -> Vec<Grid> {
        let (eye, forward) = self.anchor.unwrap_or((eye, forward));
        lightlab_core::lpv::cascade_grids(
            self.grid_for(scene),
            self.cascades,
            eye,
            forward,
            self.snap,
        )
    }
}

/// WGSL `LpvUniforms`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LpvUniforms {
    pub origin: [f32; 3],
    pub cell: f32,
    pub n: u32,
    pub use_gv: u32,
    pub scale: f32,
    pub gv_scale: f32,
    pub rsm_size: u32,
    pub wpi_samples: u32,
    pub store_last: u32,
    /// 1: the injection also fills the geometry volume.
    pub occlusion: u32,
    /// First z texel of this cascade in the stacked 3D textures.
    pub layer: u32,
    /// Side faces' re-emission: 0 around the face normal (Kaplanyan), 1 along the light's
    /// direction (`lightlab_core::lpv::Reemit`).
    pub reemit: u32,
    pub bounces: u32,
    /// `reemit` = 1: the side faces' lobe (`lightlab_core::lpv::reemission_lobe`).
    pub lobe: f32,
    /// Wind sway (lightlab_core::wind::Wind::uniform), the same as the camera passes'.
    pub wind_a: [f32; 4],
    pub wind_b: [f32; 4],
}

/// WGSL `RsmLight`: one light of the reflective shadow maps.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RsmLight {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    /// 0 directional, 1 spot, 2 emissive area, 3 the camera, 4 a cube face of a goniometric
    /// light.
    pub kind: u32,
    pub axis: [f32; 3],
    pub texel: f32,
    pub color: [f32; 3],
    pub cos_inner: f32,
    pub cos_outer: f32,
    /// Kind 4: the layer of its candela table (`photometric.rs`), its C0 axis and nadir.
    pub profile: u32,
    /// 1: a cell of the sky ([`LpvSettings::sky_lights`]): its surfels light but do not
    /// block (the scene's lights and the camera see the surfaces that matter, and blockers
    /// of several views add up).
    pub sky: u32,
    /// The side of the RSM this view renders (its viewport's, from the top-left corner).
    pub size: u32,
    pub c0: [f32; 3],
    pub pad3: f32,
    pub nadir: [f32; 3],
    pub pad4: f32,
}

/// An RSM side for a grid of `grid` cells per axis: 32 texels per cell (clamped to 256..=2048,
/// a power of two). Fewer texels than that leave a surface seen at a grazing angle with a few
/// bright VPLs per cell, whose 2-band lobes (negative behind them) speckle the indirect light
/// with dark and bright spots (cornell's tall box at 32³ with a 256² RSM).
pub fn rsm_size_for_grid(grid: u32) -> u32 {
    grid.saturating_mul(32).next_power_of_two().clamp(256, 2048)
}

/// The candela tables of the scene's goniometric lights, in the scene's order (the layers
/// [`rsm_lights`] gives them).
fn profile_texture(ctx: &GpuContext, scene: &Scene) -> wgpu::TextureView {
    let profiles: Vec<_> = scene
        .lights
        .iter()
        .filter_map(|l| match &l.kind {
            LightKind::Goniometric { profile, .. } => Some(&**profile),
            _ => None,
        })
        .collect();
    crate::photometric::profile_texture(ctx, &profiles)
}

/// Half-angle of the frustum an emissive instance is seen through.
const AREA_HALF_ANGLE: f32 = 75.0 * std::f32::consts::PI / 180.0;
/// Sky directions injected by default ([`LpvSettings::sky_lights`]).
pub const DEFAULT_SKY_LIGHTS: u32 = 16;
/// At most this many RSM views (the first ones of the scene; a point light takes six).
pub const MAX_RSM_LIGHTS: usize = 24;

/// The RSM lights of a scene, and of `extra` (the environment's sun taken out as a light), for
/// a volume `grid`, with an upper bound of the flux each can put into its RSM (for the
/// fixed-point scale).
pub fn rsm_lights(
    scene: &Scene,
    extra: Option<&lightlab_scene::Light>,
    sky: &[(Vec3, Vec3)],
    grid: &Grid,
    size: u32,
) -> Vec<(RsmLight, f32)> {
    let half = 0.5 * grid.cell * grid.n as f32;
    let centre = grid.origin + Vec3::splat(half);
    let radius = half * 3f32.sqrt();
    let mut out = Vec::new();
    let up_for = |d: Vec3| {
        if d.y.abs() > 0.99 { Vec3::X } else { Vec3::Y }
    };
    let far_from = |eye: Vec3| (eye - centre).length() + radius;
    let mut layers = 0u32;
    for l in scene.lights.iter().chain(extra) {
        let colour = l.color * l.intensity;
        // A square perspective view of half-angle `half` from `eye` along `d` (kind 1).
        let spot_view = |eye: Vec3, d: Vec3, half: f32| RsmLight {
            kind: 1,
            color: colour.to_array(),
            ..square_view(eye, d, up_for(d), half, far_from(eye), size)
        };
        match &l.kind {
            LightKind::Directional { .. } => {
                out.push(directional_view(l.direction, colour, centre, radius, size));
            }
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => {
                let d = l.direction.normalize();
                let half = outer_cone.clamp(0.01, 1.48);
                out.push((
                    RsmLight {
                        cos_inner: inner_cone.cos(),
                        cos_outer: outer_cone.cos(),
                        ..spot_view(l.position, d, half)
                    },
                    colour.max_element() * 2.0 * std::f32::consts::PI * (1.0 - half.cos()),
                ));
            }
            LightKind::Goniometric { profile, .. } => {
                // Six 90° faces, each scaled by the candela table's lookup (kind 4); layers
                // in the scene's order ([`profile_texture`]).
                let layer = layers;
                layers += 1;
                let tilt = profile.tilt_factor(l.tilt_angle());
                for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
                    out.push((
                        RsmLight {
                            kind: 4,
                            profile: layer,
                            c0: l.local_frame().row(0).to_array(),
                            nadir: l.direction.normalize().to_array(),
                            color: (colour * tilt).to_array(),
                            ..spot_view(l.position, d, std::f32::consts::FRAC_PI_4)
                        },
                        l.peak_intensity() * 4.0 * std::f32::consts::PI / 6.0,
                    ));
                }
            }
            LightKind::Point => {
                // Six 90° faces of a cube around the light, each a spot light without falloff
                // (cos_outer = −1 keeps the spot factor at 1 over the face).
                let half = std::f32::consts::FRAC_PI_4;
                for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
                    out.push((
                        RsmLight {
                            cos_inner: 0.0,
                            cos_outer: -1.0,
                            ..spot_view(l.position, d, half)
                        },
                        // Each face holds at most a sixth of 4π·I (its solid angle is 4π/6).
                        colour.max_element() * 4.0 * std::f32::consts::PI / 6.0,
                    ));
                }
            }
        }
    }
    for e in scene.planar_emitters() {
        let (n, c, area, emission) = (e.normal, e.centre, e.area, e.radiance);
        let eye = c + n * (1e-3 * grid.cell);
        let far = far_from(eye).max(1e-3);
        let view = look_to_mat4(eye, n, up_for(n));
        let proj = directx::perspective(2.0 * AREA_HALF_ANGLE, 1.0, far * 1e-4, far);
        let texel = (2.0 * AREA_HALF_ANGLE.tan() / size as f32).powi(2);
        let colour = emission * area;
        out.push((
            RsmLight {
                view_proj: (proj * view).to_cols_array_2d(),
                eye: eye.to_array(),
                kind: 2,
                axis: n.to_array(),
                texel,
                color: colour.to_array(),
                size,
                ..Default::default()
            },
            colour.max_element() * std::f32::consts::PI,
        ));
    }
    // The sky's cells last: the scene's own lights keep their views when there are too many.
    // Sky light is smooth: a quarter of the side (a sixteenth of the texels) per cell.
    let sky_size = (size / 4).max(64).min(size);
    for (towards, e) in sky {
        let (light, bound) = directional_view(-*towards, *e, centre, radius, sky_size);
        out.push((RsmLight { sky: 1, ..light }, bound));
    }
    out.truncate(MAX_RSM_LIGHTS);
    out
}

/// `near`'s share of the irradiance that the directional views among `lights` (the scene's
/// directional lights, the environment's sun, the sky's cells) give an open surface facing up:
/// how much of the light the volume holds the near field's light brings, as it lights the
/// ground and what stands on it. On thin translucent surfaces the near field takes the place of
/// that share of the volume's light (ambient_lpv.wgsl, docs/lpv.md). Point, spot and area
/// lights do not count: on leaves their light is kept at 1 − the share. 1 where no view
/// lights an upward surface.
pub fn near_field_share<'a>(near: &RsmLight, lights: impl Iterator<Item = &'a RsmLight>) -> f32 {
    let up = |l: &RsmLight| luminance(Vec3::from(l.color)) * (-l.axis[1]).max(0.0);
    let total: f32 = lights.filter(|l| l.kind == 0).map(up).sum();
    if total > 0.0 {
        (up(near) / total).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// A directional light travelling along `d` with irradiance `colour` on a surface facing it:
/// an orthographic view over the sphere (centre, radius), and its flux bound.
fn directional_view(
    d: Vec3,
    colour: Vec3,
    centre: Vec3,
    radius: f32,
    size: u32,
) -> (RsmLight, f32) {
    let d = d.normalize();
    let up = if d.y.abs() > 0.99 { Vec3::X } else { Vec3::Y };
    let eye = centre - d * (radius * 1.01);
    let view = look_to_mat4(eye, d, up);
    let proj = directx::orthographic(-radius, radius, -radius, radius, 0.0, 2.02 * radius);
    let texel = (2.0 * radius / size as f32).powi(2);
    let light = RsmLight {
        view_proj: (proj * view).to_cols_array_2d(),
        eye: eye.to_array(),
        kind: 0,
        axis: d.to_array(),
        texel,
        color: colour.to_array(),
        size,
        ..Default::default()
    };
    (light, colour.max_element() * 4.0 * radius * radius)
}

/// The camera as an RSM view without light (kind 3): a square frustum covering its field of
/// view, whose surfels only block.
fn camera_view(camera: &lightlab_scene::Camera, aspect: f32, grid: &Grid, size: u32) -> RsmLight {
    let eye = camera.position();
    let forward = camera
        .transform
        .transform_vector3(-Vec3::Z)
        .normalize_or(-Vec3::Z);
    let up = camera
        .transform
        .transform_vector3(Vec3::Y)
        .normalize_or(Vec3::Y);
    let t = (0.5 * camera.yfov).tan();
    let half = (t * aspect.max(1.0)).atan().min(1.48);
    let centre = grid.origin + Vec3::splat(0.5 * grid.cell * grid.n as f32);
    let far = (eye - centre).length() + 0.87 * grid.cell * grid.n as f32;
    RsmLight {
        kind: 3,
        color: [0.0; 3],
        ..square_view(eye, forward, up, half, far, size)
    }
}

/// A square perspective RSM view of half-angle `half` from `eye` along `d` reaching `far`, with
/// the solid angle of one of its `size`² texels at the centre.
fn square_view(eye: Vec3, d: Vec3, up: Vec3, half: f32, far: f32, size: u32) -> RsmLight {
    let far = far.max(1e-3);
    let view = look_to_mat4(eye, d, up);
    let proj = directx::perspective(2.0 * half, 1.0, far * 1e-4, far);
    RsmLight {
        view_proj: (proj * view).to_cols_array_2d(),
        eye: eye.to_array(),
        axis: d.to_array(),
        texel: (2.0 * half.tan() / size as f32).powi(2),
        size,
        ..Default::default()
    }
}

const RSM_FORMATS: [wgpu::TextureFormat; 3] = [
    wgpu::TextureFormat::Rgba16Float,
    wgpu::TextureFormat::Rgba16Float,
    wgpu::TextureFormat::Rgba32Float,
];
const SLOT: u64 = 256;

/// The compute pipelines of injection, propagation and storing.
struct Compute {
    inject: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    propagate: wgpu::ComputePipeline,
    inject_wpi: wgpu::ComputePipeline,
    propagate_wpi: wgpu::ComputePipeline,
    store: wgpu::ComputePipeline,
}

/// One cascade's atomics, ping-pong buffers and bind groups.
struct Cascade {
    /// Ping-pong bind groups: [0] reads A writes B, [1] reads B writes A.
    groups: [wgpu::BindGroup; 2],
    /// As `groups[1]`, reading the sky views' RSM (when there are sky views).
    sky_group: Option<wgpu::BindGroup>,
    lpv_atomic: wgpu::Buffer,
    gv_atomic: wgpu::Buffer,
    /// The geometry volume: blocking SH at 2i, albedo sums at 2i + 1, per cell corner.
    gv: wgpu::Buffer,
    buffers: [wgpu::Buffer; 2],
}

/// The GPU resources of a light propagation volume (one per cascade).
pub struct Lpv {
    pub settings: LpvSettings,
    /// The cascades' grids, finest first; the last is fitted around the scene.
    pub grids: Vec<Grid>,
    /// Each RSM view's side and whether it is the sky's, in the order they are rendered.
    light_sizes: Vec<(u32, bool)>,
    /// `lpv-faithful` lit by one directional light: that light's RSM view, whose depth the
    /// report's composite reads as its shadow map ([`Lpv::composite_light`]).
    composite_light: Option<RsmLight>,
    near_field_light: Option<RsmLight>,
    near_field_share: f32,
    rsm_pipeline: wgpu::RenderPipeline,
    rsm_group: wgpu::BindGroup,
    rsm_views: Vec<wgpu::TextureView>,
    rsm_textures: Vec<wgpu::Texture>,
    rsm_depth: wgpu::TextureView,
    /// The sky views' own RSM targets (views and depth), smaller than the lights'.
    sky_rsm: Option<(Vec<wgpu::TextureView>, wgpu::TextureView)>,
    compute: Compute,
    cascades: Vec<Cascade>,
    /// The uniform slots (2 per cascade) and their bytes, rewritten when the wind changes.
    uniforms: wgpu::Buffer,
    uniform_bytes: Vec<u8>,
    /// The three 3D textures (r, g, b) the renderer samples, the cascades stacked along z.
    pub textures: [wgpu::Texture; 3],
}

/// The environment's light the volume injects besides the scene's lights.
#[derive(Clone, Copy, Default)]
pub struct EnvLights<'a> {
    /// The environment's sun taken out as a directional light.
    pub sun: Option<&'a lightlab_scene::Light>,
    /// The environment's diffuse light as directional lights, (unit direction towards the sky,
    /// E⊥) each ([`LpvSettings::sky_lights`]).
    pub sky: &'a [(Vec3, Vec3)],
}

/// Bytes of one cell's 12 floats.
const CELL_BYTES: u64 = 48;

impl Lpv {
    /// The volumes for `camera` (where the cascades go, and whose view adds blockers) with an
    /// image of `aspect` = width/height, lit by the scene's lights and the environment's.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        env: EnvLights,
        settings: LpvSettings,
        camera: &lightlab_scene::Camera,
        aspect: f32,
        wind: &lightlab_core::wind::Wind,
    ) -> Result<Lpv, LpvError> {
        settings.validate()?;
        let device = &ctx.device;
        let eye = camera.position();
        let forward = camera
            .transform
            .transform_vector3(-Vec3::Z)
            .normalize_or(-Vec3::Z);
        let grids = settings.grids_for(scene, eye, forward);
        let grid = *grids.last().expect("at least one cascade");
        let size = settings.rsm_size;
        // The report's volume holds its sun's light only (its sky is a term of the composite).
        let sky = if settings.scheme == LpvScheme::Wpi {
            &[]
        } else {
            env.sky
        };
        let mut lights = rsm_lights(scene, env.sun, sky, &grid, size);
        // The sky's cells first, so that the last view rendered (the RSM textures' content,
        // for the debug views) is a light's at the full size.
        lights.sort_by_key(|l| l.0.sky == 0);
        let bound = lights.iter().map(|l| l.1).sum::<f32>().max(1e-12);
        if settings.occlusion && settings.camera_blockers && settings.scheme == LpvScheme::Kaplanyan
        {
            // First, so that the last view rendered (the RSM textures' content) is a light's.
            lights.insert(0, (camera_view(camera, aspect, &grid, size), 0.0));
        }
        let light_sizes = lights.iter().map(|l| (l.0.size, l.0.sky == 1)).collect();
        let composite_light = match lights.as_slice() {
            [(only, _)] if settings.scheme == LpvScheme::Wpi && only.kind == 0 => Some(*only),
            _ => None,
        };
        let near_field_light = lights
            .last()
            .filter(|l| l.0.kind == 0 && l.0.sky == 0 && settings.scheme == LpvScheme::Kaplanyan)
            .map(|l| l.0);
        let near_field_share = near_field_light.as_ref().map_or(0.0, |near| {
            near_field_share(near, lights.iter().map(|l| &l.0))
        });
        let uniform_bytes = setup::uniform_slots(&settings, &grids, bound, wind);
        let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lpv uniforms"),
            contents: &uniform_bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let light_buf = setup::light_slots(device, &lights);
        let textures = setup::volume_textures(device, grid.n, grids.len() as u32);
        let (rsm_textures, rsm_views, rsm_depth) = setup::rsm_targets(device, size);
        let sky_rsm = lights.iter().find(|l| l.0.sky == 1).map(|l| {
            let (_, views, depth) = setup::rsm_targets(device, l.0.size);
            (views, depth)
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lpv"),
            source: wgpu::ShaderSource::Wgsl(LPV_SOURCE.as_str().into()),
        });
        let profiles = profile_texture(ctx, scene);
        let (rsm_pipeline, rsm_group) =
            setup::rsm_pass(device, &module, &uniforms, &light_buf, &profiles);
        let layout = setup::compute_layout(device);
        let compute = setup::compute_pipelines(device, &module, &layout);
        let inputs = setup::CascadeInputs {
            layout: &layout,
            uniforms: &uniforms,
            lights: &light_buf,
            rsm: &rsm_views,
            sky_rsm: sky_rsm.as_ref().map(|r| r.0.as_slice()),
            out: &textures
                .each_ref()
                .map(|t| t.create_view(&Default::default())),
        };
        let cascades = grids
            .iter()
            .map(|g| setup::cascade(device, &inputs, g.n))
            .collect();
        Ok(Lpv {
            settings,
            grids,
            light_sizes,
            composite_light,
            near_field_light,
            near_field_share,
            rsm_pipeline,
            rsm_group,
            rsm_views,
            rsm_textures,
            rsm_depth,
            sky_rsm,
            compute,
            cascades,
            uniforms,
            uniform_bytes,
            textures,
        })
    }

    /// The lookup's reach [m]: the volume's light comes only from surfaces further than this
    /// (0: off). A lookup reads the volume half a cell out along the normal and, with damping,
    /// `damping` cells further: a surface nearer than that is below what the volume resolves,
    /// and the light the volume holds there arrives around it; a direction that sees the sky
    /// brings the sky's light and no bounce, though the 2-band lobes spread a surface's
    /// outgoing light over it. The ambient pass keeps, of the volume's light, the share of the
    /// sky's shadow-mapped directions (cosine and solid-angle weighted) whose first surface
    /// lies beyond this radius (Crytek paired their volumes with screen-space occlusion of
    /// about a cell for the near part).
    pub fn near_occlusion_radius(&self) -> f32 {
        if !self.settings.near_occlusion || self.settings.scheme != LpvScheme::Kaplanyan {
            return 0.0;
        }
        let cell = self.grids.last().map_or(0.0, |g| g.cell);
        (0.5 + self.settings.damping.max(0.0)) * cell
    }

    /// GPU memory of the volumes and the RSM [bytes]: per cascade the fixed-point injection
    /// atomics (48 B/cell), the ping-pong and accumulation buffers (3 × 48 B/cell), the geometry
    /// volume (blocking SH and albedo: 32 B) and its atomics (lights', camera's blockers and the
    /// albedo: 48 B) per (n+1)³ cell, plus the three RGBA16F 3D textures
    /// (24 B/cell) and the RSM (flux, normal: 8 B, position: 16 B, depth: 4 B per texel), the
    /// lights' and the sky views' smaller one.
    pub fn memory_bytes(&self) -> u64 {
        let n = self.grids[0].n as u64;
        let cascades = self.grids.len() as u64;
        let per_cascade = 4 * CELL_BYTES * n.pow(3) + 80 * (n + 1).pow(3) + 24 * n.pow(3);
        let texel = 8 + 8 + 16 + 4;
        let rsm = (self.settings.rsm_size as u64).pow(2) * texel;
        let sky = self
            .light_sizes
            .iter()
            .find(|l| l.1)
            .map_or(0, |l| (l.0 as u64).pow(2) * texel);
        cascades * per_cascade + rsm + sky
    }

    /// Sway the RSM's geometry with `wind` from the next frame on.
    pub fn set_wind(&mut self, ctx: &GpuContext, wind: &lightlab_core::wind::Wind) {
        let size = std::mem::size_of::<LpvUniforms>();
        for slot in self.uniform_bytes.chunks_mut(SLOT as usize) {
            let mut u: LpvUniforms = bytemuck::pod_read_unaligned(&slot[..size]);
            [u.wind_a, u.wind_b] = wind.uniform();
            slot[..size].copy_from_slice(bytemuck::bytes_of(&u));
        }
        ctx.queue
            .write_buffer(&self.uniforms, 0, &self.uniform_bytes);
    }

    /// Number of RSM lights (directional, spot, emissive instances).
    pub fn light_count(&self) -> usize {
        self.light_sizes.len()
    }

    /// The light the WPI report's composite shades with (`lpv-faithful` lit by exactly one
    /// directional light, as the report's scene): its RSM view, whose positions the composite
    /// reads as its shadow map. None otherwise: the usual light passes light the frame.
    pub fn composite_light(&self) -> Option<&RsmLight> {
        self.composite_light.as_ref()
    }

    /// The last light rendered into the RSM textures (after the camera's and the sky's views)
    /// when it is directional and the scheme Kaplanyan's: the near field gathers from its
    /// texels ([`LpvSettings::near_field`]).
    pub fn near_field_light(&self) -> Option<&RsmLight> {
        self.near_field_light.as_ref()
    }

    /// The near field's light's share of the volume's directional light
    /// ([`near_field_share`]); 0 without a near field.
    pub fn near_field_share(&self) -> f32 {
        self.near_field_share
    }

    /// The finest cascade's geometry volume (blocking SH at 2i, albedo sums at 2i + 1, per
    /// cell corner).
    pub fn finest_geometry_volume(&self) -> &wgpu::Buffer {
        &self.cascades.last().expect("at least one cascade").gv
    }

    /// The RSM's views (flux, normal, position) of the last light rendered.
    pub fn rsm_views(&self) -> &[wgpu::TextureView] {
        &self.rsm_views
    }

    /// The RSM's position texture (world position, w = texel area; 0 = empty) of the last
    /// light rendered.
    pub fn rsm_position_view(&self) -> &wgpu::TextureView {
        &self.rsm_views[2]
    }

    /// The RSM textures (flux, normal, position) of the last light rendered.
    pub fn rsm_textures(&self) -> &[wgpu::Texture] {
        &self.rsm_textures
    }

    /// The last light's RSM read back, row-major: flux (+0), unit normal + diffuse
    /// transmission, position + texel area (0 where the light sees nothing).
    pub fn read_rsm(&self, ctx: &GpuContext) -> Result<[Vec<[f32; 4]>; 3], LpvError> {
        let read =
            |i: usize, bpp: u32| crate::resources::read_texture(ctx, &self.rsm_textures[i], bpp);
        let half4 = |b: Vec<u8>| -> Vec<[f32; 4]> {
            bytemuck::cast_slice::<u8, [half::f16; 4]>(&b)
                .iter()
                .map(|c| c.map(|v| v.to_f32()))
                .collect()
        };
        Ok([
            half4(read(0, 8)?),
            half4(read(1, 8)?),
            bytemuck::cast_slice::<u8, [f32; 4]>(&read(2, 16)?).to_vec(),
        ])
    }

    /// Record the LPV passes of one frame. `ts(label, compute)` hands out timestamp writes.
    pub fn record<'q>(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        ts: &mut dyn FnMut(&'static str) -> Option<(&'q wgpu::QuerySet, u32, u32)>,
    ) {
        let n = self.grids[0].n;
        let wg3 = n.div_ceil(4);
        let wg_gv = (n + 1).div_ceil(4);
        let wpi = self.settings.scheme == LpvScheme::Wpi;
        for c in &self.cascades {
            enc.clear_buffer(&c.lpv_atomic, 0, None);
            enc.clear_buffer(&c.gv_atomic, 0, None);
            if wpi {
                // The gather injection adds into buffer A, light by light.
                enc.clear_buffer(&c.buffers[0], 0, None);
            }
        }
        // Cascade c's uniforms: slot 2c without, 2c + 1 with the geometry volume.
        let slot = |c: usize, gv: bool| ((2 * c + gv as usize) as u64 * SLOT) as u32;
        let compute_ts = |t: Option<(&'q wgpu::QuerySet, u32, u32)>| {
            t.map(|(query_set, b, e)| wgpu::ComputePassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(b),
                end_of_pass_write_index: Some(e),
            })
        };
        for (li, &(size, sky)) in self.light_sizes.iter().enumerate() {
            let light_offset = (li as u64 * SLOT) as u32;
            let wg_rsm = size.div_ceil(8);
            let (views, depth) = match (&self.sky_rsm, sky) {
                (Some((v, d)), true) => (v.as_slice(), d),
                _ => (self.rsm_views.as_slice(), &self.rsm_depth),
            };
            {
                let t = ts("lpv rsm");
                let color = |v| {
                    Some(wgpu::RenderPassColorAttachment {
                        view: v,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })
                };
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("lpv rsm"),
                    color_attachments: &[color(&views[0]), color(&views[1]), color(&views[2])],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: t.map(|(query_set, b, e)| wgpu::RenderPassTimestampWrites {
                        query_set,
                        beginning_of_pass_write_index: Some(b),
                        end_of_pass_write_index: Some(e),
                    }),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.rsm_pipeline);
                pass.set_bind_group(0, &self.rsm_group, &[0, light_offset]);
                pass.set_vertex_buffer(0, scene.vertices.slice(..));
                pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
                for (ii, d) in scene.draws.iter().enumerate() {
                    pass.set_bind_group(1, &scene.materials[d.material].bind_group, &[]);
                    pass.draw_indexed(
                        d.first_index..d.first_index + d.index_count,
                        0,
                        ii as u32..ii as u32 + 1,
                    );
                }
            }
            let t = ts("lpv inject");
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("lpv inject"),
                timestamp_writes: compute_ts(t),
            });
            for (ci, c) in self.cascades.iter().enumerate() {
                let group = match (&c.sky_group, sky) {
                    (Some(g), true) => g,
                    _ => &c.groups[1],
                };
                pass.set_bind_group(0, group, &[slot(ci, false), light_offset]);
                if wpi {
                    // Group 1 writes buffer A.
                    pass.set_pipeline(&self.compute.inject_wpi);
                    pass.dispatch_workgroups(wg3, wg3, wg3);
                } else {
                    pass.set_pipeline(&self.compute.inject);
                    pass.dispatch_workgroups(wg_rsm, wg_rsm, 1);
                }
            }
        }
        let t = ts("lpv propagate");
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("lpv propagate"),
            timestamp_writes: compute_ts(t),
        });
        for (ci, c) in self.cascades.iter().enumerate() {
            // The seed lands in buffer A (group 1's destination) and the accumulation.
            let mut current = 0; // the group whose source holds the latest light
            if !wpi {
                pass.set_pipeline(&self.compute.resolve);
                pass.set_bind_group(0, &c.groups[1], &[slot(ci, false), 0]);
                pass.dispatch_workgroups(wg_gv, wg_gv, wg_gv);
            }
            for i in 0..self.settings.iterations() {
                // No occlusion on the first step (against self-shadowing).
                pass.set_pipeline(if wpi {
                    &self.compute.propagate_wpi
                } else {
                    &self.compute.propagate
                });
                pass.set_bind_group(0, &c.groups[current], &[slot(ci, i > 0), 0]);
                pass.dispatch_workgroups(wg3, wg3, wg3);
                current = 1 - current;
            }
            pass.set_pipeline(&self.compute.store);
            pass.set_bind_group(0, &c.groups[current], &[slot(ci, false), 0]);
            pass.dispatch_workgroups(wg3, wg3, wg3);
        }
    }

    /// Read cascade `cascade`'s stored volume back (cells in x-fastest order, r/g/b SH per
    /// cell).
    pub fn read_volume(
        &self,
        ctx: &GpuContext,
        cascade: usize,
    ) -> Result<lightlab_core::lpv::Volume, LpvError> {
        let grid = *self
            .grids
            .get(cascade)
            .ok_or(LpvError::NoCascade(cascade))?;
        let mut vol = lightlab_core::lpv::Volume::new(grid);
        let first = grid.len() * cascade;
        for (ch, tex) in self.textures.iter().enumerate() {
            let data = crate::resources::read_texture(ctx, tex, 8)?;
            let halves: &[u16] = &bytemuck::cast_slice(&data)[first * 4..];
            for (i, cell) in vol.cells.iter_mut().enumerate() {
                for k in 0..4 {
                    cell[ch][k] = half::f16::from_bits(halves[i * 4 + k]).to_f32();
                }
            }
        }
        Ok(vol)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::check_struct;
    use crate::rust_layout;

    #[test]
    fn rsm_sizes_follow_the_grid() {
        let sizes: Vec<u32> = [4, 8, 16, 32, 48, 64, 256].map(rsm_size_for_grid).to_vec();
        assert_eq!(sizes, [256, 256, 512, 1024, 2048, 2048, 2048]);
        assert!(LpvSettings::default().rsm_size <= rsm_size_for_grid(32));
    }

    #[test]
    fn the_near_fields_share_is_its_light_on_an_upward_surface_over_all_directional_light() {
        let view = |kind: u32, d: Vec3, e: f32, sky: u32| RsmLight {
            kind,
            axis: d.normalize().to_array(),
            color: [e; 3],
            sky,
            ..Default::default()
        };
        let sun = view(0, Vec3::new(0.0, -1.0, 1.0), 4.0, 0);
        let lights = [
            view(0, Vec3::NEG_Y, 1.0, 1),
            view(0, Vec3::new(1.0, -1.0, 0.0), 2.0, 1),
            // Below the horizon, or not directional: no part of it.
            view(0, Vec3::Y, 5.0, 1),
            view(1, Vec3::NEG_Y, 7.0, 0),
            sun,
        ];
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let expected = 4.0 * h / (1.0 + 2.0 * h + 4.0 * h);
        let share = near_field_share(&sun, lights.iter());
        assert!(
            (share - expected).abs() < 1e-5,
            "{share} against {expected}"
        );
        assert_eq!(near_field_share(&sun, [sun].iter()), 1.0);
        let below = view(0, Vec3::Y, 1.0, 0);
        assert_eq!(near_field_share(&below, [below].iter()), 1.0);
    }

    #[test]
    fn lpv_structs_match_the_wgsl_layout() {
        let src = LPV_SOURCE.as_str();
        check_struct(
            src,
            "LpvUniforms",
            &rust_layout!(
                LpvUniforms,
                origin,
                cell,
                n,
                use_gv,
                scale,
                gv_scale,
                rsm_size,
                wpi_samples,
                store_last,
                occlusion,
                layer,
                reemit,
                bounces,
                lobe,
                wind_a,
                wind_b
            ),
        )
        .unwrap();
        check_struct(
            src,
            "RsmLight",
            &rust_layout!(
                RsmLight, view_proj, eye, kind, axis, texel, color, cos_inner, cos_outer, profile,
                sky, size, c0, pad3, nadir, pad4
            ),
        )
        .unwrap();
    }
}
