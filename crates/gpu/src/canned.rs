//! Canned light sources on the GPU (Heidrich 1999 §7.2.2): a light slab drawn as its (u,v)
//! grid points, each a spot light of intensity A (the cell's area) × cos θ' (cutoff 90°,
//! exponent 1, inverse-square fall-off) modulated by a projective texture, the grid point's
//! (s,t) slice, looked up bilinearly (`slab_irradiance` in `common.wgsl`). The slices are the
//! layers of an `Rgba16Float` array (frame binding 17, filtered by binding 18).
//!
//! Two schemes ([`CannedPasses`]): one additive pass per grid point (kind 5; the seed's
//! N_u × N_v passes) or one pass whose shader sums every grid point (kind 6). Shadows: one
//! cube of shadow maps at the window's centre for the whole slab ("a shadow map per group of
//! points", §7.2.3), shared by every pass.
//!
//! Light record fields (`GpuLight`): position = the window's centre, direction = its normal,
//! edge_u/edge_v = its unit axes, cascade_ends = (half u, half v, far half s, far half t),
//! area_offset = the far plane's distance (0: at infinity), intensity = the cell area,
//! profile = the grid point's layer (kind 5), two_sided = N_u | N_v << 16.

use crate::raster::{CannedLight, CannedPasses};
use crate::uniforms::GpuLight;
use lightlab_core::light_slab::{Far, LightSlab};

/// The light records of `c`: N_u × N_v of kind 5, or one of kind 6.
pub fn gpu_lights(c: &CannedLight) -> Vec<GpuLight> {
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

/// The slab's (s,t) slices as the layers of an `Rgba16Float` array (layer iu · N_v + iv, s
/// along x) and their bilinear, clamping sampler (`resources::upload_array`); black layers
/// without a slab.
pub fn slab_texture(
    ctx: &crate::GpuContext,
    slab: Option<&LightSlab>,
) -> (wgpu::TextureView, wgpu::Sampler) {
    let (size, layers) = match slab {
        None => ([1, 1], 1),
        Some(s) => (
            [s.n_st[0] as u32, s.n_st[1] as u32],
            (s.n_uv[0] * s.n_uv[1]) as u32,
        ),
    };
    crate::resources::upload_array(ctx, size, layers, |layer, texels| {
        let Some(s) = slab else { return };
        let layer = layer as usize;
        if layer >= s.n_uv[0] * s.n_uv[1] {
            return;
        }
        let (iu, iv) = (layer / s.n_uv[1], layer % s.n_uv[1]);
        for it in 0..s.n_st[1] {
            for is in 0..s.n_st[0] {
                let l = s.sample(iu, iv, is, it);
                let k = (it * s.n_st[0] + is) * 4;
                texels[k..k + 3].copy_from_slice(&l.to_array().map(half::f16::from_f32));
            }
        }
    })
}
