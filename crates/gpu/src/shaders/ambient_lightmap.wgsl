// Ambient source `lightmap` (Fuchs §3.4): diffuse × the light-map (E/π), bilinear or
// bicubic, with directional light-maps for normal-mapped surfaces. Compiled after raster.wgsl.

@group(2) @binding(3) var<uniform> lm_u: LightmapUniforms;
// Light-maps (E/π): one layer per page; UV1 carries the page in its integer part. Directional
// page k is layer lm_u.pages + k.
@group(2) @binding(4) var lightmap: texture_2d_array<f32>;
@group(2) @binding(5) var lightmap_sampler: sampler;

// Bilinear light-map read at UV1 (page in the integer part of x).
fn lightmap_bilinear(uv1: vec2<f32>, extra: u32) -> vec3<f32> {
    let layer = floor(uv1.x);
    let uv = vec2<f32>(uv1.x - layer, uv1.y);
    return textureSampleLevel(lightmap, lightmap_sampler, uv, i32(layer) + i32(extra), 0.0).rgb;
}

// Cubic B-spline light-map read from four bilinear taps (the weights of each 2×2 pair folded
// into one tap's position), as the CPU's `sample_bicubic`.
fn lightmap_bicubic(uv1: vec2<f32>, extra: u32) -> vec3<f32> {
    let layer = floor(uv1.x);
    let size = lm_u.size;
    let x = vec2<f32>(uv1.x - layer, uv1.y) * size - 0.5;
    let i = floor(x);
    let f = x - i;
    let f2 = f * f;
    let f3 = f2 * f;
    let w0 = (1.0 - f) * (1.0 - f) * (1.0 - f) / 6.0;
    let w1 = (3.0 * f3 - 6.0 * f2 + 4.0) / 6.0;
    let w2 = (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0) / 6.0;
    let w3 = f3 / 6.0;
    let g0 = w0 + w1;
    let g1 = w2 + w3;
    // Tap positions in texel units (texel k's centre is at k + 0.5).
    let h0 = i - 1.0 + w1 / g0 + 0.5;
    let h1 = i + 1.0 + w3 / g1 + 0.5;
    let l = i32(layer) + i32(extra);
    let a = textureSampleLevel(lightmap, lightmap_sampler, vec2<f32>(h0.x, h0.y) / size, l, 0.0).rgb;
    let b = textureSampleLevel(lightmap, lightmap_sampler, vec2<f32>(h1.x, h0.y) / size, l, 0.0).rgb;
    let c = textureSampleLevel(lightmap, lightmap_sampler, vec2<f32>(h0.x, h1.y) / size, l, 0.0).rgb;
    let d = textureSampleLevel(lightmap, lightmap_sampler, vec2<f32>(h1.x, h1.y) / size, l, 0.0).rgb;
    return g0.y * (g0.x * a + g1.x * b) + g1.y * (g0.x * c + g1.x * d);
}

fn lightmap_read(uv1: vec2<f32>, extra: u32) -> vec3<f32> {
    if (lm_u.mode & 3u) == 2u {
        return lightmap_bicubic(uv1, extra);
    }
    return lightmap_bilinear(uv1, extra);
}

// The tangent frame of directional light-maps (lightlab_bake::gather::directional_frame).
fn directional_frame(n: vec3<f32>) -> mat2x3<f32> {
    return orthonormal_basis(n);
}

// Weights of the three basis directions (Half-Life 2's radiosity normal mapping basis) for a
// tangent-space normal, as lightlab_bake::gather::directional_weights.
fn directional_weights(n: vec3<f32>) -> vec3<f32> {
    let c = max(vec3<f32>(
        dot(n, vec3<f32>(-0.4082483, 0.70710677, 0.57735026)),
        dot(n, vec3<f32>(-0.4082483, -0.70710677, 0.57735026)),
        dot(n, vec3<f32>(0.8164966, 0.0, 0.57735026)),
    ), vec3<f32>(0.0));
    let w = c * c;
    let t = w.x + w.y + w.z;
    if t > 0.0 {
        return w / t;
    }
    return vec3<f32>(1.0 / 3.0);
}

fn source_vertex(p: vec3<f32>, vi: u32, ii: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// `nv`: the interpolated vertex normal (before the normal map), turned like s.n.
fn source_radiance(s: Surface, in: VertexOut, nv: vec3<f32>, glossy: vec3<f32>) -> vec3<f32> {
    let uv1 = in.uv1;
    var e = lightmap_read(uv1, 0u);
    if (lm_u.mode & 4u) != 0u {
        let r = lightmap_read(uv1, lm_u.pages);
        let f = directional_frame(nv);
        let nl = vec3<f32>(dot(s.n, f[0]), dot(s.n, f[1]), dot(s.n, nv));
        e *= max(dot(directional_weights(nl), r), 0.0);
    }
    return s.diffuse * max(e, vec3<f32>(0.0)) + glossy + emission(in);
}
