// The specular environment term (Heidrich 1999 ch. 8; raster/env.rs): prefiltered maps of the
// environment in one parameterisation, a level per roughness, looked up around the reflected
// direction. Compiled after raster.wgsl.

struct EnvUniforms {
    // World → map rotation, by rows.
    row0: vec4<f32>,
    row1: vec4<f32>,
    row2: vec4<f32>,
    // The constant environment's radiance (mode 4).
    constant: vec4<f32>,
    // The levels' roughness values, four per vector.
    roughness: array<vec4<f32>, 4>,
    // 0 none, 1 dual paraboloid, 2 cube, 3 sphere map, 4 constant.
    mode: u32,
    levels: u32,
    phong_set: u32,
    ggx_set: u32,
    // 0 auto (GGX for PBR materials, Phong otherwise), 1 Phong, 2 GGX.
    prefilter: u32,
    faces: u32,
    mips: f32,
    texel_angle: f32,
    // Whether glossy surfaces reflect the maps (or the constant).
    specular: u32,
    // The irradiance map's first layer (E/π); 0xffffffff without one.
    irradiance_layer: u32,
    // How many instances have dynamic maps (env_instances says which).
    dynamic_objects: u32,
    pad0: u32,
    pad1: u32,
    // 1: glass refracts through one interface; 2: through two (the instance's bounding sphere).
    refraction: u32,
    // The scene's own punctual lights (derived ones follow: area lights, the sun, a canned light).
    scene_lights: u32,
    // The object light field's first layer in env_extra (after the mirrors').
    field_layer: u32,
    // The object light field's box and (instance + 1 or 0, n_uv, n_st, 0 geometry / 1 radiance).
    field_min: vec4<f32>,
    field_max: vec4<f32>,
    field: vec4<u32>,
}

// Per scene instance: its bounding sphere (centre, radius) and its dynamic maps (first colour
// layer, first inverse-distance layer, 1 when it has them; they are centred on the sphere's
// centre), then k + 1 when it is planar mirror k (0: not one).
struct EnvInstance {
    sphere: vec4<f32>,
    dynamic: vec4<u32>,
}

@group(2) @binding(20) var env_maps: texture_2d_array<f32>;
@group(2) @binding(21) var env_sampler: sampler;
@group(2) @binding(23) var<uniform> env_u: EnvUniforms;
@group(2) @binding(24) var<storage, read> env_instances: array<EnvInstance>;
// One array of smaller images (one binding: GL's 16 sampled textures per stage): layer 0 the
// split-sum table (32² in its corner), then the planar mirrors' reflected views, pixel-aligned
// with the frame (raster/mirror.rs), then the object light field's six slabs from layer
// env_u.field_layer, each an atlas of (u,v) tiles of
// (s,t) texels in its layer's top-left corner, holding (exit direction, throughput) of a
// geometry field (§10.2) or (radiance, coverage) of a radiance field (§10.1).
@group(2) @binding(25) var env_extra: texture_2d_array<f32>;


// Component i of v (no dynamic vector index on every backend).
fn env_comp(v: vec3<f32>, i: u32) -> f32 {
    return select(select(v.z, v.y, i == 1u), v.x, i == 0u);
}

