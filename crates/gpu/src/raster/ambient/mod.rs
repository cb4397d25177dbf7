//! The sources of the ambient term, one per renderer, each owning its resources, its uniform
//! block, its bind-group entries (group 2 from binding 3) and its pre-passes, and compiled with
//! its own WGSL (`shaders/ambient_*.wgsl`):
//! - `Sky`: the environment's SH irradiance (in the frame uniforms), occluded by the scene
//!   through shadow-mapped sky directions (`sky`): the Phong techniques;
//! - `Lightmap`: diffuse × light-map (Fuchs §3.4), `lightmap`;
//! - `Sh`: diffuse × SH transfer · SH light (the PRT techniques, `crate::prt`);
//! - `Lpv`: the light propagation volume's indirect light plus the sky, occluded as `Sky`'s
//!   (`crate::lpv`);
//! - `Normals`: the shading normal as a colour (the `normals` debug technique).

mod lightmap;
mod lpv;
mod sh;
mod sky;

pub(super) use sh::ShResources;
pub use sky::{
    DEFAULT_DIRECTIONS as SKY_OCCLUSION_DIRECTIONS, MAX_DIRECTIONS as MAX_SKY_OCCLUSION_DIRECTIONS,
    SkyOcclusion, sky_lights,
};

use super::bindings::{buffer, filtered_texture, sampler};
use super::settings::Ambient;
use crate::GpuContext;
use crate::gpu_scene::{GpuScene, UvRect};
use crate::resources::upload_array;
use lightlab_core::image::Image;
use lightlab_scene::Scene;
use wgpu::BindGroupLayoutEntry as LayoutEntry;
use wgpu::TextureViewDimension as Dim;

/// Which ambient source a shader module is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    Sky,
    Lightmap,
    Sh,
    Lpv,
    Normals,
}

impl SourceKind {
    pub const ALL: [SourceKind; 5] = [
        SourceKind::Sky,
        SourceKind::Lightmap,
        SourceKind::Sh,
        SourceKind::Lpv,
        SourceKind::Normals,
    ];

    /// The source's WGSL (compiled after raster.wgsl).
    pub fn wgsl(self) -> &'static str {
        match self {
            SourceKind::Sky => concat!(
                include_str!("../../shaders/sky_occlusion.wgsl"),
                include_str!("../../shaders/ambient_sky.wgsl")
            ),
            SourceKind::Lightmap => include_str!("../../shaders/ambient_lightmap.wgsl"),
            SourceKind::Sh => include_str!("../../shaders/ambient_sh.wgsl"),
            SourceKind::Lpv => concat!(
                include_str!("../../shaders/sky_occlusion.wgsl"),
                include_str!("../../shaders/ambient_lpv.wgsl")
            ),
            SourceKind::Normals => include_str!("../../shaders/ambient_normals.wgsl"),
        }
    }

    /// Group 2's entries from binding 3 on.
    pub(super) fn layout_entries(self) -> Vec<LayoutEntry> {
        use wgpu::BufferBindingType::Uniform;
        use wgpu::SamplerBindingType::Filtering;
        match self {
            SourceKind::Normals => vec![],
            SourceKind::Sky => sky::layout_entries(),
            SourceKind::Lightmap => vec![
                buffer(3, Uniform, false),
                filtered_texture(4, Dim::D2Array),
                sampler(5, Filtering),
            ],
            SourceKind::Sh => vec![
                buffer(3, Uniform, false),
                filtered_texture(4, Dim::D2Array),
                sampler(5, Filtering),
                super::bindings::storage(6),
                super::bindings::storage(7),
                super::bindings::texture(8, wgpu::TextureSampleType::Uint, Dim::D2Array),
                super::bindings::storage(9),
            ],
            SourceKind::Lpv => [
                vec![
                    buffer(3, Uniform, false),
                    filtered_texture(4, Dim::D3),
                    filtered_texture(5, Dim::D3),
                    filtered_texture(6, Dim::D3),
                    sampler(7, Filtering),
                    super::bindings::texture(
                        11,
                        wgpu::TextureSampleType::Float { filterable: false },
                        Dim::D2,
                    ),
                    super::bindings::texture(
                        13,
                        wgpu::TextureSampleType::Float { filterable: false },
                        Dim::D2,
                    ),
                    super::bindings::texture(
                        14,
                        wgpu::TextureSampleType::Float { filterable: false },
                        Dim::D2,
                    ),
                    super::bindings::storage(15),
                ],
                sky::layout_entries(),
            ]
            .concat(),
        }
    }
}

