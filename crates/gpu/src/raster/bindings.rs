//! The renderer's bind-group layouts, named by role, and typed helpers for their entries.
//!
//! Groups: `frame` (0: frame uniforms, lights, shadow views, the per-pass slot, the
//! goniometric lights' candela tables at 16, a canned light's slices and sampler at 17–18, the
//! materials' BRDF lookup tables at 19), the
//! material (1, `gpu_scene`), `lighting` (2: shadow maps, then the ambient source's resources),
//! and the full-screen inputs (3: G-buffer, tonemap source, sky).

use wgpu::{BindGroupLayoutEntry as Entry, BindingType, ShaderStages, TextureViewDimension as Dim};

/// A uniform or storage buffer, seen by the vertex and fragment stages.
pub fn buffer(binding: u32, ty: wgpu::BufferBindingType, dynamic: bool) -> Entry {
    Entry {
        binding,
        visibility: ShaderStages::VERTEX_FRAGMENT,
        ty: BindingType::Buffer {
            ty,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A read-only storage buffer.
pub fn storage(binding: u32) -> Entry {
    buffer(
        binding,
        wgpu::BufferBindingType::Storage { read_only: true },
        false,
    )
}

/// A texture read by the fragment stage.
pub fn texture(binding: u32, sample_type: wgpu::TextureSampleType, dim: Dim) -> Entry {
    Entry {
        binding,
        visibility: ShaderStages::FRAGMENT,
        ty: BindingType::Texture {
            sample_type,
            view_dimension: dim,
            multisampled: false,
        },
        count: None,
    }
}

/// A texture read texel by texel (unfilterable float).
pub fn texel_texture(binding: u32, dim: Dim) -> Entry {
    texture(
        binding,
        wgpu::TextureSampleType::Float { filterable: false },
        dim,
    )
}

/// A filterable float texture.
pub fn filtered_texture(binding: u32, dim: Dim) -> Entry {
    texture(
        binding,
        wgpu::TextureSampleType::Float { filterable: true },
        dim,
    )
}

/// A sampler of the fragment stage.
pub fn sampler(binding: u32, ty: wgpu::SamplerBindingType) -> Entry {
    Entry {
        binding,
        visibility: ShaderStages::FRAGMENT,
        ty: BindingType::Sampler(ty),
        count: None,
    }
}

fn layout(device: &wgpu::Device, label: &str, entries: &[Entry]) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries,
    })
}

/// The bind-group layouts of the renderer, by role.
pub(super) struct GroupLayouts {
    pub frame: wgpu::BindGroupLayout,
    pub material: wgpu::BindGroupLayout,
    pub lighting: wgpu::BindGroupLayout,
    pub gbuffer: wgpu::BindGroupLayout,
    pub tonemap: wgpu::BindGroupLayout,
    pub sky: wgpu::BindGroupLayout,
}

impl GroupLayouts {
    /// The layouts of a renderer whose ambient source adds `source` to group 2.
    pub fn new(device: &wgpu::Device, source: &[Entry]) -> GroupLayouts {
        use wgpu::SamplerBindingType as S;
        let frame = layout(
            device,
            "frame",
            &[
                buffer(0, wgpu::BufferBindingType::Uniform, false),
                storage(1),
                storage(2),
                buffer(3, wgpu::BufferBindingType::Uniform, true),
                texel_texture(16, Dim::D2Array),
                filtered_texture(17, Dim::D2Array),
                sampler(18, S::Filtering),
                texel_texture(19, Dim::D2Array),
            ],
        );
        // Shadow maps (0–2), the ambient source's bindings (3..), the environment term's (20–25).
        let mut entries = vec![
            texture(0, wgpu::TextureSampleType::Depth, Dim::D2Array),
            sampler(1, S::Comparison),
            texel_texture(2, Dim::D2Array),
        ];
        entries.extend_from_slice(source);
        entries.extend(super::env::layout_entries());
        let lighting = layout(device, "lighting", &entries);
        let gbuffer = layout(
            device,
            "g-buffer",
            &(0..5)
                .map(|b| texel_texture(b, Dim::D2))
                .collect::<Vec<_>>(),
        );
        GroupLayouts {
            frame,
            material: crate::gpu_scene::material_layout(device),
            lighting,
            gbuffer,
            tonemap: layout(device, "tonemap", &[texel_texture(4, Dim::D2)]),
            sky: layout(device, "sky", &[texel_texture(5, Dim::D2)]),
        }
    }
}

/// The pipeline layouts: which groups each kind of pass binds.
pub(super) struct PipelineLayouts {
    /// Scene passes: frame, material, lighting.
    pub scene: wgpu::PipelineLayout,
    /// Deferred lighting and the shadow-map mask: … and the G-buffer.
    pub deferred: wgpu::PipelineLayout,
    /// Shadow maps and planar projections: frame, material.
    pub shadow: wgpu::PipelineLayout,
    /// Shadow volumes and the stencil mask: frame only.
    pub frame: wgpu::PipelineLayout,
    pub tonemap: wgpu::PipelineLayout,
    pub sky: wgpu::PipelineLayout,
}

impl PipelineLayouts {
    pub fn new(device: &wgpu::Device, g: &GroupLayouts) -> PipelineLayouts {
        let pl = |label, groups: &[Option<&wgpu::BindGroupLayout>]| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: groups,
                immediate_size: 0,
            })
        };
        let (f, m, l) = (Some(&g.frame), Some(&g.material), Some(&g.lighting));
        PipelineLayouts {
            scene: pl("scene", &[f, m, l]),
            // No material group: the G-buffer holds the material, and the GL backend allows 16
            // sampled textures per stage, which the material's five would overrun.
            deferred: pl("deferred", &[f, None, l, Some(&g.gbuffer)]),
            shadow: pl("shadow", &[f, m]),
            frame: pl("frame only", &[f]),
            tonemap: pl("tonemap", &[f, m, l, Some(&g.tonemap)]),
            sky: pl("sky", &[f, m, l, Some(&g.sky)]),
        }
    }
}

/// A bind-group entry.
pub fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}
