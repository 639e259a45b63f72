//! Render targets and the pass state every raster technique sets up the same way.

/// A single-sample 2-D texture of `size` (width, height) with one mip level. Takes the bare
/// device so that passes recorded on a caller's own device can use it too.
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&single_mip(label, size, format, usage))
}

/// A sampled single-mip 2-D texture of `size` (width, height) holding `data` (rows of texels,
/// tightly packed), as map data (depths, colours, derived maps) is uploaded.
pub fn texture_2d_with_data(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    data: &[u8],
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    let descriptor = single_mip(label, size, format, wgpu::TextureUsages::TEXTURE_BINDING);
    device.create_texture_with_data(
        queue,
        &descriptor,
        wgpu::util::TextureDataOrder::LayerMajor,
        data,
    )
}

fn single_mip(
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::TextureDescriptor<'_> {
    wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    }
}

/// The usual depth test: the nearest fragment wins and writes its depth.
pub fn nearest_depth(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// A colour attachment cleared to `clear` and stored.
pub fn cleared_attachment(
    view: &wgpu::TextureView,
    clear: wgpu::Color,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(clear),
            store: wgpu::StoreOp::Store,
        },
    })
}
