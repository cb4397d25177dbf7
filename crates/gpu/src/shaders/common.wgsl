// Shared GPU-visible structs and functions of lightlab's real-time techniques. Every technique's
// WGSL file is compiled as this file followed by its own. The Rust twins of the structs live in
// `crates/gpu/src/uniforms.rs` and are checked against naga's layout of this file in a test.

const PI: f32 = 3.14159265358979;

struct FrameUniforms {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    camera_pos: vec3<f32>,
    exposure: f32,
    viewport: vec2<f32>,
    light_count: u32,
    // 0 none / stencil, 1 shadow map (depth compare), 2 Heidrich's linear-depth comparison.
    shadow_mode: u32,
    // Irradiance as 9 SH coefficients (RGB in xyz): E(n) = Σ c_k·Y_k(n).
    ambient_sh: array<vec4<f32>, 9>,
    // PCF kernel half-width in texels (0 = one bilinear comparison).
    pcf_radius: i32,
    // Normal-offset bias in shadow-map texels.
    normal_offset: f32,
    // Heidrich variant: bias on the normalised linear depth.
    linear_bias: f32,
    shadow_size: f32,
    // Wind sway (lightlab_core::wind::Wind::uniform).
    wind_a: vec4<f32>,
    wind_b: vec4<f32>,
    // Fragments with n·x + d < 0 are discarded (a planar mirror's reflected view); zero: none.
    clip_plane: vec4<f32>,
    // Normal maps: 0 box-mipped, 1 Toksvig-widened (variance in alpha), 2 finest level only.
    normal_filter: u32,
    // 1: Torrance–Sparrow and Banks materials read their lookup tables (brdf_tables.rs).
    brdf_tables: u32,
    _pad1: u32,
    _pad2: u32,
}

// The light-map source's reads: 1 bilinear, 2 bicubic, +4 directional; E/π pages (directional
// page k is layer pages + k); the page size in texels.
struct LightmapUniforms {
    mode: u32,
    pages: u32,
    size: vec2<f32>,
}

// The SH source: 1 textured (coefficients 4j..4j+3 in layer page·layers + j), 2 per vertex,
// 3 compressed (index map + relit representatives); vec4s per transfer vector (⌈bands²/4⌉);
// incident-light sample points per group, groups being instances (per_object 1) or the scene;
// compressed reads (0 nearest, 1 bilinear of relit representatives, 2 Fuchs's 4-tap); the
// representatives; where the light coefficients start in sh_light; the number of groups.
struct ShUniforms {
    mode: u32,
    layers: u32,
    points: u32,
    per_object: u32,
    read_filter: u32,
    reps: u32,
    coeff_base: u32,
    groups: u32,
}

// The volume source (ambient_lpv.wgsl): 1 Kaplanyan (irradiance) / 2 WPI (point evaluation at
// −n), cells per axis, 1 = indirect light only, damping [cells], cascades, and per cascade
// (finest first) origin (xyz) and cell size (w).
struct LpvAmbientUniforms {
    mode: u32,
    size: f32,
    indirect_only: u32,
    damping: f32,
    cascades: u32,
    // Sub-cell occlusion of the volume's light: the radius [m] within which the sky's depth maps
    // count a surface as occluding (0: off).
    occlusion_radius: f32,
    // The near field gathered from the last light's RSM: samples per pixel (0: off).
    near_samples: u32,
    // Its light's share of the volume's light, which it replaces on thin translucent surfaces.
    near_share: f32,
    grids: array<vec4<f32>, 4>,
    // lpv-faithful's composite (App. B): the sun's direction of travel (w = 1: on), its
    // irradiance (w: shadow bias in RSM depth); the view-projection of the RSM it or the near
    // field reads.
    sun_dir: vec4<f32>,
    sun_e: vec4<f32>,
    rsm_view_proj: mat4x4<f32>,
    // The near field's light: its direction of travel, w the RSM's texel side [m].
    near: vec4<f32>,
}

// One light. kind: 0 point, 1 spot, 2 directional, 3 area (a Lambertian rectangle: centre
// position − area_offset·direction, normal direction, corners centre ± edge_u ± edge_v,
// radiance color, area intensity), 4 goniometric (a measured lamp: a point light whose
// intensity is scaled by the candela towards each direction, `profile_candela`; edge_u is
// its C0 axis), 5 one grid point of a canned light, 6 a whole canned light (`canned.rs`: the
// fields' meanings). Spot cones as cosines.
// attenuation: 0 inverse square (glTF range window), 1..4 Fuchs (2005) §4.1 atten₁..atten₄.
struct GpuLight {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    // Radius r of the attenuation functions and of culling; 0 = infinite.
    range: f32,
    color: vec3<f32>,
    intensity: f32,
    cos_inner: f32,
    cos_outer: f32,
    // Normalisation of the Fuchs attenuation functions (see `lights.rs`).
    atten_scale: f32,
    attenuation: u32,
    // First shadow view of this light and how many (spot 1, point 6, directional cascades).
    shadow_first: u32,
    shadow_count: u32,
    // 1: lights the diffuse term only (the environment's sun, whose specular part the
    // environment map holds).
    diffuse_only: u32,
    // Kind 4: the layer of `light_profiles` holding its candela table.
    profile: u32,
    // View-space distances ending the cascades of a directional light.
    cascade_ends: vec4<f32>,
    edge_u: vec3<f32>,
    area_offset: f32,
    edge_v: vec3<f32>,
    two_sided: u32,
}

