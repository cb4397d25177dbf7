//! The passes of a frame, one function each, in the order [`Renderer::render`] records them:
//! the SH relighting compute pass, shadow maps, the base pass (depth, ambient and emission, or
//! the G-buffer), the sky, per light its stencil marks and lighting, and the tonemap.

use super::settings::{RenderPath, ShadowMethod};
use super::{Renderer, SLOT};
use crate::GpuContext;
use crate::lights;
use crate::shadow_volume::{LightPos, build_volume};
use glam::{Mat4, Vec3, Vec4};

/// The next pair of timestamp queries for a pass named `label` (recorded in `labels`), if the
/// adapter has timestamps and the query set has room.
pub(super) fn timestamp_slot<'q>(
    queries: Option<&'q (wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
    labels: &mut Vec<&'static str>,
    label: &'static str,
) -> Option<(&'q wgpu::QuerySet, u32, u32)> {
    let (set, _, _) = queries?;
    let i = labels.len() as u32;
    if 2 * i + 1 >= set.count() {
        return None;
    }
    labels.push(label);
    Some((set, 2 * i, 2 * i + 1))
}

/// Rectangle `a` (x, y, w, h) within `b` (None: the whole frame); None when they miss.
fn intersect(
    a: (u32, u32, u32, u32),
    b: Option<(u32, u32, u32, u32)>,
) -> Option<(u32, u32, u32, u32)> {
    let Some(b) = b else {
        return Some(a);
    };
    let (x0, y0) = (a.0.max(b.0), a.1.max(b.1));
    let (x1, y1) = ((a.0 + a.2).min(b.0 + b.2), (a.1 + a.3).min(b.1 + b.3));
    (x1 > x0 && y1 > y0).then_some((x0, y0, x1 - x0, y1 - y0))
}

pub(super) fn load_f32() -> wgpu::Operations<f32> {
    wgpu::Operations {
        load: wgpu::LoadOp::Load,
        store: wgpu::StoreOp::Store,
    }
}

pub(super) fn load_u32() -> wgpu::Operations<u32> {
    wgpu::Operations {
        load: wgpu::LoadOp::Load,
        store: wgpu::StoreOp::Store,
    }
}

impl Renderer {
    /// Whether light `li`'s sphere of influence can touch the box `b`.
    pub(super) fn reaches(&self, li: usize, b: &(Vec3, Vec3)) -> bool {
        if !self.settings.scissor {
            return true;
        }
        match (self.light_pos[li], self.light_radius[li]) {
            (LightPos::Point(p), Some(r)) => p.clamp(b.0, b.1).distance_squared(p) <= r * r,
            _ => true,
        }
    }

    /// The light's screen rectangle (x, y, w, h), or None when it covers nothing.
    pub(super) fn scissor(&self, li: usize) -> Option<(u32, u32, u32, u32)> {
        let (w, h) = (self.settings.width, self.settings.height);
        let full = Some((0, 0, w, h));
        if !self.settings.scissor {
            return full;
        }
        let (LightPos::Point(p), Some(r)) = (self.light_pos[li], self.light_radius[li]) else {
            return full;
        };
        let vp = Mat4::from_cols_array_2d(&self.frame.view_proj);
        let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
        for c in lights::box_corners((p - Vec3::splat(r), p + Vec3::splat(r))) {
            let q = vp * c.extend(1.0);
            if q.w <= 1e-4 {
                return full;
            }
            let ndc = glam::Vec2::new(q.x, q.y) / q.w;
            lo = lo.min(ndc);
            hi = hi.max(ndc);
        }
        let x0 = (((lo.x + 1.0) * 0.5 * w as f32).floor().max(0.0) as u32).min(w);
        let x1 = (((hi.x + 1.0) * 0.5 * w as f32).ceil().max(0.0) as u32).min(w);
        let y0 = (((1.0 - hi.y) * 0.5 * h as f32).floor().max(0.0) as u32).min(h);
        let y1 = (((1.0 - lo.y) * 0.5 * h as f32).ceil().max(0.0) as u32).min(h);
        (x1 > x0 && y1 > y0).then_some((x0, y0, x1 - x0, y1 - y0))
    }

