// Ambient source `lpv` (Kaplanyan & Dachsbacher 2010; the WPI 2011 report): the volume's
// indirect light on the diffuse surface (through thin foliage from both sides), plus the sky's
// SH irradiance, occluded through the shadow-mapped sky directions (sky_occlusion.wgsl, before
// this), and emission. Compiled after raster.wgsl.

@group(2) @binding(3) var<uniform> lpv_u: LpvAmbientUniforms;
// Light propagation volume (r, g, b intensity SH per cell), trilinear.
@group(2) @binding(4) var lpv_r: texture_3d<f32>;
@group(2) @binding(5) var lpv_g: texture_3d<f32>;
@group(2) @binding(6) var lpv_b: texture_3d<f32>;
@group(2) @binding(7) var lpv_sampler: sampler;

// The 2-band real SH basis towards d, in the volume's order (Y00, Y1−1, Y10, Y11: 1, y, z, x).
fn sh2(d: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(0.2820948, 0.4886025 * d.y, 0.4886025 * d.z, 0.4886025 * d.x);
}

// The LPV's three colour SH read trilinearly at q in cascade c (the cascades are stacked along
// z; reads clamp to the cascade's cell centres, as lightlab_core::lpv::Volume::sample).
struct LpvSample {
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
}

fn lpv_sample(q: vec3<f32>, c: u32) -> LpvSample {
    let g = lpv_u.grids[c];
    let n = lpv_u.size;
    let f = clamp((q - g.xyz) / g.w, vec3<f32>(0.5), vec3<f32>(n - 0.5));
    let uvw = (f + vec3<f32>(0.0, 0.0, f32(c) * n)) / vec3<f32>(n, n, n * f32(lpv_u.cascades));
    return LpvSample(
        textureSampleLevel(lpv_r, lpv_sampler, uvw, 0.0),
        textureSampleLevel(lpv_g, lpv_sampler, uvw, 0.0),
        textureSampleLevel(lpv_b, lpv_sampler, uvw, 0.0),
    );
}

// Kaplanyan's irradiance on normal n from cascade c read at q (lightlab_core::lpv::irradiance_of).
fn lpv_read(q: vec3<f32>, n: vec3<f32>, c: u32) -> vec3<f32> {
    let s = lpv_u.grids[c].w;
    let v = lpv_sample(q, c);
    let y = sh2(-n);
    let k = vec4<f32>(PI, 2.0 * PI / 3.0, 2.0 * PI / 3.0, 2.0 * PI / 3.0) * y / (s * s);
    return max(vec3<f32>(dot(v.r, k), dot(v.g, k), dot(v.b, k)), vec3<f32>(0.0));
}

// Cascade c's damped irradiance (lightlab_core::lpv::Volume::irradiance_damped): read half a
// cell along n and, with damping, keep the smaller of that and the read lpv_damping cells out.
fn lpv_cascade_irradiance(p: vec3<f32>, n: vec3<f32>, c: u32) -> vec3<f32> {
    let s = lpv_u.grids[c].w;
    let q = p + 0.5 * s * n;
    let e = lpv_read(q, n, c);
    if lpv_u.damping > 0.0 {
        return min(e, lpv_read(q + lpv_u.damping * s * n, n, c));
    }
    return e;
}

// Indirect irradiance E from the LPV at a surface. Kaplanyan: the finest cascade holding p
// (2 + damping) cells inside, blended over 2 cells towards its edge with the next coarser
// (lightlab_core::lpv::cascade_weight). WPI (lpv-faithful): the SH evaluated at −n just off
// the surface, as the report's compositor.
fn lpv_irradiance(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    if lpv_u.mode == 2u {
        let q = p + 0.001 * lpv_u.grids[0].w * lpv_u.size * n;
        let v = lpv_sample(q, 0u);
        let y = sh2(-n);
        return max(vec3<f32>(dot(v.r, y), dot(v.g, y), dot(v.b, y)), vec3<f32>(0.0));
    }
    let cw = lpv_cascade_of(p);
    let c = u32(cw.x);
    let e = lpv_cascade_irradiance(p, n, c);
    if cw.y < 1.0 {
        return cw.y * e + (1.0 - cw.y) * lpv_cascade_irradiance(p, n, c + 1u);
    }
    return e;
}

