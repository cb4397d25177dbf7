// The scene's vertex layout and material bind group (group 1), shared by the renderer and the
// LPV's reflective shadow maps. Compiled after common.wgsl.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) tangent: vec4<f32>,
    @location(3) uv0: vec2<f32>,
    @location(4) uv1: vec2<f32>,
    // COLOR_0 (white without): multiplies the base colour.
    @location(5) color: vec4<f32>,
}

@group(1) @binding(0) var<uniform> material: GpuMaterial;
@group(1) @binding(1) var base_tex: texture_2d<f32>;
@group(1) @binding(2) var mr_tex: texture_2d<f32>;
@group(1) @binding(3) var normal_tex: texture_2d<f32>;
@group(1) @binding(4) var emissive_tex: texture_2d<f32>;
@group(1) @binding(5) var tex_sampler: sampler;
// Translucency map (KHR_materials_diffuse_transmission: alpha scales the factor); flag bit 5.
@group(1) @binding(6) var transmission_tex: texture_2d<f32>;

// The coordinates texture `i` reads: its UV set (bit i of uv_sets) and its transform.
fn material_uv(i: u32, uv0: vec2<f32>, uv1: vec2<f32>) -> vec2<f32> {
    let uv = select(uv0, uv1, ((material.uv_sets >> i) & 1u) == 1u);
    let r0 = material.uv_transform[2u * i];
    let r1 = material.uv_transform[2u * i + 1u];
    return vec2<f32>(dot(r0.xy, uv) + r0.z, dot(r1.xy, uv) + r1.z);
}

// Diffuse transmission of thin surfaces: the factor × the translucency map's alpha.
fn material_transmission(uv0: vec2<f32>, uv1: vec2<f32>) -> f32 {
    var t = material.transmission;
    if (material.flags & 32u) != 0u {
        t *= textureSample(transmission_tex, tex_sampler, material_uv(5u, uv0, uv1)).a;
    }
    return clamp(t, 0.0, 1.0);
}

fn material_base(uv0: vec2<f32>, uv1: vec2<f32>, color: vec4<f32>) -> vec4<f32> {
    var c = material.base_color * color;
    if (material.flags & 1u) != 0u {
        c *= textureSample(base_tex, tex_sampler, material_uv(0u, uv0, uv1));
    }
    return c;
}