// One rendered shadow-map layer.
struct ShadowView {
    view_proj: mat4x4<f32>,
    // World size of one texel: at unit distance (perspective) or everywhere (orthographic).
    texel_scale: f32,
    ortho: u32,
    // Far distance of a perspective view (normalises Heidrich's linear depth).
    far: f32,
    // Near distance of a perspective view (linearises its depth for soft shadows).
    near: f32,
}

// Per-pass constants, addressed with a dynamic offset.
struct PassUniforms {
    light_index: u32,
    shadow_view: u32,
    _pad0: u32,
    _pad1: u32,
}

struct GpuMaterial {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    metallic: f32,
    roughness: f32,
    specular: f32,
    normal_scale: f32,
    // < 0: opaque; otherwise alpha-test threshold.
    alpha_cutoff: f32,
    transmission: f32,
    // 0 pbr, 1 lambert, 2 phong, 3 blinn-phong, 4 torrance-sparrow, 5 cook-torrance, 6 ward,
    // 7 banks, 8 lafortune (gpu_scene::gpu_material).
    model: u32,
    // bit 0 base colour, 1 metallic-roughness, 2 normal, 3 emissive texture; bit 4 double-sided;
    // bit 5 translucency map.
    flags: u32,
    // 1 bit per texture (same order; bit 5 the translucency map): which UV set.
    uv_sets: u32,
    // Wind sway weight of the material's vertices (lightlab_core::wind).
    sway: f32,
    // KHR_materials_ior and the KHR_materials_transmission factor (a smooth dielectric
    // interface; env.wgsl refracts through it).
    ior: f32,
    spec_transmission: f32,
    // KHR_materials_volume thickness: 0 = thin-walled glass (a sheet: straight through).
    thickness: f32,
    // KHR_texture_transform of texture i (bit order of `flags`): rows 2i and 2i + 1 of the
    // 2×3 matrix, uv' = (dot(row0.xy, uv) + row0.z, dot(row1.xy, uv) + row1.z).
    uv_transform: array<vec4<f32>, 12>,
    // A measured metal (Material::conductor): the complex index η + ik per channel, w = 1 when
    // present (the metallic part's Fresnel is then exact instead of Schlick's).
    conductor_eta: vec4<f32>,
    conductor_k: vec4<f32>,
    // KHR_materials_anisotropy: (strength, cos rotation, sin rotation, 0).
    anisotropy: vec4<f32>,
    // The Lafortune lobe's (C_x, C_y, C_z, 0).
    lafortune: vec4<f32>,
    // Lookup tables (brdf_tables.rs): scales of the two tables, first layer, 1 when it has them.
    tables: vec4<f32>,
}

// The wind displacement of a world-space vertex (lightlab_core::wind::Wind::sway): `a` =
// (direction × amplitude, frequency), `b` = (wavelength, time, ground, height).
fn sway(p: vec3<f32>, weight: f32, a: vec4<f32>, b: vec4<f32>) -> vec3<f32> {
    let amp = length(a.xyz);
    if weight == 0.0 || amp == 0.0 {
        return p;
    }
    let d = a.xyz / amp;
    let h = clamp((p.y - b.z) / b.w, 0.0, 1.0);
    let phi = 6.2831853 * (a.w * b.y - dot(d, p) / b.x);
    let g = sin(phi) + 0.3 * sin(2.7 * phi + 1.3 * p.x + 0.7 * p.z);
    return p + a.xyz * (weight * h * h * g);
}

