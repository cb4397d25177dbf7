// The sky's occlusion (raster/ambient/sky.rs) for the `sky` and `lpv` ambient sources:
// the fraction of the environment's diffuse light that reaches a point, from shadow-mapped sky
// directions. Compiled after raster.wgsl, before the source's own WGSL; group 2, bindings 8–10
// and 12.

// One sky direction (raster/ambient/sky.rs `SkyDir`): the x, y and z rows of its orthographic
// view-projection (affine), and its cell's E⊥ = Σ L·ΔΩ (rgb) with the cell's solid angle (w).
// The unit direction towards the sky (the cell's flux-weighted mean direction) is −z row × the
// depth range (3 radii).
struct SkyDir {
    rows: array<vec4<f32>, 3>,
    cell: vec4<f32>,
}

@group(2) @binding(8) var sky_depth: texture_depth_2d_array;
@group(2) @binding(9) var sky_cmp: sampler_comparison;
// The directions, read by every fragment in the same order: a uniform buffer (on lavapipe 40 %
// less time in the sky's loop than from a storage buffer); 256 = sky.rs `MAX_DIRECTIONS`.
@group(2) @binding(10) var<uniform> sky_dirs: array<SkyDir, 256>;
// x: directions (0: no occlusion), y: a map texel in world units, z: the scene's radius.
@group(2) @binding(12) var<uniform> sky: vec4<f32>;

// How far [m] along ng a point moves before its depth comparison with a map looking along a
// direction at cos θ = cg to ng, `texel` the map's texel [m]. The bilinear comparison reads
// texels up to one texel across, where the surface lies texel·tan θ deeper; the comparison's
// own bias is one texel of depth, so the point must rise by texel·(tan θ − 1) towards the
// map: an offset δ along ng gains δ·cos θ, so δ = texel·(sin θ − cos θ)/cos²θ (0 up to 45°,
// capped at two texels from 65° on, where the cosine weight is small). A constant offset of
// two texels (before) opened the gaps of a dense canopy to the sky. GPU test
// `the_occluded_sky_leaves_convex_objects_unshadowed` holds it to no acne; figures in
// docs/phong-and-shadows.md.
fn receiver_offset(cg: f32, texel: f32) -> f32 {
    let c = clamp(abs(cg), 0.0, 1.0);
    let sn = sqrt(1.0 - c * c);
    return texel * clamp((sn - c) / max(c * c, 0.05), 0.0, 2.0);
}

// The fraction of the sky's irradiance at n that reaches p (rgb) and, when `radius` > 0, the
// share of the hemisphere from which the light volume's light can arrive (a), in one pass over
// the directions (they share each direction's projection).
//
// rgb: Σ V_k E_k(n) / Σ E_k(n) per channel, E_k(n) = E⊥_k ⟨n, ω_k⟩₊ the cell as a small source,
// V_k one bilinear depth comparison (2 × 2 texels) with the point moved off the surface along
// ng by `receiver_offset`; 1 without occlusion. Directions whose cell does not light n are not
// sampled for it. Per channel, not by luminance: where a building hides the pale horizon and
// leaves the blue zenith, the light that reaches the point is bluer than the whole sky's
// (a luminance ratio on the whole sky's irradiance turned a courtyard's shade grey).
//
// a: the share of the hemisphere around n (cosine-weighted, each direction by its cell's solid
// angle, cell.w) in which the first surface seen from p along ω_k lies further than `radius`.
// Indirect light arrives only from surfaces: where p sees the sky (V_k = 1) it gets the sky's
// light, which rgb covers, and no bounce; where the first surface lies within `radius` it is
// nearer than the volume's cells resolve (the volume holds light from beyond it). The volume's
// blurred 2-band light stands for the rest; 1 without directions.
fn sky_terms(s: Surface, radius: f32) -> vec4<f32> {
    let count = u32(sky.x);
    let texel = sky.y;
    let range = 3.0 * sky.z;
    var lit = vec3<f32>(0.0);
    var seen = vec3<f32>(0.0);
    var area = 0.0;
    var far = 0.0;
    for (var k = 0u; k < count; k++) {
        let d = sky_dirs[k];
        let dir = -d.rows[2].xyz * range;
        let c = dot(s.n, dir);
        let w = d.cell.xyz * c;
        if c <= 0.0 || (all(w <= vec3<f32>(0.0)) && radius <= 0.0) {
            continue;
        }
        let q = vec4<f32>(s.p + s.ng * receiver_offset(dot(s.ng, dir), texel), 1.0);
        let clip = vec3<f32>(dot(d.rows[0], q), dot(d.rows[1], q), dot(d.rows[2], q));
        let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
        // Nothing between p and the sky (one texel's depth, in the map's 0..1 range over
        // 3 radii, as a bias).
        let v = textureSampleCompareLevel(sky_depth, sky_cmp, uv, i32(k), clip.z - texel / range);
        let wl = max(w, vec3<f32>(0.0));
        lit += wl;
        seen += wl * v;
        if radius > 0.0 {
            // Nothing nearer to the sky than `radius` from p: where this is 0 a surface lies
            // beyond the radius (comparisons only: depth textures cannot be read as values on
            // every backend).
            let within = textureSampleCompareLevel(sky_depth, sky_cmp, uv, i32(k), clip.z - radius / range);
            let wo = d.cell.w * c;
            area += wo;
            far += wo * (1.0 - within);
        }
    }
    return vec4<f32>(
        select(vec3<f32>(1.0), seen / max(lit, vec3<f32>(1e-8)), lit > vec3<f32>(0.0)),
        select(1.0, far / max(area, 1e-8), area > 0.0),
    );
}

// The fraction of the sky's irradiance at n that reaches p, per channel (`sky_terms`' rgb).
fn sky_visibility(s: Surface) -> vec3<f32> {
    return sky_terms(s, 0.0).rgb;
}
