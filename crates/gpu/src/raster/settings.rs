//! What a renderer is asked to draw ([`RasterSettings`], with its render path, shadow method
//! and ambient term), its errors and its timings.

use crate::GpuError;
use crate::lights::Attenuation;
use glam::camera::rh::proj::directx;
use glam::{Mat4, Vec3, Vec4};
use lightlab_scene::Camera;
use std::collections::BTreeMap;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderPath {
    Forward,
    Deferred,
}

lightlab_core::named_enum!(RenderPath, "render path", {
    Forward => "forward",
    Deferred => "deferred",
});

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowMethod {
    None,
    /// Stencil shadow volumes, z-fail (Carmack's reverse) with capped volumes.
    VolumesZFail,
    /// Stencil shadow volumes, z-pass (wrong when the camera is inside a volume).
    VolumesZPass,
    /// Shadow maps with hardware depth comparison.
    Map,
    /// Shadow maps with Heidrich's (1999, ch. 6) linear-depth comparison.
    MapLinear,
    /// Projected planar shadows on one receiver plane (Heidrich 1999 §6.1).
    Planar,
}

impl ShadowMethod {
    pub(super) fn stencil(self) -> bool {
        matches!(
            self,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass | ShadowMethod::Planar
        )
    }
    pub(super) fn map(self) -> bool {
        matches!(self, ShadowMethod::Map | ShadowMethod::MapLinear)
    }
}

/// The parameterisation of the prefiltered environment maps of the specular environment term
/// (Heidrich 1999 ch. 8), or none.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvMapKind {
    /// Two paraboloids, looked up from any viewpoint (§8.2.1).
    DualParaboloid,
    /// Six faces, each face chosen in the shader (no seamless filtering across edges).
    Cube,
    /// The OpenGL sphere map, made for the camera's viewing direction (view-dependent, §8.1).
    Sphere,
    /// No specular environment term.
    None,
}

lightlab_core::named_enum!(EnvMapKind, "environment map", {
    DualParaboloid => "dual-paraboloid",
    Cube => "cube",
    Sphere => "sphere",
    None => "none",
});

/// The lobe the environment is prefiltered with, per material or forced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvPrefilter {
    /// GGX with the split-sum table for PBR materials, the Phong lobe for Phong and
    /// Blinn-Phong materials.
    Auto,
    /// Heidrich's Phong-lobe prefilter (§8.3.2) for every material.
    Phong,
    /// GGX with the split-sum table (Karis 2013) for every material.
    Ggx,
}

lightlab_core::named_enum!(EnvPrefilter, "environment prefilter", {
    Auto => "auto",
    Phong => "phong",
    Ggx => "ggx",
});

/// How glass refracts the environment (Heidrich §8.3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refraction {
    /// One interface: the refracted direction is looked up as it enters.
    One,
    /// Two interfaces: the ray refracts in, crosses the object's bounding sphere and refracts
    /// out (exact for a ball; an approximation for other solids).
    Two,
}

lightlab_core::named_enum!(Refraction, "refraction", {
    One => "one",
    Two => "two",
});

/// The diffuse part of the environment light in the Phong techniques' ambient term.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvDiffuse {
    /// Nine SH coefficients of irradiance (Ramamoorthi & Hanrahan 2001).
    Sh,
    /// An irradiance map (Heidrich Eq 8.13) in the `--env-map` parameterisation (the dual
    /// paraboloid when that is `none`).
    Map,
}

lightlab_core::named_enum!(EnvDiffuse, "environment diffuse", {
    Sh => "sh",
    Map => "map",
});

/// The constant or environment light of the ambient term (Fuchs's ambient uses the light-map;
/// until light-maps exist it is this irradiance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ambient {
    None,
    /// A uniform sky of this radiance (unshadowed).
    Constant(Vec3),
    /// The scene's environment map, projected on 9 SH coefficients (unshadowed).
    Environment,
}

/// An `--ambient` that is neither `env`, `none` nor three non-negative numbers `r,g,b`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the ambient term must be env, none or r,g,b (non-negative), not '{0}'")]
pub struct BadAmbient(pub String);

