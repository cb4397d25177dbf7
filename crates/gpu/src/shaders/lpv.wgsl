// Light propagation volumes (issue 7): reflective shadow maps, VPL and blocker injection,
// propagation, and the store into three RGBA16F 3D textures (one per colour) that the
// renderer's ambient pass samples. Compiled after common.wgsl and material.wgsl.
//
// The CPU reference of every pass is lightlab_core::lpv; the SH order is lightlab's
// (Y00, Y1-1 ∝ y, Y10 ∝ z, Y11 ∝ x), all signs positive. A cell holds radiant intensity I(ω).

const Y00: f32 = 0.2820948;
const C1: f32 = 0.4886025;
const LOBE0: f32 = 0.8862269; // √π/2
const LOBE1: f32 = 1.0233267; // √(π/3)
const SOLID_FAR: f32 = 0.4006697;
const SOLID_SIDE: f32 = 0.42343135;
const BLOCKER_SCALE: f32 = 1.3333333;
const WPI_FALLOFF: f32 = 0.65;
const WPI_TRANSMIT: f32 = 0.75;

struct LpvUniforms {
    origin: vec3<f32>,
    cell: f32,
    // Cells per axis of the light volume; the geometry volume has n + 1.
    n: u32,
    // 1: attenuate by the geometry volume in this dispatch.
    use_gv: u32,
    // Fixed-point scales of the atomic accumulators.
    scale: f32,
    gv_scale: f32,
    rsm_size: u32,
    // WPI gather injection: samples per voxel.
    wpi_samples: u32,
    // 1: store the last propagated volume (WPI) instead of the accumulation.
    store_last: u32,
    // 1: the injection also fills the geometry volume.
    occlusion: u32,
    // First z texel of this cascade in the stacked 3D textures.
    layer: u32,
    // Side faces' re-emission: 0 a cosine lobe around the face normal (Kaplanyan), 1 around
    // the direction the light travelled (lightlab_core::lpv::Reemit).
    reemit: u32,
    // 1: light the geometry volume blocks is reflected × its albedo (multiple bounces).
    bounces: u32,
    // reemit = 1: the side faces' lobe's band-1 weight relative to a delta's (⅔: a cosine
    // lobe; lightlab_core::lpv::reemission_lobe).
    lobe: f32,
    // Wind sway, as FrameUniforms.
    wind_a: vec4<f32>,
    wind_b: vec4<f32>,
}

// One light of the reflective shadow maps.
struct RsmLight {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // 0 directional (orthographic), 1 spot, 2 emissive area (perspective from its centre),
    // 3 the camera (perspective; no light, its surfels only block), 4 a cube face of a
    // goniometric light (perspective, × its candela table).
    kind: u32,
    // The direction the light travels (directional) or the view axis.
    axis: vec3<f32>,
    // Orthographic: texel area [m²]; perspective: pixel area on the image plane at distance 1.
    texel: f32,
    // Colour × intensity: irradiance (directional), intensity (spot), radiance × area (area).
    color: vec3<f32>,
    cos_inner: f32,
    cos_outer: f32,
    // Kind 4 (a cube face of a goniometric light): its candela table's layer, C0 axis, nadir.
    profile: u32,
    // 1: a cell of the sky, whose surfels light but do not block.
    sky: u32,
    // The side of the RSM this view renders (from the top-left corner).
    size: u32,
    c0: vec3<f32>,
    pad3: f32,
    nadir: vec3<f32>,
    pad4: f32,
}

@group(0) @binding(0) var<uniform> lpv: LpvUniforms;
@group(0) @binding(1) var<uniform> light: RsmLight;

// ---- reflective shadow map ---------------------------------------------------------------------

struct RsmVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv0: vec2<f32>,
    @location(3) uv1: vec2<f32>,
    @location(4) color: vec4<f32>,
}

@vertex
fn rsm_vs(v: VertexIn) -> RsmVertex {
    var o: RsmVertex;
    let p = sway(v.position, material.sway, lpv.wind_a, lpv.wind_b);
    o.clip = light.view_proj * vec4<f32>(p, 1.0);
    o.world = p;
    o.normal = v.normal;
    o.uv0 = v.uv0;
    o.uv1 = v.uv1;
    o.color = v.color;
    return o;
}

