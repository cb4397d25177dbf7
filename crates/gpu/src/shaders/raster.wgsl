// Rasterised lighting: forward and deferred Phong after Fuchs (2005) §4.1, stencil shadow
// volumes, shadow maps (depth comparison and Heidrich's linear-depth variant), projected planar
// shadows. Compiled after common.wgsl and material.wgsl, and before one ambient source
// (ambient_sky, ambient_lightmap, ambient_sh or ambient_lpv.wgsl), which defines
// `source_vertex` and `source_radiance` and its bindings 3.. of group 2.
//
// Bind groups: 0 frame (uniforms, lights, shadow views, per-pass uniforms), 1 material,
// 2 lighting (shadow maps, then the ambient source's), 3 G-buffer (deferred lighting only).

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(2) var<storage, read> shadow_views: array<ShadowView>;
@group(0) @binding(3) var<uniform> pass_u: PassUniforms;


@group(2) @binding(0) var shadow_depth: texture_depth_2d_array;
@group(2) @binding(1) var shadow_cmp: sampler_comparison;
// Heidrich's linear depths (shadow_mode 2); otherwise the shadow maps' raw depths.
@group(2) @binding(2) var shadow_linear: texture_2d_array<f32>;
// Bindings 3 and up of group 2 belong to the ambient source (ambient_*.wgsl).

@group(3) @binding(0) var gb_diffuse: texture_2d<f32>;
@group(3) @binding(1) var gb_normal: texture_2d<f32>;
@group(3) @binding(2) var gb_specular: texture_2d<f32>;
@group(3) @binding(3) var gb_position: texture_2d<f32>;
@group(3) @binding(4) var gb_lobe: texture_2d<f32>;

struct VertexOut {
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) tangent: vec4<f32>,
    @location(3) uv0: vec2<f32>,
    @location(4) uv1: vec2<f32>,
    // The draw's scene instance.
    @location(5) @interpolate(flat) instance: u32,
    // The ambient source's per-vertex term (per-vertex PRT: E/π shaded at the vertex,
    // Gouraud); zero for the others.
    @location(6) vertex_light: vec3<f32>,
    @location(7) color: vec4<f32>,
}

@vertex
fn scene_vs(
    v: VertexIn,
    @builtin(vertex_index) vi: u32,
    @builtin(instance_index) ii: u32,
) -> VertexOut {
    var o: VertexOut;
    let p = sway(v.position, material.sway, frame.wind_a, frame.wind_b);
    o.clip = frame.view_proj * vec4<f32>(p, 1.0);
    o.world = p;
    o.normal = v.normal;
    o.tangent = v.tangent;
    o.uv0 = v.uv0;
    o.uv1 = v.uv1;
    o.color = v.color;
    o.instance = ii;
    o.vertex_light = source_vertex(v.position, vi, ii);
    return o;
}

fn uv_for(i: u32, in: VertexOut) -> vec2<f32> {
    return material_uv(i, in.uv0, in.uv1);
}

fn base_color(in: VertexOut) -> vec4<f32> {
    return material_base(in.uv0, in.uv1, in.color);
}

// Alpha-masked texels, and what lies behind a planar mirror in its reflected view.
fn alpha_test(in: VertexOut) {
    if material.alpha_cutoff >= 0.0 && base_color(in).a < material.alpha_cutoff {
        discard;
    }
    if dot(frame.clip_plane.xyz, in.world) + frame.clip_plane.w < 0.0 {
        discard;
    }
}

// The interpolated vertex normal, turned to the fragment's side (the normal map's base).
fn vertex_normal(in: VertexOut, front: bool) -> vec3<f32> {
    let n = safe_normalize(in.normal, vec3<f32>(0.0, 1.0, 0.0));
    return select(-n, n, front);
}

// A normal-map texel t4 (xyz·½ + ½) as a world normal around the front-facing vertex normal
// n, in the vertex's tangent frame (glTF: bitangent n × t · w).
// One tap of the rooks filter: the unit normal at uv + o texels, weighted by its agreement
// with the centre n0 (negative beyond 90°).
fn rook_tap(uv: vec2<f32>, o: vec2<f32>, texel: vec2<f32>, n0: vec3<f32>) -> vec3<f32> {
    let t = textureSample(normal_tex, tex_sampler, uv + o * texel).xyz * 2.0 - 1.0;
    let ni = safe_normalize(t, n0);
    return ni * dot(ni, n0);
}