// What the lighting passes need of a visible surface point.
struct Surface {
    p: vec3<f32>,
    // Shading normal and geometric normal, both turned towards the viewer.
    n: vec3<f32>,
    ng: vec3<f32>,
    // Diffuse reflectance (1 − metallic)·base.
    diffuse: vec3<f32>,
    // Specular reflectance (F0) and the dielectric F0 that scales the diffuse lobe.
    f0: vec3<f32>,
    f0d: f32,
    roughness: f32,
    model: u32,
    transmission: f32,
    // Weight of the smooth dielectric interface (glass), its index and its tint (the base
    // colour); the other terms are scaled by 1 − delta (as the path tracer's BSDF).
    delta: f32,
    ior: f32,
    tint: vec3<f32>,
    // Thin-walled glass (1): transmits straight through, reflects as a sheet.
    thin: u32,
    // A measured metal (1) with its complex index and metallic × base colour; its Fresnel is
    // (1 − metallic)·Schlick(c, f0d) + metal·F_conductor(c). 0 where unknown (the deferred
    // path's G-buffer does not carry it: Schlick with f0 there).
    conductor: u32,
    metallic: f32,
    metal: vec3<f32>,
    eta: vec3<f32>,
    k: vec3<f32>,
    // The anisotropy direction (unit, orthogonal to n; zero where the model reads none) and
    // the model's lobe parameters: Ward (strength, 0, 0), Lafortune (C_x, C_y, C_z).
    t: vec3<f32>,
    lobe: vec3<f32>,
    // The material's lookup tables (GpuMaterial::tables) when the frame reads them; w = 0: the
    // formulas.
    table: vec4<f32>,
}

// Two unit vectors completing n to an orthonormal frame (Duff et al. 2017; the same as
// lightlab_core::sampling::orthonormal_basis).
fn orthonormal_basis(n: vec3<f32>) -> mat2x3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return mat2x3<f32>(
        vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3<f32>(b, sign + n.y * n.y * a, -n.y),
    );
}

// Whether the model reads the tangent frame (ward, banks, lafortune: BrdfModel::uses_tangent).
fn uses_tangent(model: u32) -> bool {
    return model >= 6u && model <= 8u;
}

// W(m) = ∫₀^{π/2} sinᵐ (lightlab_core::brdf::wallis): the gamma ratio's asymptotic series once
// x = m/2 ≥ 32, reached by its recurrence.
fn wallis(m: f32) -> f32 {
    var x = m * 0.5;
    var scale = 1.0;
    for (var i = 0; i < 64 && x < 32.0; i++) {
        scale *= (x + 1.0) / (x + 0.5);
        x += 1.0;
    }
    let y = 1.0 / x;
    let series = 1.0 - y / 8.0 + y * y / 128.0 + 5.0 * y * y * y / 1024.0;
    return 0.5 * sqrt(PI) * scale * series / sqrt(x);
}

// Banks's lobe normalisation 1/(4·W(n+2)) (lightlab_core::brdf::Banks::normalization).
fn banks_normalization(e: f32) -> f32 {
    return 1.0 / (4.0 * wallis(e + 2.0));
}

// The anisotropic lobes (ward, banks, lafortune) of brdf_cos, without the cosine; `b` the
// bitangent n × t.
fn tangent_lobe(s: Surface, v: vec3<f32>, l: vec3<f32>, nv: f32, nl: f32) -> vec3<f32> {
    let b = cross(s.n, s.t);
    if s.model == 6u {
        // Ward's elliptical Gaussian: α_t = mix(α, 1, strength²) along t, α_b = α, × F0.
        let a = max(s.roughness * s.roughness, 1e-3);
        let h = normalize(v + l);
        let hn = max(dot(s.n, h), 1e-6);
        // Isotropic where the surface has no tangent.
        var ax = a;
        var e = (1.0 - hn * hn) / (a * a);
        if dot(s.t, s.t) > 0.5 {
            ax = a + (1.0 - a) * s.lobe.x * s.lobe.x;
            let ht = dot(h, s.t) / ax;
            let hb = dot(h, b) / a;
            e = ht * ht + hb * hb;
        }
        return s.f0 * (exp(-e / (hn * hn)) / (4.0 * PI * ax * a * sqrt(nl * nv)));
    }
    let e = phong_exponent(s.roughness);
    if s.model == 7u {
        // Banks: the specular term of the fibre (the diffuse one is in brdf_cos).
        let a = dot(l, s.t);
        let c = dot(v, s.t);
        let d = sqrt(max(1.0 - a * a, 0.0)) * sqrt(max(1.0 - c * c, 0.0)) - a * c;
        return s.f0 * (banks_normalization(e) * pow(max(d, 0.0), e));
    }
    // Lafortune's generalised cosine lobe, Lewis-normalised.
    let d = s.lobe.x * dot(l, s.t) * dot(v, s.t) + s.lobe.y * dot(l, b) * dot(v, b)
        + s.lobe.z * nl * nv;
    return s.f0 * ((e + 2.0) / (2.0 * PI) * pow(max(d, 0.0), e));
}

fn sh9(n: vec3<f32>) -> array<f32, 9> {
    return array<f32, 9>(
        0.282094792,
        0.488602512 * n.y,
        0.488602512 * n.z,
        0.488602512 * n.x,
        1.092548431 * n.x * n.y,
        1.092548431 * n.y * n.z,
        0.315391565 * (3.0 * n.z * n.z - 1.0),
        1.092548431 * n.x * n.z,
        0.546274215 * (n.x * n.x - n.y * n.y),
    );
}

