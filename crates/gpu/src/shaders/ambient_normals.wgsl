// Ambient source `normals` (the `normals` debug technique): the shading normal (after the normal
// map, turned to the viewer) as a colour, n/2 + ½, unlit. Compiled after raster.wgsl; no
// bindings of its own.

fn source_vertex(p: vec3<f32>, vi: u32, ii: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn source_radiance(s: Surface, in: VertexOut, nv: vec3<f32>, glossy: vec3<f32>) -> vec3<f32> {
    return 0.5 * s.n + vec3<f32>(0.5);
}