// The WPI report's normal-map filter (§5.5; NormalFilter::Rook): eight taps in a rooks
// pattern at 0.35 × the report's offsets, in texels of the map, n′ = normalize(n₀ + Σ nᵢ·(nᵢ·n₀))
// with n₀ the unnormalised centre. Returns the packed texel map_normal reads.
fn rook_filtered(uv: vec2<f32>) -> vec4<f32> {
    let texel = 0.35 / vec2<f32>(textureDimensions(normal_tex, 0));
    let c = textureSample(normal_tex, tex_sampler, uv);
    let n0 = c.xyz * 2.0 - 1.0;
    var sum = n0;
    sum += rook_tap(uv, vec2<f32>(1.0, 4.0), texel, n0);
    sum += rook_tap(uv, vec2<f32>(3.0, 1.0), texel, n0);
    sum += rook_tap(uv, vec2<f32>(4.0, -2.0), texel, n0);
    sum += rook_tap(uv, vec2<f32>(1.5, -3.0), texel, n0);
    sum += rook_tap(uv, vec2<f32>(-1.0, -4.0), texel, n0);
    sum += rook_tap(uv, vec2<f32>(-3.0, -1.0), texel, n0);
    sum += rook_tap(uv, vec2<f32>(-4.0, 2.0), texel, n0);
    sum += rook_tap(uv, vec2<f32>(-1.5, 3.0), texel, n0);
    return vec4<f32>(safe_normalize(sum, vec3<f32>(0.0, 0.0, 1.0)) * 0.5 + 0.5, c.w);
}

fn map_normal(in: VertexOut, n: vec3<f32>, t4: vec4<f32>) -> vec3<f32> {
    let t = t4.xyz * 2.0 - 1.0;
    let tn = safe_normalize(vec3<f32>(t.xy * material.normal_scale, t.z), vec3<f32>(0.0, 0.0, 1.0));
    var tg = in.tangent.xyz - n * dot(in.tangent.xyz, n);
    if dot(tg, tg) <= 1e-12 {
        return n;
    }
    tg = normalize(tg);
    let bt = cross(n, tg) * in.tangent.w;
    return safe_normalize(tg * tn.x + bt * tn.y + n * tn.z, n);
}

// Interpolated and mapped normals can face away from the viewer at silhouettes: keep them in
// front (ng faces the viewer, v towards it).
fn face_viewer(n: vec3<f32>, ng: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    if dot(n, v) < 0.0 {
        return safe_normalize(n - ng * (dot(n, ng) - 1e-3), ng);
    }
    return n;
}

const LIT_SAMPLES: i32 = 4;

// Heidrich §9.1.1 (`--normal-filter lit`): light the normals under the pixel, then average,
// instead of lighting their average. LIT_SAMPLES² samples over the pixel's footprint in the
// map (its UV derivatives du, dv), each read with a footprint LIT_SAMPLES times smaller (the
// gradients du, dv / LIT_SAMPLES: the sampler picks the level, anisotropy included), each lobe
// widened by its own texels' spread; the average of their lighting. 4 × 4 reaches the 8 × 8
// supersampled reference's noise floor on `builtin::bumps` (8 × 8 samples: no closer).
fn lit_then_filtered(in: VertexOut, front: bool, s0: Surface, li: GpuLight, v: vec3<f32>, uv: vec2<f32>, du: vec2<f32>, dv: vec2<f32>, roughness: f32) -> vec3<f32> {
    let nv = vertex_normal(in, front);
    let scale2 = material.normal_scale * material.normal_scale;
    var sum = vec3<f32>(0.0);
    for (var j = 0; j < LIT_SAMPLES; j++) {
        for (var i = 0; i < LIT_SAMPLES; i++) {
            let o = (vec2<f32>(f32(i), f32(j)) + 0.5) / f32(LIT_SAMPLES) - 0.5;
            let t4 = textureSampleGrad(normal_tex, tex_sampler, uv + o.x * du + o.y * dv, du / f32(LIT_SAMPLES), dv / f32(LIT_SAMPLES));
            var sk = s0;
            sk.n = face_viewer(map_normal(in, nv, t4), s0.ng, v);
            sk.roughness = widened_roughness(roughness, t4.w * scale2, material.model);
            sum += shade_light(sk, li, v);
        }
    }
    return sum / f32(LIT_SAMPLES * LIT_SAMPLES);
}