fn schlick(c: f32, f0: vec3<f32>) -> vec3<f32> {
    let m = pow(1.0 - clamp(c, 0.0, 1.0), 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * m;
}

// Toksvig's (2005) filter in roughness terms. Normals spread with per-axis slope variance σ²
// (Toksvig: the mean of unit normals has length r = 1/(1 + σ²)) widen a lobe over the
// half-vector of RMS slope α = roughness² (Beckmann, GGX, Blinn-Phong as e = 2/α² − 2, Ward) to
// α'² = α² + 2σ². Lobes about the mirror direction (Phong, Banks, Lafortune) move twice as fast
// as the normal, so their exponent widens four times as much: 1/e' = 1/e + 4σ², α'² = α² + 8σ².
fn widened_roughness(roughness: f32, var2: f32, model: u32) -> f32 {
    let k = select(2.0, 8.0, model == 2u || model == 7u || model == 8u);
    let a = roughness * roughness;
    return min(sqrt(sqrt(a * a + k * max(var2, 0.0))), 1.0);
}

// Phong / Blinn-Phong exponent of a roughness (as `BrdfModel::exponent`).
fn phong_exponent(roughness: f32) -> f32 {
    let a2 = max(pow(roughness * roughness, 2.0), 1e-6);
    return clamp(2.0 / a2 - 2.0, 1.0, 1e4);
}

fn ggx_lambda(c: f32, a: f32) -> f32 {
    let c2 = max(c * c, 1e-12);
    let t2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + sqrt(1.0 + a * a * t2));
}

// The diffuse part of the BRDF (constant in l): albedo·(1 − transmission)/π, less what the
// dielectric coat reflects at the view angle (model 0).
fn diffuse_coef(s: Surface, nv: f32) -> vec3<f32> {
    var kd = 1.0;
    if s.model == 0u && s.f0d > 0.0 {
        kd = 1.0 - schlick(nv, vec3<f32>(s.f0d)).x;
    }
    return s.diffuse * (kd * (1.0 - s.transmission) / PI);
}

// erfc(x) to 1.2e-7 relative (Numerical Recipes' Chebyshev fit; lightlab_core::brdf::erfc).
fn erfc_approx(x: f32) -> f32 {
    let z = abs(x);
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t * exp(-z * z - 1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418
        + t * (-0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587
        + t * (-0.82215223 + t * 0.17087277)))))))));
    return select(2.0 - r, r, x >= 0.0);
}

// Smith's Λ of a Beckmann surface of RMS slope m for a direction of cosine c
// (lightlab_core::brdf::Distribution::lambda).
fn beckmann_lambda(c: f32, m: f32) -> f32 {
    let c2 = clamp(c * c, 1e-12, 1.0);
    let tan = sqrt((1.0 - c2) / c2);
    if tan <= 0.0 {
        return 0.0;
    }
    let a = 1.0 / (m * tan);
    if a > 8.0 {
        return 0.0;
    }
    return 0.5 * (exp(-a * a) / (a * 1.7724539) - erfc_approx(a));
}

// Heidrich's lookup tables (brdf_tables.rs): TABLE_SIZE² layers sampled at i/(n − 1), read
// as the CPU reads them (four loads, bilinear). Bound by the raster passes only.
@group(0) @binding(19) var brdf_tables: texture_2d_array<f32>;

fn table_read(layer: i32, x: f32, y: f32) -> vec4<f32> {
    let n = i32(textureDimensions(brdf_tables).x);
    let fx = clamp(x, 0.0, 1.0) * f32(n - 1);
    let fy = clamp(y, 0.0, 1.0) * f32(n - 1);
    let x0 = min(i32(fx), n - 1);
    let y0 = min(i32(fy), n - 1);
    let x1 = min(x0 + 1, n - 1);
    let y1 = min(y0 + 1, n - 1);
    let tx = fx - f32(x0);
    let ty = fy - f32(y0);
    let a = mix(textureLoad(brdf_tables, vec2<i32>(x0, y0), layer, 0), textureLoad(brdf_tables, vec2<i32>(x1, y0), layer, 0), tx);
    let b = mix(textureLoad(brdf_tables, vec2<i32>(x0, y1), layer, 0), textureLoad(brdf_tables, vec2<i32>(x1, y1), layer, 0), tx);
    return mix(a, b, ty);
}

