//! The light-map source: the pages (E/π, then directional ratios) as one array texture, read
//! bilinearly or bicubically.

use super::super::bindings::entry;
use super::LightmapInput;
use crate::GpuContext;
use crate::uniforms::LightmapUniforms;
use wgpu::BindingResource as R;
use wgpu::util::DeviceExt;

pub(in crate::raster) struct LightmapSource {
    uniforms: wgpu::Buffer,
    pages: wgpu::TextureView,
    sampler: wgpu::Sampler,
}

impl LightmapSource {
    /// The pages in an array of `page_size` (the largest page).
    pub fn new(ctx: &GpuContext, lm: &LightmapInput, page_size: [u32; 2]) -> LightmapSource {
        let u = LightmapUniforms {
            mode: if lm.bicubic { 2 } else { 1 } | if lm.directional.is_some() { 4 } else { 0 },
            pages: lm.pages.len() as u32,
            size: [page_size[0] as f32, page_size[1] as f32],
        };
        let uniforms = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("light-map uniforms"),
                contents: bytemuck::bytes_of(&u),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let (pages, sampler) = super::upload_lightmaps(ctx, Some(lm), None, page_size);
        LightmapSource {
            uniforms,
            pages,
            sampler,
        }
    }

    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        vec![
            entry(3, self.uniforms.as_entire_binding()),
            entry(4, R::TextureView(&self.pages)),
            entry(5, R::Sampler(&self.sampler)),
        ]
    }
}
