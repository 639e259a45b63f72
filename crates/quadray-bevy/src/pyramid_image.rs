//! A Bevy depth-map image to the pyramid image the material traces: the first channel as the
//! GPU would sample it, quadray_displace's CPU builder, one R32Float mip per level.

use bevy::asset::RenderAssetUsages;
use bevy::image::{Image, TextureFormatPixelInfo};
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use quadray_displace::heightmap::{Convention, Fit, HeightMap, HeightMapError};
use quadray_displace::pyramid::Pyramid;
use std::path::Path;

/// Why a depth map cannot be traced.
#[derive(Debug, thiserror::Error)]
pub enum PyramidImageError {
    /// The image has no CPU-side data (e.g. a render target, or loaded for the GPU only).
    #[error("{name}: the image has no CPU-side data (load it with RenderAssetUsages::MAIN_WORLD)")]
    NoData {
        /// The asset.
        name: String,
    },
    /// A texel format this crate does not read.
    #[error(
        "{name}: texture format {format:?} is not a depth map this crate reads (8/16-bit unorm, 16-bit uint, 32-bit float)"
    )]
    Format {
        /// The asset.
        name: String,
        /// Its format.
        format: TextureFormat,
    },
    /// The data is shorter than the size says.
    #[error("{name}: {len} bytes for a {width}x{height} {format:?} image")]
    Truncated {
        /// The asset.
        name: String,
        /// Its format.
        format: TextureFormat,
        /// Bytes present.
        len: usize,
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
    },
    /// quadray_displace refused the values (size, NaN ...).
    #[error(transparent)]
    Map(#[from] HeightMapError),
}

/// The height field the material traces for a depth-map image: its first channel as a shader
/// sampling it reads it, 0 at the surface and 1 deepest, at the image's own size (any size is
/// traced exactly, no resampling). `name` names the asset in errors.
pub fn depth_map(name: &str, image: &Image) -> Result<HeightMap, PyramidImageError> {
    let values = first_channel(name, image)?;
    Ok(HeightMap::from_values(
        Path::new(name),
        image.width(),
        image.height(),
        &values,
        Convention::Depth,
        Fit::Exact,
    )?)
}

/// The pyramid image of a height field: the point pyramid of `quadray_displace` (mip 0 the map
/// padded to powers of two with depth 1, each mip above the minimum depth of the four below, down
/// to 1x1), in an R32Float texture that the material reads with `textureLoad`.
pub fn pyramid_image(map: &HeightMap) -> Image {
    let pyramid = Pyramid::build(map);
    let bytes: Vec<u8> = pyramid
        .levels
        .iter()
        .flat_map(|level| level.iter().flat_map(|d| d.to_le_bytes()))
        .collect();
    let (width, height) = pyramid.level_size(0);
    let mut out = Image::new_uninit(
        Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        TextureFormat::R32Float,
        RenderAssetUsages::RENDER_WORLD,
    );
    out.texture_descriptor.mip_level_count = pyramid.levels.len() as u32;
    out.data = Some(bytes);
    out
}

