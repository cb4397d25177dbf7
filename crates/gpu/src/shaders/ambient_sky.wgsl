// Ambient source `sky` (the Phong techniques): the environment's SH irradiance, occluded by
// the scene through shadow-mapped sky directions (sky_occlusion.wgsl, before this), and its
// glossy reflection.

fn source_vertex(p: vec3<f32>, vi: u32, ii: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// The glossy reflection stays unoccluded here: these techniques know no light but the sky's and
// the lights', and occluded directions would reflect black where the path tracer sees lit
// surfaces (a chrome ball's lower half over a sunlit ground: `spheres` 0.0358 → 0.0443).
fn source_radiance(s: Surface, in: VertexOut, nv: vec3<f32>, glossy: vec3<f32>) -> vec3<f32> {
    let none = vec4<f32>(0.0);
    return sky_light(s, sky_terms(s, 0.0, none, Surroundings(none, none, none))) + glossy + emission(in);
}