impl std::str::FromStr for Ambient {
    type Err = BadAmbient;
    /// `env`, `none`, or a constant sky radiance `r,g,b`.
    fn from_str(s: &str) -> Result<Ambient, BadAmbient> {
        match s {
            "env" => return Ok(Ambient::Environment),
            "none" => return Ok(Ambient::None),
            _ => {}
        }
        let v: Vec<f32> = s
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| BadAmbient(s.into()))?;
        match v[..] {
            [r, g, b] if v.iter().all(|x| x.is_finite() && *x >= 0.0) => {
                Ok(Ambient::Constant(Vec3::new(r, g, b)))
            }
            _ => Err(BadAmbient(s.into())),
        }
    }
}

/// How a normal map's mip levels are lit (Heidrich §9.1.1): a texel of a distant surface
/// covers many bumps, whose lit average is not the lighting of their average normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalFilter {
    /// Box-mipped normals, renormalised after sampling: distant bumps turn into a flat,
    /// too-shiny surface.
    Box,
    /// Toksvig's filter from a precomputed map: each mip texel's spread of full-resolution
    /// normals σ² (from the length r of their mean, σ² = (1 − r)/r) widens the reflection
    /// lobe (`widened_roughness` in common.wgsl).
    Variance,
    /// The finest level only, unfiltered: aliases at a distance, exact when supersampled (the
    /// reference the filters are measured against).
    None,
    /// Heidrich's order, lighting before filtering: the per-light passes of the forward path
    /// light 4 × 4 normals under each pixel (each read over a sixteenth of its footprint and
    /// Toksvig-widened) and average them (`lit_then_filtered` in raster.wgsl); the ambient and
    /// environment terms filter as `Variance`. The deferred path refuses it.
    Lit,
    /// The WPI report's filter (Dickson et al. 2011, §5.5, `lpv-faithful`'s): eight taps in
    /// a rooks pattern at 0.35 × (1, 4), (3, 1), (4, −2), (1.5, −3) and their negatives, in
    /// texels of the map (the report's was 512²), each weighted by its agreement with the
    /// centre: n′ = normalize(n₀ + Σ nᵢ (nᵢ·n₀)). The authors' own, against specular noise of
    /// a too-dense map; it reads the box-mipped levels.
    Rook,
}

lightlab_core::named_enum!(NormalFilter, "normal filter", {
    Box => "box",
    Variance => "variance",
    None => "none",
    Lit => "lit",
    Rook => "rook",
});