// Torrance–Sparrow's specular f·⟨n,l⟩ from its tables (§5.1): T1(cos θ, √(1 − cos δ)) = F·D
// (RGB; rows by √(1 − cos δ), not cos δ: see brdf_tables.rs), T2(cos α, cos β) = G/(4 cos β).
fn torrance_sparrow_tables(s: Surface, v: vec3<f32>, l: vec3<f32>, nv: f32, nl: f32) -> vec3<f32> {
    let h = normalize(v + l);
    let layer = i32(s.table.z);
    let t1 = table_read(layer, dot(l, h), sqrt(max(1.0 - dot(s.n, h), 0.0))).rgb * s.table.x;
    let t2 = table_read(layer + 1, nl, nv).r * s.table.y;
    return t1 * t2;
}

// f(v, l)·⟨n,l⟩ for the front side, the same models as the path tracer (`trace::bsdf`).
fn brdf_cos(s: Surface, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    let nl = dot(s.n, l);
    let nv = dot(s.n, v);
    if nl <= 0.0 || nv <= 0.0 {
        return vec3<f32>(0.0);
    }
    var f = diffuse_coef(s, nv);
    if s.model == 7u {
        // Banks's diffuse term: ⟨n', l⟩ = √(1 − ⟨l,t⟩²).
        let a = dot(l, s.t);
        if s.table.w > 0.0 {
            // §5.2: one table over (⟨l,t⟩, ⟨v,t⟩): the diffuse factor and the specular term.
            let tb = table_read(i32(s.table.z), 0.5 * a + 0.5, 0.5 * dot(v, s.t) + 0.5);
            return (f * tb.r + s.f0 * (tb.g * s.table.y)) * nl;
        }
        f *= sqrt(max(1.0 - a * a, 0.0));
    }
    if s.model == 1u || all(s.f0 <= vec3<f32>(0.0)) {
        return f * nl;
    }
    if s.model == 0u {
        // The smooth lobe is 1 − delta of the BSDF; the glass interface is a delta lobe.
        let h = normalize(v + l);
        let a = max(s.roughness * s.roughness, 1e-3);
        let a2 = a * a;
        let nh = max(dot(s.n, h), 0.0);
        let dd = nh * nh * (a2 - 1.0) + 1.0;
        let d = a2 / (PI * dd * dd);
        let g = 1.0 / (1.0 + ggx_lambda(nv, a) + ggx_lambda(nl, a));
        f += surface_fresnel(s, dot(v, h)) * (d * g / (4.0 * nv * nl) * (1.0 - s.delta));
        // Frosted glass (roughness from trace::bsdf::ROUGH_INTERFACE): the interface's microfacet
        // reflection with the exact dielectric Fresnel; a smooth one is a delta lobe that only
        // the environment term sees.
        let frosted = select(0.0, s.delta, s.roughness >= 0.05 && s.thin == 0u);
        f += vec3<f32>(fresnel_dielectric(dot(v, h), s.ior) * d * g / (4.0 * nv * nl) * frosted);
    } else if s.model == 4u && s.table.w > 0.0 {
        f += torrance_sparrow_tables(s, v, l, nv, nl) / nl;
    } else if s.model == 4u || s.model == 5u {
        // Torrance–Sparrow (separable Smith G) and Cook–Torrance (V-groove G): Beckmann D of
        // RMS slope m = roughness², the material's Fresnel (trace::bsdf).
        let h = normalize(v + l);
        let m = max(s.roughness * s.roughness, 1e-3);
        let nh = max(dot(s.n, h), 1e-6);
        let c2 = nh * nh;
        let d = exp(-(1.0 - c2) / (c2 * m * m)) / (PI * m * m * c2 * c2);
        var g: f32;
        if s.model == 4u {
            g = 1.0 / ((1.0 + beckmann_lambda(nv, m)) * (1.0 + beckmann_lambda(nl, m)));
        } else {
            let vh = max(dot(v, h), 1e-6);
            g = clamp(min(2.0 * nh * nv / vh, 2.0 * nh * nl / vh), 0.0, 1.0);
        }
        f += surface_fresnel(s, dot(v, h)) * (d * g / (4.0 * nv * nl));
    } else if uses_tangent(s.model) {
        f += tangent_lobe(s, v, l, nv, nl);
    } else if s.model == 2u {
        let e = phong_exponent(s.roughness);
        let r = 2.0 * nv * s.n - v;
        f += s.f0 * ((e + 2.0) / (2.0 * PI) * pow(max(dot(r, l), 0.0), e));
    } else {
        let e = phong_exponent(s.roughness);
        let h = normalize(v + l);
        let norm = (e + 2.0) * (e + 4.0) / (8.0 * PI * (exp2(-e / 2.0) + e));
        f += s.f0 * (norm * pow(max(dot(s.n, h), 0.0), e));
    }
    return f * nl;
}