// The surface of a rasterised fragment: textures, normal map, normals turned to the viewer.
fn surface(in: VertexOut, front: bool) -> Surface {
    var s: Surface;
    s.p = in.world;
    let base = base_color(in);
    var metallic = material.metallic;
    var roughness = material.roughness;
    if (material.flags & 2u) != 0u {
        let t = textureSample(mr_tex, tex_sampler, uv_for(1u, in));
        roughness *= t.y;
        metallic *= t.z;
    }
    let v = frame.camera_pos - in.world;
    var ng = safe_normalize(cross(dpdx(in.world), dpdy(in.world)), safe_normalize(v, vec3<f32>(0.0, 1.0, 0.0)));
    if dot(ng, v) < 0.0 {
        ng = -ng;
    }
    var n = safe_normalize(in.normal, ng);
    if !front {
        n = -n;
    }
    if (material.flags & 4u) != 0u {
        let nuv = uv_for(2u, in);
        // The variance filter reads one level coarser: what that level averages away turns
        // into its spread (gloss) instead of detail at the pixel's scale, which shimmers as the
        // camera moves (measured: `lightlab bench normal-filter`, docs/normal-maps.md). The lit
        // filter does the same outside the per-light passes (`lit_then_filtered`).
        let variance = frame.normal_filter == 1u || frame.normal_filter == 3u;
        var t4 = textureSampleBias(normal_tex, tex_sampler, nuv, select(0.0, 1.0, variance));
        if frame.normal_filter == 2u {
            t4 = textureSampleLevel(normal_tex, tex_sampler, nuv, 0.0);
        } else if frame.normal_filter == 4u {
            t4 = rook_filtered(nuv);
        }
        if variance {
            // The map's alpha: the spread σ² of the full-resolution normals under this texel
            // (`gpu_scene::normal_mip_chain`), in slopes scaled as the normals are.
            let scale2 = material.normal_scale * material.normal_scale;
            roughness = widened_roughness(roughness, t4.w * scale2, material.model);
        }
        n = map_normal(in, n, t4);
    }
    s.n = face_viewer(n, ng, v);
    s.ng = ng;
    s.delta = material.spec_transmission * (1.0 - metallic);
    s.ior = material.ior;
    s.tint = base.rgb;
    s.thin = u32(material.thickness <= 0.0);
    s.diffuse = base.rgb * (1.0 - metallic) * (1.0 - s.delta);
    let r = (material.ior - 1.0) / (material.ior + 1.0);
    s.f0d = r * r * material.specular;
    s.f0 = mix(vec3<f32>(s.f0d), base.rgb, metallic);
    s.metallic = metallic;
    s.metal = base.rgb * metallic;
    s.eta = material.conductor_eta.xyz;
    s.k = material.conductor_k.xyz;
    s.conductor = u32(material.conductor_eta.w > 0.0);
    let measured = s.f0d * (1.0 - metallic) + s.metal * fresnel_conductor(1.0, s.eta, s.k);
    s.f0 = select(s.f0, measured, s.conductor != 0u);
    if material.model == 1u {
        s.f0 = vec3<f32>(0.0);
    }
    s.roughness = roughness;
    s.model = material.model;
    s.transmission = material_transmission(in.uv0, in.uv1);
    s.t = vec3<f32>(0.0);
    s.lobe = select(vec3<f32>(material.anisotropy.x, 0.0, 0.0), material.lafortune.xyz, s.model == 8u);
    s.table = select(vec4<f32>(0.0), material.tables, frame.brdf_tables != 0u && material.tables.w > 0.0);
    if uses_tangent(s.model) {
        // The anisotropy direction (trace::render::anisotropy_direction): the tangent made
        // orthogonal to n, turned towards the bitangent (of the authored front side's normal).
        var tg = in.tangent.xyz - n * dot(in.tangent.xyz, n);
        if dot(tg, tg) > 1e-12 {
            tg = normalize(tg);
            let nf = select(-n, n, front);
            let bt = cross(nf, tg) * select(1.0, -1.0, in.tangent.w < 0.0);
            s.t = tg * material.anisotropy.y + bt * material.anisotropy.z;
        }
    }
    return s;
}

fn emission(in: VertexOut) -> vec3<f32> {
    var e = material.emissive;
    if (material.flags & 8u) != 0u {
        e *= textureSample(emissive_tex, tex_sampler, uv_for(3u, in)).rgb;
    }
    return e;
}

