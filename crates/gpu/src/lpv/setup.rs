//! Making a volume's GPU resources: the uniform slots, the RSM targets and pass, the compute
//! pipelines, and each cascade's buffers and ping-pong bind groups.

use super::{
    CELL_BYTES, Cascade, Compute, LpvScheme, LpvSettings, LpvUniforms, RSM_FORMATS, RsmLight, SLOT,
};
use crate::gpu_scene::vertex_layout;
use lightlab_core::lpv::{self, Grid};
use wgpu::ShaderStages as S;
use wgpu::util::DeviceExt;

/// Two uniform slots per cascade (without and with the geometry volume), packed at `SLOT`.
pub(super) fn uniform_slots(
    settings: &LpvSettings,
    grids: &[Grid],
    bound: f32,
    wind: &lightlab_core::wind::Wind,
) -> Vec<u8> {
    let n = grids.last().expect("at least one cascade").n;
    let gv_on = settings.occlusion && settings.scheme == LpvScheme::Kaplanyan;
    // Fixed point: the largest |coefficient| is below 1.03·Φ/π of all the RSMs' flux.
    let base = LpvUniforms {
        n,
        use_gv: 0,
        scale: (1u32 << 30) as f32 / bound,
        gv_scale: 65536.0,
        rsm_size: settings.rsm_size,
        wpi_samples: settings.wpi_samples,
        store_last: (settings.scheme == LpvScheme::Wpi) as u32,
        occlusion: gv_on as u32,
        reemit: (settings.reemit == lpv::Reemit::Central) as u32,
        bounces: (settings.bounces == lpv::Bounces::Multiple) as u32,
        lobe: settings.reemit_lobe,
        wind_a: wind.uniform()[0],
        wind_b: wind.uniform()[1],
        ..Default::default()
    };
    let mut bytes = vec![0u8; 2 * grids.len() * SLOT as usize];
    for (c, g) in grids.iter().enumerate() {
        for (k, use_gv) in [0u32, gv_on as u32].into_iter().enumerate() {
            let u = LpvUniforms {
                origin: g.origin.to_array(),
                cell: g.cell,
                use_gv,
                layer: c as u32 * n,
                ..base
            };
            let o = (2 * c + k) * SLOT as usize;
            bytes[o..o + std::mem::size_of::<LpvUniforms>()]
                .copy_from_slice(bytemuck::bytes_of(&u));
        }
    }
    bytes
}

/// One uniform slot per RSM view.
pub(super) fn light_slots(device: &wgpu::Device, lights: &[(RsmLight, f32)]) -> wgpu::Buffer {
    let mut bytes = vec![0u8; SLOT as usize * lights.len().max(1)];
    for (i, (l, _)) in lights.iter().enumerate() {
        let o = i * SLOT as usize;
        bytes[o..o + std::mem::size_of::<RsmLight>()].copy_from_slice(bytemuck::bytes_of(l));
    }
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("rsm lights"),
        contents: &bytes,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// The three 3D textures (r, g, b) the renderer samples, `count` cascades stacked along z.
pub(super) fn volume_textures(device: &wgpu::Device, n: u32, count: u32) -> [wgpu::Texture; 3] {
    ["lpv r", "lpv g", "lpv b"].map(|label| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: n,
                height: n,
                depth_or_array_layers: n * count,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    })
}

/// The RSM's flux, normal and position targets (with their views) and its depth buffer.
pub(super) fn rsm_targets(
    device: &wgpu::Device,
    size: u32,
) -> (
    Vec<wgpu::Texture>,
    Vec<wgpu::TextureView>,
    wgpu::TextureView,
) {
    let textures: Vec<wgpu::Texture> = RSM_FORMATS
        .iter()
        .zip(["rsm flux", "rsm normal", "rsm position"])
        .map(|(f, label)| {
            crate::resources::texture(
                device,
                label,
                size,
                size,
                1,
                *f,
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
            )
        })
        .collect();
    let views = textures
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let depth = crate::resources::texture(
        device,
        "rsm depth",
        size,
        size,
        1,
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    )
    .create_view(&Default::default());
    (textures, views, depth)
}

/// A uniform buffer with a dynamic offset.
fn uniform_entry(binding: u32, visibility: S) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: None,
        },
        count: None,
    }
}

/// One slot of `size` bytes of a uniform buffer.
fn uniform_binding(binding: u32, buffer: &wgpu::Buffer, size: usize) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset: 0,
            size: wgpu::BufferSize::new(size as u64),
        }),
    }
}