// Exact unpolarised Fresnel reflectance of a conductor of complex index eta + i·k per channel
// (lightlab_core::brdf::fresnel_conductor).
fn fresnel_conductor(c_in: f32, eta: vec3<f32>, k: vec3<f32>) -> vec3<f32> {
    let c = min(abs(c_in), 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - vec3<f32>(s2);
    let a2b2 = sqrt(t0 * t0 + 4.0 * eta * eta * k * k);
    let a = sqrt(max(0.5 * (a2b2 + t0), vec3<f32>(0.0)));
    let t1 = a2b2 + vec3<f32>(c2);
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2b2 + vec3<f32>(s2 * s2);
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5 * (rs + rp);
}

// The specular lobe's Fresnel reflectance at cosine c with the microfacet normal.
// `select`, not a branch on the material's flag (see env.wgsl on lavapipe).
fn surface_fresnel(s: Surface, c: f32) -> vec3<f32> {
    let measured = schlick(c, vec3<f32>(s.f0d)) * (1.0 - s.metallic) + s.metal * fresnel_conductor(c, s.eta, s.k);
    return select(schlick(c, s.f0), measured, s.conductor != 0u);
}

// Exact unpolarised Fresnel reflectance for cosine c and relative index eta = n_t / n_i
// (lightlab_core::brdf::fresnel_dielectric); 1 under total internal reflection.
fn fresnel_dielectric(c_in: f32, eta: f32) -> f32 {
    let c = min(abs(c_in), 1.0);
    let g2 = eta * eta + c * c - 1.0;
    var f = 1.0;
    if g2 >= 0.0 {
        let g = sqrt(g2);
        let a = (g - c) / (g + c);
        let b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
        f = 0.5 * a * a * (1.0 + b * b);
    }
    return f;
}

// Fuchs (2005) §4.1 attenuation functions of d/r; atten₃ clamps before squaring (erratum).
fn fuchs_attenuation(kind: u32, d: f32, r: f32) -> f32 {
    let x = d / r;
    switch kind {
        case 1u: {
            // atten₁ = min(1, 1/(b·d)), b = 0.5 m⁻¹ (see `lights.rs`)
            return min(1.0, 1.0 / (0.5 * d));
        }
        case 2u: {
            return max(1.0 - x, 0.0);
        }
        case 3u: {
            let t = max(1.0 - x, 0.0);
            return t * t;
        }
        default: {
            return max(1.0 - x * x, 0.0);
        }
    }
}

// Goniometric lights' candela tables (`photometric.rs`): layer `profile`, texel (i, j) at
// C = i·360°/width, γ = j·180°/(height − 1) in the light's frame (γ from its direction, C from
// its C0 axis edge_u towards direction × edge_u). Bound by the raster passes only.
@group(0) @binding(16) var light_profiles: texture_2d_array<f32>;

// Candela of a goniometric light towards unit direction `d` (from the light), bilinear.
fn profile_candela(li: GpuLight, d: vec3<f32>) -> f32 {
    return profile_lookup(li.profile, li.direction, li.edge_u, d);
}

// Layer `layer`'s candela towards unit `d`, for a light shining along `nadir` with C0 axis
// `c0` (unit, at right angles).
fn profile_lookup(layer: u32, nadir: vec3<f32>, c0: vec3<f32>, d: vec3<f32>) -> f32 {
    let z = -nadir;
    let x = c0;
    let y = cross(z, x);
    let gamma = acos(clamp(dot(d, nadir), -1.0, 1.0));
    var c = atan2(dot(d, y), dot(d, x));
    if c < 0.0 {
        c += 2.0 * PI;
    }
    let dims = textureDimensions(light_profiles);
    let fu = c / (2.0 * PI) * f32(dims.x);
    let fv = gamma / PI * f32(dims.y - 1u);
    let u0 = min(u32(floor(fu)), dims.x - 1u);
    let u1 = (u0 + 1u) % dims.x;
    let tu = clamp(fu - f32(u0), 0.0, 1.0);
    let v0 = min(u32(floor(fv)), dims.y - 2u);
    let tv = clamp(fv - f32(v0), 0.0, 1.0);
    let a00 = textureLoad(light_profiles, vec2<u32>(u0, v0), layer, 0).r;
    let a10 = textureLoad(light_profiles, vec2<u32>(u1, v0), layer, 0).r;
    let a01 = textureLoad(light_profiles, vec2<u32>(u0, v0 + 1u), layer, 0).r;
    let a11 = textureLoad(light_profiles, vec2<u32>(u1, v0 + 1u), layer, 0).r;
    return mix(mix(a00, a10, tu), mix(a01, a11, tu), tv);
}

// The canned lights' (s,t) slices, one layer per (u,v) grid point, light by light, each in
// the top-left N_s × N_t texels (`canned.rs`).
@group(0) @binding(17) var slab_slices: texture_2d_array<f32>;
@group(0) @binding(18) var slab_sampler: sampler;

// Grid point `layer` of a canned light: its position on the window.
fn slab_point(li: GpuLight, layer: u32) -> vec3<f32> {
    let nu = li.two_sided & 0xffffu;
    let nv = li.two_sided >> 16u;
    let iu = layer / nv;
    let iv = layer % nv;
    let a = (f32(iu) + 0.5) / f32(nu) * 2.0 - 1.0;
    let b = (f32(iv) + 0.5) / f32(nv) * 2.0 - 1.0;
    return li.position + li.edge_u * (a * li.cascade_ends.x) + li.edge_v * (b * li.cascade_ends.y);
}

// Irradiance at normal incidence (RGB) at `x` from grid point `point` at `p` (§7.2.2, Eq 7.4):
// a spot light of intensity A·cos θ' (cutoff 90°, exponent 1) × its slice's radiance towards x.
fn slab_irradiance(li: GpuLight, p: vec3<f32>, point: u32, x: vec3<f32>) -> vec3<f32> {
    let d = x - p;
    let r2 = max(dot(d, d), 1e-12);
    let dn = dot(d, li.direction);
    if dn <= 0.0 {
        return vec3<f32>(0.0);
    }
    var st: vec2<f32>;
    if li.area_offset > 0.0 {
        // The far plane at distance area_offset: where the ray crosses it.
        let q = p + d * (li.area_offset / dn) - (li.position + li.direction * li.area_offset);
        st = vec2<f32>(dot(q, li.edge_u), dot(q, li.edge_v));
    } else {
        st = vec2<f32>(dot(d, li.edge_u), dot(d, li.edge_v)) / dn;
    }
    let uv = (st / li.cascade_ends.zw + 1.0) * 0.5;
    if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) {
        return vec3<f32>(0.0);
    }
    // The slab's N_s × N_t corner of the array, clamped to its edge samples' centres.
    let dims = vec2<f32>(textureDimensions(slab_slices));
    let n = vec2<f32>(li.cos_inner, li.cos_outer);
    let texel = clamp(uv * n, vec2<f32>(0.5), n - vec2<f32>(0.5));
    let l = textureSampleLevel(slab_slices, slab_sampler, texel / dims, li.attenuation + point, 0.0).rgb;
    let cos_p = dn * inverseSqrt(r2);
    return l * (li.intensity * cos_p / r2);
}