// The field at ray (o, d): its slab by d's dominant axis (ties to the lower axis), (u,v) where
// the ray crosses the box's central plane, (s,t) its slope; quadrilinear as four bilinear reads
// inside the (u,v) tiles around it. Returns the interpolated (direction, throughput).
fn env_field_lookup(o: vec3<f32>, d: vec3<f32>) -> vec4<f32> {
    let c = (env_u.field_min.xyz + env_u.field_max.xyz) * 0.5;
    let h = (env_u.field_max.xyz - env_u.field_min.xyz) * 0.5;
    let ad = abs(d);
    var a = 2u;
    if ad.x >= ad.y && ad.x >= ad.z {
        a = 0u;
    } else if ad.y >= ad.z {
        a = 1u;
    }
    let ua = (a + 1u) % 3u;
    let va = (a + 2u) % 3u;
    let da = env_comp(d, a);
    let p = o + d * ((env_comp(c, a) - env_comp(o, a)) / da);
    let half_uv = vec2<f32>(env_comp(h, ua), env_comp(h, va)) + env_comp(h, a);
    let uv = vec2<f32>(env_comp(p, ua) - env_comp(c, ua), env_comp(p, va) - env_comp(c, va)) / half_uv;
    let st = vec2<f32>(env_comp(d, ua), env_comp(d, va)) / max(abs(da), 1e-6);
    let layer = env_u.field_layer + 2u * a + u32(da < 0.0);
    let n_uv = max(f32(env_u.field.y), 2.0);
    let n_st = max(f32(env_u.field.z), 1.0);
    let f = clamp((uv * 0.5 + 0.5) * n_uv - 0.5, vec2<f32>(0.0), vec2<f32>(n_uv - 1.0));
    let i0 = min(floor(f), vec2<f32>(n_uv - 2.0));
    let w = f - i0;
    // (s,t) in texels within a tile, off its border so that bilinear reads stay inside.
    let sti = clamp((st * 0.5 + 0.5) * n_st, vec2<f32>(0.5), vec2<f32>(n_st - 0.5));
    let dims = vec2<f32>(textureDimensions(env_extra));
    var sum = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let o2 = vec2<f32>(f32(k & 1u), f32(k >> 1u));
        let wk = mix(1.0 - w.x, w.x, o2.x) * mix(1.0 - w.y, w.y, o2.y);
        let at = ((i0 + o2) * n_st + sti) / dims;
        sum += textureSampleLevel(env_extra, env_sampler, at, layer, 0.0) * wk;
    }
    return sum;
}

// Whether `instance` takes its light besides the scene's punctual lights from a radiance
// field (§10.1).
fn env_radiance_field(instance: u32) -> bool {
    return (env_u.field.x == instance + 1u) & (env_u.field.w == 1u);
}

// The split-sum table (32 × 32 over ⟨n,v⟩ and roughness, texel centres at the ends) in layer 0
// of the extras, read bilinearly inside its corner.
fn env_split_sum(nv: f32, roughness: f32) -> vec2<f32> {
    let t = clamp(vec2<f32>(nv, roughness) * 32.0, vec2<f32>(0.5), vec2<f32>(31.5));
    let at = t / vec2<f32>(textureDimensions(env_extra));
    return textureSampleLevel(env_extra, env_sampler, at, 0u, 0.0).rg;
}

// A planar mirror's reflection (Heidrich 1999 ch. 10 intro): the scene drawn from the mirrored
// eye, read at this fragment's own pixel, times the surface's Fresnel reflectance at the view
// angle (the mirror limit of the GGX lobe, as the path tracer's).
fn env_planar_mirror(s: Surface, nv: f32, pixel: vec2<f32>, layer: u32) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(env_extra));
    let p = clamp(vec2<i32>(pixel), vec2<i32>(0), size - vec2<i32>(1));
    let l = textureLoad(env_extra, p, i32(layer), 0).rgb;
    return l * surface_fresnel(s, clamp(nv, 0.0, 1.0));
}

// (face, u, v) of map direction m, as lightlab_core::param::Param::dir_to_uv.
fn env_face_uv(m: vec3<f32>) -> vec3<f32> {
    if env_u.mode == 1u {
        let q = m.xy / (1.0 + abs(m.z));
        return vec3<f32>(select(1.0, 0.0, m.z >= 0.0), (q + 1.0) * 0.5);
    }
    if env_u.mode == 3u {
        let k = 2.0 * sqrt(m.x * m.x + m.y * m.y + (m.z + 1.0) * (m.z + 1.0));
        return vec3<f32>(0.0, m.xy / max(k, 1e-20) + 0.5);
    }
    let a = abs(m);
    var f = 0.0;
    var sc = 0.0;
    var tc = 0.0;
    var ma = 0.0;
    if a.x >= a.y && a.x >= a.z {
        ma = a.x;
        tc = -m.y;
        if m.x > 0.0 {
            f = 0.0;
            sc = -m.z;
        } else {
            f = 1.0;
            sc = m.z;
        }
    } else if a.y >= a.z {
        ma = a.y;
        sc = m.x;
        if m.y > 0.0 {
            f = 2.0;
            tc = m.z;
        } else {
            f = 3.0;
            tc = -m.z;
        }
    } else {
        ma = a.z;
        tc = -m.y;
        if m.z > 0.0 {
            f = 4.0;
            sc = m.x;
        } else {
            f = 5.0;
            sc = -m.x;
        }
    }
    return vec3<f32>(f, (vec2<f32>(sc, tc) / max(ma, 1e-20) + 1.0) * 0.5);
}