/// The first channel of every texel, row-major, as a shader sampling the image would read it
/// (sRGB formats decoded, unorm in [0, 1], 16-bit uint over 65535 as Bevy stores 16-bit PNGs).
fn first_channel(name: &str, image: &Image) -> Result<Vec<f32>, PyramidImageError> {
    let format = image.texture_descriptor.format;
    let data = image
        .data
        .as_deref()
        .ok_or_else(|| PyramidImageError::NoData { name: name.into() })?;
    let unsupported = || PyramidImageError::Format {
        name: name.into(),
        format,
    };
    let texel_bytes = format.pixel_size().map_err(|_| unsupported())?;
    let (width, height) = (image.width(), image.height());
    let texels = width as usize * height as usize;
    if data.len() < texels * texel_bytes {
        return Err(PyramidImageError::Truncated {
            name: name.into(),
            format,
            len: data.len(),
            width,
            height,
        });
    }
    let first: fn(&[u8]) -> f32 = match format {
        TextureFormat::R8Unorm | TextureFormat::Rg8Unorm | TextureFormat::Rgba8Unorm => {
            |t| f32::from(t[0]) / 255.0
        }
        TextureFormat::Rgba8UnormSrgb => |t| srgb_to_linear(f32::from(t[0]) / 255.0),
        TextureFormat::R16Unorm
        | TextureFormat::Rg16Unorm
        | TextureFormat::Rgba16Unorm
        | TextureFormat::R16Uint
        | TextureFormat::Rg16Uint
        | TextureFormat::Rgba16Uint => |t| f32::from(u16::from_le_bytes([t[0], t[1]])) / 65535.0,
        TextureFormat::R32Float | TextureFormat::Rg32Float | TextureFormat::Rgba32Float => {
            |t| f32::from_le_bytes([t[0], t[1], t[2], t[3]])
        }
        _ => return Err(unsupported()),
    };
    Ok(data
        .chunks_exact(texel_bytes)
        .take(texels)
        .map(first)
        .collect())
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, format: TextureFormat, data: Vec<u8>) -> Image {
        let mut image = Image::new_uninit(
            Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            TextureDimension::D2,
            format,
            RenderAssetUsages::MAIN_WORLD,
        );
        image.data = Some(data);
        image
    }

    #[test]
    fn the_first_channel_is_read_as_a_shader_samples_it() {
        let grey = image(2, 2, TextureFormat::R8Unorm, vec![0, 51, 204, 255]);
        assert_eq!(
            depth_map("grey", &grey).unwrap().depth,
            [0.0, 0.2, 0.8, 1.0]
        );
        let sixteen: Vec<u8> = [0u16, 65535, 13107, 0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let bevy_png16 = image(2, 2, TextureFormat::R16Uint, sixteen);
        assert_eq!(
            depth_map("png16", &bevy_png16).unwrap().depth,
            [0.0, 1.0, 0.2, 0.0]
        );
        let srgb = image(
            2,
            2,
            TextureFormat::Rgba8UnormSrgb,
            [[188u8, 0, 0, 255]; 4].concat(),
        );
        let d = depth_map("srgb", &srgb).unwrap().depth[0];
        assert!((d - 0.5029).abs() < 1e-3, "sRGB 188 decodes to {d}");
    }

    #[test]
    fn the_pyramid_holds_every_level_down_to_one_texel() {
        let map = depth_map(
            "m",
            &image(
                4,
                4,
                TextureFormat::R8Unorm,
                (0..16).map(|i| 255 - i * 10).collect(),
            ),
        )
        .unwrap();
        let pyramid = pyramid_image(&map);
        assert_eq!(pyramid.texture_descriptor.mip_level_count, 3);
        let texels: Vec<f32> = bytemuck::pod_collect_to_vec(pyramid.data.as_ref().unwrap());
        assert_eq!(texels.len(), 16 + 4 + 1);
        // The root is the smallest depth (the highest point) of the map.
        assert_eq!(texels[20], 105.0 / 255.0);
    }

    #[test]
    fn an_odd_sized_map_keeps_its_size_and_pads_its_pyramid() {
        let map = depth_map("odd", &image(3, 5, TextureFormat::R8Unorm, vec![0; 15])).unwrap();
        assert_eq!((map.width, map.height), (3, 5));
        let pyramid = pyramid_image(&map);
        let size = pyramid.texture_descriptor.size;
        assert_eq!((size.width, size.height), (4, 8));
        assert_eq!(pyramid.texture_descriptor.mip_level_count, 4);
        let texels: Vec<f32> = bytemuck::pod_collect_to_vec(pyramid.data.as_ref().unwrap());
        // Levels 4x8, 2x4, 1x2, 1x1; padding is deepest, the map's texels at depth 0.
        assert_eq!(texels.len(), 32 + 8 + 2 + 1);
        assert_eq!((texels[0], texels[3], texels[4 * 5]), (0.0, 1.0, 1.0));
        assert_eq!(texels[42], 0.0);
    }

    #[test]
    fn unusable_maps_are_errors_naming_the_asset() {
        let cases = [
            (
                image(2, 2, TextureFormat::Bgra8Unorm, vec![0; 16]),
                "texture format",
            ),
            (
                image(4, 4, TextureFormat::R8Unorm, vec![0; 5]),
                "5 bytes for a 4x4",
            ),
            (
                image(
                    1,
                    1,
                    TextureFormat::R32Float,
                    f32::NAN.to_le_bytes().to_vec(),
                ),
                "NaN",
            ),
        ];
        for (image, reason) in cases {
            let e = depth_map("maps/bad.png", &image).unwrap_err().to_string();
            assert!(e.contains("maps/bad.png") && e.contains(reason), "{e}");
        }
        let mut no_data = image(2, 2, TextureFormat::R8Unorm, vec![0; 4]);
        no_data.data = None;
        assert!(
            depth_map("gpu-only", &no_data)
                .unwrap_err()
                .to_string()
                .contains("no CPU-side data")
        );
    }
}
