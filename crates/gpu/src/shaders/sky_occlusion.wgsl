// The sky's occlusion (raster/ambient/sky.rs) for the `sky` and `lpv` ambient sources:
// the fraction of the environment's diffuse light that reaches a point, from shadow-mapped sky
// directions. Compiled after raster.wgsl, before the source's own WGSL; group 2, bindings 8–10.

// One sky direction: its orthographic view-projection, the unit direction towards the sky
// (xyz) with its cell's solid angle (w), and its cell: the flux-weighted mean direction (xyz)
// and the luminance of E⊥ = Σ L·ΔΩ (w).
struct SkyDir {
    view_proj: mat4x4<f32>,
    dir: vec4<f32>,
    cell: vec4<f32>,
}

// x: directions (0: no occlusion), y: a map texel in world units, z: the scene's radius.
struct SkyOcclusion {
    header: vec4<f32>,
    dirs: array<SkyDir>,
}

@group(2) @binding(8) var sky_depth: texture_depth_2d_array;
@group(2) @binding(9) var sky_cmp: sampler_comparison;
@group(2) @binding(10) var<storage, read> sky: SkyOcclusion;

// Whether p (geometric normal ng) sees the sky along direction k: one bilinear depth
// comparison (2 × 2 texels), the point moved off the surface by two texels along ng.
fn sky_visible(k: u32, p: vec3<f32>, ng: vec3<f32>) -> f32 {
    let texel = sky.header.y;
    let q = p + ng * (2.0 * texel);
    let clip = sky.dirs[k].view_proj * vec4<f32>(q, 1.0);
    let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
    // One texel's depth in the map's 0..1 range (over 3 radii), as a bias.
    let z = clip.z - texel / (3.0 * sky.header.z);
    return textureSampleCompareLevel(sky_depth, sky_cmp, uv, i32(k), z);
}

// The fraction of the sky's irradiance at n that reaches p: Σ V_k E_k(n) / Σ E_k(n) by
// luminance, E_k(n) = E⊥_k ⟨n, ω_k⟩₊ the cell as a small source (1 without occlusion).
// Directions whose cell does not light n are not sampled.
fn sky_visibility(s: Surface) -> f32 {
    let count = u32(sky.header.x);
    var all = 0.0;
    var seen = 0.0;
    for (var k = 0u; k < count; k++) {
        let c = sky.dirs[k].cell;
        let w = c.w * dot(s.n, c.xyz);
        if w > 0.0 {
            all += w;
            seen += w * sky_visible(k, s.p, s.ng);
        }
    }
    return select(1.0, seen / max(all, 1e-8), count > 0u && all > 0.0);
}

// The share of the hemisphere around n (cosine-weighted, each direction by its cell's solid
// angle, dir.w) in which the first surface seen from the sky along ω_k lies between p and the
// sky within `radius` of p: occlusion closer than the light volume's cells, which the volume
// cannot resolve. 0 without directions.
fn sky_near_occlusion(s: Surface, radius: f32) -> f32 {
    let count = u32(sky.header.x);
    let texel = sky.header.y;
    let range = 3.0 * sky.header.z;
    let size = vec2<f32>(textureDimensions(sky_depth));
    var all = 0.0;
    var near = 0.0;
    for (var k = 0u; k < count; k++) {
        let d = sky.dirs[k].dir;
        let w = d.w * dot(s.n, d.xyz);
        if w <= 0.0 {
            continue;
        }
        all += w;
        let q = s.p + s.ng * (2.0 * texel);
        let clip = sky.dirs[k].view_proj * vec4<f32>(q, 1.0);
        let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
        if any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0)) {
            continue;
        }
        let zb = textureLoad(sky_depth, vec2<i32>(uv * size), i32(k), 0);
        let gap = (clip.z - zb) * range;
        if gap > texel && gap < radius {
            near += w;
        }
    }
    return select(0.0, near / max(all, 1e-8), count > 0u && all > 0.0);
}
