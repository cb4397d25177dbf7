//! The volume source: the light propagation volume (recomputed every frame by its pre-passes)
//! read trilinearly from its three 3D textures, and the sky's light occluded through the
//! `sky` source's shadow-mapped directions (bindings 8–10 and 12), and the near field gathered
//! from the last light's RSM (bindings 11, 13–15; 19 sampled textures in all, past the 16 of
//! wgpu's default limits, so the device asks for the adapter's).

use super::super::bindings::entry;
use crate::GpuContext;
use crate::lpv::{Lpv, LpvScheme};
use crate::uniforms::LpvAmbientUniforms;
use wgpu::BindingResource as R;
use wgpu::util::DeviceExt;

pub(in crate::raster) struct LpvSource {
    pub volume: Lpv,
    pub indirect_only: bool,
    pub(super) sky: super::SkyOcclusion,
    uniforms: wgpu::Buffer,
    views: Vec<wgpu::TextureView>,
    sampler: wgpu::Sampler,
}

/// The report's shadow bias, in the RSM's depth (0..1 over the light's orthographic range): not
/// stated (a global of its `defshade.c`). Two texels of a 1024² RSM: the range is about the
/// view's width, so a texel is about 1/1024 of it.
const COMPOSITE_SHADOW_BIAS: f32 = 2e-3;

impl LpvSource {
    pub fn new(
        ctx: &GpuContext,
        volume: Lpv,
        sky: super::SkyOcclusion,
        indirect_only: bool,
    ) -> LpvSource {
        let mut u = LpvAmbientUniforms {
            mode: match volume.settings.scheme {
                LpvScheme::Kaplanyan => 1,
                LpvScheme::Wpi => 2,
            },
            size: volume.grids[0].n as f32,
            indirect_only: indirect_only as u32,
            damping: match volume.settings.scheme {
                LpvScheme::Kaplanyan => volume.settings.damping,
                LpvScheme::Wpi => 0.0,
            },
            cascades: volume.grids.len() as u32,
            occlusion_radius: volume.near_occlusion_radius(),
            grids: [[0.0, 0.0, 0.0, 1.0]; 4],
            ..Default::default()
        };
        for (k, grid) in volume.grids.iter().enumerate() {
            u.grids[k] = grid.origin.extend(grid.cell).to_array();
        }
        // The near field fills what near occlusion takes out of the volume's light: it needs
        // the lookup's reach, the sky's directions that find the near surfaces, and a
        // directional light's RSM left in the textures.
        if let Some(l) = volume.near_field_light()
            && u.occlusion_radius > 0.0
            && sky.directions() > 0
        {
            u.near_samples = volume.settings.near_field;
            u.near_share = volume.near_field_share();
            u.near = [l.axis[0], l.axis[1], l.axis[2], l.texel.sqrt()];
            u.rsm_view_proj = l.view_proj;
        }
        if let Some(l) = volume.composite_light() {
            u.sun_dir = [l.axis[0], l.axis[1], l.axis[2], 1.0];
            u.sun_e = [l.color[0], l.color[1], l.color[2], COMPOSITE_SHADOW_BIAS];
            u.rsm_view_proj = l.view_proj;
        }
        let uniforms = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lpv ambient uniforms"),
                contents: bytemuck::bytes_of(&u),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let views = volume
            .textures
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("lpv"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        LpvSource {
            volume,
            indirect_only,
            sky,
            uniforms,
            views,
            sampler,
        }
    }

    /// Whether the report's composite lights the frame (the light passes are skipped).
    pub fn composite(&self) -> bool {
        self.volume.composite_light().is_some() && !self.indirect_only
    }

    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        let mut e = vec![
            entry(3, self.uniforms.as_entire_binding()),
            entry(4, R::TextureView(&self.views[0])),
            entry(5, R::TextureView(&self.views[1])),
            entry(6, R::TextureView(&self.views[2])),
            entry(7, R::Sampler(&self.sampler)),
            entry(11, R::TextureView(self.volume.rsm_position_view())),
            entry(13, R::TextureView(&self.volume.rsm_views()[0])),
            entry(14, R::TextureView(&self.volume.rsm_views()[1])),
            entry(15, self.volume.finest_geometry_volume().as_entire_binding()),
        ];
        e.extend(self.sky.entries());
        e
    }
}