fn env_level_roughness(i: u32) -> f32 {
    // Component i % 4 of vector i / 4.
    let v = env_u.roughness[i / 4u];
    let k = i % 4u;
    return select(select(select(v.w, v.z, k == 2u), v.y, k == 1u), v.x, k == 0u);
}

// Level `level` of lobe set `lobe_set` around map direction m.
// `base` is 0 for the static maps, or where the dynamic ones start.
fn env_read(base: u32, lobe_set: u32, level: u32, m: vec3<f32>, lod: f32) -> vec3<f32> {
    let fuv = env_face_uv(m);
    let layer = base + (lobe_set * env_u.levels + level) * env_u.faces + u32(fuv.x);
    return textureSampleLevel(env_maps, env_sampler, fuv.yz, layer, lod).rgb;
}

// The lobe-averaged radiance of set `lobe_set` at `roughness` around world direction d: the two
// levels around it, interpolated (exact where a material's roughness has its own level).
fn env_lobe(base: u32, lobe_set: u32, roughness: f32, d: vec3<f32>, lod: f32) -> vec3<f32> {
    if env_u.mode == 4u {
        return env_u.constant.rgb;
    }
    let m = normalize(vec3<f32>(dot(env_u.row0.xyz, d), dot(env_u.row1.xyz, d), dot(env_u.row2.xyz, d)));
    // The first level at or above `roughness` (the last when none is).
    var hi = 0u;
    for (var i = 1u; i < 16u; i++) {
        if i < env_u.levels && env_level_roughness(i - 1u) < roughness {
            hi = i;
        }
    }
    let rh = env_level_roughness(hi);
    if hi == 0u || rh <= roughness {
        return env_read(base, lobe_set, hi, m, lod);
    }
    let rl = env_level_roughness(hi - 1u);
    let t = clamp((roughness - rl) / max(rh - rl, 1e-6), 0.0, 1.0);
    return mix(env_read(base, lobe_set, hi - 1u, m, lod), env_read(base, lobe_set, hi, m, lod), t);
}

// The environment reflected by the specular lobe of `s` towards v (unit, to the viewer): GGX
// with the split-sum table, or Heidrich's Phong prefilter (f0·⟨n,r⟩·map) (`glossy`), and the
// smooth dielectric interface (`glass`). `dr` is the reflected direction's change across a
// pixel (radians), which picks the minification level. Kept apart because the ambient source
// occludes the glossy term (`source_radiance`), not the glass's.
// The uniform test stays apart from the per-fragment one: lavapipe (Debian 12, LLVM 15)
// crashes compiling a branch whose condition mixes the two around these texture reads.
struct EnvSpecular {
    glossy: vec3<f32>,
    glass: vec3<f32>,
}

fn env_specular(s: Surface, v: vec3<f32>, r: vec3<f32>, dr: f32, instance: u32) -> EnvSpecular {
    var out: EnvSpecular;
    out.glossy = vec3<f32>(0.0);
    out.glass = vec3<f32>(0.0);
    // The dynamic maps' layers for their instance (a layer offset: no branch on it), and the
    // reflected direction corrected for the map's parallax.
    let inst = env_instances[instance];
    let dynamic = inst.dynamic.z != 0u;
    let base = select(0u, inst.dynamic.x, dynamic);
    var rd = r;
    if dynamic {
        rd = env_parallax(s.p, r, inst.sphere.xyz, inst.dynamic.y);
    }
    let nv = dot(s.n, v);
    if env_u.specular != 0u {
        if env_has_glossy(s, nv) {
            out.glossy = env_glossy(s, nv, rd, dr, base) * (1.0 - s.delta);
        }
        let glass = (s.delta > 0.0) & (nv > 0.0);
        if glass {
            out.glass = env_glass(s, v, nv, rd, dr, base, instance) * s.delta;
        }
    }
    return out;
}

// The glossy term's lobe as a function of the direction ω it reflects, for the sky's
// specular occlusion (sky_occlusion.wgsl): (r, κ) for the weight exp(κ(⟨r,ω⟩ − 1)), r the
// view reflected about n. A von Mises–Fisher fit: GGX's half-vector distribution falls as
// exp(−θh²/α²) near its peak and the reflected direction turns by 2θh, so κ = 1/(2α²);
// Heidrich's Phong lobe cosⁿ about r is exp(n(cos − 1)) to the same order, κ = n. κ = 0
// where s has no glossy environment term (then every direction weighs the same).
fn env_occlusion_lobe(s: Surface) -> vec4<f32> {
    let v = safe_normalize(frame.camera_pos - s.p, s.n);
    let alpha = max(s.roughness * s.roughness, 1e-3);
    let k = select(phong_exponent(env_phong_roughness(s)), 0.5 / (alpha * alpha), env_reads_ggx(s));
    return vec4<f32>(reflect(-v, s.n), select(0.0, min(k, 1e4), env_has_glossy(s, dot(s.n, v))));
}

