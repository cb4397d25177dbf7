// Ambient source `sh` (SH light-maps, Fuchs §5; PRT, McKenzie Chapter ch. 4): diffuse ×
// transfer · the frame's SH light, per vertex, per texel or per compressed texel. Compiled after
// raster.wgsl.

@group(2) @binding(3) var<uniform> sh_u: ShUniforms;
// Textured transfer: coefficients 4j..4j+3 of page p in layer p·sh_u.layers + j.
@group(2) @binding(4) var lightmap: texture_2d_array<f32>;
@group(2) @binding(5) var lightmap_sampler: sampler;
// Per-vertex vectors (sh_u.layers vec4s per vertex), the frame's light (sample points, then per
// group and point sh_u.layers·4 RGB coefficients), the compressed index map and the
// representatives relit this frame ((group·points + point)·reps + r).
@group(2) @binding(6) var<storage, read> sh_vertex: array<vec4<f32>>;
@group(2) @binding(7) var<storage, read> sh_light: array<vec4<f32>>;
@group(2) @binding(8) var sh_index: texture_2d_array<u32>;
@group(2) @binding(9) var<storage, read> sh_relit: array<vec4<f32>>;

fn sh_group(instance: u32) -> u32 {
    return select(0u, instance, sh_u.per_object == 1u);
}

// Blend weights of the group's sample points at p: ∝ 1/distance, summing to 1
// (lightlab_bake::sh_light::point_weights).
fn sh_weights(g: u32, p: vec3<f32>) -> array<f32, 6> {
    var w = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    var total = 0.0;
    for (var k = 0u; k < sh_u.points; k++) {
        let q = sh_light[g * sh_u.points + k].xyz;
        w[k] = 1.0 / max(length(p - q), 1e-6);
        total += w[k];
    }
    for (var k = 0u; k < sh_u.points; k++) {
        w[k] /= total;
    }
    return w;
}

// Σ tᵢ·lᵢ over coefficients 4j..4j+3, the light blended from the group's sample points.
fn sh_dot4(g: u32, w: array<f32, 6>, j: u32, t: vec4<f32>) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    for (var k = 0u; k < sh_u.points; k++) {
        let b = sh_u.coeff_base + (g * sh_u.points + k) * 4u * sh_u.layers + 4u * j;
        e += w[k] * (t.x * sh_light[b].xyz + t.y * sh_light[b + 1u].xyz
            + t.z * sh_light[b + 2u].xyz + t.w * sh_light[b + 3u].xyz);
    }
    return e;
}

// Textured transfer (SH light-maps, textured PRT): bilinear coefficient reads.
fn sh_textured(uv1: vec2<f32>, g: u32, w: array<f32, 6>) -> vec3<f32> {
    let page = floor(uv1.x);
    let uv = vec2<f32>(uv1.x - page, uv1.y);
    var e = vec3<f32>(0.0);
    for (var j = 0u; j < sh_u.layers; j++) {
        let l = i32(u32(page) * sh_u.layers + j);
        e += sh_dot4(g, w, j, textureSampleLevel(lightmap, lightmap_sampler, uv, l, 0.0));
    }
    return e;
}

// One compressed texel: its representative, relit this frame, blended over sample points.
fn sh_texel(c: vec2<i32>, page: i32, g: u32, w: array<f32, 6>) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(sh_index));
    let cc = clamp(c, vec2<i32>(0), size - 1);
    let r = textureLoad(sh_index, cc, page, 0).x;
    var e = vec3<f32>(0.0);
    for (var k = 0u; k < sh_u.points; k++) {
        e += w[k] * sh_relit[(g * sh_u.points + k) * sh_u.reps + r].xyz;
    }
    return e;
}

// Compressed SH light-maps (Fuchs §5.6) with the filters of §5.8: nearest; bilinear of the
// relit representatives (what hardware filtering would do to decompressed data); Fuchs's 4-tap
// average of nearest decompressions at ±¼ texel.
fn sh_compressed(uv1: vec2<f32>, g: u32, w: array<f32, 6>) -> vec3<f32> {
    let page = floor(uv1.x);
    let layer = i32(page);
    let size = vec2<f32>(textureDimensions(sh_index));
    let x = vec2<f32>(uv1.x - page, uv1.y) * size;
    if sh_u.read_filter == 1u {
        let y = x - 0.5;
        let i = vec2<i32>(floor(y));
        let f = y - floor(y);
        let a = sh_texel(i, layer, g, w);
        let b = sh_texel(i + vec2<i32>(1, 0), layer, g, w);
        let c = sh_texel(i + vec2<i32>(0, 1), layer, g, w);
        let d = sh_texel(i + vec2<i32>(1, 1), layer, g, w);
        return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
    }
    if sh_u.read_filter == 2u {
        var e = vec3<f32>(0.0);
        for (var k = 0; k < 4; k++) {
            let o = vec2<f32>(f32(k & 1) - 0.5, f32(k >> 1u) - 0.5) * 0.5;
            e += 0.25 * sh_texel(vec2<i32>(floor(x + o)), layer, g, w);
        }
        return e;
    }
    return sh_texel(vec2<i32>(floor(x)), layer, g, w);
}

// E/π of the SH techniques at a fragment.
fn sh_ambient(in: VertexOut) -> vec3<f32> {
    if sh_u.mode == 2u {
        return in.vertex_light;
    }
    let g = sh_group(in.instance);
    let w = sh_weights(g, in.world);
    if sh_u.mode == 3u {
        return sh_compressed(in.uv1, g, w);
    }
    return sh_textured(in.uv1, g, w);
}

fn source_vertex(p: vec3<f32>, vi: u32, ii: u32) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    if sh_u.mode == 2u {
        let g = sh_group(ii);
        let w = sh_weights(g, p);
        for (var j = 0u; j < sh_u.layers; j++) {
            e += sh_dot4(g, w, j, sh_vertex[vi * sh_u.layers + j]);
        }
    }
    return e;
}

fn source_radiance(s: Surface, in: VertexOut, nv: vec3<f32>, glossy: vec3<f32>) -> vec3<f32> {
    return s.diffuse * max(sh_ambient(in), vec3<f32>(0.0)) + glossy + emission(in);
}