// The finest cascade holding p (2 + damping) cells inside (x) and its weight against the next
// coarser (y).
fn lpv_cascade_of(p: vec3<f32>) -> vec2<f32> {
    let last = lpv_u.cascades - 1u;
    let border = 2.0 + lpv_u.damping;
    for (var k = 0u; k < last; k++) {
        let g = lpv_u.grids[k];
        let f = (p - g.xyz) / g.w;
        let d = min(min(f.x, min(f.y, f.z)), lpv_u.size - max(f.x, max(f.y, f.z)));
        if d > border {
            return vec2<f32>(f32(k), min((d - border) / 2.0, 1.0));
        }
    }
    return vec2<f32>(f32(last), 1.0);
}

// The volume's light where its lookup reads for a surface at p facing n, as radiance (the
// intensity SH over the cell's face area): what weights the near-occlusion shares and lights
// the glossy lobe's occluded directions (sky_terms).
fn lpv_surroundings(p: vec3<f32>, n: vec3<f32>) -> Surroundings {
    let c = u32(lpv_cascade_of(p).x);
    let s = lpv_u.grids[c].w;
    let v = lpv_sample(p + 0.5 * s * n, c);
    let k = 1.0 / (s * s);
    return Surroundings(v.r * k, v.g * k, v.b * k);
}

// ---- the near field, gathered from the last light's RSM ------------------------------------
// (Dachsbacher & Stamminger 2005's RSM gathering, within the lookup's reach only: the light of
// the surfaces nearer than the volume resolves, which near occlusion takes out of the volume's
// light.)

@group(2) @binding(13) var rsm_flux: texture_2d<f32>;
@group(2) @binding(14) var rsm_normal: texture_2d<f32>;
// The finest cascade's geometry volume (blocking SH at 2i, per cell corner).
@group(2) @binding(15) var<storage, read> near_gv: array<vec4<f32>>;

// Transmittance from p to x along l through the finest cascade's geometry volume: the nearest
// node at each point a whole number of cells from p and at least a cell from both ends,
// 1 − max(B(l), B(−l)) each (blockers from both sides, as the propagation). Nearer the ends
// the nearest nodes hold the ends' own surfaces (a wall's node blocked what the ground beside
// it sent).
fn near_transmittance(p: vec3<f32>, x: vec3<f32>, l: vec3<f32>) -> f32 {
    let g = lpv_u.grids[lpv_u.cascades - 1u];
    let gn = i32(lpv_u.size) + 1;
    let m = i32(floor(length(x - p) / g.w)) - 1;
    let yf = sh2(l);
    let yb = sh2(-l);
    var t = 1.0;
    for (var j = 1; j <= m; j++) {
        let k = vec3<i32>(round((p + l * (f32(j) * g.w) - g.xyz) / g.w));
        if any(k < vec3<i32>(0)) || any(k >= vec3<i32>(gn)) {
            continue;
        }
        let b = near_gv[2 * ((k.z * gn + k.y) * gn + k.x)];
        t *= 1.0 - clamp(max(dot(b, yf), dot(b, yb)), 0.0, 1.0);
    }
    return t;
}

// The near field's irradiance around n (front) and, when asked, around −n (back).
struct NearField {
    front: vec3<f32>,
    back: vec3<f32>,
}

