//! The sources of the ambient term and the resources each binds: the environment's SH
//! irradiance (in the frame uniforms), light-maps (Fuchs §3.4), SH transfer (the PRT
//! techniques, `crate::prt`) and the light propagation volume (`crate::lpv`). A renderer has
//! at most one of the last three; the others are bound as one-texel dummies.

use super::settings::Ambient;
use crate::GpuContext;
use crate::gpu_scene::UvRect;
use crate::resources::{array_view, texture, upload_array};
use crate::uniforms::FrameUniforms;
use lightlab_core::image::Image;
use lightlab_scene::Scene;
use wgpu::util::DeviceExt;

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
pub(super) fn upload_lightmaps(
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

/// GPU data of the SH techniques (dummies when there are none).
pub(super) struct ShResources {
    pub(super) bands: usize,
    pub(super) vertex: wgpu::Buffer,
    /// Sample points then coefficients; rewritten by `set_sh_light`.
    pub(super) light: wgpu::Buffer,
    pub(super) index: wgpu::TextureView,
    pub(super) relit: wgpu::Buffer,
    /// The relighting compute pass of compressed transfer: pipeline, bind group, workgroups.
    pub(super) relight: Option<(wgpu::ComputePipeline, wgpu::BindGroup, [u32; 2])>,
}

impl ShResources {
    pub(super) fn new(
        ctx: &GpuContext,
        sh: Option<&crate::prt::ShInput>,
        frame: &FrameUniforms,
        size: [u32; 2],
        frame_buf: &wgpu::Buffer,
    ) -> ShResources {
        use crate::prt::{ShTransfer, pack_representatives, pack_vertex_transfer};
        let device = &ctx.device;
        let storage = |label: &str, data: &[[f32; 4]], extra: wgpu::BufferUsages| {
            let dummy = [[0.0f32; 4]];
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(if data.is_empty() { &dummy } else { data }),
                usage: wgpu::BufferUsages::STORAGE | extra,
            })
        };
        let bands = sh.map_or(1, |s| s.bands);
        let vertex = match sh.map(|s| &s.transfer) {
            Some(ShTransfer::Vertex { instances }) => pack_vertex_transfer(instances, bands),
            _ => vec![],
        };
        let vertex = storage("sh vertex transfer", &vertex, wgpu::BufferUsages::empty());
        let gp = (frame.sh_groups * frame.sh_points) as usize;
        let light = vec![[0.0f32; 4]; gp + gp * 4 * frame.sh_layers as usize];
        let light = storage("sh light", &light, wgpu::BufferUsages::COPY_DST);
        let relit = vec![[0.0f32; 4]; gp * frame.sh_reps as usize];
        let relit = storage("sh relit", &relit, wgpu::BufferUsages::empty());
        let (pages, reps): (&[crate::prt::IndexPage], &[f32]) = match sh.map(|s| &s.transfer) {
            Some(ShTransfer::Compressed {
                pages,
                representatives,
                ..
            }) => (pages, representatives),
            _ => (&[], &[]),
        };
        let isize = if pages.is_empty() { [1, 1] } else { size };
        let tex = texture(
            device,
            "sh index",
            isize[0],
            isize[1],
            (pages.len() as u32).max(2),
            wgpu::TextureFormat::R16Uint,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        for (k, p) in pages.iter().enumerate() {
            // Indices are checked below 65536 (`ShInput::validate`).
            let idx: Vec<u16> = p.indices.iter().map(|&i| i as u16).collect();
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &tex,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: k as u32,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(&idx),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(p.width * 2),
                    rows_per_image: Some(p.height),
                },
                wgpu::Extent3d {
                    width: p.width,
                    height: p.height,
                    depth_or_array_layers: 1,
                },
            );
        }
        let index = array_view(&tex);
        let relight = (!pages.is_empty()).then(|| {
            let reps = storage(
                "sh representatives",
                &pack_representatives(reps, bands),
                wgpu::BufferUsages::empty(),
            );
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("prt relit"),
                source: wgpu::ShaderSource::Wgsl(crate::prt::RELIT_SOURCE.as_str().into()),
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("sh relight"),
                layout: None,
                module: &module,
                entry_point: Some("relight_cs"),
                compilation_options: Default::default(),
                cache: None,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sh relight"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: frame_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: reps.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: light.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: relit.as_entire_binding(),
                    },
                ],
            });
            let wg = ((gp * frame.sh_reps as usize).div_ceil(64) as u32).max(1);
            let x = wg.min(65535);
            (pipeline, group, [x, wg.div_ceil(x)])
        });
        ShResources {
            bands,
            vertex,
            light,
            index,
            relit,
            relight,
        }
    }
}

/// The ambient light as 9 SH coefficients of irradiance.
pub(super) fn sh_irradiance(scene: &Scene, ambient: Ambient) -> [[f32; 4]; 9] {
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
                    &env.image,
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

/// The volume's three SH textures (red, green, blue), or black one-texel dummies.
pub(super) fn lpv_views(ctx: &GpuContext, lpv: Option<&crate::lpv::Lpv>) -> Vec<wgpu::TextureView> {
    if let Some(l) = lpv {
        return l
            .textures
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
    }
    let t = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("no lpv"),
        size: wgpu::Extent3d {
            width: 1,
            height: 1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    (0..3).map(|_| t.create_view(&Default::default())).collect()
}