struct RsmTexel {
    // Reflected flux Φ [W] (diffuse albedo × the light's flux through the texel); w = the
    // light's flux per unit colour and area of the texel (Φ = albedo × colour × w × A), so
    // that the injection can recover the albedo. The camera's view (kind 3): albedo, w = 1.
    @location(0) flux: vec4<f32>,
    // Unit normal turned towards the light; w = diffuse transmission (thin foliage).
    @location(1) normal: vec4<f32>,
    // World position; w = the texel's area perpendicular to the light (0 = empty).
    @location(2) position: vec4<f32>,
}

@fragment
fn rsm_fs(in: RsmVertex) -> RsmTexel {
    let base = material_base(in.uv0, in.uv1, in.color);
    if material.alpha_cutoff >= 0.0 && base.a < material.alpha_cutoff {
        discard;
    }
    var to_light = -light.axis;
    // The light's flux through the texel per unit colour (× light.color).
    var per_colour = light.texel;
    var area = light.texel;
    if light.kind != 0u {
        let d = in.world - light.eye;
        let dist = max(length(d), 1e-6);
        let w = d / dist;
        let c = max(dot(w, light.axis), 1e-4);
        // Solid angle of the texel: pixel area × cos³θ on a unit image plane.
        let solid = light.texel * c * c * c;
        area = solid * dist * dist;
        to_light = -w;
        if light.kind == 1u {
            let s = clamp((c - light.cos_outer) / max(light.cos_inner - light.cos_outer, 1e-4), 0.0, 1.0);
            per_colour = (s * s) * solid;
        } else if light.kind == 4u {
            per_colour = profile_lookup(light.profile, light.nadir, light.c0, w) * solid;
        } else {
            // A Lambertian emitter: I(θ) = L·A·cosθ.
            per_colour = c * solid;
        }
    }
    var n = safe_normalize(in.normal, to_light);
    if dot(n, to_light) < 0.0 {
        n = -n;
    }
    let albedo = base.rgb * (1.0 - material.metallic);
    var o: RsmTexel;
    if light.kind == 3u {
        o.flux = vec4<f32>(albedo, 1.0);
    } else {
        o.flux = vec4<f32>(albedo * light.color * per_colour, per_colour / max(area, 1e-30));
    }
    o.normal = vec4<f32>(n, material_transmission(in.uv0, in.uv1));
    o.position = vec4<f32>(in.world, area);
    return o;
}

// ---- injection ---------------------------------------------------------------------------------

@group(0) @binding(2) var rsm_flux: texture_2d<f32>;
@group(0) @binding(3) var rsm_normal: texture_2d<f32>;
@group(0) @binding(4) var rsm_position: texture_2d<f32>;
@group(0) @binding(5) var<storage, read_write> lpv_atomic: array<atomic<i32>>;
@group(0) @binding(6) var<storage, read_write> gv_atomic: array<atomic<i32>>;
@group(0) @binding(7) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> dst: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> gv: array<vec4<f32>>;
@group(0) @binding(11) var out_r: texture_storage_3d<rgba16float, write>;
@group(0) @binding(12) var out_g: texture_storage_3d<rgba16float, write>;
@group(0) @binding(13) var out_b: texture_storage_3d<rgba16float, write>;

fn sh_basis(d: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(Y00, C1 * d.y, C1 * d.z, C1 * d.x);
}

fn cosine_lobe(n: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(LOBE0, LOBE1 * n.y, LOBE1 * n.z, LOBE1 * n.x);
}

// A unit-flux lobe around `axis` whose band-1 weight is k times a delta's
// (lightlab_core::lpv::reemission_lobe).
fn reemission_lobe(axis: vec3<f32>, k: f32) -> vec4<f32> {
    return vec4<f32>(Y00, k * C1 * axis.y, k * C1 * axis.z, k * C1 * axis.x);
}

fn cell_index(c: vec3<i32>, n: i32) -> i32 {
    return (c.z * n + c.y) * n + c.x;
}

fn inside(c: vec3<i32>, n: i32) -> bool {
    return all(c >= vec3<i32>(0)) && all(c < vec3<i32>(n));
}

fn add_fixed(base: i32, v: vec4<f32>, scale: f32) {
    let q = vec4<i32>(round(v * scale));
    atomicAdd(&lpv_atomic[base + 0], q.x);
    atomicAdd(&lpv_atomic[base + 1], q.y);
    atomicAdd(&lpv_atomic[base + 2], q.z);
    atomicAdd(&lpv_atomic[base + 3], q.w);
}