// The irradiance on n (and on −n when `two_sided`) at p from the surfaces the RSM's light
// lights within `radius` of p:
// `near_samples` texels on a spiral over the disc of that radius around p's texel, at radii
// spaced evenly (density ∝ 1/r, which the 1/d² fall-off favours), each standing for its share
// of the disc's texels (2π·r·R/N). The spiral turns and shifts over each 2 × 2 pixels (Keller &
// Heidrich's interleaved sampling), so that supersampling averages four patterns: one pattern
// for all pixels drew bands where its few far samples met thin lit surfaces (the atrium's
// columns). A texel is a Lambertian patch of flux Φ (its normal turned to the light; w:
// diffuse transmission t, so 1 − t of Φ leaves on the lit side and t through the back) and
// surface area A = A⊥/|n_p·l_light|; its irradiance at distance d, Φ·cos_p·cos / (π d² + A),
// is the disc formula, bounded where d is small. Texels within a texel's side of p (its own
// surface) and beyond the radius are skipped.
fn rsm_near_field(p: vec3<f32>, n: vec3<f32>, radius: f32, pixel: vec2<f32>, two_sided: bool) -> NearField {
    var e = NearField(vec3<f32>(0.0), vec3<f32>(0.0));
    let count = lpv_u.near_samples;
    if count == 0u || radius <= 0.0 {
        return e;
    }
    let side = lpv_u.near.w;
    let dims = vec2<i32>(textureDimensions(rsm_position, 0));
    let c = lpv_u.rsm_view_proj * vec4<f32>(p, 1.0);
    let uv = vec2<f32>(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5) * vec2<f32>(dims);
    let rt = radius / side;
    let cell = vec2<u32>(pixel) % vec2<u32>(2u);
    let pattern = f32(cell.x + 2u * cell.y);
    let shift = (pattern + 0.5) / 4.0;
    for (var i = 0u; i < count; i++) {
        let r = rt * (f32(i) + shift) / f32(count);
        let a = (f32(i) + pattern * 0.25) * 2.39996323;
        let share = 2.0 * PI * r * rt / f32(count);
        let t = vec2<i32>(floor(uv + r * vec2<f32>(cos(a), sin(a))));
        if any(t < vec2<i32>(0)) || any(t >= dims) {
            continue;
        }
        let q = textureLoad(rsm_position, t, 0);
        let d = q.xyz - p;
        let d2 = dot(d, d);
        if q.w <= 0.0 || d2 > radius * radius || d2 < side * side {
            continue;
        }
        let l = d * inverseSqrt(d2);
        let cos_r = dot(n, l);
        if cos_r <= 0.0 && !two_sided {
            continue;
        }
        let np = textureLoad(rsm_normal, t, 0);
        let cp = dot(np.xyz, -l);
        let emit = (1.0 - np.w) * max(cp, 0.0) + np.w * max(-cp, 0.0);
        let area = q.w * share / max(abs(dot(np.xyz, lpv_u.near.xyz)), 0.25);
        let phi = textureLoad(rsm_flux, t, 0).rgb * share;
        let g = phi * (emit * abs(cos_r) / (PI * d2 + area)) * near_transmittance(p, q.xyz, l);
        e.front += select(vec3<f32>(0.0), g, cos_r > 0.0);
        e.back += select(g, vec3<f32>(0.0), cos_r > 0.0);
    }
    return e;
}

// ---- lpv-faithful's composite (the WPI report's App. B, defCompositor) ----------------------

// The RSM's world positions (w: texel area, 0 = empty) of the composite's light: its shadow map.
@group(2) @binding(11) var rsm_position: texture_2d<f32>;

// One tap of the report's depth-difference shadow: max(0, z − z_occluder − bias) in the RSM's
// depth (0..1 over the light's orthographic range); 0 off the map or where it saw nothing.
fn wpi_depth_gap(uv: vec2<f32>, z: f32) -> f32 {
    if any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0)) {
        return 0.0;
    }
    let q = textureLoad(rsm_position, vec2<i32>(uv * vec2<f32>(textureDimensions(rsm_position, 0))), 0);
    if q.w <= 0.0 {
        return 0.0;
    }
    let zo = (lpv_u.rsm_view_proj * vec4<f32>(q.xyz, 1.0)).z;
    return max(0.0, z - zo - lpv_u.sun_e.w);
}

