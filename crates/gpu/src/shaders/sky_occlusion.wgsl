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

// How a point at cos θ = cg to a map's direction moves ahead of its own surface before the
// depth comparison, `texel` the map's texel [m]: (offset along ng, depth bias), both in metres.
// The bilinear comparison reads the map's texels up to one texel across, where the surface
// lies up to texel·tan θ nearer the map than the point.
// - The depth bias covers that up to 45°: texel·(min(tan θ, 1) + 0.1), the 0.1 for the
//   rasteriser's and the interpolated position's rounding. Only as deep as the slope needs: a
//   point sees past every occluder within the bias of it, and in the bush's canopy, leaves a
//   few centimetres apart, a constant bias of one texel let in 1.19 times the sky light of the
//   path tracer, 1.17 with this one (512² maps).
// - Beyond 45° the point rises by the rest, texel·(tan θ − 1): an offset δ along ng gains
//   δ·cos θ, so δ = texel·(sin θ − cos θ)/cos²θ, capped at two texels from 65° on, where the
//   cosine weight is small. A constant offset of two texels (before) opened the gaps of a
//   dense canopy to the sky.
// GPU test `the_occluded_sky_leaves_convex_objects_unshadowed` holds both to no acne; figures
// in docs/phong-and-shadows.md.
fn receiver_shift(cg: f32, texel: f32) -> vec2<f32> {
    let c = clamp(abs(cg), 0.0, 1.0);
    let sn = sqrt(1.0 - c * c);
    // 1/cos θ up to 77° (tan θ = 4.4), where the offset reaches its cap: one division.
    let ic = 1.0 / max(c, 0.2236);
    return texel * vec2<f32>(clamp((sn - c) * ic * ic, 0.0, 2.0), min(sn * ic, 1.0) + 0.1);
}

// The light arriving at a point from its surroundings, as 2-band SH of radiance per colour
// channel (towards the direction the light travels): the light volume's, which weights the
// far shares and lights the glossy lobe's occluded directions; zero where there is none.
struct Surroundings {
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
}

// The radiance arriving from direction w (unit, towards where it comes from).
fn surroundings_from(a: Surroundings, w: vec3<f32>) -> vec3<f32> {
    let y = vec4<f32>(0.2820948, -0.4886025 * w.y, -0.4886025 * w.z, -0.4886025 * w.x);
    return max(vec3<f32>(dot(a.r, y), dot(a.g, y), dot(a.b, y)), vec3<f32>(0.0));
}

// What sky_terms finds at a point: the fraction of the sky's irradiance that reaches it around
// n (front) and, on thin translucent surfaces, around −n (back; 1 elsewhere), per channel; the
// shares of the hemispheres around n and −n from which the light volume's light can arrive
// (far, far_back); and the fraction of the sky's light in the glossy lobe that reaches it
// (spec).
struct SkyTerms {
    front: vec3<f32>,
    back: vec3<f32>,
    far: f32,
    far_back: f32,
    spec: vec3<f32>,
}

// seen / lit per channel; 1 where nothing lit.
fn lit_share(seen: vec3<f32>, lit: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(1.0), seen / max(lit, vec3<f32>(1e-8)), lit > vec3<f32>(0.0));
}