    /// Build every light's shadow volume on the CPU and upload it.
    pub(super) fn build_volumes(&mut self, ctx: &GpuContext) {
        let mut verts: Vec<Vec4> = vec![];
        self.volume_ranges.clear();
        for li in 0..self.light_pos.len() {
            let start = verts.len() as u32;
            for d in &self.scene.draws {
                if let Some(vm) = &d.volume
                    && self.reaches(li, &d.bounds)
                {
                    build_volume(vm, self.light_pos[li], &mut verts);
                }
            }
            self.volume_ranges.push(start..verts.len() as u32);
        }
        if verts.is_empty() {
            verts.push(Vec4::ZERO);
        }
        let bytes = (verts.len() * 16) as u64;
        if self.volume_buf.as_ref().is_none_or(|b| b.size() < bytes) {
            self.volume_buf = Some(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow volumes"),
                size: bytes.next_power_of_two(),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        ctx.queue.write_buffer(
            self.volume_buf.as_ref().expect("allocated above"),
            0,
            bytemuck::cast_slice(&verts),
        );
    }

    pub(super) fn draw_scene<'a>(
        &'a self,
        pass: &mut wgpu::RenderPass<'a>,
        pipes: &'a [super::pipelines::Lazy; 2],
        li: Option<usize>,
    ) {
        pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
        pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        let mut current: Option<bool> = None;
        for (ii, d) in self.scene.draws.iter().enumerate() {
            if li.is_some_and(|li| !self.reaches(li, &d.bounds)) || self.hidden == Some(ii) {
                continue;
            }
            let m = &self.scene.materials[d.material];
            if current != Some(m.double_sided) {
                pass.set_pipeline(pipes[m.double_sided as usize].get());
                current = Some(m.double_sided);
            }
            pass.set_bind_group(1, &m.bind_group, &[]);
            // The instance index is the scene instance (per-object SH light groups).
            pass.draw_indexed(
                d.first_index..d.first_index + d.index_count,
                0,
                ii as u32..ii as u32 + 1,
            );
        }
    }

    pub(super) fn timestamps<'q>(
        &'q self,
        labels: &mut Vec<&'static str>,
        label: &'static str,
    ) -> Option<wgpu::RenderPassTimestampWrites<'q>> {
        let (set, begin, end) = timestamp_slot(self.queries.as_ref(), labels, label)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(begin),
            end_of_pass_write_index: Some(end),
        })
    }

    /// The ambient source's passes before the frame's (SH relighting, the volume's RSMs,
    /// injection and propagation).
    pub(super) fn prepasses(&self, enc: &mut wgpu::CommandEncoder, labels: &mut Vec<&'static str>) {
        let queries = self.queries.as_ref();
        self.ambient.prepasses(enc, &self.scene, &mut |label| {
            timestamp_slot(queries, labels, label)
        });
    }

    pub(super) fn shadow_map_passes(
        &self,
        enc: &mut wgpu::CommandEncoder,
        labels: &mut Vec<&'static str>,
    ) {
        let n = self.lights.len();
        let linear = self.settings.shadows == ShadowMethod::MapLinear;
        for v in 0..self.views.len() {
            let ts = self.timestamps(labels, "shadow maps");
            let color = linear.then(|| wgpu::RenderPassColorAttachment {
                view: &self.shadow.linear_layers[v],
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 1e30,
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            });
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map"),
                color_attachments: if color.is_some() {
                    std::slice::from_ref(&color)
                } else {
                    &[]
                },
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: if linear {
                        &self.shadow.linear_depth
                    } else {
                        &self.shadow.layers[v]
                    },
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: ts,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(if linear {
                self.pipelines.shadow_linear.get()
            } else {
                self.pipelines.shadow_depth.get()
            });
            pass.set_bind_group(0, &self.group0, &[((n + v) as u64 * SLOT) as u32]);
            pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
            pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            let li = self.view_light[v];
            for d in &self.scene.draws {
                if !self.reaches(li, &d.bounds) {
                    continue;
                }
                pass.set_bind_group(1, &self.scene.materials[d.material].bind_group, &[]);
                pass.draw_indexed(d.first_index..d.first_index + d.index_count, 0, 0..1);
            }
        }
    }

    /// Stencil marks of light `li` (volumes or planar projections) into the current pass.
    pub(super) fn stencil_marks<'a>(
        &'a self,
        pass: &mut wgpu::RenderPass<'a>,
        li: usize,
        mask_target: bool,
    ) {
        let m = mask_target as usize;
        match self.settings.shadows {
            ShadowMethod::VolumesZFail | ShadowMethod::VolumesZPass => {
                let r = self.volume_ranges[li].clone();
                if r.is_empty() {
                    return;
                }
                pass.set_pipeline(if self.settings.shadows == ShadowMethod::VolumesZFail {
                    self.pipelines.zfail[m].get()
                } else {
                    self.pipelines.zpass[m].get()
                });
                pass.set_stencil_reference(0);
                pass.set_vertex_buffer(0, self.volume_buf.as_ref().expect("built").slice(..));
                pass.draw(r, 0..1);
            }
            ShadowMethod::Planar => {
                if self.planar[li].is_none() {
                    return;
                }
                pass.set_pipeline(self.pipelines.planar[m].get());
                pass.set_stencil_reference(1);
                pass.set_vertex_buffer(0, self.scene.vertices.slice(..));
                pass.set_index_buffer(self.scene.indices.slice(..), wgpu::IndexFormat::Uint32);
                let Some(p) = self.plane else {
                    return;
                };
                for d in &self.scene.draws {
                    // Only objects wholly above the plane cast onto it (the receiver would
                    // project onto itself).
                    let lowest = lights::box_corners(d.bounds)
                        .iter()
                        .map(|c| p.truncate().dot(*c) + p.w)
                        .fold(f32::INFINITY, f32::min);
                    if lowest < -1e-3 {
                        continue;
                    }
                    pass.set_bind_group(1, &self.scene.materials[d.material].bind_group, &[]);
                    pass.draw_indexed(d.first_index..d.first_index + d.index_count, 0, 0..1);
                }
            }
            _ => {}
        }
    }

    /// Depth, ambient and emission (and the G-buffer when `deferred`).
    pub(super) fn base_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        labels: &mut Vec<&'static str>,
        deferred: bool,
    ) {
        let clear = wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        };
        let depth_clear = Some(wgpu::RenderPassDepthStencilAttachment {
            view: &self.targets.depth_view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(0.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(0),
                store: wgpu::StoreOp::Store,
            }),
        });
        {
            let ts = self.timestamps(
                labels,
                if deferred {
                    "g-buffer"
                } else {
                    "depth+ambient"
                },
            );
            let att = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear,
                })
            };
            let mut colors = vec![att(&self.targets.hdr_view)];
            if deferred {
                colors.extend(self.targets.gbuffer.iter().map(att));
            }
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("base"),
                color_attachments: &colors,
                depth_stencil_attachment: depth_clear,
                timestamp_writes: ts,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let Some((x, y, w, h)) = self.clip_rect {
                pass.set_scissor_rect(x, y, w, h);
            }
            pass.set_bind_group(0, &self.group0, &[0]);
            pass.set_bind_group(2, &self.group2, &[]);
            let pipes = if deferred {
                &self.pipelines.gbuffer
            } else {
                &self.pipelines.ambient
            };
            self.draw_scene(&mut pass, pipes, None);
        }
    }

    /// A pass adding to the HDR target over the frame's depth and stencil (kept).
    pub(super) fn hdr_pass_loading_depth<'e>(
        &self,
        enc: &'e mut wgpu::CommandEncoder,
        labels: &mut Vec<&'static str>,
        label: &'static str,
    ) -> wgpu::RenderPass<'e> {
        let ts = self.timestamps(labels, label);
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.targets.hdr_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.targets.depth_view,
                depth_ops: Some(load_f32()),
                stencil_ops: Some(load_u32()),
            }),
            timestamp_writes: ts,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// The environment where no surface was drawn.
    pub(super) fn sky_pass(&self, enc: &mut wgpu::CommandEncoder, labels: &mut Vec<&'static str>) {
        let Some(group) = &self.sky_group else {
            return;
        };
        let mut pass = self.hdr_pass_loading_depth(enc, labels, "sky");
        if let Some((x, y, w, h)) = self.clip_rect {
            pass.set_scissor_rect(x, y, w, h);
        }
        pass.set_pipeline(self.pipelines.sky.get());
        pass.set_bind_group(0, &self.group0, &[0]);
        pass.set_bind_group(1, &self.scene.materials[0].bind_group, &[]);
        pass.set_bind_group(2, &self.group2, &[]);
        pass.set_bind_group(3, group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Per light: stencil marks, then its additive lighting pass.
    pub(super) fn light_passes(
        &self,
        enc: &mut wgpu::CommandEncoder,
        labels: &mut Vec<&'static str>,
    ) {
        let deferred = self.settings.path == RenderPath::Deferred;
        for li in 0..self.light_pos.len() {
            let Some(sc) = self
                .scissor(li)
                .and_then(|sc| intersect(sc, self.clip_rect))
            else {
                continue;
            };
            let slot = [(li as u64 * SLOT) as u32];
            if self.settings.shadows.stencil() {
                let ts = self.timestamps(labels, "volumes");
                // Depth and stencil only: no colour target to load and store.
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("volumes"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &self.targets.depth_view,
                        depth_ops: Some(load_f32()),
                        stencil_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(0),
                            store: wgpu::StoreOp::Store,
                        }),
                    }),
                    timestamp_writes: ts,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_scissor_rect(sc.0, sc.1, sc.2, sc.3);
                pass.set_bind_group(0, &self.group0, &slot);
                self.stencil_marks(&mut pass, li, false);
            }
            let mut pass = self.hdr_pass_loading_depth(enc, labels, "lighting");
            pass.set_scissor_rect(sc.0, sc.1, sc.2, sc.3);
            pass.set_stencil_reference(0);
            pass.set_bind_group(0, &self.group0, &slot);
            pass.set_bind_group(2, &self.group2, &[]);
            if deferred {
                pass.set_pipeline(self.pipelines.deferred_light.get());
                pass.set_bind_group(3, &self.group3, &[]);
                pass.draw(0..3, 0..1);
            } else {
                self.draw_scene(&mut pass, &self.pipelines.light, Some(li));
            }
        }
    }
}
