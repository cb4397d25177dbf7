//! GPU side of the SH/PRT techniques (`shl`, `shl-compressed`, `shl-normalmapped`, `prt-vertex`,
//! `prt-textured`): transfer data as f16 textures or buffers, the frame's SH light in a storage
//! buffer, and — for compressed SH light-maps — a compute pass that relights the
//! representatives once per frame (Fuchs 2005 §5.6, §5.8).
//!
//! The shading itself is part of the rasteriser's ambient term (`raster.wgsl`, `sh_ambient`):
//! radiance = diffuse × max(Σ lᵢ tᵢ, 0), where tᵢ is the transfer (E/π convention, see
//! `lightlab_bake::prt`) and lᵢ the incident radiance blended from the sample points of the
//! fragment's group (`lightlab_bake::sh_light`). Per-vertex transfer is shaded in the vertex
//! shader and interpolated (Gouraud), as Sloan et al.'s per-vertex PRT.
//!
//! Layout on the GPU: a transfer vector is ⌈n²/4⌉ vec4s ("layers"); textured transfer lives in the
//! light-map array texture (Rgba16Float) at layer page·layers + j; per-vertex transfer in a
//! storage buffer (f32, vertex-major in the order of `GpuScene`'s vertex buffer); compressed
//! transfer as an R16Uint index array (one layer per page) and a representative buffer.

use crate::gpu_scene::UvRect;

/// WGSL of the relighting compute pass: common.wgsl followed by prt_relit.wgsl.
pub static RELIT_SOURCE: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!(
        "{}\n{}",
        crate::uniforms::COMMON_WGSL,
        include_str!("shaders/prt_relit.wgsl")
    )
});
use glam::Vec3;
use lightlab_core::image::Image;

/// How a compressed SH light-map is read (Fuchs §5.8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShFilter {
    /// The texel's representative only (Fuchs's unfiltered renderer: blocky).
    Nearest,
    /// Bilinear interpolation of the four neighbouring texels' relit representatives.
    Bilinear,
    /// Fuchs's "quadruple multi-sampling": four nearest decompressions at ±¼ texel, averaged.
    FourTap,
}

lightlab_core::named_enum!(ShFilter, "SH light-map filter", {
    Nearest => "nearest",
    Bilinear => "bilinear",
    FourTap => "4tap",
}, aliases { "four-tap" => FourTap });

impl ShFilter {
    pub fn code(self) -> u32 {
        match self {
            ShFilter::Nearest => 0,
            ShFilter::Bilinear => 1,
            ShFilter::FourTap => 2,
        }
    }
}

/// One page of a compressed SH light-map: the representative index of every texel (row-major).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndexPage<'a> {
    pub width: u32,
    pub height: u32,
    pub indices: &'a [u32],
}

/// Transfer data of an SH technique.
pub enum ShTransfer<'a> {
    /// Per page, the coefficient images (coefficient c in channel c%3 of image c/3), as
    /// `lightlab_bake::prt::ShLightmaps`; placed by `ShInput::rects`.
    Textured { pages: &'a [Vec<Image>] },
    /// Per instance, its mesh's vertex count × n² coefficients (vertex-major).
    Vertex { instances: &'a [Vec<f32>] },
    /// Vector-quantised: index pages and `representatives` (count × n², row-major).
    Compressed {
        pages: &'a [IndexPage<'a>],
        representatives: &'a [f32],
        filter: ShFilter,
    },
}

/// What [`crate::raster::Renderer::with_sh`] needs.
pub struct ShInput<'a> {
    pub bands: usize,
    pub transfer: ShTransfer<'a>,
    /// Per instance, where its TEXCOORD_1 lands in the pages (textured and compressed).
    pub rects: &'a [Option<UvRect>],
    /// One light group per instance (true) or one for the scene.
    pub per_object: bool,
    /// Incident-light sample points per group (1 to 6).
    pub points: usize,
}

/// Number of vec4s per transfer vector.
pub fn layers(bands: usize) -> usize {
    (bands * bands).div_ceil(4)
}

/// SH transfer that the renderer cannot take.
#[derive(Debug, thiserror::Error)]
#[error("SH transfer does not fit: {0}")]
pub struct ShInputError(pub String);