// The radiance a fragment gets besides the per-light passes: the ambient source's term and
// emission with the specular environment term's glossy part (`source_radiance`, defined by the
// ambient source compiled after this file, which may occlude it), and the environment's glass
// term (env.wgsl), or a planar mirror's reflected view instead of both.
fn base_radiance(s: Surface, in: VertexOut, nv: vec3<f32>) -> vec3<f32> {
    let v = safe_normalize(frame.camera_pos - s.p, s.n);
    let r = reflect(-v, s.n);
    let dr = max(length(dpdx(r)), length(dpdy(r)));
    // A planar mirror shows its reflected view instead of the environment map (`select`: the
    // lookups stay out of a branch on per-fragment data, see env.wgsl on lavapipe).
    let layer = env_instances[in.instance].dynamic.w;
    let mirror = layer != 0u;
    let spec = env_specular(s, v, r, dr, in.instance);
    let planar = env_planar_mirror(s, dot(s.n, v), in.clip.xy, layer);
    let glossy = select(spec.glossy, vec3<f32>(0.0), mirror);
    let own = source_radiance(s, in, nv, glossy) + select(spec.glass, planar, mirror);
    // A radiance field's object: everything but the scene's punctual lights from the field.
    let field = env_field_lookup(frame.camera_pos, -v);
    return select(own, field.rgb, env_radiance_field(in.instance));
}

// The environment's unshadowed irradiance over π arriving around n (what a white Lambertian
// surface facing n sends back): from its SH coefficients (frame.ambient_sh), or the irradiance
// map (`--env-diffuse map`, env.wgsl).
fn sky_irradiance(n: vec3<f32>) -> vec3<f32> {
    if env_u.irradiance_layer != 0xffffffffu {
        return env_irradiance(n);
    }
    let y = sh9(n);
    var e = vec3<f32>(0.0);
    for (var k = 0u; k < 9u; k++) {
        e += frame.ambient_sh[k].xyz * y[k];
    }
    return max(e, vec3<f32>(0.0)) / PI;
}

// ---- shadow maps -------------------------------------------------------------------------------

fn shadow_view_index(li: GpuLight, p: vec3<f32>) -> u32 {
    var i = li.shadow_first;
    // Point, area, goniometric and canned lights: six cube faces around the light's position.
    if li.kind == 0u || li.kind >= 3u {
        let d = p - li.position;
        let a = abs(d);
        if a.x >= a.y && a.x >= a.z {
            i += select(1u, 0u, d.x > 0.0);
        } else if a.y >= a.z {
            i += select(3u, 2u, d.y > 0.0);
        } else {
            i += select(5u, 4u, d.z > 0.0);
        }
    } else if li.kind == 2u {
        let vz = -(frame.view * vec4<f32>(p, 1.0)).z;
        var c = 0u;
        for (var k = 0u; k + 1u < li.shadow_count; k++) {
            if vz > li.cascade_ends[k] {
                c = k + 1u;
            }
        }
        i += c;
    }
    return i;
}

// Distance along the view axis of a perspective shadow view's stored depth (directx
// projection: z = f·(d − n) / (d·(f − n))).
fn shadow_linear_depth(sv: ShadowView, z: f32) -> f32 {
    return sv.near * sv.far / max(sv.far - z * (sv.far - sv.near), 1e-9);
}

// Shadow-map coordinates (uv, depth) of a world point.
fn shadow_uvz(sv: ShadowView, x: vec3<f32>) -> vec3<f32> {
    let c = sv.view_proj * vec4<f32>(x, 1.0);
    let n = c.xyz / max(c.w, 1e-9);
    return vec3<f32>(n.x * 0.5 + 0.5, 0.5 - n.y * 0.5, n.z);
}

// The receiver's plane in the shadow map: dz/duv at (uv, z), from the points `e` away from q
// along two tangents of its geometric normal ng (0 where the plane is seen edge-on). A tap at
// uv + o then compares against z + grad·o, the receiver's own depth there, so taps spread
// over a slanted receiver do not shadow it (receiver-plane depth bias).
fn receiver_plane(sv: ShadowView, q: vec3<f32>, ng: vec3<f32>, uv: vec2<f32>, z: f32, e: f32) -> vec2<f32> {
    let inv = 1.0 / frame.shadow_size;
    var t1 = cross(ng, vec3<f32>(0.0, 1.0, 0.0));
    if dot(t1, t1) < 1e-4 {
        t1 = cross(ng, vec3<f32>(1.0, 0.0, 0.0));
    }
    t1 = normalize(t1);
    let t2 = cross(ng, t1);
    let p1 = shadow_uvz(sv, q + t1 * e);
    let p2 = shadow_uvz(sv, q + t2 * e);
    let a = p1.xy - uv;
    let b = p2.xy - uv;
    let det = a.x * b.y - a.y * b.x;
    if abs(det) <= 1e-3 * inv * inv {
        return vec2<f32>(0.0);
    }
    let dz1 = p1.z - z;
    let dz2 = p2.z - z;
    return vec2<f32>(b.y * dz1 - a.y * dz2, a.x * dz2 - b.x * dz1) / det;
}

