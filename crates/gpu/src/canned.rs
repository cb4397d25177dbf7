//! Canned light sources on the GPU (Heidrich 1999 §7.2.2): a light slab drawn as its (u,v)
//! grid points, each a spot light of intensity A (the cell's area) × cos θ' (cutoff 90°,
//! exponent 1, inverse-square fall-off) modulated by a projective texture, the grid point's
//! (s,t) slice, looked up bilinearly (`slab_irradiance` in `common.wgsl`). The slices are the
//! layers of an `Rgba16Float` array (frame binding 17, filtered by binding 18); several
//! canned lights share it, each from its first layer, their slices in its top-left corner.
//!
//! Two schemes ([`CannedPasses`]): one additive pass per grid point (kind 5; the seed's
//! N_u × N_v passes) or one pass whose shader sums every grid point (kind 6). Shadows: one
//! cube of shadow maps at the window's centre for the whole slab ("a shadow map per group of
//! points", §7.2.3), shared by every pass.
//!
//! Light record fields (`GpuLight`): position = the window's centre, direction = its normal,
//! edge_u/edge_v = its unit axes, cascade_ends = (half u, half v, far half s, far half t),
//! area_offset = the far plane's distance (0: at infinity), intensity = the cell area,
//! profile = the grid point (kind 5), two_sided = N_u | N_v << 16, attenuation = the slab's
//! first layer in the array, cos_inner/cos_outer = its N_s/N_t.

use crate::raster::{CannedLight, CannedPasses};
use crate::uniforms::GpuLight;
use lightlab_core::light_slab::Far;

/// The light records of `c`, its slices from layer `first`: N_u × N_v of kind 5, or one of
/// kind 6.
pub fn gpu_lights(c: &CannedLight, first: u32) -> Vec<GpuLight> {
    let s = &*c.slab;
    let base = GpuLight {
        position: s.centre.to_array(),
        direction: s.normal().to_array(),
        color: [1.0; 3],
        intensity: s.cell_area(),
        edge_u: s.u_axis.to_array(),
        edge_v: s.v_axis.to_array(),
        cascade_ends: [s.half.x, s.half.y, s.far_half.x, s.far_half.y],
        area_offset: match s.far {
            Far::Plane(d) => d,
            Far::Infinity => 0.0,
        },
        two_sided: s.n_uv[0] as u32 | (s.n_uv[1] as u32) << 16,
        attenuation: first,
        cos_inner: s.n_st[0] as f32,
        cos_outer: s.n_st[1] as f32,
        ..Default::default()
    };
    match c.passes {
        CannedPasses::Array => vec![GpuLight { kind: 6, ..base }],
        CannedPasses::PerPoint => (0..s.n_uv[0] * s.n_uv[1])
            .map(|layer| GpuLight {
                kind: 5,
                profile: layer as u32,
                ..base
            })
            .collect(),
    }
}

/// The layer each canned light's slices start from, and the layers in all.
pub fn first_layers(lights: &[CannedLight]) -> (Vec<u32>, u32) {
    let mut next = 0;
    let firsts = lights
        .iter()
        .map(|c| {
            let first = next;
            next += (c.slab.n_uv[0] * c.slab.n_uv[1]) as u32;
            first
        })
        .collect();
    (firsts, next)
}

/// The canned lights' (s,t) slices as the layers of an `Rgba16Float` array (light k's grid
/// point iu · N_v + iv at its first layer plus that, s along x, in the top-left N_s × N_t
/// texels of an array as large as the largest slice) and their bilinear, clamping sampler
/// (`resources::upload_array`); one black layer without a canned light.
pub fn slab_texture(
    ctx: &crate::GpuContext,
    lights: &[CannedLight],
) -> (wgpu::TextureView, wgpu::Sampler) {
    let (firsts, layers) = first_layers(lights);
    let size = lights.iter().fold([1u32, 1u32], |m, c| {
        [
            m[0].max(c.slab.n_st[0] as u32),
            m[1].max(c.slab.n_st[1] as u32),
        ]
    });
    let width = size[0] as usize;
    crate::resources::upload_array(ctx, size, layers.max(1), |layer, texels| {
        let Some(k) = firsts.iter().rposition(|&f| f <= layer) else {
            return;
        };
        let s = &*lights[k].slab;
        let point = (layer - firsts[k]) as usize;
        if point >= s.n_uv[0] * s.n_uv[1] {
            return;
        }
        let (iu, iv) = (point / s.n_uv[1], point % s.n_uv[1]);
        for it in 0..s.n_st[1] {
            for is in 0..s.n_st[0] {
                let l = s.sample(iu, iv, is, it);
                let k = (it * width + is) * 4;
                texels[k..k + 3].copy_from_slice(&l.to_array().map(half::f16::from_f32));
            }
        }
    })
}
