// Shared GPU-visible structs of lightlab's real-time techniques. Their Rust twins live in
// `crates/gpu/src/uniforms.rs` and are checked against naga's layout of this file in a test.

struct FrameUniforms {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    camera_pos: vec3<f32>,
    exposure: f32,
    viewport: vec2<f32>,
    light_count: u32,
    frame: u32,
}

// One light. kind: 0 point, 1 spot, 2 directional. Spot cones as cosines; `range` 0 = infinite.
struct GpuLight {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    range: f32,
    color: vec3<f32>,
    intensity: f32,
    cos_inner: f32,
    cos_outer: f32,
    angular_radius: f32,
    attenuation: u32,
}

@group(0) @binding(0) var<uniform> frame_uniforms: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<GpuLight>;

// Keeps both declarations alive for validation until a technique includes this file.
@compute @workgroup_size(1)
fn touch() {
    let l = lights[0];
    _ = frame_uniforms.exposure + l.intensity;
}
