//! GPU-visible structs, defined once on the Rust side (`bytemuck::Pod`, explicit padding) and
//! checked against naga's layout of `shaders/common.wgsl` (see `layout::check_struct` and the
//! test below).

use bytemuck::{Pod, Zeroable};

/// Per-frame constants (WGSL `FrameUniforms`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub view: [[f32; 4]; 4],
    pub camera_pos: [f32; 3],
    pub exposure: f32,
    pub viewport: [f32; 2],
    pub light_count: u32,
    /// 0 none (or stencil shadows), 1 shadow-map depth comparison, 2 Heidrich linear depth.
    pub shadow_mode: u32,
    /// Irradiance SH coefficients (RGB in xyz).
    pub ambient_sh: [[f32; 4]; 9],
    pub pcf_radius: i32,
    pub normal_offset: f32,
    pub linear_bias: f32,
    pub shadow_size: f32,
    /// Wind sway (lightlab_core::wind::Wind::uniform).
    pub wind_a: [f32; 4],
    pub wind_b: [f32; 4],
    /// Plane (n, d): fragments with n·x + d < 0 are discarded (a planar mirror's reflected
    /// view, `raster::mirror`); zero keeps everything.
    pub clip_plane: [f32; 4],
    /// Normal maps: 0 box-mipped, 1 Toksvig-widened (variance in the map's alpha), 2 the
    /// finest level (`raster::NormalFilter`).
    pub normal_filter: u32,
    /// 1: Torrance–Sparrow and Banks materials read their lookup tables (`brdf_tables`).
    pub brdf_tables: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// The light-map source's uniforms (WGSL `LightmapUniforms`): `mode` 1 bilinear, 2 bicubic,
/// +4 directional; E/π pages (directional page k is layer `pages + k`); page size in texels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LightmapUniforms {
    pub mode: u32,
    pub pages: u32,
    pub size: [f32; 2],
}

/// The SH source's uniforms (WGSL `ShUniforms`), shared with the relighting pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ShUniforms {
    /// 1 textured, 2 per vertex, 3 compressed.
    pub mode: u32,
    /// vec4s per transfer vector: ⌈bands²/4⌉.
    pub layers: u32,
    /// Sample points per group.
    pub points: u32,
    /// 1: one group per instance; 0: one for the scene.
    pub per_object: u32,
    /// Compressed reads: 0 nearest, 1 bilinear, 2 Fuchs's 4-tap.
    pub read_filter: u32,
    pub reps: u32,
    pub coeff_base: u32,
    pub groups: u32,
}

/// The volume source's uniforms (WGSL `LpvAmbientUniforms`): 1 Kaplanyan / 2 WPI, cells per
/// axis, 1 = indirect light only (debug view), damping distance in cells, number of cascades,
/// and per cascade (finest first) the grid's origin and cell size.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LpvAmbientUniforms {
    pub mode: u32,
    pub size: f32,
    pub indirect_only: u32,
    pub damping: f32,
    pub cascades: u32,
    /// Sub-cell occlusion of the volume's light: the radius [m] within which the sky's depth
    /// maps count a surface as occluding (0: off).
    pub occlusion_radius: f32,
    /// The near field gathered from the last light's RSM: samples per pixel (0: off).
    pub near_samples: u32,
    /// The near field's light's share of the volume's light (`Lpv::near_field_share`): what
    /// the near field replaces of it on thin translucent surfaces.
    pub near_share: f32,
    pub grids: [[f32; 4]; 4],
    /// `lpv-faithful`'s composite (the WPI report's App. B): the sun's direction of travel
    /// (w: 1 when the composite replaces the light passes).
    pub sun_dir: [f32; 4],
    /// The sun's irradiance on a surface facing it (rgb); w: the shadow bias in the RSM's
    /// depth units.
    pub sun_e: [f32; 4],
    /// The view-projection of the RSM the composite's sun or the near field reads (the last
    /// light's; orthographic, depth 0..1).
    pub rsm_view_proj: [[f32; 4]; 4],
    /// The near field's light: its direction of travel; w: the RSM's texel side [m].
    pub near: [f32; 4],
}

/// One light (WGSL `GpuLight`). `kind`: 0 point, 1 spot, 2 directional, 3 area (an emissive
/// instance as a Lambertian rectangle: `position` its centre moved `area_offset` along its
/// normal `direction`, corners centre ± `edge_u` ± `edge_v`, `color` its radiance, `intensity`
/// its area).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub range: f32,
    pub color: [f32; 3],
    pub intensity: f32,
    pub cos_inner: f32,
    pub cos_outer: f32,
    pub atten_scale: f32,
    /// 0 inverse square; 1..=4 Fuchs's atten₁..atten₄ (§4.1).
    pub attenuation: u32,
    pub shadow_first: u32,
    pub shadow_count: u32,
    /// 1: the diffuse term only (the environment's sun).
    pub diffuse_only: u32,
    /// Kind 4 (goniometric): the layer of its candela table (`photometric.rs`).
    pub profile: u32,
    pub cascade_ends: [f32; 4],
    /// Area lights: half the rectangle's first edge; goniometric lights: the C0 axis.
    pub edge_u: [f32; 3],
    pub area_offset: f32,
    pub edge_v: [f32; 3],
    pub two_sided: u32,
}