// Scatter one VPL into the cell holding it shifted half a cell along its normal.
fn inject_vpl(p: vec3<f32>, n: vec3<f32>, flux: vec3<f32>) {
    let nn = i32(lpv.n);
    let c = vec3<i32>(floor((p + 0.5 * lpv.cell * n - lpv.origin) / lpv.cell));
    if !inside(c, nn) || all(flux <= vec3<f32>(0.0)) {
        return;
    }
    let lobe = cosine_lobe(n) / PI;
    let base = cell_index(c, nn) * 12;
    add_fixed(base, lobe * flux.r, lpv.scale);
    add_fixed(base + 4, lobe * flux.g, lpv.scale);
    add_fixed(base + 8, lobe * flux.b, lpv.scale);
}

// Kaplanyan: one invocation per RSM texel; the reflected flux on the lit side, and for thin
// translucent surfaces the transmitted part on the back side; with occlusion, the texel is also
// a blocker of the geometry volume.
@compute @workgroup_size(8, 8, 1)
fn inject_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= light.size || id.y >= light.size {
        return;
    }
    let t = vec2<i32>(id.xy);
    let pos = textureLoad(rsm_position, t, 0);
    if pos.w <= 0.0 {
        return;
    }
    let nrm = textureLoad(rsm_normal, t, 0);
    let n = safe_normalize(nrm.xyz, vec3<f32>(0.0, 1.0, 0.0));
    let f = textureLoad(rsm_flux, t, 0);
    if light.kind == 3u {
        // The camera's surfels: blockers of their own half of the geometry atomics.
        if lpv.occlusion == 1u {
            inject_blocker(pos.xyz, n, pos.w, f.rgb);
        }
        return;
    }
    let flux = f.rgb;
    let tr = clamp(nrm.w, 0.0, 1.0);
    inject_vpl(pos.xyz, n, flux * (1.0 - tr));
    if tr > 0.0 {
        inject_vpl(pos.xyz, -n, flux * tr);
    }
    if lpv.occlusion == 1u && light.sky == 0u {
        inject_blocker(pos.xyz, n, pos.w, rsm_albedo(f, pos.w));
    }
}

// The albedo behind a light's RSM texel: Φ / (colour × w × A); 0 in channels the light lacks.
fn rsm_albedo(f: vec4<f32>, area: f32) -> vec3<f32> {
    let lit = light.color * (f.w * area);
    return select(vec3<f32>(0.0), f.rgb / max(lit, vec3<f32>(1e-30)), lit > vec3<f32>(0.0));
}

// A blocker of area A⊥/|n·l| (capped at 4·A⊥) in the geometry volume, whose cells are centred on
// the light volume's cell corners.
fn inject_blocker(p: vec3<f32>, n: vec3<f32>, area_perp: f32, albedo: vec3<f32>) {
    var to_light = -light.axis;
    if light.kind != 0u {
        to_light = normalize(light.eye - p);
    }
    let area = area_perp / max(abs(dot(n, to_light)), 0.25);
    let gn = i32(lpv.n) + 1;
    let c = vec3<i32>(floor((p - (lpv.origin - vec3<f32>(0.5 * lpv.cell))) / lpv.cell));
    if !inside(c, gn) {
        return;
    }
    let a = area / (lpv.cell * lpv.cell) * lpv.gv_scale;
    let q = vec4<i32>(round(cosine_lobe(n) * (BLOCKER_SCALE * a)));
    // Light views fill the first third of the atomics, the camera the second; the albedo
    // (Σ albedo·A, Σ A) of both goes to the last.
    let gcells = gn * gn * gn * 4;
    let base = cell_index(c, gn) * 4 + select(0, gcells, light.kind == 3u);
    atomicAdd(&gv_atomic[base + 0], q.x);
    atomicAdd(&gv_atomic[base + 1], q.y);
    atomicAdd(&gv_atomic[base + 2], q.z);
    atomicAdd(&gv_atomic[base + 3], q.w);
    let r = vec4<i32>(round(vec4<f32>(clamp(albedo, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0) * a));
    let ab = cell_index(c, gn) * 4 + 2 * gcells;
    atomicAdd(&gv_atomic[ab + 0], r.x);
    atomicAdd(&gv_atomic[ab + 1], r.y);
    atomicAdd(&gv_atomic[ab + 2], r.z);
    atomicAdd(&gv_atomic[ab + 3], r.w);
}

// Fixed point → float: the seed goes to `dst` and to the accumulation; the geometry volume to gv.
@compute @workgroup_size(4, 4, 4)
fn resolve_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    let gn = lpv.n + 1u;
    if all(id < vec3<u32>(gn)) {
        let gi = i32((id.z * gn + id.y) * gn + id.x);
        let b = gi * 4;
        let from_lights = vec4<f32>(
            f32(atomicLoad(&gv_atomic[b])),
            f32(atomicLoad(&gv_atomic[b + 1])),
            f32(atomicLoad(&gv_atomic[b + 2])),
            f32(atomicLoad(&gv_atomic[b + 3])),
        ) / lpv.gv_scale;
        let c = b + i32(gn * gn * gn * 4u);
        let from_camera = vec4<f32>(
            f32(atomicLoad(&gv_atomic[c])),
            f32(atomicLoad(&gv_atomic[c + 1])),
            f32(atomicLoad(&gv_atomic[c + 2])),
            f32(atomicLoad(&gv_atomic[c + 3])),
        ) / lpv.gv_scale;
        // A surface seen by a light and by the camera is one blocker, not two: per cell, the
        // source with more blocking area.
        gv[2 * gi] = select(from_lights, from_camera, from_camera.x > from_lights.x);
        let a = b + 2 * i32(gn * gn * gn * 4u);
        gv[2 * gi + 1] = vec4<f32>(
            f32(atomicLoad(&gv_atomic[a])),
            f32(atomicLoad(&gv_atomic[a + 1])),
            f32(atomicLoad(&gv_atomic[a + 2])),
            f32(atomicLoad(&gv_atomic[a + 3])),
        ) / lpv.gv_scale;
    }
    if any(id >= vec3<u32>(lpv.n)) {
        return;
    }
    let i = cell_index(vec3<i32>(id), i32(lpv.n));
    for (var ch = 0; ch < 3; ch++) {
        let b = i * 12 + ch * 4;
        let v = vec4<f32>(
            f32(atomicLoad(&lpv_atomic[b])),
            f32(atomicLoad(&lpv_atomic[b + 1])),
            f32(atomicLoad(&lpv_atomic[b + 2])),
            f32(atomicLoad(&lpv_atomic[b + 3])),
        ) / lpv.scale;
        dst[i * 3 + ch] = v;
        accum[i * 3 + ch] = v;
    }
}