const AREA_SEARCH_TAPS: u32 = 16u;
const AREA_FILTER_TAPS: u32 = 32u;
const GOLDEN_ANGLE: f32 = 2.3999632;

// Tap i of n on a unit disc (Vogel's spiral), turned by phi.
fn disc_tap(i: u32, n: u32, phi: f32) -> vec2<f32> {
    let r = sqrt((f32(i) + 0.5) / f32(n));
    let a = f32(i) * GOLDEN_ANGLE + phi;
    return r * vec2<f32>(cos(a), sin(a));
}

// Soft shadows of an area light from the shadow map of its centre: percentage-closer soft
// shadows (Fernando 2005). The emitter is a disc of its area (radius R). A blocker search over
// the region from which blockers could hide part of the light gives the mean blocker depth d_b;
// the penumbra at receiver depth d_r then spans R·(d_r − d_b)/(d_r·d_b) texel-scales, and PCF
// over that disc gives the visible fraction. Each tap compares against the receiver's own
// plane (its depth gradient in the map, from two tangent points), so wide kernels on surfaces
// slanted to the light do not shadow themselves. Taps are a spiral turned per point (noise
// instead of banding). Limits: taps beyond a cube face's edge read the face's border.
fn area_shadow(
    li: GpuLight,
    vi: u32,
    sv: ShadowView,
    q: vec3<f32>,
    ng: vec3<f32>,
    uv: vec2<f32>,
    z: f32,
) -> f32 {
    let radius = sqrt(li.intensity / PI);
    let d_r = shadow_linear_depth(sv, z);
    let ts = sv.texel_scale;
    let inv = 1.0 / frame.shadow_size;
    let grad = receiver_plane(sv, q, ng, uv, z, ts * d_r);
    let phi = 6.2831853 * fract(sin(dot(q, vec3<f32>(12.9898, 78.233, 37.719))) * 43758.547);
    let cap = 0.15;
    // Blockers between a quarter of the receiver's depth and the receiver can hide the light.
    let d_min = max(sv.near, 0.25 * d_r);
    let search = min(radius * (d_r - d_min) / (d_r * ts * d_min) * inv, cap);
    let size = i32(frame.shadow_size);
    var blockers = 0.0;
    var depth_sum = 0.0;
    for (var i = 0u; i < AREA_SEARCH_TAPS; i++) {
        let o = disc_tap(i, AREA_SEARCH_TAPS, phi) * search;
        let t = clamp(vec2<i32>((uv + o) * frame.shadow_size), vec2<i32>(0), vec2<i32>(size - 1));
        let stored = textureLoad(shadow_linear, t, i32(vi), 0).x;
        if stored < z + dot(grad, o) {
            blockers += 1.0;
            depth_sum += shadow_linear_depth(sv, stored);
        }
    }
    if blockers == 0.0 {
        return 1.0;
    }
    let d_b = depth_sum / blockers;
    let k = clamp(
        radius * max(d_r - d_b, 0.0) / (d_r * ts * max(d_b, sv.near)) * inv,
        f32(max(frame.pcf_radius, 1)) * inv,
        cap,
    );
    var lit = 0.0;
    for (var i = 0u; i < AREA_FILTER_TAPS; i++) {
        let o = disc_tap(i, AREA_FILTER_TAPS, phi) * k;
        lit += textureSampleCompareLevel(shadow_depth, shadow_cmp, uv + o, i32(vi), z + dot(grad, o));
    }
    return lit / f32(AREA_FILTER_TAPS);
}