// The report's soft shadow: the depth gaps of 1 + 16 taps within 1/256 of the map summed (not
// averaged), a summed gap of 1 being full shadow; 1 = lit. Its taps come from a random texture,
// here a fixed Vogel spiral over the disc of radius 1/256.
fn wpi_shadow(p: vec3<f32>) -> f32 {
    let c = lpv_u.rsm_view_proj * vec4<f32>(p, 1.0);
    let uv = vec2<f32>(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5);
    var gap = wpi_depth_gap(uv, c.z);
    for (var i = 0u; i < 16u; i++) {
        let r = sqrt((f32(i) + 0.5) / 16.0) / 256.0;
        let a = f32(i) * 2.39996323;
        gap += wpi_depth_gap(uv + r * vec2<f32>(cos(a), sin(a)), c.z);
    }
    return 1.0 - clamp(gap, 0.0, 1.0);
}

// The volume's SH (r, g, b) evaluated towards d.
fn lpv_toward(v: LpvSample, d: vec3<f32>) -> vec3<f32> {
    let y = sh2(d);
    return vec3<f32>(dot(v.r, y), dot(v.g, y), dot(v.b, y));
}

// The report's shading, in its units (1 = the sun's full irradiance; its volume held albedo,
// ours albedo × the sun's irradiance, so GI and TI are divided by it), then back to radiance:
//   GI = clamp(SH(p + 0.001·n)·Y(−n)), TI = backScatter · clamp(SH·Y(L)) · shadow,
//   backScatter = 0.05 + min(2, max(n·L, 0) / max(0.1, 1 − t)),  L the sun's travel,
//   illum = diffuse + (1 − diffuse)·GI, then illum + (1 − illum)·TI (screen blends),
//   diffuse = clamp(n·l) · shadow,
//   colour = albedo·illum·E/π + 0.2·sky(n) + spec·shadow·E,
//   spec = (p + 8)/(8π)·(n·h)^p·(n·l)  (the report's 0.8 is Eq 2.3's 8, its erratum).
// Deviations: the specular colour is the material's F0 (the report's is white); the sky is the
// environment's sharpest level along n (the report's angular map), occluded as the other
// techniques' sky (the report's scene was open; a closed room would glow), and `--ambient none`
// drops it.
fn wpi_composite(s: Surface) -> vec3<f32> {
    let l = lpv_u.sun_dir.xyz;
    let e = lpv_u.sun_e.xyz;
    let inv_e = select(vec3<f32>(0.0), vec3<f32>(1.0) / e, e > vec3<f32>(0.0));
    let shadow = wpi_shadow(s.p);
    let q = s.p + 0.001 * lpv_u.grids[0].w * lpv_u.size * s.n;
    let v = lpv_sample(q, 0u);
    let gi = clamp(lpv_toward(v, -s.n) * inv_e, vec3<f32>(0.0), vec3<f32>(1.0));
    let back = 0.05 + min(2.0, max(dot(s.n, l), 0.0) / max(0.1, 1.0 - s.transmission));
    let ti = back * clamp(lpv_toward(v, l) * inv_e, vec3<f32>(0.0), vec3<f32>(1.0)) * shadow;
    let diffuse = clamp(dot(s.n, -l), 0.0, 1.0) * shadow;
    var illum = vec3<f32>(diffuse) + (1.0 - diffuse) * gi;
    illum = illum + (vec3<f32>(1.0) - illum) * ti;
    let view = safe_normalize(frame.camera_pos - s.p, s.n);
    let h = safe_normalize(view - l, s.n);
    let p = phong_exponent(s.roughness);
    let spec = (p + 8.0) / (8.0 * PI) * pow(clamp(dot(s.n, h), 0.0, 1.0), p) * clamp(dot(s.n, -l), 0.0, 1.0);
    let has_sky = any(frame.ambient_sh[0].xyz != vec3<f32>(0.0));
    let sky = select(vec3<f32>(0.0), 0.2 * env_lobe(0u, 0u, 0.0, s.n, 0.0), has_sky) * sky_visibility(s);
    return s.diffuse * e / PI * illum + sky + s.f0 * spec * shadow * e;
}