// ---- propagation -------------------------------------------------------------------------------

fn axis_of(k: u32) -> vec3<i32> {
    var a = vec3<i32>(0);
    a[k / 2u] = select(1, -1, (k & 1u) == 1u);
    return a;
}

// The geometry volume's cells (gv: blocking SH at 2i, albedo sums at 2i + 1) at the four
// corners of the face between cell c and c + axis.
fn face_corners(c: vec3<i32>, axis: vec3<i32>) -> array<i32, 4> {
    let along = c + max(axis, vec3<i32>(0));
    var u = vec3<i32>(0, 1, 0);
    var v = vec3<i32>(0, 0, 1);
    if axis.y != 0 {
        u = vec3<i32>(1, 0, 0);
    } else if axis.z != 0 {
        u = vec3<i32>(1, 0, 0);
        v = vec3<i32>(0, 1, 0);
    }
    let gn = i32(lpv.n) + 1;
    return array<i32, 4>(
        cell_index(along, gn),
        cell_index(along + u, gn),
        cell_index(along + v, gn),
        cell_index(along + u + v, gn),
    );
}

// Transmittance of light travelling along `dir` through the face between cell c and c + axis:
// 1 − max(B(−dir), B(dir)), B summed over the face's four corners of the geometry volume and
// divided by four: surfaces block from both sides (lightlab_core::lpv::Occlusion::transmittance).
fn transmittance(c: vec3<i32>, axis: vec3<i32>, dir: vec3<f32>) -> f32 {
    let g = face_corners(c, axis);
    let y_front = sh_basis(-dir);
    let y_back = sh_basis(dir);
    var front = 0.0;
    var back = 0.0;
    for (var k = 0; k < 4; k++) {
        let b = gv[2 * g[k]];
        front += dot(b, y_front);
        back += dot(b, y_back);
    }
    return 1.0 - clamp(0.25 * max(front, back), 0.0, 1.0);
}

// The mean albedo of the surfaces at that face (0 where there are none).
fn face_albedo(c: vec3<i32>, axis: vec3<i32>) -> vec3<f32> {
    let g = face_corners(c, axis);
    var a = vec4<f32>(0.0);
    for (var k = 0; k < 4; k++) {
        a += gv[2 * g[k] + 1];
    }
    return select(vec3<f32>(0.0), a.xyz / max(a.w, 1e-30), a.w > 0.0);
}