/// A renderer's ambient source and its resources.
pub(super) enum AmbientSource {
    Sky(Box<SkyOcclusion>),
    Lightmap(lightmap::LightmapSource),
    Sh(Box<ShResources>),
    Lpv(Box<lpv::LpvSource>),
    Normals,
}

impl AmbientSource {
    /// Objects have moved: the sky occlusion's depth maps are drawn again.
    pub fn geometry_moved(&self, ctx: &GpuContext, gscene: &crate::gpu_scene::GpuScene) {
        match self {
            AmbientSource::Sky(sky) => sky.rerender(ctx, gscene),
            AmbientSource::Lpv(l) => l.sky.rerender(ctx, gscene),
            _ => {}
        }
    }

    pub fn lightmap(ctx: &GpuContext, lm: &LightmapInput, page_size: [u32; 2]) -> AmbientSource {
        AmbientSource::Lightmap(lightmap::LightmapSource::new(ctx, lm, page_size))
    }

    pub fn sh(
        ctx: &GpuContext,
        sh: &crate::prt::ShInput,
        instances: usize,
        page_size: [u32; 2],
    ) -> AmbientSource {
        AmbientSource::Sh(Box::new(ShResources::new(ctx, sh, instances, page_size)))
    }

    pub fn lpv(
        ctx: &GpuContext,
        volume: crate::lpv::Lpv,
        sky: SkyOcclusion,
        indirect_only: bool,
    ) -> AmbientSource {
        AmbientSource::Lpv(Box::new(lpv::LpvSource::new(
            ctx,
            volume,
            sky,
            indirect_only,
        )))
    }

    pub fn kind(&self) -> SourceKind {
        match self {
            AmbientSource::Sky(_) => SourceKind::Sky,
            AmbientSource::Lightmap(_) => SourceKind::Lightmap,
            AmbientSource::Sh(_) => SourceKind::Sh,
            AmbientSource::Lpv(_) => SourceKind::Lpv,
            AmbientSource::Normals => SourceKind::Normals,
        }
    }

    /// Group 2's entries from binding 3 on.
    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        match self {
            AmbientSource::Sky(o) => o.entries(),
            AmbientSource::Normals => vec![],
            AmbientSource::Lightmap(l) => l.entries(),
            AmbientSource::Sh(s) => s.entries(),
            AmbientSource::Lpv(l) => l.entries(),
        }
    }

    /// The light propagation volume, for the LPV source.
    pub fn volume(&self) -> Option<&crate::lpv::Lpv> {
        match self {
            AmbientSource::Lpv(l) => Some(&l.volume),
            _ => None,
        }
    }

    pub fn volume_mut(&mut self) -> Option<&mut crate::lpv::Lpv> {
        match self {
            AmbientSource::Lpv(l) => Some(&mut l.volume),
            _ => None,
        }
    }

    /// Whether only the volume's indirect light is drawn (no sky, no lights).
    pub fn indirect_only(&self) -> bool {
        matches!(self, AmbientSource::Lpv(l) if l.indirect_only)
    }

    /// Whether the source's own shading replaces the light passes (`lpv-faithful`'s composite).
    pub fn composite(&self) -> bool {
        matches!(self, AmbientSource::Lpv(l) if l.composite())
    }

    /// Timestamped passes this source records before the frame's: compressed SH relighting,
    /// the volume's RSMs, injection and propagation. `slot(label)` gives the pass's timestamp
    /// query indices.
    pub fn prepasses<'q>(
        &self,
        enc: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        slot: &mut dyn FnMut(&'static str) -> Option<(&'q wgpu::QuerySet, u32, u32)>,
    ) {
        match self {
            AmbientSource::Sh(s) => s.relight_pass(enc, slot),
            AmbientSource::Lpv(l) => l.volume.record(enc, scene, slot),
            _ => {}
        }
    }

    /// How many timestamped passes `prepasses` records.
    pub fn prepass_count(&self) -> usize {
        match self {
            AmbientSource::Sh(s) => s.relight.is_some() as usize,
            AmbientSource::Lpv(l) => 2 * l.volume.light_count() + 1,
            _ => 0,
        }
    }
}

