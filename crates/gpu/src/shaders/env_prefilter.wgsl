// Dynamic environment maps prefiltered on the GPU (raster/env_dynamic.rs): the port of
// lightlab_core::envmap::prefilter with a cube source in place of the lat-long one.
//
// 1. `gather`: a face render (HDR colour, camera-relative positions) → one layer of the source
//    cube: radiance in rgb, the inverse distance from the centre in alpha (0: the sky).
// 2. `downsample`: a solid-angle-weighted 2×2 mip step (source cube and destination maps).
// 3. `prefilter`: each level's faces at their own size into a scratch array: the mirror level
//    (the source over the texel's footprint) or a lobe average by filtered importance sampling
//    (Phong cosⁿ or GGX seen along its normal), as the CPU does.
// 4. `upsample`: the scratch faces bilinearly to the maps' face size, into mip 0 of their layers.

struct Params {
    // The map's frame rows (world → map); `gather`: the face camera's right, up and back axes.
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
    // 1 dual paraboloid, 2 cube, 3 sphere map.
    param: u32,
    faces: u32,
    // The output face size of this step.
    size: u32,
    // `gather`: the cube face written; `downsample`, `upsample`: the first layer.
    layer: u32,
    // The input face size (`gather`: the render's; `downsample`: the finer level's).
    src_size: u32,
    src_mips: f32,
    // Solid angle of a source texel at level 0 (its mean).
    src_texel: f32,
    // `downsample`: where the input level's texel weights start in `weights`.
    weights: u32,
}

// One prefiltered face: its size, lobe, roughness and samples.
struct Level {
    n: u32,
    // 0 GGX, 1 Phong, 2 the inverse-distance mirror level (alpha of the source).
    lobe: u32,
    face: u32,
    samples: u32,
    roughness: f32,
    pad0: f32,
    pad1: f32,
    pad2: f32,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var face_hdr: texture_2d<f32>;
@group(0) @binding(2) var face_pos: texture_2d<f32>;
@group(0) @binding(3) var out_tex: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(4) var in_tex: texture_2d_array<f32>;
@group(0) @binding(5) var src_cube: texture_cube<f32>;
@group(0) @binding(6) var src_sampler: sampler;
@group(0) @binding(7) var<storage, read> levels: array<Level>;
@group(0) @binding(8) var<storage, read> weights: array<f32>;

const PI: f32 = 3.14159265358979;

// Direction of (s, t) ∈ [−1, 1]² on cube face f (lightlab_core::param::Param::Cube, the
// convention of the hardware's cube maps).
fn cube_dir(f: u32, s: f32, t: f32) -> vec3<f32> {
    var d = vec3<f32>(-s, -t, -1.0);
    switch f {
        case 0u: { d = vec3<f32>(1.0, -t, -s); }
        case 1u: { d = vec3<f32>(-1.0, -t, s); }
        case 2u: { d = vec3<f32>(s, 1.0, t); }
        case 3u: { d = vec3<f32>(s, -1.0, -t); }
        case 4u: { d = vec3<f32>(s, -t, 1.0); }
        default: {}
    }
    return normalize(d);
}

// lightlab_core::envmap::texel_direction: texel centre uv of `face` in the map's frame,
// extended past the paraboloid's disc and clamped to the sphere map's rim.
fn texel_dir(face: u32, uv: vec2<f32>) -> vec3<f32> {
    var q = uv * 2.0 - 1.0;
    if p.param == 1u {
        let r2 = dot(q, q);
        let z = (1.0 - r2) / (1.0 + r2);
        return normalize(vec3<f32>(2.0 * q / (1.0 + r2), select(-z, z, face == 0u)));
    }
    if p.param == 3u {
        if length(q) > 0.999 {
            q = normalize(q) * 0.999;
        }
        let nz = sqrt(max(1.0 - dot(q, q), 0.0));
        return normalize(vec3<f32>(2.0 * nz * q, 2.0 * nz * nz - 1.0));
    }
    return cube_dir(face, q.x, q.y);
}

@compute @workgroup_size(8, 8, 1)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= p.size || id.y >= p.size {
        return;
    }
    let q = (vec2<f32>(id.xy) + 0.5) / f32(p.size) * 2.0 - 1.0;
    let d = cube_dir(p.layer, q.x, q.y);
    // The face camera's view of d (90° field: ndc = xy / −z), its nearest pixel.
    let v = vec3<f32>(dot(p.r0.xyz, d), dot(p.r1.xyz, d), dot(p.r2.xyz, d));
    let ndc = v.xy / max(-v.z, 1e-6);
    let n = f32(p.src_size);
    let px = clamp((ndc.x + 1.0) * 0.5 * n, 0.0, n - 1.0);
    let py = clamp((1.0 - ndc.y) * 0.5 * n, 0.0, n - 1.0);
    let at = vec2<i32>(i32(px), i32(py));
    let c = textureLoad(face_hdr, at, 0);
    let pos = textureLoad(face_pos, at, 0);
    // Inverse distances: filtering across an edge between a near object and the sky then
    // blends to a distance near the object's instead of halfway to infinity.
    let inv = select(0.0, 1.0 / max(length(pos.xyz), 1e-4), pos.w > 0.0);
    textureStore(out_tex, id.xy, p.layer, vec4<f32>(c.rgb, inv));
}