#[derive(Clone, Debug)]
pub struct RasterSettings {
    pub width: u32,
    pub height: u32,
    pub camera: usize,
    pub path: RenderPath,
    pub shadows: ShadowMethod,
    pub attenuation: Attenuation,
    /// Override of the light radius r of the Fuchs attenuation functions.
    pub light_radius: Option<f32>,
    pub ambient: Ambient,
    pub shadow_size: u32,
    pub pcf_radius: i32,
    /// Normal offset in texels: a shadow-map lookup moves this far off the surface along its
    /// geometric normal (on top of the shadow pass's depth biases). 0.5 by default, with the
    /// PCF taps compared against the receiver's plane (docs/phong-and-shadows.md): 0.25 drew
    /// acne on the room's sunlit floor.
    pub normal_offset: f32,
    /// Slope-scaled depth bias of the shadow-map pass, in texels × tan θ along the light. 0.5 by
    /// default: 1.5 pushed a grazing leaf's depth back by 1.5·tan θ texels (8.5 at 80°), and the
    /// leaves behind it within that reach were lit through it (`phong-shadow-maps` against
    /// `direct` on bush 0.00363 → 0.00296 with the receiver plane; room and the atrium
    /// 0.00255 → 0.00246, 0.00742 → 0.00721).
    pub slope_bias: f32,
    /// Constant depth bias (depth-buffer units) of the shadow-map pass.
    pub constant_bias: i32,
    /// Bias on the normalised linear depth (Heidrich's variant).
    pub linear_bias: f32,
    pub cascades: usize,
    /// Receiver plane (n, d) with n·x + d = 0 of planar shadows; None = the largest up-facing
    /// plane of the scene.
    pub planar_plane: Option<Vec4>,
    /// Scissor each light's passes to its screen rectangle, and cull objects outside its radius.
    pub scissor: bool,
    pub exposure: f32,
    /// Wind sway of foliage, the same in every pass (amplitude 0: none). Shadow volumes are
    /// built on the CPU from the rest pose, so wind needs another shadow method.
    pub wind: lightlab_core::wind::Wind,
    /// Draw the scene's environment map where no surface is seen, as the path tracer does
    /// (so that renders compare pixel by pixel); false leaves the background black.
    pub background: bool,
    /// Light with the scene's planar emitters as Lambertian rectangle lights (after its
    /// punctual lights; at most [`MAX_AREA_LIGHTS`], brightest first). Renderers built
    /// `with_lightmap` (a light-map already holds the emitters' light) or `with_sh` (lit by
    /// their SH light alone) ignore it.
    pub area_lights: bool,
    /// The specular environment term's map (with `ambient` = the environment; a constant
    /// ambient reflects as a constant environment).
    pub env_map: EnvMapKind,
    pub env_prefilter: EnvPrefilter,
    pub env_diffuse: EnvDiffuse,
    /// Dynamic environment maps: the scene rendered into a cube at the centre of each of its
    /// (up to four) mirror-like objects, which then reflect their neighbours
    /// (`raster::env_dynamic`).
    pub dynamic_env: bool,
    /// Update the dynamic maps every this many frames (1: every frame, as objects move; 0:
    /// only when the renderer is made).
    pub dynamic_env_every: u32,
    /// Shadow the environment's sun: its bright region becomes a shadow-casting directional
    /// light for the diffuse term and leaves the SH ambient (`lightlab_core::sh_env::extract_sun`;
    /// the Phong and LPV techniques, `ambient` = the environment).
    pub env_sun: bool,
    /// Sky directions whose shadow maps occlude the Phong techniques' diffuse sky light
    /// (`raster::ambient::SkyOcclusion`); 0 leaves it unshadowed.
    pub sky_occlusion: u32,
    pub refraction: Refraction,
    /// Texels of the environment map's level 0 over all faces (equal memory across
    /// parameterisations).
    pub env_texels: u32,
    /// A canned light source (Heidrich ch. 7) added to the scene's lights (`canned.rs`).
    pub light_field: Vec<CannedLight>,
    /// Draw each planar mirror's reflection from the mirrored eye (`raster::mirror`, up to
    /// four, one level deep); false: mirrors reflect the environment maps like any surface.
    pub planar_mirrors: bool,
    /// A geometry light field (Heidrich §10.2) for one glass object: its fragments refract
    /// through the baked exit directions instead of the bounding sphere (`refraction`).
    pub object_field: Option<FieldObject>,
    /// How normal maps are filtered (Heidrich §9.1.1).
    pub normal_filter: NormalFilter,
    /// Torrance–Sparrow and Banks materials from their formulas or Heidrich's lookup tables
    /// (forward path; `brdf_tables`).
    pub brdf_eval: crate::brdf_tables::BrdfEval,
}

/// A glass instance and its geometry light field (`lightlab_core::object_field`).
#[derive(Clone, Debug)]
pub struct FieldObject {
    pub instance: usize,
    pub field: std::sync::Arc<lightlab_core::object_field::ObjectField>,
}

/// How a canned light is drawn (§7.2.2): one additive pass per (u,v) grid point, each a spot
/// light with a projective texture of its (s,t) slice, or one pass whose shader sums every
/// grid point from a texture array.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CannedPasses {
    #[default]
    PerPoint,
    Array,
}

lightlab_core::named_enum!(CannedPasses, "canned-light pass scheme", {
    PerPoint => "per-point",
    Array => "array",
});

/// A light slab to light the scene with.
#[derive(Clone, Debug)]
pub struct CannedLight {
    pub slab: std::sync::Arc<lightlab_core::light_slab::LightSlab>,
    pub passes: CannedPasses,
}