// Whether s has a glossy environment term seen at ⟨n,v⟩ = nv (not Lambert, some F0, facing
// the viewer).
fn env_has_glossy(s: Surface, nv: f32) -> bool {
    return (s.model != 1u) & any(s.f0 > vec3<f32>(0.0)) & (nv > 0.0);
}

// Whether the glossy term of s reads the GGX maps: the microfacet models (pbr,
// torrance-sparrow, cook-torrance, ward), or every model under `--env-prefilter ggx`.
fn env_reads_ggx(s: Surface) -> bool {
    return (env_u.prefilter == 2u) | ((env_u.prefilter == 0u) & ((s.model == 0u) | (s.model >= 4u)));
}

// The roughness the Phong maps are read at: Blinn-Phong as the Phong lobe of a quarter of its
// exponent.
fn env_phong_roughness(s: Surface) -> f32 {
    if s.model == 3u {
        let e = phong_exponent(s.roughness) / 4.0;
        return pow(2.0 / (max(e, 1.0) + 2.0), 0.25);
    }
    return s.roughness;
}

// The smooth dielectric interface (Heidrich §8.3.1, §8.3.3 with one interface): Fresnel-
// weighted mirror reflection plus the refracted direction looked up in the same maps, tinted
// by the base colour. One interface: the ray is not followed out of the object again.
fn env_glass(s: Surface, v: vec3<f32>, nv: f32, r: vec3<f32>, dr: f32, base: u32, instance: u32) -> vec3<f32> {
    let lod = clamp(log2(max(dr, 1e-8) / max(env_u.texel_angle, 1e-8)), 0.0, max(env_u.mips - 1.0, 0.0));
    let f1 = fresnel_dielectric(nv, s.ior);
    var t = refract(-v, s.n, 1.0 / s.ior);
    if env_u.refraction == 2u {
        t = env_exit(s, t, instance);
    }
    // A thin-walled sheet: its two faces' reflections, and light straight through (`select`:
    // no branch on the material's flag, as above).
    let thin = s.thin != 0u;
    let f = select(f1, 2.0 * f1 / (1.0 + f1), thin);
    t = select(t, -v, thin);
    // The object with a geometry light field: the baked exit direction and throughput of the
    // camera's ray (the view ray through this fragment), its map read unfiltered.
    let field = env_field_lookup(frame.camera_pos, safe_normalize(s.p - frame.camera_pos, -v));
    let use_field = (env_u.field.x == instance + 1u) & (env_u.field.w == 0u) & !thin;
    t = select(t, field.xyz, use_field);
    let through = select(1.0 - f, field.w, use_field);
    let reflected = env_lobe(base, env_u.ggx_set, s.roughness, r, lod);
    let refracted = env_lobe(base, env_u.ggx_set, s.roughness, safe_normalize(t, -v), select(lod, 0.0, use_field));
    return reflected * f + s.tint * refracted * through;
}

// Distance impostors (Szirmay-Kalos et al. 2005): the direction from the dynamic map's centre
// c to where the ray p + t·r meets the surroundings. A map seen from c, looked up as if from p,
// shows near things misplaced. The ray is searched on a geometric ladder of distances for the
// first point beyond the surface the distance map records in its direction, then refined by
// two secant steps; no crossing means the sky (direction r). Fixed-point steps from the
// centre's view fail where that view sees the sky and p's ray meets something near (a floor's
// far edge).
const ENV_MARCH_STEPS: u32 = 32u;
fn env_map_distance(d: vec3<f32>, layer: u32) -> f32 {
    let m = normalize(vec3<f32>(dot(env_u.row0.xyz, d), dot(env_u.row1.xyz, d), dot(env_u.row2.xyz, d)));
    // The map holds inverse distances (0: the sky).
    return 1.0 / max(env_read(layer, 0u, 0u, m, 0.0).r, 1e-4);
}