// Multiple bounces (lightlab_core::lpv::reflected): the light this cell sends through each
// face, where the face blocks it, comes back × the face's albedo as a lobe facing back.
fn reflected(c: vec3<i32>) -> array<vec4<f32>, 3> {
    let nn = i32(lpv.n);
    var acc = array<vec4<f32>, 3>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    let ci = cell_index(c, nn) * 3;
    let own = array<vec4<f32>, 3>(src[ci], src[ci + 1], src[ci + 2]);
    for (var k = 0u; k < 6u; k++) {
        let d = axis_of(k);
        if !inside(c + d, nn) {
            continue;
        }
        let dv = vec3<f32>(d);
        let blocked = 1.0 - transmittance(c, d, dv);
        if blocked <= 0.0 {
            continue;
        }
        let yf = sh_basis(dv);
        var f = vec3<f32>(0.0);
        for (var ch = 0; ch < 3; ch++) {
            f[ch] = SOLID_FAR * dot(own[ch], yf);
        }
        for (var j = 0u; j < 6u; j++) {
            if j / 2u == k / 2u {
                continue;
            }
            let y = sh_basis(normalize(dv + 0.5 * vec3<f32>(axis_of(j))));
            for (var ch = 0; ch < 3; ch++) {
                f[ch] += SOLID_SIDE * dot(own[ch], y);
            }
        }
        let rho = face_albedo(c, d) * blocked;
        let back = cosine_lobe(-dv) / PI;
        for (var ch = 0; ch < 3; ch++) {
            acc[ch] += back * (rho[ch] * max(f[ch], 0.0));
        }
    }
    return acc;
}

// Kaplanyan: gather from the 6 face neighbours onto the 5 faces of this cell, each face's flux
// re-emitted as a cosine lobe around the face normal or (reemit = 1) around the direction it
// arrived from; the new light goes to `dst` and is added to the accumulation.
@compute @workgroup_size(4, 4, 4)
fn propagate_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    let nn = i32(lpv.n);
    if any(id >= vec3<u32>(lpv.n)) {
        return;
    }
    let c = vec3<i32>(id);
    var acc = array<vec4<f32>, 3>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    for (var k = 0u; k < 6u; k++) {
        let d = axis_of(k);
        let s = c - d;
        if !inside(s, nn) {
            continue;
        }
        let dv = vec3<f32>(d);
        var t = 1.0;
        if lpv.use_gv == 1u {
            t = transmittance(s, d, dv);
        }
        if t <= 0.0 {
            continue;
        }
        let si = cell_index(s, nn) * 3;
        let source = array<vec4<f32>, 3>(src[si], src[si + 1], src[si + 2]);
        // The far face.
        let yf = sh_basis(dv);
        let lf = cosine_lobe(dv) * (t * SOLID_FAR / PI);
        for (var ch = 0; ch < 3; ch++) {
            acc[ch] += lf * dot(source[ch], yf);
        }
        // The four side faces.
        for (var j = 0u; j < 6u; j++) {
            if j / 2u == k / 2u {
                continue;
            }
            let sv = vec3<f32>(axis_of(j));
            let w = normalize(dv + 0.5 * sv);
            let y = sh_basis(w);
            let shape = select(cosine_lobe(sv) / PI, reemission_lobe(w, lpv.lobe), lpv.reemit == 1u);
            let l = shape * (t * SOLID_SIDE);
            for (var ch = 0; ch < 3; ch++) {
                acc[ch] += l * dot(source[ch], y);
            }
        }
    }
    if lpv.use_gv == 1u && lpv.bounces == 1u {
        let r = reflected(c);
        for (var ch = 0; ch < 3; ch++) {
            acc[ch] += r[ch];
        }
    }
    let i = cell_index(c, nn) * 3;
    for (var ch = 0; ch < 3; ch++) {
        dst[i + ch] = acc[ch];
        accum[i + ch] += acc[ch];
    }
}

// ---- the WPI report's scheme (lpv-faithful) ----------------------------------------------------