/// One shadow-map layer (WGSL `ShadowView`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadowView {
    pub view_proj: [[f32; 4]; 4],
    pub texel_scale: f32,
    pub ortho: u32,
    pub far: f32,
    /// Near distance of a perspective view (linearises its depth for soft shadows).
    pub near: f32,
}

/// Per-pass constants (WGSL `PassUniforms`), one 256-byte slot each (dynamic offsets).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PassUniforms {
    pub light_index: u32,
    pub shadow_view: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// A material (WGSL `GpuMaterial`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    pub base_color: [f32; 4],
    pub emissive: [f32; 3],
    pub metallic: f32,
    pub roughness: f32,
    pub specular: f32,
    pub normal_scale: f32,
    pub alpha_cutoff: f32,
    pub transmission: f32,
    pub model: u32,
    pub flags: u32,
    pub uv_sets: u32,
    pub sway: f32,
    pub ior: f32,
    pub spec_transmission: f32,
    /// KHR_materials_volume thickness (0: thin-walled glass).
    pub thickness: f32,
    /// The KHR_texture_transform of each texture (WGSL comment), two rows each.
    pub uv_transform: [[f32; 4]; 12],
    /// A measured metal's complex index η + ik (xyz), w = 1 when present.
    pub conductor_eta: [f32; 4],
    pub conductor_k: [f32; 4],
    /// KHR_materials_anisotropy: (strength, cos rotation, sin rotation, 0).
    pub anisotropy: [f32; 4],
    /// The Lafortune lobe's (C_x, C_y, C_z, 0).
    pub lafortune: [f32; 4],
    /// Lookup tables (`brdf_tables::gpu_entry`): scales of the two tables, first layer, 1 when
    /// the material has them.
    pub tables: [f32; 4],
}

/// The WGSL source that declares these structs.
pub const COMMON_WGSL: &str = include_str!("shaders/common.wgsl");
/// The scene vertex layout and the material bind group (group 1), after common.wgsl.
pub const MATERIAL_WGSL: &str = include_str!("shaders/material.wgsl");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::check_struct;
    use crate::rust_layout;

    #[test]
    fn rust_structs_match_the_wgsl_layout() {
        let src = crate::raster::shader_source(crate::raster::SourceKind::Sky);
        let checks = [
            (
                "FrameUniforms",
                rust_layout!(
                    FrameUniforms,
                    view_proj,
                    inv_view_proj,
                    view,
                    camera_pos,
                    exposure,
                    viewport,
                    light_count,
                    shadow_mode,
                    ambient_sh,
                    pcf_radius,
                    normal_offset,
                    linear_bias,
                    shadow_size,
                    wind_a,
                    wind_b,
                    clip_plane,
                    normal_filter,
                    brdf_tables,
                    _pad1,
                    _pad2
                ),
            ),
            (
                "LightmapUniforms",
                rust_layout!(LightmapUniforms, mode, pages, size),
            ),
            (
                "ShUniforms",
                rust_layout!(
                    ShUniforms,
                    mode,
                    layers,
                    points,
                    per_object,
                    read_filter,
                    reps,
                    coeff_base,
                    groups
                ),
            ),
            (
                "LpvAmbientUniforms",
                rust_layout!(
                    LpvAmbientUniforms,
                    mode,
                    size,
                    indirect_only,
                    damping,
                    cascades,
                    occlusion_radius,
                    near_samples,
                    near_share,
                    grids,
                    sun_dir,
                    sun_e,
                    rsm_view_proj,
                    near
                ),
            ),
            (
                "GpuLight",
                rust_layout!(
                    GpuLight,
                    position,
                    kind,
                    direction,
                    range,
                    color,
                    intensity,
                    cos_inner,
                    cos_outer,
                    atten_scale,
                    attenuation,
                    shadow_first,
                    shadow_count,
                    diffuse_only,
                    profile,
                    cascade_ends,
                    edge_u,
                    area_offset,
                    edge_v,
                    two_sided,
                ),
            ),
            (
                "ShadowView",
                rust_layout!(ShadowView, view_proj, texel_scale, ortho, far, near),
            ),
            (
                "PassUniforms",
                rust_layout!(PassUniforms, light_index, shadow_view, _pad0, _pad1),
            ),
            (
                "GpuMaterial",
                rust_layout!(
                    GpuMaterial,
                    base_color,
                    emissive,
                    metallic,
                    roughness,
                    specular,
                    normal_scale,
                    alpha_cutoff,
                    transmission,
                    model,
                    flags,
                    uv_sets,
                    sway,
                    ior,
                    spec_transmission,
                    thickness,
                    uv_transform,
                    conductor_eta,
                    conductor_k,
                    anisotropy,
                    lafortune,
                    tables
                ),
            ),
        ];
        for (name, layout) in checks {
            check_struct(src, name, &layout).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}