// Fraction of the light that reaches p (1 = lit), from the light's shadow maps.
fn shadow_map_visibility(li: GpuLight, p: vec3<f32>, ng: vec3<f32>) -> f32 {
    if li.shadow_count == 0u || frame.shadow_mode == 0u {
        return 1.0;
    }
    let vi = shadow_view_index(li, p);
    let sv = shadow_views[vi];
    var texel = sv.texel_scale;
    if sv.ortho == 0u {
        texel *= length(p - li.position);
    }
    // Normal-offset bias: move the lookup point off the surface by a few texels, on the light's
    // side: a thin translucent surface lit from behind (seen from its unlit side) is lit through
    // its back, and moved away from the light it would shadow itself.
    let nl = select(-ng, ng, dot(ng, light_dir(li, p)) >= 0.0);
    let q = p + nl * (frame.normal_offset * texel);
    let clip = sv.view_proj * vec4<f32>(q, 1.0);
    if clip.w <= 0.0 {
        return 1.0;
    }
    let ndc = clip.xyz / clip.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) || ndc.z > 1.0 {
        return 1.0;
    }
    if li.kind == 3u && frame.shadow_mode == 1u && sv.ortho == 0u {
        return area_shadow(li, vi, sv, q, nl, uv, ndc.z);
    }
    let r = frame.pcf_radius;
    let inv = 1.0 / frame.shadow_size;
    var sum = 0.0;
    var count = 0.0;
    if frame.shadow_mode == 1u {
        var grad = vec2<f32>(0.0);
        if r > 0 {
            grad = receiver_plane(sv, q, nl, uv, ndc.z, texel);
        }
        for (var y = -r; y <= r; y++) {
            for (var x = -r; x <= r; x++) {
                let o = vec2<f32>(f32(x), f32(y)) * inv;
                sum += textureSampleCompareLevel(shadow_depth, shadow_cmp, uv + o, i32(vi), ndc.z + dot(grad, o));
                count += 1.0;
            }
        }
    } else {
        // Heidrich (1999) ch. 6: compare linear depths (distance to the light, or the
        // orthographic depth), which are uniform in precision, instead of post-projective z.
        var depth = ndc.z;
        if sv.ortho == 0u {
            depth = length(q - li.position) / sv.far;
        }
        let size = i32(frame.shadow_size);
        let c = vec2<i32>(uv * frame.shadow_size);
        for (var y = -r; y <= r; y++) {
            for (var x = -r; x <= r; x++) {
                let t = clamp(c + vec2<i32>(x, y), vec2<i32>(0), vec2<i32>(size - 1));
                let stored = textureLoad(shadow_linear, t, i32(vi), 0).x;
                sum += select(0.0, 1.0, depth - frame.linear_bias <= stored);
                count += 1.0;
            }
        }
    }
    return sum / count;
}

// ---- forward path ------------------------------------------------------------------------------

// Depth + the light-independent terms: ambient (diffuse·irradiance) and emission.
@fragment
fn ambient_fs(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    alpha_test(in);
    let s = surface(in, front);
    return vec4<f32>(base_radiance(s, in, vertex_normal(in, front)), 1.0);
}

// One light's contribution, blended additively (one pass per light, Fuchs §4.4).
@fragment
fn light_fs(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    alpha_test(in);
    let s = surface(in, front);
    let li = lights[pass_u.light_index];
    let v = normalize(frame.camera_pos - s.p);
    let vis = shadow_map_visibility(li, s.p, s.ng);
    // A radiance field holds a derived light's share (area lights, the environment's sun).
    let derived = pass_u.light_index >= env_u.scene_lights;
    let keep = select(1.0, 0.0, derived & env_radiance_field(in.instance));
    // Derivatives in uniform control flow, for the lit normal filter.
    let nuv = uv_for(2u, in);
    let du = dpdx(nuv);
    let dv = dpdy(nuv);
    let ruv = uv_for(1u, in);
    let rdx = dpdx(ruv);
    let rdy = dpdy(ruv);
    var c: vec3<f32>;
    if frame.normal_filter == 3u && (material.flags & 4u) != 0u {
        var roughness = material.roughness;
        if (material.flags & 2u) != 0u {
            roughness *= textureSampleGrad(mr_tex, tex_sampler, ruv, rdx, rdy).y;
        }
        c = lit_then_filtered(in, front, s, li, v, nuv, du, dv, roughness);
    } else {
        c = shade_light(s, li, v);
    }
    return vec4<f32>(c * vis * keep, 0.0);
}

// ---- deferred path -----------------------------------------------------------------------------

struct GBufferOut {
    @location(0) accum: vec4<f32>,
    @location(1) diffuse: vec4<f32>,
    @location(2) normal: vec4<f32>,
    @location(3) specular: vec4<f32>,
    @location(4) position: vec4<f32>,
    @location(5) lobe: vec4<f32>,
}

