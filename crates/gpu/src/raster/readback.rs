//! Reading a renderer's targets back: the HDR frame, the G-buffer, and the shadow tests'
//! masks (for tests).

use super::passes::load_f32;
use super::settings::{RasterError, RenderPath, ShadowMethod};
use super::{Renderer, SLOT};
use crate::GpuContext;
use crate::resources::read_texture;
use glam::Vec3;
use lightlab_core::image::Image;

impl Renderer {
    /// The last frame's linear radiance.
    pub fn read_hdr(&self, ctx: &GpuContext) -> Result<Image, RasterError> {
        let bytes = read_texture(ctx, &self.targets.hdr, 8)?;
        let halves: &[half::f16] = bytemuck::cast_slice(&bytes);
        let mut img = Image::new(self.settings.width, self.settings.height);
        for (px, c) in img.data.iter_mut().zip(halves.chunks_exact(4)) {
            *px = Vec3::new(c[0].to_f32(), c[1].to_f32(), c[2].to_f32());
        }
        Ok(img)
    }

    /// The last frame's G-buffer (deferred path only), row-major per layer: diffuse
    /// reflectance + dielectric F0, shading normal + roughness, F0 + (model + transmission),
    /// camera-relative position + 1 (0 where nothing was drawn).
    pub fn read_gbuffer(&self, ctx: &GpuContext) -> Result<Vec<Vec<[f32; 4]>>, RasterError> {
        if self.settings.path != RenderPath::Deferred {
            return Err(RasterError::Settings(
                "only the deferred path writes a G-buffer".into(),
            ));
        }
        self.targets
            .gbuffer_textures
            .iter()
            .map(|t| {
                let bytes = read_texture(ctx, t, t.format().block_copy_size(None).unwrap_or(8))?;
                Ok(if t.format() == wgpu::TextureFormat::Rgba32Float {
                    bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec()
                } else {
                    bytemuck::cast_slice::<u8, [half::f16; 4]>(&bytes)
                        .iter()
                        .map(|c| c.map(|v| v.to_f32()))
                        .collect()
                })
            })
            .collect()
    }

    /// Per light, which pixels the shadow method lets the light reach (255) or not (0),
    /// row-major. Renders a G-buffer for it, so call it on its own (not between frames).
    pub fn shadow_masks(&mut self, ctx: &GpuContext) -> Result<Vec<Vec<u8>>, RasterError> {
        if matches!(
            self.settings.shadows,
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass
        ) {
            self.build_volumes(ctx);
        }
        let mut labels = vec![];
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        self.prepasses(&mut enc, &mut labels);
        if self.settings.shadows.map() {
            self.shadow_map_passes(&mut enc, &mut labels);
        }
        self.base_pass(&mut enc, &mut labels, true);
        ctx.queue.submit([enc.finish()]);
        let mut masks = vec![];
        for li in 0..self.light_pos.len() {
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            {
                let map = self.settings.shadows.map();
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("mask"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &self.targets.mask_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: (!map).then(|| {
                        wgpu::RenderPassDepthStencilAttachment {
                            view: &self.targets.depth_view,
                            depth_ops: Some(load_f32()),
                            stencil_ops: Some(wgpu::Operations {
                                load: wgpu::LoadOp::Clear(0),
                                store: wgpu::StoreOp::Store,
                            }),
                        }
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, &self.group0, &[(li as u64 * SLOT) as u32]);
                if map {
                    pass.set_pipeline(self.pipelines.map_mask.get());
                    pass.set_bind_group(2, &self.group2, &[]);
                    pass.set_bind_group(3, &self.group3, &[]);
                } else {
                    self.stencil_marks(&mut pass, li, true);
                    pass.set_pipeline(self.pipelines.mask.get());
                    pass.set_stencil_reference(0);
                }
                pass.draw(0..3, 0..1);
            }
            ctx.queue.submit([enc.finish()]);
            masks.push(read_texture(ctx, &self.targets.mask, 1)?);
        }
        Ok(masks)
    }
}