impl Default for RasterSettings {
    fn default() -> Self {
        RasterSettings {
            width: 256,
            height: 256,
            camera: 0,
            path: RenderPath::Forward,
            shadows: ShadowMethod::VolumesZFail,
            attenuation: Attenuation::InverseSquare,
            light_radius: None,
            ambient: Ambient::Environment,
            shadow_size: 2048,
            pcf_radius: 1,
            normal_offset: 0.5,
            slope_bias: 0.5,
            constant_bias: 2,
            linear_bias: 0.002,
            cascades: 4,
            planar_plane: None,
            scissor: true,
            exposure: 1.0,
            wind: Default::default(),
            background: true,
            area_lights: true,
            env_map: EnvMapKind::DualParaboloid,
            env_prefilter: EnvPrefilter::Auto,
            env_diffuse: EnvDiffuse::Sh,
            dynamic_env: false,
            dynamic_env_every: 1,
            env_sun: true,
            sky_occlusion: super::ambient::SKY_OCCLUSION_DIRECTIONS,
            refraction: Refraction::Two,
            env_texels: 2 * 256 * 256,
            light_field: vec![],
            planar_mirrors: true,
            object_field: None,
            normal_filter: NormalFilter::Variance,
            brdf_eval: Default::default(),
        }
    }
}

impl RasterSettings {
    /// Refuse sizes and counts the renderer does not support, and wind it cannot sway with.
    pub fn validate(&self) -> Result<(), RasterError> {
        let s = self;
        check_wind(&s.wind, s.shadows)?;
        if s.width == 0 || s.height == 0 || s.width > 16384 || s.height > 16384 {
            return Err(RasterError::Settings(format!(
                "image size {}×{} must be within 1..=16384",
                s.width, s.height
            )));
        }
        if !(64..=8192).contains(&s.shadow_size) {
            return Err(RasterError::Settings(format!(
                "shadow map size {} must be within 64..=8192",
                s.shadow_size
            )));
        }
        let max_sky = super::ambient::MAX_SKY_OCCLUSION_DIRECTIONS;
        if s.sky_occlusion > max_sky {
            return Err(RasterError::Settings(format!(
                "sky occlusion directions {} must be at most {max_sky} (one depth-map layer each)",
                s.sky_occlusion
            )));
        }
        if !(1..=4).contains(&s.cascades) {
            return Err(RasterError::Settings("cascades must be 1 to 4".into()));
        }
        if !(0..=4).contains(&s.pcf_radius) {
            return Err(RasterError::Settings("PCF radius must be 0 to 4".into()));
        }
        if !(64..=(1 << 24)).contains(&s.env_texels) {
            return Err(RasterError::Settings(format!(
                "environment map texels {} must be within 64..=16777216",
                s.env_texels
            )));
        }
        Ok(())
    }
}

/// At most this many emitters become area lights (each costs a light's passes and shadows).
pub const MAX_AREA_LIGHTS: usize = 8;

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum RasterError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("the scene has no camera {0}")]
    NoCamera(usize),
    #[error("invalid settings: {0}")]
    Settings(String),
    #[error(transparent)]
    Wind(#[from] lightlab_core::wind::WindError),
    #[error(transparent)]
    Sh(#[from] crate::prt::ShInputError),
    #[error(transparent)]
    Lpv(#[from] crate::lpv::LpvError),
    #[error(transparent)]
    Readback(#[from] crate::resources::ReadbackError),
}

/// GPU and CPU times of one frame, by pass category (milliseconds).
#[derive(Clone, Debug, Default)]
pub struct FrameTimes {
    /// Sum of GPU timestamp intervals per category; empty without timestamp support.
    pub gpu_ms: BTreeMap<&'static str, f64>,
    /// CPU time building shadow volumes / planar data this frame.
    pub cpu_volumes_ms: f64,
    /// Wall time from recording to the GPU being idle.
    pub wall_ms: f64,
}

/// Valid wind parameters, and a shadow method that sways with them.
pub(super) fn check_wind(
    wind: &lightlab_core::wind::Wind,
    shadows: ShadowMethod,
) -> Result<(), RasterError> {
    wind.validate()?;
    if wind.amplitude > 0.0
        && matches!(
            shadows,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass
        )
    {
        return Err(RasterError::Settings(
            "wind sway needs shadow maps: shadow volumes are built on the CPU from the rest pose"
                .into(),
        ));
    }
    Ok(())
}

/// The camera projection: reversed depth with an infinite far plane.
pub fn projection(camera: &Camera, aspect: f32) -> Mat4 {
    directx::perspective_infinite_reverse(camera.yfov, aspect, camera.znear.max(1e-4))
}