// The G-buffer's anisotropy direction: its angle φ around n from tangent_basis(n), which the
// deferred pass recomputes from the stored (16-bit) normal; 100 where there is none.
// orthonormal_basis branches on the sign of n.z, which 16-bit rounding keeps.
fn tangent_basis(n: vec3<f32>) -> mat2x3<f32> {
    return orthonormal_basis(n);
}

fn encode_tangent(n: vec3<f32>, t: vec3<f32>) -> f32 {
    if dot(t, t) < 0.5 {
        return 100.0;
    }
    let m = tangent_basis(n);
    return atan2(dot(t, m[1]), dot(t, m[0]));
}

fn decode_tangent(n: vec3<f32>, phi: f32) -> vec3<f32> {
    if phi > 50.0 {
        return vec3<f32>(0.0);
    }
    let m = tangent_basis(n);
    return normalize(m[0] * cos(phi) + m[1] * sin(phi));
}

@fragment
fn gbuffer_fs(in: VertexOut, @builtin(front_facing) front: bool) -> GBufferOut {
    alpha_test(in);
    let s = surface(in, front);
    var o: GBufferOut;
    o.accum = vec4<f32>(base_radiance(s, in, vertex_normal(in, front)), 1.0);
    o.diffuse = vec4<f32>(s.diffuse, s.f0d);
    o.normal = vec4<f32>(s.n, s.roughness);
    o.specular = vec4<f32>(s.f0, f32(s.model) + min(s.transmission, 0.99));
    // Camera-relative: keeps precision near the viewer when the target is 16-bit (GLES).
    o.position = vec4<f32>(s.p - frame.camera_pos, 1.0 + s.delta);
    o.lobe = vec4<f32>(encode_tangent(s.n, s.t), s.lobe);
    // The geometric normal is not stored: the deferred path uses the shading normal for the
    // horizon test (documented deviation; the forward path is the exact one).
    return o;
}

struct FullscreenOut {
    @builtin(position) clip: vec4<f32>,
}

@vertex
fn fullscreen_vs(@builtin(vertex_index) i: u32) -> FullscreenOut {
    var o: FullscreenOut;
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    o.clip = vec4<f32>(xy, 0.0, 1.0);
    return o;
}

fn gbuffer_surface(c: vec2<i32>) -> Surface {
    var s: Surface;
    let d = textureLoad(gb_diffuse, c, 0);
    let n = textureLoad(gb_normal, c, 0);
    let sp = textureLoad(gb_specular, c, 0);
    s.p = textureLoad(gb_position, c, 0).xyz + frame.camera_pos;
    s.n = safe_normalize(n.xyz, vec3<f32>(0.0, 1.0, 0.0));
    s.ng = s.n;
    s.diffuse = d.rgb;
    s.f0d = d.a;
    s.f0 = sp.rgb;
    s.roughness = n.w;
    s.model = u32(floor(sp.a));
    s.transmission = fract(sp.a);
    // The glass interface's weight rides on the position's w (1 + delta; 0 = no surface).
    s.delta = textureLoad(gb_position, c, 0).w - 1.0;
    s.ior = 1.5;
    s.tint = vec3<f32>(1.0);
    s.conductor = 0u;
    let lobe = textureLoad(gb_lobe, c, 0);
    s.t = decode_tangent(s.n, lobe.x);
    s.lobe = lobe.yzw;
    return s;
}

@fragment
fn deferred_light_fs(in: FullscreenOut) -> @location(0) vec4<f32> {
    let c = vec2<i32>(in.clip.xy);
    if textureLoad(gb_position, c, 0).w == 0.0 {
        discard;
    }
    let s = gbuffer_surface(c);
    let li = lights[pass_u.light_index];
    let v = normalize(frame.camera_pos - s.p);
    let vis = shadow_map_visibility(li, s.p, s.ng);
    return vec4<f32>(shade_light(s, li, v) * vis, 0.0);
}

// ---- stencil shadow volumes --------------------------------------------------------------------

// Volume vertices in homogeneous world coordinates: w = 0 for points extruded to infinity.
@vertex
fn volume_vs(@location(0) p: vec4<f32>) -> @invariant @builtin(position) vec4<f32> {
    return frame.view_proj * p;
}

// Volumes write only the stencil (colour writes are masked off).
@fragment
fn volume_fs() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}

// Writes 1 where the current stencil test passes (shadow masks for tests and debug views).
@fragment
fn mask_fs(in: FullscreenOut) -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}