// A 2×2 step weighted by the input texels' solid angles; texels outside a disc weigh nothing
// unless all four are outside (the CPU's `mip_chain`).
@compute @workgroup_size(8, 8, 1)
fn downsample(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= p.size || id.y >= p.size {
        return;
    }
    let n = p.src_size;
    let layer = p.layer + id.z;
    var s = vec4<f32>(0.0);
    var ws = 0.0;
    var plain = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let cx = min(2u * id.x + (k & 1u), n - 1u);
        let cy = min(2u * id.y + (k >> 1u), n - 1u);
        let v = textureLoad(in_tex, vec2<u32>(cx, cy), layer, 0);
        let w = weights[p.weights + cy * n + cx];
        s += v * w;
        ws += w;
        plain += v * 0.25;
    }
    textureStore(out_tex, id.xy, layer, select(plain, s / max(ws, 1e-30), ws > 0.0));
}

// The source level whose texels have solid angle `omega` (fractional).
fn source_lod(omega: f32) -> f32 {
    return clamp(0.5 * log2(max(omega / p.src_texel, 1e-12)), 0.0, p.src_mips - 1.0);
}

fn radical_inverse2(i: u32) -> f32 {
    return f32(reverseBits(i)) * 2.3283064365386963e-10;
}

// lightlab_core::sampling::orthonormal_basis.
fn basis(n: vec3<f32>) -> mat2x3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return mat2x3<f32>(
        vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3<f32>(b, sign + n.y * n.y * a, -n.y),
    );
}