impl ShInput<'_> {
    /// Check the input against the scene (instance count, vertex counts, sizes).
    /// Refuse transfer that does not match the scene or the GPU's limits.
    pub fn validate(&self, scene: &lightlab_scene::Scene) -> Result<(), ShInputError> {
        self.problem(scene).map_err(ShInputError)
    }

    fn problem(&self, scene: &lightlab_scene::Scene) -> Result<(), String> {
        if !(1..=8).contains(&self.bands) {
            return Err(format!("SH bands must be 1 to 8, not {}", self.bands));
        }
        if !(1..=6).contains(&self.points) {
            return Err(format!(
                "sample points per group must be 1 to 6, not {}",
                self.points
            ));
        }
        let nc = self.bands * self.bands;
        match &self.transfer {
            ShTransfer::Vertex { instances } => {
                if instances.len() != scene.instances.len() {
                    return Err("one per-vertex transfer array per instance is needed".into());
                }
                for (i, (t, inst)) in instances.iter().zip(&scene.instances).enumerate() {
                    let n = scene.meshes[inst.mesh].positions.len();
                    if t.len() != n * nc {
                        return Err(format!(
                            "instance {i}: {} transfer values for {n} vertices × {nc}",
                            t.len()
                        ));
                    }
                }
            }
            ShTransfer::Textured { pages } => {
                self.check_rects(scene, pages.len())?;
                for (k, imgs) in pages.iter().enumerate() {
                    if imgs.len() != nc.div_ceil(3)
                        || imgs.iter().any(|i| {
                            i.width == 0
                                || i.height == 0
                                || (i.width, i.height) != (imgs[0].width, imgs[0].height)
                        })
                    {
                        return Err(format!(
                            "page {k}: {} coefficient images of one size are needed",
                            nc.div_ceil(3)
                        ));
                    }
                }
            }
            ShTransfer::Compressed {
                pages,
                representatives,
                ..
            } => {
                self.check_rects(scene, pages.len())?;
                if representatives.is_empty() || representatives.len() % nc != 0 {
                    return Err("representatives must be a non-empty multiple of n²".into());
                }
                let count = (representatives.len() / nc) as u32;
                if count > 65536 {
                    return Err("at most 65536 representatives (16-bit indices)".into());
                }
                for (k, p) in pages.iter().enumerate() {
                    if p.width == 0
                        || p.height == 0
                        || p.indices.len() != (p.width * p.height) as usize
                        || p.indices.iter().any(|&i| i >= count)
                    {
                        return Err(format!("index page {k} is malformed"));
                    }
                }
            }
        }
        Ok(())
    }

    fn check_rects(&self, scene: &lightlab_scene::Scene, pages: usize) -> Result<(), String> {
        if pages == 0 {
            return Err("no pages".into());
        }
        if self.rects.len() != scene.instances.len()
            || self
                .rects
                .iter()
                .flatten()
                .any(|r| r.page as usize >= pages)
        {
            return Err("one page rectangle per instance, within the pages, is needed".into());
        }
        Ok(())
    }

    /// Page sizes (textured and compressed).
    pub fn page_sizes(&self) -> Vec<[u32; 2]> {
        match &self.transfer {
            ShTransfer::Textured { pages } => {
                pages.iter().map(|p| [p[0].width, p[0].height]).collect()
            }
            ShTransfer::Compressed { pages, .. } => {
                pages.iter().map(|p| [p.width, p.height]).collect()
            }
            ShTransfer::Vertex { .. } => vec![],
        }
    }

    /// Representatives of compressed transfer (0 otherwise).
    pub fn representatives(&self) -> usize {
        match &self.transfer {
            ShTransfer::Compressed {
                representatives, ..
            } => representatives.len() / (self.bands * self.bands),
            _ => 0,
        }
    }

    /// The shader's mode code.
    pub fn mode(&self) -> u32 {
        match self.transfer {
            ShTransfer::Textured { .. } => 1,
            ShTransfer::Vertex { .. } => 2,
            ShTransfer::Compressed { .. } => 3,
        }
    }

    /// Groups of sample points.
    pub fn groups(&self, instances: usize) -> usize {
        if self.per_object { instances.max(1) } else { 1 }
    }
}

/// Pack per-vertex transfer for the GPU: `layers` vec4s per vertex, instances in order.
pub fn pack_vertex_transfer(instances: &[Vec<f32>], bands: usize) -> Vec<[f32; 4]> {
    let nc = bands * bands;
    let l = layers(bands);
    let mut out = vec![];
    for t in instances {
        for v in t.chunks_exact(nc) {
            for j in 0..l {
                out.push(std::array::from_fn(|c| {
                    v.get(4 * j + c).copied().unwrap_or(0.0)
                }));
            }
        }
    }
    if out.is_empty() {
        out.push([0.0; 4]);
    }
    out
}

/// The texel of light-map layer `layer` for textured transfer: coefficients 4j..4j+3 of page
/// `layer / layers`.
pub fn textured_texel(
    pages: &[Vec<Image>],
    bands: usize,
    layer: usize,
    x: u32,
    y: u32,
) -> [f32; 4] {
    let l = layers(bands);
    let (page, j) = (layer / l, layer % l);
    let nc = bands * bands;
    std::array::from_fn(|c| {
        let k = 4 * j + c;
        if k >= nc {
            return 0.0;
        }
        pages[page][k / 3].get(x, y)[k % 3]
    })
}

/// Pack one frame's SH light: the sample points (`groups × points`), then per group and point
/// `layers·4` RGB coefficients (zero-padded).
pub fn pack_light(points: &[Vec3], coeffs: &[Vec3], bands: usize) -> Vec<[f32; 4]> {
    let nc = bands * bands;
    let l4 = 4 * layers(bands);
    let mut out: Vec<[f32; 4]> = points.iter().map(|p| p.extend(1.0).to_array()).collect();
    for c in coeffs.chunks_exact(nc) {
        for k in 0..l4 {
            out.push(c.get(k).map_or([0.0; 4], |v| v.extend(0.0).to_array()));
        }
    }
    out
}

/// Pack representatives: `layers` vec4s each.
pub fn pack_representatives(reps: &[f32], bands: usize) -> Vec<[f32; 4]> {
    pack_vertex_transfer(&[reps.to_vec()], bands)
}
