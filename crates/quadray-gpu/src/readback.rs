//! Copies textures back to the CPU, honouring wgpu's 256-byte row alignment.

use crate::{Gpu, GpuError};

/// Maps `buffer` for reading, waits (bounded), hands the bytes to `f`, and unmaps.
pub(crate) fn map_buffer<T>(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    what: &str,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T, GpuError> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait(what)?;
    rx.recv()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let view = slice.get_mapped_range();
    let out = f(&view);
    drop(view);
    buffer.unmap();
    Ok(out)
}

/// Reads mip `level` of a 2-D texture whose texels are `texel_bytes` wide, row by row, unpadded.
fn read_texture_bytes(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    level: u32,
    texel_bytes: u32,
) -> Result<Vec<u8>, GpuError> {
    let size = texture
        .size()
        .mip_level_size(level, wgpu::TextureDimension::D2);
    let row = size.width * texel_bytes;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: u64::from(padded) * u64::from(size.height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: level,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size.height),
            },
        },
        wgpu::Extent3d {
            depth_or_array_layers: 1,
            ..size
        },
    );
    gpu.queue.submit([encoder.finish()]);
    let what = format!(
        "the readback of mip {level} of a {}x{} texture",
        size.width, size.height
    );
    map_buffer(gpu, &buffer, &what, |bytes| {
        bytes
            .chunks(padded as usize)
            .flat_map(|r| &r[..row as usize])
            .copied()
            .collect()
    })
}

/// Reads a float texture (R32Float, Rg32Float or Rgba32Float: `channels` floats per texel).
pub fn read_texture_f32(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    level: u32,
    channels: u32,
) -> Result<Vec<f32>, GpuError> {
    let bytes = read_texture_bytes(gpu, texture, level, 4 * channels)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

/// Reads an Rgba8 texture.
pub fn read_texture_rgba8(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<u8>, GpuError> {
    read_texture_bytes(gpu, texture, 0, 4)
}

/// Copies a whole buffer (with COPY_SRC usage) back to the CPU.
pub fn read_buffer(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("buffer readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    gpu.queue.submit([encoder.finish()]);
    let what = format!("the readback of a {}-byte buffer", buffer.size());
    map_buffer(gpu, &staging, &what, <[u8]>::to_vec)
}
