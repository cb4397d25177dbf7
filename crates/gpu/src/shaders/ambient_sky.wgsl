// Ambient source `sky` (the Phong techniques): the environment's SH irradiance and its glossy
// reflection, occluded by the scene through shadow-mapped sky directions (sky_occlusion.wgsl,
// before this).

fn source_vertex(p: vec3<f32>, vi: u32, ii: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn source_radiance(s: Surface, in: VertexOut, nv: vec3<f32>, glossy: vec3<f32>) -> vec3<f32> {
    let t = sky_terms(s, 0.0, env_occlusion_lobe(s));
    return sky_light(s, t) + glossy * t.spec + emission(in);
}