// The sky terms of s, in one pass over the directions (they share each direction's
// projection; on lavapipe a second pass for the back doubled the leaves' cost).
//
// front: Σ V_k E_k(n) / Σ E_k(n) per channel, E_k(n) = E⊥_k ⟨n, ω_k⟩₊ the cell as a small
// source, V_k one bilinear depth comparison (2 × 2 texels) with the point moved off the surface
// along ng by `receiver_shift`; 1 without occlusion. Directions whose cell does not light n are
// not sampled for it. Per channel, not by luminance: where a building hides the pale horizon and
// leaves the blue zenith, the light that reaches the point is bluer than the whole sky's
// (a luminance ratio on the whole sky's irradiance turned a courtyard's shade grey).
//
// back: the same around −n, the point moved along −ng, on thin translucent surfaces (foliage:
// the sky behind a leaf lights it through its back, as the path tracer's thin BSDF); 1 on
// opaque ones, which skip the back hemisphere.
//
// far: the share of the hemisphere around n (cosine-weighted, each direction by its cell's
// solid angle, cell.w) in which the first surface seen from p along ω_k lies further than
// `radius`. Indirect light arrives only from surfaces: where p sees the sky (V_k = 1) it gets
// the sky's light, which front covers, and no bounce; where the first surface lies within
// `radius` it is nearer than the volume's cells resolve (the volume holds light from beyond
// it). The volume's blurred 2-band light stands for the rest; 1 without directions.
// far_back: the same around −n on thin translucent surfaces (the light arriving on their back
// passes through); far elsewhere.
//
// spec: the glossy lobe's light over the open sky's, each direction weighted by the lobe,
// g_k = exp(κ(⟨r,ω_k⟩ − 1)) with `lobe` = (r, κ) (env.wgsl `env_occlusion_lobe`):
// Σ g_k (V_k E_k(n) + (1 − V_k) L_k(ω_k) ΔΩ_k ⟨n,ω_k⟩) / Σ g_k E_k(n), where a direction the
// scene hides reflects what `around` sends from it (L_k) instead of the sky. Unoccluded, the
// shaded inside of the bush's canopy reflected the open sky; unlit (L = 0), a chrome ball
// reflected a black ground. κ is capped at N/8 for N directions (below). The weights are kept
// relative to the largest so far (a sharp lobe would underflow far from its nearest
// direction): one exponential per direction.
//
// The far shares weight each direction also by the luminance of `around`'s light from it: where
// the far directions are the bright ones, the volume's light is kept in proportion.
fn sky_terms(s: Surface, radius: f32, lobe: vec4<f32>, around: Surroundings) -> SkyTerms {
    let count = u32(sky.x);
    let texel = sky.y;
    let range = 3.0 * sky.z;
    let two_sided = s.transmission > 0.0;
    var lit = vec3<f32>(0.0);
    var seen = vec3<f32>(0.0);
    var lit_back = vec3<f32>(0.0);
    var seen_back = vec3<f32>(0.0);
    // The hemispheres' weights and their far shares: front in x, back in y.
    var area = vec2<f32>(0.0);
    var far = vec2<f32>(0.0);
    var lit_spec = vec3<f32>(0.0);
    var seen_spec = vec3<f32>(0.0);
    var peak = -3.0e38;
    // No sharper than the directions resolve: a lobe of angular spread 1/√κ about their
    // spacing, √(4π/N), so that a mirror's reflection blends its nearest directions instead
    // of breaking into the patches each one sees.
    let kappa = min(lobe.w, f32(count) / 8.0);
    for (var k = 0u; k < count; k++) {
        let d = sky_dirs[k];
        let dir = -d.rows[2].xyz * range;
        let c = dot(s.n, dir);
        let front = c > 0.0;
        if !(front || (two_sided && c < 0.0)) {
            continue;
        }
        let w = d.cell.xyz * abs(c);
        if all(w <= vec3<f32>(0.0)) && radius <= 0.0 {
            continue;
        }
        let ng = select(-s.ng, s.ng, front);
        let shift = receiver_shift(dot(ng, dir), texel);
        let q = vec4<f32>(s.p + ng * shift.x, 1.0);
        let clip = vec3<f32>(dot(d.rows[0], q), dot(d.rows[1], q), dot(d.rows[2], q));
        let uv = vec2<f32>(clip.x * 0.5 + 0.5, 0.5 - clip.y * 0.5);
        // Nothing between p and the sky (in the map's 0..1 depth over 3 radii).
        let v = textureSampleCompareLevel(sky_depth, sky_cmp, uv, i32(k), clip.z - shift.y / range);
        let wl = max(w, vec3<f32>(0.0));
        if front {
            lit += wl;
            seen += wl * v;
            // The lobe's weight over the largest before (x < 1), or this one the largest
            // (the sums scaled down by x): selects, no branch.
            let e = kappa * (dot(lobe.xyz, dir) - 1.0);
            let x = exp(-abs(e - peak));
            let top = e > peak;
            let g = wl * select(x, 1.0, top);
            lit_spec = select(lit_spec, lit_spec * x, top) + g;
            let fill = surroundings_from(around, dir) * (d.cell.w * c);
            seen_spec = select(seen_spec, seen_spec * x, top) + select(x, 1.0, top) * (wl * v + fill * (1.0 - v));
            peak = max(peak, e);
        } else {
            lit_back += wl;
            seen_back += wl * v;
        }
        if radius > 0.0 {
            // Nothing nearer to the sky than `radius` from p: where this is 0 a surface lies
            // beyond the radius (comparisons only: depth textures cannot be read as values on
            // every backend).
            let within = textureSampleCompareLevel(sky_depth, sky_cmp, uv, i32(k), clip.z - radius / range);
            let side = select(vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), front);
            let lk = dot(surroundings_from(around, dir), vec3<f32>(0.2126, 0.7152, 0.0722));
            let wo = d.cell.w * abs(c) * lk;
            area += side * wo;
            far += side * (wo * (1.0 - within));
        }
    }
    var t: SkyTerms;
    t.front = lit_share(seen, lit);
    t.back = lit_share(seen_back, lit_back);
    t.spec = lit_share(seen_spec, lit_spec);
    let share = select(vec2<f32>(1.0), far / max(area, vec2<f32>(1e-8)), area > vec2<f32>(0.0));
    t.far = share.x;
    t.far_back = select(share.x, share.y, two_sided);
    return t;
}

// The fraction of the sky's irradiance at n that reaches p, per channel (`sky_terms`' front).
fn sky_visibility(s: Surface) -> vec3<f32> {
    let none = vec4<f32>(0.0);
    return sky_terms(s, 0.0, none, Surroundings(none, none, none)).front;
}

// The sky's diffuse light leaving s towards the viewer, occluded by `t`: the light arriving
// around n reflected, 1 − transmission of it on thin translucent surfaces, and transmission of
// the light arriving around −n (as `diffuse_coef` and the lights' thin transmission).
fn sky_light(s: Surface, t: SkyTerms) -> vec3<f32> {
    let front = s.diffuse * sky_irradiance(s.n) * t.front;
    if s.transmission <= 0.0 {
        return front;
    }
    let back = s.diffuse * sky_irradiance(-s.n) * t.back;
    return (1.0 - s.transmission) * front + s.transmission * back;
}
