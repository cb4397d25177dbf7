// The image-based lens model's morph (Heidrich 1999 §11.2.1, step 5): one projection's
// render, texture-mapped onto its film-grid mesh and weighted by each vertex's exposure,
// added into the film's accumulation (additive blending).

struct VsOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) weight: f32,
};

@group(0) @binding(0) var render: texture_2d<f32>;
@group(0) @binding(1) var bilinear: sampler;

@vertex
fn vs(@location(0) ndc: vec2<f32>, @location(1) uv: vec2<f32>, @location(2) weight: f32) -> VsOut {
    var out: VsOut;
    out.pos = vec4<f32>(ndc, 0.0, 1.0);
    out.uv = uv;
    out.weight = weight;
    return out;
}

@fragment
fn fs(in: VsOut) -> @location(0) vec4<f32> {
    let c = textureSampleLevel(render, bilinear, in.uv, 0.0).rgb;
    // Alpha sums the weights (the exposure the film received, for diagnostics).
    return vec4<f32>(c * in.weight, in.weight);
}