/// Baked light-maps for [`Renderer::with_lightmap`]: pages of E/π and, per scene instance, where
/// its TEXCOORD_1 lands (page coordinates `offset + uv1 · scale`).
pub struct LightmapInput<'a> {
    pub pages: &'a [Image],
    pub rects: &'a [Option<UvRect>],
    /// Cubic B-spline filtering (four bilinear taps) instead of bilinear.
    pub bicubic: bool,
    /// Directional light-maps: per page, the luminance ratios of the three basis directions
    /// (`lightlab_bake::gather`); normal-mapped surfaces then respond to the baked light.
    pub directional: Option<&'a [Image]>,
}

/// Light-map pages (E/π, then the directional ratios at layer pages + k) or textured SH
/// transfer (layer page·layers + j) in one array; a black array when there are none.
fn upload_lightmaps(
    ctx: &GpuContext,
    lightmap: Option<&LightmapInput>,
    sh: Option<&crate::prt::ShInput>,
    size: [u32; 2],
) -> (wgpu::TextureView, wgpu::Sampler) {
    let put = |data: &mut [half::f16], w: u32, h: u32, f: &dyn Fn(u32, u32) -> [f32; 4]| {
        for y in 0..h {
            for x in 0..w {
                let v = f(x, y);
                let o = ((y * size[0] + x) * 4) as usize;
                for c in 0..4 {
                    data[o + c] = half::f16::from_f32(v[c].clamp(-65000.0, 65000.0));
                }
            }
        }
    };
    if let Some(crate::prt::ShInput {
        bands,
        transfer: crate::prt::ShTransfer::Textured { pages },
        ..
    }) = sh
    {
        let l = crate::prt::layers(*bands);
        let layers = (pages.len() * l) as u32;
        return upload_array(ctx, size, layers, |layer, data| {
            if layer < layers {
                let p = &pages[layer as usize / l][0];
                put(data, p.width, p.height, &|x, y| {
                    crate::prt::textured_texel(pages, *bands, layer as usize, x, y)
                });
            }
        });
    }
    let pages = lightmap.map_or(0, |lm| lm.pages.len() as u32);
    let dir = lightmap.and_then(|lm| lm.directional);
    // Directional pages follow the E/π pages (layer pages + k).
    let layers = pages * if dir.is_some() { 2 } else { 1 };
    upload_array(ctx, size, layers, |layer, data| {
        let page = match (lightmap, dir) {
            (Some(lm), _) if layer < pages => Some(&lm.pages[layer as usize]),
            (Some(_), Some(d)) if layer < 2 * pages => d.get((layer - pages) as usize),
            _ => None,
        };
        if let Some(p) = page {
            put(data, p.width, p.height, &|x, y| {
                let v = p.get(x, y);
                [v.x.max(0.0), v.y.max(0.0), v.z.max(0.0), 1.0]
            });
        }
    })
}

/// The ambient light as 9 SH coefficients of irradiance.
/// The environment's sun as a directional light, and the environment without it
/// (`RasterSettings::env_sun`); None without an environment ambient or a sun in it, and when
/// the scene has a directional light of its own (a sky made with its sun apart, as lightlab's
/// daylight is, whose brightest region is then the sun's aureole, not the sun).
pub(super) fn environment_sun(
    scene: &Scene,
    ambient: Ambient,
) -> Option<(lightlab_scene::Light, lightlab_core::sh_env::EnvSun)> {
    let env = scene
        .environment
        .as_ref()
        .filter(|_| ambient == Ambient::Environment)?;
    if scene
        .lights
        .iter()
        .any(|l| matches!(l.kind, lightlab_scene::LightKind::Directional { .. }))
    {
        return None;
    }
    let sun = lightlab_core::sh_env::extract_sun(&env.image, SUN_MIN_RATIO)?;
    let e = sun.irradiance * env.intensity;
    let peak = e.max_element();
    let light = lightlab_scene::Light {
        name: "environment sun".into(),
        kind: lightlab_scene::LightKind::Directional {
            angular_diameter: sun.angular_diameter,
        },
        color: e / peak,
        intensity: peak,
        position: glam::Vec3::ZERO,
        direction: -sun.direction,
        range: None,
    };
    Some((light, sun))
}