// Incident irradiance at normal incidence (RGB) and the unit direction to the light.
fn light_incidence(li: GpuLight, p: vec3<f32>) -> vec4<f32> {
    if li.kind == 2u {
        return vec4<f32>(li.intensity, 0.0, 0.0, 0.0);
    }
    let to = li.position - p;
    let d2 = max(dot(to, to), 1e-12);
    let d = sqrt(d2);
    var e = 0.0;
    if li.attenuation == 0u {
        var window = 1.0;
        if li.range > 0.0 {
            let q = d / li.range;
            let w = clamp(1.0 - q * q * q * q, 0.0, 1.0);
            window = w * w;
        }
        e = li.intensity * window / d2;
    } else {
        e = li.intensity * li.atten_scale * fuchs_attenuation(li.attenuation, d, max(li.range, 1e-6));
    }
    if li.kind == 1u {
        let cd = dot(li.direction, -to / d);
        let t = clamp((cd - li.cos_outer) / max(li.cos_inner - li.cos_outer, 1e-4), 0.0, 1.0);
        e *= t * t;
    }
    if li.kind == 4u {
        e *= profile_candela(li, -to / d);
    }
    return vec4<f32>(e, 0.0, 0.0, 0.0);
}

fn light_dir(li: GpuLight, p: vec3<f32>) -> vec3<f32> {
    if li.kind == 2u {
        return -li.direction;
    }
    return normalize(li.position - p);
}

