//! The viewer's display pass shows exactly what `lightlab render` writes to PNG: the same
//! exposure, tone operators and sRGB encoding as `lightlab_core::color::to_srgb8`.

use glam::Vec3;
use lightlab_core::color::{ToneMap, to_srgb8};
use lightlab_gpu::test_context;
use lightlab_viewer::display::display_to_rgb8;
use wgpu::util::DeviceExt;

#[test]
fn display_pass_matches_the_cpu_tone_operators() {
    let Some(ctx) = test_context() else { return };
    let (w, h) = (64u32, 16u32);
    // A ramp over five decades of radiance, with coloured and black pixels.
    let px: Vec<Vec3> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let l = 10f32.powf(-3.0 + 5.0 * x as f32 / (w - 1) as f32);
            match y % 4 {
                0 => Vec3::splat(l),
                1 => Vec3::new(l, 0.3 * l, 0.05 * l),
                2 => Vec3::new(0.02 * l, 0.5 * l, l),
                _ => Vec3::ZERO,
            }
        })
        .collect();
    let halves: Vec<half::f16> = px
        .iter()
        .flat_map(|c| [c.x, c.y, c.z, 1.0])
        .map(half::f16::from_f32)
        .collect();
    let tex = ctx.device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some("hdr"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&halves),
    );
    let view = tex.create_view(&Default::default());
    for tone in [ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Filmic] {
        for exposure in [0.5f32, 2.0] {
            let gpu = display_to_rgb8(&ctx, &view, w, h, exposure, tone).expect("readback");
            let mut worst = 0;
            for (i, g) in gpu.iter().enumerate() {
                // The CPU side sees the same half-float values the GPU reads.
                let c = Vec3::from_array([0, 1, 2].map(|k| halves[4 * i + k].to_f32()));
                let cpu = to_srgb8(c, exposure, tone);
                for k in 0..3 {
                    worst = worst.max((g[k] as i32 - cpu[k] as i32).abs());
                }
            }
            // One step of 8-bit rounding; a missing or doubled sRGB encode, a wrong exposure
            // or operator differs by tens of steps.
            assert!(
                worst <= 1,
                "{tone:?} exposure {exposure}: worst difference {worst}"
            );
        }
    }
}