// The lobe's average of the source around world direction r (envmap::lobe_average).
fn lobe_average(lv: Level, r: vec3<f32>) -> vec3<f32> {
    let tb = basis(r);
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    // One level coarser than a sample's solid angle with few samples (as the CPU).
    let extra = select(1.0, 0.0, lv.samples >= 1024u);
    for (var i = 0u; i < lv.samples; i++) {
        let u = vec2<f32>((f32(i) + 0.5) / f32(lv.samples), radical_inverse2(i));
        let phi = 2.0 * PI * u.y;
        var l = r;
        var pdf = 1.0;
        var w = 1.0;
        if lv.lobe == 1u {
            // Phong cosⁿ: cos θ = u^(1/(n+1)), pdf = (n+1)/2π · cosⁿ = (n+1)/2π · u^(n/(n+1)).
            let a2 = max(pow(lv.roughness * lv.roughness, 2.0), 1e-6);
            let n = clamp(2.0 / a2 - 2.0, 1.0, 1e4);
            let c = pow(u.x, 1.0 / (n + 1.0));
            let s = sqrt(max(1.0 - c * c, 0.0));
            l = normalize(tb[0] * (s * cos(phi)) + tb[1] * (s * sin(phi)) + r * c);
            pdf = (n + 1.0) / (2.0 * PI) * pow(u.x, n / (n + 1.0));
        } else {
            // GGX half vectors; p(l) = D(h)/4 with n = v = r, weighted by ⟨n,l⟩.
            let alpha = max(lv.roughness * lv.roughness, 1e-3);
            let a2 = alpha * alpha;
            let tan2 = a2 * u.x / max(1.0 - u.x, 1e-30);
            let c = 1.0 / sqrt(1.0 + tan2);
            let s = sqrt(max(1.0 - c * c, 0.0));
            let h = tb[0] * (s * cos(phi)) + tb[1] * (s * sin(phi)) + r * c;
            l = 2.0 * dot(h, r) * h - r;
            w = dot(l, r);
            let dd = c * c * (a2 - 1.0) + 1.0;
            pdf = a2 / (PI * dd * dd) / 4.0;
        }
        if w > 0.0 {
            let omega = 1.0 / (f32(lv.samples) * max(pdf, 1e-12));
            let lod = min(source_lod(omega) + extra, p.src_mips - 1.0);
            sum += textureSampleLevel(src_cube, src_sampler, l, lod).rgb * w;
            wsum += w;
        }
    }
    return select(vec3<f32>(0.0), sum / max(wsum, 1e-30), wsum > 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn prefilter(@builtin(global_invocation_id) id: vec3<u32>) {
    let lv = levels[id.z];
    if id.x >= lv.n || id.y >= lv.n {
        return;
    }
    let uv = (vec2<f32>(id.xy) + 0.5) / f32(lv.n);
    let m = texel_dir(lv.face, uv);
    // Map → world: the frame's transpose.
    let d = normalize(p.r0.xyz * m.x + p.r1.xyz * m.y + p.r2.xyz * m.z);
    var c = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    if lv.roughness <= 0.0 {
        // The mirror level: the source over the texel's footprint.
        let omega = 4.0 * PI / (f32(p.faces) * f32(lv.n * lv.n));
        let s = textureSampleLevel(src_cube, src_sampler, d, source_lod(omega));
        c = select(vec4<f32>(s.rgb, 1.0), vec4<f32>(vec3<f32>(s.a), 1.0), lv.lobe == 2u);
    } else {
        c = vec4<f32>(lobe_average(lv, d), 1.0);
    }
    textureStore(out_tex, id.xy, id.z, c);
}

// envmap::upsample: texel centres aligned, edges clamped.
@compute @workgroup_size(8, 8, 1)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= p.size || id.y >= p.size {
        return;
    }
    let n = levels[id.z].n;
    let q = (vec2<f32>(id.xy) + 0.5) * (f32(n) / f32(p.size)) - 0.5;
    let q0 = floor(q);
    let f = q - q0;
    let hi = i32(n) - 1;
    let x0 = clamp(i32(q0.x), 0, hi);
    let x1 = clamp(i32(q0.x) + 1, 0, hi);
    let y0 = clamp(i32(q0.y), 0, hi);
    let y1 = clamp(i32(q0.y) + 1, 0, hi);
    let z = i32(id.z);
    let a = mix(textureLoad(in_tex, vec2<i32>(x0, y0), z, 0), textureLoad(in_tex, vec2<i32>(x1, y0), z, 0), f.x);
    let b = mix(textureLoad(in_tex, vec2<i32>(x0, y1), z, 0), textureLoad(in_tex, vec2<i32>(x1, y1), z, 0), f.x);
    textureStore(out_tex, id.xy, p.layer + id.z, mix(a, b, f.y));
}