fn source_vertex(p: vec3<f32>, vi: u32, ii: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// A thin translucent surface (foliage; diffuse transmission t): 1 − t of the light arriving
// on the front is reflected, t of the light arriving on the back leaves through the front.
// Within a canopy the volume's 2-band light holds the neighbouring leaves' light, finer than
// its cells, the geometry volume's or the sky maps resolve, so near occlusion cannot take it
// out, and the near field gathered on top of it counted it twice (bush 1.15× `direct`). Here
// the near field takes the place of its light's share σ of the volume's light
// (`near_share`, `Lpv::near_field_share`: the sun's share of what the volume's directional
// sources give an open upward surface), on both sides, and the volume keeps 1 − σ, the
// sky's bounce: a bright sky lights the canopy's inside mostly by its bounce, which the
// sun's RSM does not carry. The glossy lobe's hidden directions reflect the same mix, the
// near field as its irradiance over π from every direction (docs/lpv.md, *What limits bush*).
fn leaf_radiance(s: Surface, in: VertexOut, glossy: vec3<f32>) -> vec3<f32> {
    let radius = lpv_u.occlusion_radius;
    let near = rsm_near_field(s.p, s.n, radius, in.clip.xy, true);
    let front = near.front;
    let back = near.back;
    let kv = 1.0 - select(0.0, lpv_u.near_share, lpv_u.near_samples > 0u);
    // The near field as uniform radiance E/π: its 2-band SH is (E/π)/Y00 in the first band.
    let l = front / (PI * 0.2820948);
    let v = lpv_surroundings(s.p, s.n);
    let around = Surroundings(
        vec4<f32>(l.r, 0.0, 0.0, 0.0) + kv * v.r,
        vec4<f32>(l.g, 0.0, 0.0, 0.0) + kv * v.g,
        vec4<f32>(l.b, 0.0, 0.0, 0.0) + kv * v.b,
    );
    let sky_t = sky_terms(s, radius, env_occlusion_lobe(s), around);
    let volume = (1.0 - s.transmission) * lpv_irradiance(s.p, s.n) * sky_t.far
        + s.transmission * lpv_irradiance(s.p, -s.n) * sky_t.far_back;
    let e = (1.0 - s.transmission) * front + s.transmission * back + kv * volume;
    let indirect = s.diffuse / PI * e;
    if lpv_u.indirect_only == 1u {
        return indirect;
    }
    return indirect + sky_light(s, sky_t) + glossy * sky_t.spec + emission(in);
}

// Only the volume's indirect light in the indirect-only view.
fn source_radiance(s: Surface, in: VertexOut, nv: vec3<f32>, glossy: vec3<f32>) -> vec3<f32> {
    if lpv_u.mode == 2u && lpv_u.sun_dir.w > 0.5 && lpv_u.indirect_only == 0u {
        return wpi_composite(s) + glossy + emission(in);
    }
    if s.transmission > 0.0 {
        return leaf_radiance(s, in, glossy);
    }
    let sky_t = sky_terms(s, lpv_u.occlusion_radius, env_occlusion_lobe(s), lpv_surroundings(s.p, s.n));
    let e = lpv_irradiance(s.p, s.n) * sky_t.far + rsm_near_field(s.p, s.n, lpv_u.occlusion_radius, in.clip.xy, false).front;
    let indirect = s.diffuse / PI * e;
    if lpv_u.indirect_only == 1u {
        return indirect;
    }
    return indirect + sky_light(s, sky_t) + glossy * sky_t.spec + emission(in);
}
