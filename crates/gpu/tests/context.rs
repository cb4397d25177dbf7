//! The GPU context works headless (lavapipe in CI) and runs a compute shader.

use wgpu::util::DeviceExt;

#[test]
fn compute_shader_round_trip() {
    let Some(ctx) = lightlab_gpu::test_context() else {
        return;
    };
    eprintln!("adapter: {ctx:?}");
    let input: Vec<u32> = (0..256).collect();
    let device = &ctx.device;
    let storage = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("data"),
        contents: bytemuck::cast_slice(&input),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: 256 * 4,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("square"),
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var<storage, read_write> data: array<u32>;\n\
             @compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
                 data[id.x] = data[id.x] * data[id.x];\n\
             }"
            .into(),
        ),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("square"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: storage.as_entire_binding(),
        }],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(4, 1, 1);
    }
    enc.copy_buffer_to_buffer(&storage, 0, &readback, 0, 256 * 4);
    ctx.queue.submit([enc.finish()]);
    readback
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    lightlab_gpu::wait_idle(device).expect("poll");
    let view = readback.slice(..).get_mapped_range().expect("mapped range");
    let out: Vec<u32> = bytemuck::cast_slice(&view[..]).to_vec();
    for (i, v) in out.iter().enumerate() {
        assert_eq!(*v, (i * i) as u32);
    }
}

/// Reading a texture back in bands of rows (frames larger than one staging buffer) gives the
/// same bytes as one copy, for a 2D array and a 3D texture, whatever the band size.
#[test]
fn banded_readback_equals_one_copy() {
    let Some(ctx) = lightlab_gpu::test_context() else {
        return;
    };
    use lightlab_gpu::resources::{read_texture, read_texture_in_bands};
    for (dim, layers) in [
        (wgpu::TextureDimension::D2, 3),
        (wgpu::TextureDimension::D3, 4),
    ] {
        let (w, h) = (37u32, 29u32);
        let tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("banded"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: dim,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let data: Vec<u8> = (0..w * h * layers * 4)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        ctx.queue.write_texture(
            tex.as_image_copy(),
            &data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 4),
                rows_per_image: Some(h),
            },
            tex.size(),
        );
        let whole = read_texture(&ctx, &tex, 4).unwrap();
        assert_eq!(whole, data, "{dim:?}");
        for max in [1, 256 * 3, 256 * 7 + 5, 1 << 20] {
            assert_eq!(
                read_texture_in_bands(&ctx, &tex, 4, max).unwrap(),
                data,
                "{dim:?} {max}"
            );
        }
    }
}