// Irradiance at a point with normal n from a rectangle light of unit radiance whose centre is
// at `c` from the point: Lambert's polygon formula E = ½·Σᵢ θᵢ·(γ̂ᵢ·n) (θᵢ the angle each edge
// subtends, γ̂ᵢ its plane's normal), exact for a diffuse receiver, with the rectangle first
// clipped to the hemisphere above n (Sutherland–Hodgman: at most five vertices; room for
// eight, the most a receiver nearly in the emitter's plane can produce from rounding).
fn rect_irradiance(li: GpuLight, c: vec3<f32>, n: vec3<f32>) -> f32 {
    let q = array<vec3<f32>, 4>(
        c - li.edge_u - li.edge_v,
        c + li.edge_u - li.edge_v,
        c + li.edge_u + li.edge_v,
        c - li.edge_u + li.edge_v,
    );
    var o: array<vec3<f32>, 8>;
    var m = 0u;
    for (var i = 0u; i < 4u; i++) {
        let a = q[i];
        let b = q[(i + 1u) % 4u];
        let da = dot(a, n);
        let db = dot(b, n);
        if da >= 0.0 {
            o[m] = a;
            m++;
        }
        if (da >= 0.0) != (db >= 0.0) {
            o[m] = a + (b - a) * (da / (da - db));
            m++;
        }
    }
    if m < 3u {
        return 0.0;
    }
    var sum = 0.0;
    for (var i = 0u; i < m; i++) {
        let a = o[i];
        let b = o[(i + 1u) % m];
        let la = length(a);
        let lb = length(b);
        if la < 1e-9 || lb < 1e-9 {
            continue;
        }
        let cr = cross(a, b) / (la * lb);
        let sn = length(cr);
        if sn > 1e-9 {
            // atan2 keeps small angles (far lights) accurate, where acos of a dot would not.
            sum += atan2(sn, dot(a, b) / (la * lb)) * dot(cr / sn, n);
        }
    }
    return 0.5 * abs(sum);
}

// Radiance towards the viewer from an area light: diffuse reflection and transmission from
// the exact irradiance of the rectangle, specular from its centre as a point light of
// intensity L·A·cosθ (Lambertian).
fn shade_area(s: Surface, li: GpuLight, v: vec3<f32>) -> vec3<f32> {
    let c = li.position - li.direction * li.area_offset;
    if dot(s.p - c, li.direction) <= 0.0 && li.two_sided == 0u {
        return vec3<f32>(0.0);
    }
    let to = c - s.p;
    let d2 = max(dot(to, to), 1e-12);
    let l = to * inverseSqrt(d2);
    var out = vec3<f32>(0.0);
    let nv = dot(s.n, v);
    if nv > 0.0 {
        out += diffuse_coef(s, nv) * rect_irradiance(li, to, s.n);
        if dot(s.ng, l) > 0.0 {
            var spec = s;
            spec.diffuse = vec3<f32>(0.0);
            out += brdf_cos(spec, v, l) * (li.intensity * abs(dot(li.direction, l)) / d2);
        }
    }
    if s.transmission > 0.0 {
        // Thin diffuse transmission: light reaching the back side leaves towards the viewer.
        out += s.diffuse * (s.transmission / PI) * rect_irradiance(li, to, -s.n);
    }
    return out * li.color;
}

// Radiance towards the viewer from one light (visibility not included).
fn shade_light(s: Surface, li: GpuLight, v: vec3<f32>) -> vec3<f32> {
    if li.kind == 3u {
        return shade_area(s, li, v);
    }
    if li.kind == 5u {
        let p = slab_point(li, li.profile);
        return shade_from(s, li, v, normalize(p - s.p), slab_irradiance(li, p, li.profile, s.p));
    }
    if li.kind == 6u {
        var sum = vec3<f32>(0.0);
        let n = (li.two_sided & 0xffffu) * (li.two_sided >> 16u);
        for (var k = 0u; k < n; k++) {
            let p = slab_point(li, k);
            sum += shade_from(s, li, v, normalize(p - s.p), slab_irradiance(li, p, k, s.p));
        }
        return sum;
    }
    return shade_from(s, li, v, light_dir(li, s.p), li.color * light_incidence(li, s.p).x);
}

// Radiance towards the viewer from light arriving along unit `l` with irradiance `e` (RGB) at
// normal incidence.
fn shade_from(s: Surface, li: GpuLight, v: vec3<f32>, l: vec3<f32>, e: vec3<f32>) -> vec3<f32> {
    if max(e.x, max(e.y, e.z)) <= 0.0 {
        return vec3<f32>(0.0);
    }
    let ngl = dot(s.ng, l);
    var c = vec3<f32>(0.0);
    if ngl > 0.0 {
        // The environment's sun lights the diffuse term only (`select`: no branch on the
        // light's flag around the BRDF; see env.wgsl on lavapipe).
        let nl = max(dot(s.n, l), 0.0);
        let diffuse = select(vec3<f32>(0.0), diffuse_coef(s, dot(s.n, v)) * nl, dot(s.n, v) > 0.0);
        c = select(brdf_cos(s, v, l), diffuse, li.diffuse_only != 0u);
    } else if s.transmission > 0.0 {
        // Thin diffuse transmission: light from behind leaves towards the viewer.
        c = s.diffuse * (s.transmission / PI) * max(-dot(s.n, l), 0.0);
    }
    return c * e;
}

// `v` normalised, or `fallback` where `v` is (nearly) zero: opposed vertex normals, a flat
// grey normal-map texel or an edge-on derivative frame would otherwise normalise to NaN and
// spread through the frame.
fn safe_normalize(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l2 = dot(v, v);
    if l2 > 1e-24 {
        return normalize(v);
    }
    return fallback;
}