/// The RSM pass's pipeline and bind group (volume uniforms, the view's light, the goniometric
/// lights' candela tables).
pub(super) fn rsm_pass(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    uniforms: &wgpu::Buffer,
    lights: &wgpu::Buffer,
    profiles: &wgpu::TextureView,
) -> (wgpu::RenderPipeline, wgpu::BindGroup) {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("rsm"),
        entries: &[
            uniform_entry(0, S::VERTEX_FRAGMENT),
            uniform_entry(1, S::VERTEX_FRAGMENT),
            crate::raster::bindings::texel_texture(16, wgpu::TextureViewDimension::D2Array),
        ],
    });
    let material_layout = crate::gpu_scene::material_layout(device);
    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("rsm"),
        bind_group_layouts: &[Some(&layout), Some(&material_layout)],
        immediate_size: 0,
    });
    let targets: Vec<Option<wgpu::ColorTargetState>> =
        RSM_FORMATS.iter().map(|f| Some((*f).into())).collect();
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("rsm"),
        layout: Some(&pl),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("rsm_vs"),
            compilation_options: Default::default(),
            buffers: &[Some(vertex_layout())],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("rsm_fs"),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("rsm"),
        layout: &layout,
        entries: &[
            uniform_binding(0, uniforms, std::mem::size_of::<LpvUniforms>()),
            uniform_binding(1, lights, std::mem::size_of::<RsmLight>()),
            wgpu::BindGroupEntry {
                binding: 16,
                resource: wgpu::BindingResource::TextureView(profiles),
            },
        ],
    });
    (pipeline, group)
}

/// The compute passes' layout: uniforms, the RSM, atomics, ping-pong and accumulation
/// buffers, the geometry volume, and the three output textures.
pub(super) fn compute_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let texture_entry = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: S::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    let storage_entry = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: S::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let out_entry = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: S::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format: wgpu::TextureFormat::Rgba16Float,
            view_dimension: wgpu::TextureViewDimension::D3,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lpv compute"),
        entries: &[
            uniform_entry(0, S::COMPUTE),
            uniform_entry(1, S::COMPUTE),
            texture_entry(2),
            texture_entry(3),
            texture_entry(4),
            storage_entry(5, false),
            storage_entry(6, false),
            storage_entry(7, true),
            storage_entry(8, false),
            storage_entry(9, false),
            storage_entry(10, false),
            out_entry(11),
            out_entry(12),
            out_entry(13),
        ],
    })
}

/// Injection, resolve, propagation (both schemes) and store.
pub(super) fn compute_pipelines(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
) -> Compute {
    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("lpv compute"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let cp = |entry: &str| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pl),
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    };
    Compute {
        inject: cp("inject_cs"),
        resolve: cp("resolve_cs"),
        propagate: cp("propagate_cs"),
        inject_wpi: cp("inject_wpi_cs"),
        propagate_wpi: cp("propagate_wpi_cs"),
        store: cp("store_cs"),
    }
}

/// What every cascade's bind groups share.
pub(super) struct CascadeInputs<'a> {
    pub layout: &'a wgpu::BindGroupLayout,
    pub uniforms: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    pub rsm: &'a [wgpu::TextureView],
    /// The sky views' RSM, when there are sky views.
    pub sky_rsm: Option<&'a [wgpu::TextureView]>,
    pub out: &'a [wgpu::TextureView; 3],
}

/// One cascade of `n`³ cells: atomics, ping-pong buffers (A → B and B → A bind groups),
/// accumulation and geometry volume.
pub(super) fn cascade(device: &wgpu::Device, c: &CascadeInputs, n: u32) -> Cascade {
    let cells = (n as u64).pow(3);
    let gv_cells = (n as u64 + 1).pow(3);
    let storage = |label, bytes: u64, extra| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(16),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
            mapped_at_creation: false,
        })
    };
    let (read, none) = (wgpu::BufferUsages::COPY_SRC, wgpu::BufferUsages::empty());
    let lpv_atomic = storage("lpv atomics", cells * CELL_BYTES, none);
    // Blockers from the lights, then from the camera, then the albedo of both.
    let gv_atomic = storage("gv atomics", 3 * gv_cells * 16, none);
    let buffers = [
        storage("lpv a", cells * CELL_BYTES, read),
        storage("lpv b", cells * CELL_BYTES, read),
    ];
    let accum = storage("lpv accumulation", cells * CELL_BYTES, read);
    // Per cell: the blocking SH, then the albedo sums (Σ albedo·A, Σ A).
    let gv = storage("geometry volume", 2 * gv_cells * 16, read);
    let group = |src: &wgpu::Buffer, dst: &wgpu::Buffer, rsm: &[wgpu::TextureView]| {
        let e = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        let view = wgpu::BindingResource::TextureView;
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lpv compute"),
            layout: c.layout,
            entries: &[
                uniform_binding(0, c.uniforms, std::mem::size_of::<LpvUniforms>()),
                uniform_binding(1, c.lights, std::mem::size_of::<RsmLight>()),
                e(2, view(&rsm[0])),
                e(3, view(&rsm[1])),
                e(4, view(&rsm[2])),
                e(5, lpv_atomic.as_entire_binding()),
                e(6, gv_atomic.as_entire_binding()),
                e(7, src.as_entire_binding()),
                e(8, dst.as_entire_binding()),
                e(9, accum.as_entire_binding()),
                e(10, gv.as_entire_binding()),
                e(11, view(&c.out[0])),
                e(12, view(&c.out[1])),
                e(13, view(&c.out[2])),
            ],
        })
    };
    let groups = [
        group(&buffers[0], &buffers[1], c.rsm),
        group(&buffers[1], &buffers[0], c.rsm),
    ];
    Cascade {
        groups,
        sky_group: c.sky_rsm.map(|rsm| group(&buffers[1], &buffers[0], rsm)),
        lpv_atomic,
        gv_atomic,
        gv,
        buffers,
    }
}
