// The viewer's display pass: linear HDR (the renderer's target) to the window, with exposure,
// the tone operators of lightlab-core (color.rs: clamp, Reinhard on luminance, Narkowicz's
// ACES fit) and the sRGB transfer function unless the target format encodes it.

struct Params {
    exposure: f32,
    // 0 clamp, 1 reinhard, 2 filmic
    tone: u32,
    // 1: write sRGB-encoded values (the target is a UNORM format without sRGB encoding)
    encode: u32,
    _pad: u32,
}

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: Params;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn filmic(x: f32) -> f32 {
    let y = max(x, 0.0);
    return clamp((y * (2.51 * y + 0.03)) / (y * (2.43 * y + 0.59) + 0.14), 0.0, 1.0);
}

fn srgb(x: f32) -> f32 {
    let y = clamp(x, 0.0, 1.0);
    if y <= 0.0031308 {
        return 12.92 * y;
    }
    return 1.055 * pow(y, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let dims = textureDimensions(hdr);
    let xy = min(vec2<u32>(p.xy), dims - vec2<u32>(1u));
    let c = textureLoad(hdr, xy, 0).rgb * params.exposure;
    var t: vec3<f32>;
    if params.tone == 1u {
        let l = dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
        t = select(vec3<f32>(0.0), clamp(c / (1.0 + l), vec3<f32>(0.0), vec3<f32>(1.0)), l > 0.0);
    } else if params.tone == 2u {
        t = vec3<f32>(filmic(c.r), filmic(c.g), filmic(c.b));
    } else {
        t = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    }
    if params.encode == 1u {
        t = vec3<f32>(srgb(t.r), srgb(t.g), srgb(t.b));
    }
    return vec4<f32>(t, 1.0);
}
