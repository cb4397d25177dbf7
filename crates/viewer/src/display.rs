//! The display pass: the renderer's linear HDR target to an 8-bit window or image, with the
//! exposure and tone operators of `lightlab_core::color` (the same numbers `lightlab render`
//! writes to PNG).

use lightlab_core::color::ToneMap;
use lightlab_gpu::GpuContext;

/// WGSL of the display pass.
pub const DISPLAY_WGSL: &str = include_str!("display.wgsl");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    exposure: f32,
    tone: u32,
    encode: u32,
    _pad: u32,
}

fn tone_code(t: ToneMap) -> u32 {
    match t {
        ToneMap::Clamp => 0,
        ToneMap::Reinhard => 1,
        ToneMap::Filmic => 2,
    }
}

/// A full-screen pass from an HDR texture to one 8-bit colour format.
pub struct Display {
    pub format: wgpu::TextureFormat,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
}

impl Display {
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Display {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(DISPLAY_WGSL.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("display"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Display {
            format,
            pipeline,
            layout,
            params,
        }
    }

    /// Record the pass: `hdr` (exposure × value, then `tone`) into `target`.
    pub fn draw(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        hdr: &wgpu::TextureView,
        target: &wgpu::TextureView,
        exposure: f32,
        tone: ToneMap,
    ) {
        let p = Params {
            exposure,
            tone: tone_code(tone),
            encode: u32::from(!self.format.is_srgb()),
            _pad: 0,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(hdr),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.params.as_entire_binding(),
                },
            ],
        });
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("display"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
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
        pass.draw(0..3, 0..1);
    }
}

/// Display `hdr` (`width`×`height`) into 8-bit sRGB pixels (RGB, row-major, top row first), as
/// the window shows it: for screenshots and tests.
pub fn display_to_rgb8(
    ctx: &GpuContext,
    hdr: &wgpu::TextureView,
    width: u32,
    height: u32,
    exposure: f32,
    tone: ToneMap,
) -> Result<Vec<[u8; 3]>, lightlab_gpu::resources::ReadbackError> {
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let display = Display::new(&ctx.device, format);
    let tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("screenshot"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    display.draw(
        ctx,
        &mut enc,
        hdr,
        &tex.create_view(&Default::default()),
        exposure,
        tone,
    );
    ctx.queue.submit([enc.finish()]);
    let bytes = lightlab_gpu::resources::read_texture(ctx, &tex, 4)?;
    Ok(bytes.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wgsl_validates_and_params_match_its_layout() {
        lightlab_gpu::layout::validate_wgsl(DISPLAY_WGSL).expect("display.wgsl");
        let rust = lightlab_gpu::rust_layout!(Params, exposure, tone, encode, _pad);
        lightlab_gpu::layout::check_struct(DISPLAY_WGSL, "Params", &rust).expect("Params");
    }
}