// How far beyond the recorded surface p + t·r lies (> 0: behind it).
fn env_beyond(p: vec3<f32>, r: vec3<f32>, t: f32, c: vec3<f32>, layer: u32) -> f32 {
    let x = p + r * t - c;
    return length(x) - env_map_distance(safe_normalize(x, r), layer);
}

// The maps are centred on c; their inverse distances start at `layer`.
fn env_parallax(p: vec3<f32>, r: vec3<f32>, c: vec3<f32>, layer: u32) -> vec3<f32> {
    var t0 = 0.0;
    var f0 = env_beyond(p, r, 0.0, c, layer);
    var t1 = 0.0;
    var f1 = f0;
    var hit = false;
    for (var i = 0u; i < ENV_MARCH_STEPS; i++) {
        // 0.01 to 1000 scene units, a factor 1.45 a step.
        let t = 0.01 * pow(1e5, f32(i) / f32(ENV_MARCH_STEPS - 1u));
        let f = env_beyond(p, r, t, c, layer);
        if f >= 0.0 && f0 < 0.0 {
            t1 = t;
            f1 = f;
            hit = true;
            break;
        }
        t0 = t;
        f0 = f;
    }
    if !hit {
        return r;
    }
    for (var k = 0u; k < 4u; k++) {
        let t = t0 + (t1 - t0) * (-f0) / max(f1 - f0, 1e-6);
        let f = env_beyond(p, r, t, c, layer);
        if f >= 0.0 {
            t1 = t;
            f1 = f;
        } else {
            t0 = t;
            f0 = f;
        }
    }
    let t = t0 + (t1 - t0) * (-f0) / max(f1 - f0, 1e-6);
    return safe_normalize(p + r * t - c, r);
}

// The second interface (Heidrich §8.3.3, two interfaces): the refracted ray t crosses the
// instance's bounding sphere from s.p and refracts out there (total internal reflection:
// reflected back in, and taken as leaving, a single bounce being all this follows).
fn env_exit(s: Surface, t: vec3<f32>, instance: u32) -> vec3<f32> {
    let sphere = env_instances[instance].sphere;
    let c = sphere.xyz;
    let rr = sphere.w;
    // The far intersection of p + k·t with the sphere (p lies on or inside it).
    let q = s.p - c;
    let b = dot(q, t);
    let disc = max(b * b - (dot(q, q) - rr * rr), 0.0);
    let k = -b + sqrt(disc);
    let n2 = safe_normalize(q + t * k, -t);
    let out = refract(t, -n2, s.ior);
    let tir = dot(out, out) < 1e-6;
    return select(safe_normalize(out, t), reflect(t, -n2), tir);
}

// E/π of the irradiance map around world direction n (Heidrich Eq 8.13).
fn env_irradiance(n: vec3<f32>) -> vec3<f32> {
    let m = normalize(vec3<f32>(dot(env_u.row0.xyz, n), dot(env_u.row1.xyz, n), dot(env_u.row2.xyz, n)));
    let fuv = env_face_uv(m);
    let layer = env_u.irradiance_layer + u32(fuv.x);
    return textureSampleLevel(env_maps, env_sampler, fuv.yz, layer, 0.0).rgb;
}

fn env_glossy(s: Surface, nv: f32, r: vec3<f32>, dr: f32, base: u32) -> vec3<f32> {
    let lod = clamp(log2(max(dr, 1e-8) / max(env_u.texel_angle, 1e-8)), 0.0, max(env_u.mips - 1.0, 0.0));
    var out = vec3<f32>(0.0);
    if env_reads_ggx(s) {
        let l = env_lobe(base, env_u.ggx_set, s.roughness, r, lod);
        let ab = env_split_sum(nv, s.roughness);
        // The table integrates Schlick's Fresnel: a measured metal scales by the exact
        // conductor's ratio to it at the view angle (exact for a mirror, where the lobe sees
        // only that angle). `select`, not a branch on the material's flag (lavapipe, above).
        let ratio = surface_fresnel(s, nv) / max(schlick(nv, s.f0), vec3<f32>(1e-4));
        out = l * (s.f0 * ab.x + ab.y) * select(vec3<f32>(1.0), ratio, s.conductor != 0u);
    } else {
        let l = env_lobe(base, env_u.phong_set, env_phong_roughness(s), r, lod);
        out = s.f0 * l * max(dot(s.n, r), 0.0);
    }
    return out;
}
