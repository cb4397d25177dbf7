//! GPU resources every technique makes the same way: textures and their views, float arrays
//! uploaded as f16 layers, and the copy of a texture back to the CPU.

use crate::GpuContext;

/// A texture could not be read back (the device was lost or the mapping failed).
#[derive(Debug, thiserror::Error)]
#[error("GPU readback failed: {0}")]
pub struct ReadbackError(pub String);

/// A one-mip 2D texture of `layers` layers.
pub fn texture(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A layer count for a square array texture that the GL backend binds as an array: at least 2
/// and not a multiple of 6 (wgpu's GL backend chooses a texture's target when it is made, and
/// takes 1 layer for a 2D texture and a multiple of 6 square layers for a cube map).
pub fn array_layers(n: u32) -> u32 {
    let mut n = n.max(2);
    while n.is_multiple_of(6) {
        n += 1;
    }
    n
}

/// One layer of an array texture as a 2D view.
pub fn layer_view(t: &wgpu::Texture, layer: u32) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

/// The whole texture as a 2D array view.
pub fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// Write `data` (rows of `bytes_per_row` bytes) into the top-left `size` of layer `layer`.
pub fn write_layer(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    layer: u32,
    data: &[u8],
    bytes_per_row: u32,
    size: [u32; 2],
) {
    write_mip(ctx, tex, layer, 0, data, bytes_per_row, size);
}

/// Write `data` (rows of `bytes_per_row` bytes) into the top-left `size` of mip level `mip` of
/// layer `layer`.
pub fn write_mip(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    layer: u32,
    mip: u32,
    data: &[u8],
    bytes_per_row: u32,
    size: [u32; 2],
) {
    ctx.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: tex,
            mip_level: mip,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect: wgpu::TextureAspect::All,
        },
        data,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(bytes_per_row),
            rows_per_image: Some(size[1]),
        },
        wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: 1,
        },
    );
}

/// An Rgba16Float array texture of `layers` layers (at least two: GL decides a texture's target
/// at creation and makes a one-layer texture a plain 2D texture that cannot be bound as an
/// array), each filled by `fill(layer, texels)` from zero, and a clamping linear sampler.
pub fn upload_array(
    ctx: &GpuContext,
    size: [u32; 2],
    layers: u32,
    mut fill: impl FnMut(u32, &mut [half::f16]),
) -> (wgpu::TextureView, wgpu::Sampler) {
    let layers = layers.max(2);
    let tex = texture(
        &ctx.device,
        "light-maps",
        size[0],
        size[1],
        layers,
        wgpu::TextureFormat::Rgba16Float,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    let mut data = vec![half::f16::ZERO; (size[0] * size[1] * 4) as usize];
    for layer in 0..layers {
        data.fill(half::f16::ZERO);
        fill(layer, &mut data);
        write_layer(
            ctx,
            &tex,
            layer,
            bytemuck::cast_slice(&data),
            size[0] * 8,
            size,
        );
    }
    let view = tex.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("light-map"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    (view, sampler)
}

/// The most bytes one readback copy stages: frames larger than this are read in bands of rows
/// (wgpu's default buffer limit is 256 MiB; an 8192² Rgba16Float frame is 512 MiB).
pub const READBACK_BAND_BYTES: u64 = 64 << 20;

/// Copy a texture (tightly packed texels of `bpp` bytes, layers one after the other) to the
/// CPU. The texture needs `COPY_SRC` usage. Large textures are copied in bands of rows.
pub fn read_texture(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    bpp: u32,
) -> Result<Vec<u8>, ReadbackError> {
    let limit = ctx.device.limits().max_buffer_size.min(READBACK_BAND_BYTES);
    read_texture_in_bands(ctx, tex, bpp, limit)
}

/// [`read_texture`] with each copy staging at most `max_bytes` (at least one row).
pub fn read_texture_in_bands(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    bpp: u32,
    max_bytes: u64,
) -> Result<Vec<u8>, ReadbackError> {
    read_mip_in_bands(ctx, tex, 0, bpp, max_bytes)
}

/// Mip level `mip` of every layer, as [`read_texture`] reads level 0.
pub fn read_texture_mip(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    mip: u32,
    bpp: u32,
) -> Result<Vec<u8>, ReadbackError> {
    let limit = ctx.device.limits().max_buffer_size.min(READBACK_BAND_BYTES);
    read_mip_in_bands(ctx, tex, mip, bpp, limit)
}

fn read_mip_in_bands(
    ctx: &GpuContext,
    tex: &wgpu::Texture,
    mip: u32,
    bpp: u32,
    max_bytes: u64,
) -> Result<Vec<u8>, ReadbackError> {
    let layers = tex.depth_or_array_layers();
    let (w, h) = ((tex.width() >> mip).max(1), (tex.height() >> mip).max(1));
    let row = ((w * bpp).div_ceil(256) * 256) as u64;
    let band = (max_bytes / row).clamp(1, h as u64) as u32;
    let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: row * band as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut out = Vec::with_capacity(w as usize * h as usize * layers as usize * bpp as usize);
    for layer in 0..layers {
        let mut y0 = 0;
        while y0 < h {
            let rows = band.min(h - y0);
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            enc.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture: tex,
                    mip_level: mip,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: y0,
                        z: layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &buf,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row as u32),
                        rows_per_image: Some(rows),
                    },
                },
                wgpu::Extent3d {
                    width: w,
                    height: rows,
                    depth_or_array_layers: 1,
                },
            );
            ctx.queue.submit([enc.finish()]);
            let slice = buf.slice(..row * rows as u64);
            slice.map_async(wgpu::MapMode::Read, |_| {});
            crate::wait_idle(&ctx.device).map_err(|e| ReadbackError(e.to_string()))?;
            {
                let data = slice
                    .get_mapped_range()
                    .map_err(|e| ReadbackError(e.to_string()))?;
                for y in 0..rows as usize {
                    out.extend_from_slice(&data[y * row as usize..][..(w * bpp) as usize]);
                }
            }
            buf.unmap();
            y0 += rows;
        }
    }
    Ok(out)
}