// The report's gather injection, with its sample-position bug fixed: per voxel, `wpi_samples`
// deterministic points spread over the voxel are projected into the RSM; a texel is accepted when
// its surface lies within half a voxel of the point along the light direction. Each accepted
// texel adds an SH delta along the mirror direction of the light plus 0.75 × a delta along the
// light direction; the voxel keeps the mean × 4π (count += 2 per texel). The report injects the
// albedo; lightlab injects albedo × the light's irradiance (Φ / A⊥) so images have units.
@compute @workgroup_size(4, 4, 4)
fn inject_wpi_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    let nn = i32(lpv.n);
    if any(id >= vec3<u32>(lpv.n)) {
        return;
    }
    let c = vec3<i32>(id);
    var acc = array<vec4<f32>, 3>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    var count = 0.0;
    let m = max(lpv.wpi_samples, 1u);
    for (var s = 0u; s < m; s++) {
        // A rank-1 lattice over the voxel (golden-ratio offsets), deterministic.
        let f = fract(vec3<f32>(f32(s) + 0.5) * vec3<f32>(1.0 / f32(m), 0.7548777, 0.5698403));
        let p = lpv.origin + (vec3<f32>(c) + f) * lpv.cell;
        let clip = light.view_proj * vec4<f32>(p, 1.0);
        let ndc = clip.xyz / clip.w;
        if clip.w <= 0.0 || any(abs(ndc.xy) > vec2<f32>(1.0)) {
            continue;
        }
        let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        let t = vec2<i32>(min(uv * f32(lpv.rsm_size), vec2<f32>(f32(lpv.rsm_size) - 1.0)));
        let pos = textureLoad(rsm_position, t, 0);
        if pos.w <= 0.0 {
            continue;
        }
        var l = light.axis;
        if light.kind != 0u {
            l = normalize(pos.xyz - light.eye);
        }
        if abs(dot(pos.xyz - p, l)) > 0.5 * lpv.cell {
            continue;
        }
        let n = safe_normalize(textureLoad(rsm_normal, t, 0).xyz, -l);
        let e = textureLoad(rsm_flux, t, 0).rgb / pos.w;
        let lobe = sh_basis(reflect(l, n)) + WPI_TRANSMIT * sh_basis(l);
        acc[0] += lobe * e.r;
        acc[1] += lobe * e.g;
        acc[2] += lobe * e.b;
        count += 2.0;
    }
    let i = cell_index(c, nn) * 3;
    for (var ch = 0; ch < 3; ch++) {
        var v = vec4<f32>(0.0);
        if count > 0.0 {
            v = 4.0 * PI * acc[ch] / count;
        }
        dst[i + ch] += v;
    }
}

// The report's propagation: out = in + Σ f·w·max(0, I_n(d))·Y(d) / 18 over 6 face (w = 1) and
// 12 edge (w = ½) neighbours, d pointing from the neighbour to this voxel; borders clamp.
@compute @workgroup_size(4, 4, 4)
fn propagate_wpi_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    let nn = i32(lpv.n);
    if any(id >= vec3<u32>(lpv.n)) {
        return;
    }
    let c = vec3<i32>(id);
    var acc = array<vec4<f32>, 3>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    for (var z = -1; z <= 1; z++) {
        for (var y = -1; y <= 1; y++) {
            for (var x = -1; x <= 1; x++) {
                let o = vec3<i32>(x, y, z);
                let k = abs(x) + abs(y) + abs(z);
                if k == 0 || k == 3 {
                    continue;
                }
                let w = select(0.5, 1.0, k == 1);
                let nb = clamp(c + o, vec3<i32>(0), vec3<i32>(nn - 1));
                let yd = sh_basis(-normalize(vec3<f32>(o)));
                let ni = cell_index(nb, nn) * 3;
                for (var ch = 0; ch < 3; ch++) {
                    acc[ch] += yd * (WPI_FALLOFF * w * max(dot(src[ni + ch], yd), 0.0));
                }
            }
        }
    }
    let i = cell_index(c, nn) * 3;
    for (var ch = 0; ch < 3; ch++) {
        dst[i + ch] = src[i + ch] + acc[ch] / 18.0;
    }
}

// ---- store -------------------------------------------------------------------------------------

// Kaplanyan: the accumulation; WPI: the last propagated volume (`src`).
@compute @workgroup_size(4, 4, 4)
fn store_cs(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= vec3<u32>(lpv.n)) {
        return;
    }
    let i = cell_index(vec3<i32>(id), i32(lpv.n)) * 3;
    let c = vec3<i32>(id) + vec3<i32>(0, 0, i32(lpv.layer));
    if lpv.store_last == 1u {
        textureStore(out_r, c, src[i]);
        textureStore(out_g, c, src[i + 1]);
        textureStore(out_b, c, src[i + 2]);
    } else {
        textureStore(out_r, c, accum[i]);
        textureStore(out_g, c, accum[i + 1]);
        textureStore(out_b, c, accum[i + 2]);
    }
}
