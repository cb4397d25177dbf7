//! The SH source: transfer per vertex, per texel or per compressed texel (with its relighting
//! compute pass), and the frame's SH light (`Renderer::set_sh_light`).

use super::super::bindings::entry;
use crate::GpuContext;
use crate::prt::{ShInput, ShTransfer};
use crate::resources::{array_view, texture, write_layer};
use crate::uniforms::ShUniforms;
use wgpu::BindingResource as R;
use wgpu::util::DeviceExt;

/// GPU data of an SH technique.
pub(in crate::raster) struct ShResources {
    pub bands: usize,
    pub uniforms: ShUniforms,
    uniform_buf: wgpu::Buffer,
    /// Textured transfer (or a black array), and its sampler.
    pages: wgpu::TextureView,
    sampler: wgpu::Sampler,
    vertex: wgpu::Buffer,
    /// Sample points then coefficients; rewritten by `set_sh_light`.
    pub light: wgpu::Buffer,
    index: wgpu::TextureView,
    relit: wgpu::Buffer,
    /// The relighting compute pass of compressed transfer: pipeline, bind group, workgroups.
    pub relight: Option<(wgpu::ComputePipeline, wgpu::BindGroup, [u32; 2])>,
}

/// The SH source's uniforms for a scene of `instances` instances.
fn uniforms(sh: &ShInput, instances: usize) -> ShUniforms {
    let groups = sh.groups(instances);
    ShUniforms {
        mode: sh.mode(),
        layers: crate::prt::layers(sh.bands) as u32,
        points: sh.points as u32,
        per_object: sh.per_object as u32,
        read_filter: match &sh.transfer {
            ShTransfer::Compressed { filter, .. } => filter.code(),
            _ => 0,
        },
        reps: sh.representatives() as u32,
        coeff_base: (groups * sh.points) as u32,
        groups: groups as u32,
    }
}

impl ShResources {
    pub fn new(
        ctx: &GpuContext,
        input: &crate::prt::ShInput,
        instances: usize,
        size: [u32; 2],
    ) -> ShResources {
        let sh = Some(input);
        let u = uniforms(input, instances);
        let uniform_buf = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sh uniforms"),
                contents: bytemuck::bytes_of(&u),
                usage: wgpu::BufferUsages::UNIFORM,
            });
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
        let gp = (u.groups * u.points) as usize;
        let light = vec![[0.0f32; 4]; gp + gp * 4 * u.layers as usize];
        let light = storage("sh light", &light, wgpu::BufferUsages::COPY_DST);
        let relit = vec![[0.0f32; 4]; gp * u.reps as usize];
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
            let bytes = bytemuck::cast_slice(&idx);
            write_layer(ctx, &tex, k as u32, bytes, p.width * 2, [p.width, p.height]);
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
                        resource: uniform_buf.as_entire_binding(),
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
            let wg = ((gp * u.reps as usize).div_ceil(64) as u32).max(1);
            let x = wg.min(65535);
            (pipeline, group, [x, wg.div_ceil(x)])
        });
        let (pages, sampler) = super::upload_lightmaps(ctx, None, sh, size);
        ShResources {
            bands,
            uniforms: u,
            uniform_buf,
            pages,
            sampler,
            vertex,
            light,
            index,
            relit,
            relight,
        }
    }
}

impl ShResources {
    /// Group 2's entries from binding 3 on.
    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        vec![
            entry(3, self.uniform_buf.as_entire_binding()),
            entry(4, R::TextureView(&self.pages)),
            entry(5, R::Sampler(&self.sampler)),
            entry(6, self.vertex.as_entire_binding()),
            entry(7, self.light.as_entire_binding()),
            entry(8, R::TextureView(&self.index)),
            entry(9, self.relit.as_entire_binding()),
        ]
    }

    /// Compressed SH light-maps: relight every representative under this frame's light.
    pub fn relight_pass<'q>(
        &self,
        enc: &mut wgpu::CommandEncoder,
        slot: &mut dyn FnMut(&'static str) -> Option<(&'q wgpu::QuerySet, u32, u32)>,
    ) {
        let Some((pipeline, group, wg)) = &self.relight else {
            return;
        };
        let ts = slot("sh relight");
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("sh relight"),
            timestamp_writes: ts.map(|(query_set, b, e)| wgpu::ComputePassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(b),
                end_of_pass_write_index: Some(e),
            }),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(wg[0], wg[1], 1);
    }
}
