//! A camera lens's film: renders through a lens's views, accumulated. Each view is a
//! perspective (a camera-space transform and an eye) and a mesh that morphs its render onto
//! the film. For Heidrich's image-based lens model (1999 §11.2.1) the mesh is a projection's
//! film grid (`lightlab_core::lens::image_model`), reading the render where each vertex's
//! traced ray meets the image plane, weighted by the vertex's exposure; for a thin or thick
//! lens (Haeberli & Akeley) it is the whole frame at weight 1/N. The film is `Rgba16Float`
//! (blendable on every adapter; `Rgba32Float` blending needs an optional feature).

use crate::GpuContext;
use crate::resources::{ReadbackError, read_texture};
use glam::{Mat4, Vec3};
use lightlab_core::image::Image;
use lightlab_core::lens::image_model::MorphVertex;
use wgpu::util::DeviceExt;

const FILM: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// One render of a lens's image: camera space → the space the camera's projection applies
/// to, the eye (camera space), and the mesh that puts the render on the film.
#[derive(Clone, Debug)]
pub struct LensView {
    pub view: Mat4,
    pub eye: Vec3,
    pub vertices: Vec<MorphVertex>,
    pub indices: Vec<u32>,
}

/// The whole frame at `weight`, unmorphed (a thin lens's accumulation).
pub fn full_frame(weight: f32) -> (Vec<MorphVertex>, Vec<u32>) {
    let v = |x: f32, y: f32| MorphVertex {
        ndc: [x, y],
        uv: [0.5 * (x + 1.0), 0.5 * (1.0 - y)],
        weight,
    };
    (
        vec![v(-1.0, -1.0), v(1.0, -1.0), v(-1.0, 1.0), v(1.0, 1.0)],
        vec![0, 1, 3, 0, 3, 2],
    )
}

/// A film that accumulates morphed projections.
pub struct LensMorph {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    film: wgpu::Texture,
    film_view: wgpu::TextureView,
    /// The next `add` clears the film first.
    fresh: bool,
}

impl LensMorph {
    /// A film of `width` × `height` texels.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> LensMorph {
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lens morph"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/lens_morph.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lens morph"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lens morph"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("lens morph"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<MorphVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2, 2 => Float32],
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: FILM,
                    blend: Some(wgpu::BlendState {
                        color: add,
                        alpha: add,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("lens morph"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let film = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("lens film"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FILM,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let film_view = film.create_view(&Default::default());
        LensMorph {
            pipeline,
            layout,
            sampler,
            film,
            film_view,
            fresh: true,
        }
    }

    /// The film (for a display pass).
    pub fn film_view(&self) -> &wgpu::TextureView {
        &self.film_view
    }

    /// Start a new image (the next `add` clears the film).
    pub fn clear(&mut self) {
        self.fresh = true;
    }

    /// Morph `render` (one projection's image) onto the film through the mesh `vertices`
    /// (`indices`: a triangle list), adding it to what the film holds.
    pub fn add(
        &mut self,
        ctx: &GpuContext,
        render: &wgpu::TextureView,
        vertices: &[MorphVertex],
        indices: &[u32],
    ) {
        let device = &ctx.device;
        let vb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lens morph vertices"),
            contents: bytemuck::cast_slice(vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let ib = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lens morph indices"),
            contents: bytemuck::cast_slice(indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lens morph"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(render),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        });
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lens morph"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.film_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: if std::mem::take(&mut self.fresh) {
                            wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.set_vertex_buffer(0, vb.slice(..));
            pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..indices.len() as u32, 0, 0..1);
        }
        ctx.queue.submit([enc.finish()]);
    }

    /// Wait until the GPU has drawn everything added so far (for timing).
    pub fn wait(&self, ctx: &GpuContext) {
        let _ = crate::wait_idle(&ctx.device);
    }

    /// The film's image (linear radiance).
    pub fn read(&self, ctx: &GpuContext) -> Result<Image, ReadbackError> {
        let bytes = read_texture(ctx, &self.film, 8)?;
        let halves: &[half::f16] = bytemuck::cast_slice(&bytes);
        let size = self.film.size();
        let mut img = Image::new(size.width, size.height);
        for (px, c) in img.data.iter_mut().zip(halves.chunks_exact(4)) {
            *px = Vec3::new(c[0].to_f32(), c[1].to_f32(), c[2].to_f32());
        }
        Ok(img)
    }
}