/// How much brighter than the sphere's mean radiance a texel must be to belong to a sun.
const SUN_MIN_RATIO: f32 = 20.0;

/// The ambient term's nine SH irradiance coefficients: of the environment (without its sun
/// when `sun` took it out), of a constant sky, or none.
pub(super) fn sh_irradiance(
    scene: &Scene,
    ambient: Ambient,
    sun: Option<&lightlab_core::sh_env::EnvSun>,
) -> [[f32; 4]; 9] {
    let mut out = [[0.0; 4]; 9];
    match ambient {
        Ambient::None => {}
        Ambient::Constant(c) => {
            // E = π·c for every normal; c₀·Y₀₀ = E.
            let e = c * std::f32::consts::PI / 0.282_094_8;
            out[0] = e.extend(0.0).to_array();
        }
        Ambient::Environment => {
            if let Some(env) = &scene.environment {
                let l = lightlab_core::sh_env::project_env(
                    sun.map_or(&env.image, |s| &s.remainder),
                    lightlab_core::sh_env::EnvFormat::LatLong,
                    3,
                );
                let e = lightlab_core::sh::irradiance_from_radiance(&l);
                for (o, c) in out.iter_mut().zip(e) {
                    *o = (c * env.intensity as f64).as_vec3().extend(0.0).to_array();
                }
            }
        }
    }
    out
}

/// Light-map pages may differ in size: the array takes the largest and each instance's page
/// rectangle is scaled into it. Returns the array's size and the scaled rectangles (None
/// without light-maps or textured SH transfer).
pub(super) fn page_layout(
    lightmap: Option<&LightmapInput>,
    sh: Option<&crate::prt::ShInput>,
) -> ([u32; 2], Option<Vec<Option<UvRect>>>) {
    let (page_sizes, page_rects): (Vec<[u32; 2]>, Option<&[Option<UvRect>]>) = match (lightmap, sh)
    {
        (Some(lm), _) => (
            lm.pages.iter().map(|p| [p.width, p.height]).collect(),
            Some(lm.rects),
        ),
        (None, Some(sh)) if sh.mode() != 2 => (sh.page_sizes(), Some(sh.rects)),
        _ => (vec![], None),
    };
    let size = [
        page_sizes.iter().map(|p| p[0]).max().unwrap_or(1),
        page_sizes.iter().map(|p| p[1]).max().unwrap_or(1),
    ];
    let rects = page_rects.map(|rects| {
        rects
            .iter()
            .map(|r| {
                r.map(|r| {
                    let p = page_sizes[r.page as usize];
                    let k = [p[0] as f32 / size[0] as f32, p[1] as f32 / size[1] as f32];
                    UvRect {
                        page: r.page,
                        offset: [r.offset[0] * k[0], r.offset[1] * k[1]],
                        scale: [r.scale[0] * k[0], r.scale[1] * k[1]],
                    }
                })
            })
            .collect()
    });
    (size, rects)
}

/// Whether light-maps fit the scene: one rectangle per instance, non-empty pages, directional
/// pages of the same sizes.
pub(super) fn lightmap_fits(lm: &LightmapInput, scene: &Scene) -> bool {
    !(lm.pages.is_empty()
        || lm.rects.len() != scene.instances.len()
        || lm.pages.iter().any(|p| p.width == 0 || p.height == 0)
        || lm.directional.is_some_and(|d| {
            d.len() != lm.pages.len()
                || d.iter()
                    .zip(lm.pages)
                    .any(|(a, b)| (a.width, a.height) != (b.width, b.height))
        }))
}