// Shadow-map visibility of the G-buffer point, thresholded at ½ (tests and debug views).
@fragment
fn shadow_map_mask_fs(in: FullscreenOut) -> @location(0) vec4<f32> {
    let c = vec2<i32>(in.clip.xy);
    if textureLoad(gb_position, c, 0).w == 0.0 {
        discard;
    }
    let s = gbuffer_surface(c);
    let li = lights[pass_u.light_index];
    let vis = shadow_map_visibility(li, s.p, s.n);
    return vec4<f32>(select(0.0, 1.0, vis >= 0.5));
}

// ---- shadow maps -------------------------------------------------------------------------------

struct ShadowOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) uv0: vec2<f32>,
    @location(2) uv1: vec2<f32>,
    @location(3) alpha: f32,
}

@vertex
fn shadow_vs(v: VertexIn) -> ShadowOut {
    var o: ShadowOut;
    let p = sway(v.position, material.sway, frame.wind_a, frame.wind_b);
    o.clip = shadow_views[pass_u.shadow_view].view_proj * vec4<f32>(p, 1.0);
    o.world = p;
    o.uv0 = v.uv0;
    o.uv1 = v.uv1;
    o.alpha = v.color.a;
    return o;
}

fn shadow_alpha_test(in: ShadowOut) {
    if material.alpha_cutoff >= 0.0 {
        var a = material.base_color.a * in.alpha;
        if (material.flags & 1u) != 0u {
            a *= textureSampleLevel(base_tex, tex_sampler, material_uv(0u, in.uv0, in.uv1), 0.0).a;
        }
        if a < material.alpha_cutoff {
            discard;
        }
    }
}

@fragment
fn shadow_depth_fs(in: ShadowOut) {
    shadow_alpha_test(in);
}

// Heidrich's variant: the linear depth goes to a colour target.
@fragment
fn shadow_linear_fs(in: ShadowOut) -> @location(0) vec4<f32> {
    shadow_alpha_test(in);
    let sv = shadow_views[pass_u.shadow_view];
    if sv.ortho == 1u {
        return vec4<f32>(in.clip.z, 0.0, 0.0, 0.0);
    }
    let li = lights[pass_u.light_index];
    return vec4<f32>(length(in.world - li.position) / sv.far, 0.0, 0.0, 0.0);
}

// ---- projected planar shadows (Heidrich 1999 §6.1) ---------------------------------------------

// Casters flattened onto the receiver plane by the light's planar projection (a shadow view
// slot holds the projection matrix); they mark the stencil where the plane is in shadow.
@vertex
fn planar_vs(v: VertexIn) -> @builtin(position) vec4<f32> {
    let p = sway(v.position, material.sway, frame.wind_a, frame.wind_b);
    let flat = shadow_views[pass_u.shadow_view].view_proj * vec4<f32>(p, 1.0);
    return frame.view_proj * flat;
}

// ---- background --------------------------------------------------------------------------------

@group(3) @binding(5) var env_map: texture_2d<f32>;

// The environment where no surface was drawn, read texel by texel as the path tracer's
// `Environment::radiance` (u = ½ + atan2(x, −z)/2π, v = acos(y)/π, nearest texel).
@fragment
fn sky_fs(in: FullscreenOut) -> @location(0) vec4<f32> {
    let ndc = vec2<f32>(
        in.clip.x / frame.viewport.x * 2.0 - 1.0,
        1.0 - in.clip.y / frame.viewport.y * 2.0,
    );
    // A point on the near plane (reversed depth: z = 1) along the pixel's ray.
    let q = frame.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    let d = normalize(q.xyz / q.w - frame.camera_pos);
    let size = vec2<f32>(textureDimensions(env_map));
    let uv = vec2<f32>(
        0.5 + atan2(d.x, -d.z) / (2.0 * PI),
        acos(clamp(d.y, -1.0, 1.0)) / PI,
    );
    let t = min(vec2<i32>(uv * size), vec2<i32>(size) - vec2<i32>(1));
    return vec4<f32>(textureLoad(env_map, max(t, vec2<i32>(0)), 0).rgb, 0.0);
}

// ---- output ------------------------------------------------------------------------------------

@group(3) @binding(4) var hdr_in: texture_2d<f32>;

// Exposure and Reinhard on luminance-preserving channels: the displayed frame of `bench frame`.
@fragment
fn tonemap_fs(in: FullscreenOut) -> @location(0) vec4<f32> {
    let c = textureLoad(hdr_in, vec2<i32>(in.clip.xy), 0).rgb * frame.exposure;
    return vec4<f32>(c / (vec3<f32>(1.0) + c), 1.0);
}
