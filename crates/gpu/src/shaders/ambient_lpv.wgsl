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
    let m = -n;
    let y = vec4<f32>(0.2820948, 0.4886025 * m.y, 0.4886025 * m.z, 0.4886025 * m.x);
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
        let m = -n;
        let y = vec4<f32>(0.2820948, 0.4886025 * m.y, 0.4886025 * m.z, 0.4886025 * m.x);
        return max(vec3<f32>(dot(v.r, y), dot(v.g, y), dot(v.b, y)), vec3<f32>(0.0));
    }
    let last = lpv_u.cascades - 1u;
    let border = 2.0 + lpv_u.damping;
    var c = last;
    var w = 1.0;
    for (var k = 0u; k < last; k++) {
        let g = lpv_u.grids[k];
        let f = (p - g.xyz) / g.w;
        let d = min(min(f.x, min(f.y, f.z)), lpv_u.size - max(f.x, max(f.y, f.z)));
        if d > border {
            c = k;
            w = min((d - border) / 2.0, 1.0);
            break;
        }
    }
    let e = lpv_cascade_irradiance(p, n, c);
    if w < 1.0 {
        return w * e + (1.0 - w) * lpv_cascade_irradiance(p, n, c + 1u);
    }
    return e;
}

fn source_vertex(p: vec3<f32>, vi: u32, ii: u32) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// Only the volume's indirect light in the indirect-only view.
fn source_radiance(s: Surface, in: VertexOut, nv: vec3<f32>) -> vec3<f32> {
    // Thin foliage (diffuse transmission t): 1 − t of the light arriving on the front is
    // reflected, t of the light arriving on the back leaves through the front.
    var e = lpv_irradiance(s.p, s.n);
    if s.transmission > 0.0 {
        e = (1.0 - s.transmission) * e + s.transmission * lpv_irradiance(s.p, -s.n);
    }
    let indirect = s.diffuse / PI * e;
    if lpv_u.indirect_only == 1u {
        return indirect;
    }
    return indirect + sky_ambient(s) * sky_visibility(s) + emission(in);
}
