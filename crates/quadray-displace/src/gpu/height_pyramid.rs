//! The height pyramid as a GPU resource on the caller's device: what a shader including
//! `trace.wgsl` reads.

use crate::heightmap::HeightMap;
use crate::pyramid::{Addressing, Pyramid};

/// Hard cap on the steps of any one trace; the per-ray bound in the shader is far lower.
pub const ITERATION_CAP: u32 = 1 << 20;
/// Hard cap on the refinement rounds of `bilinear_trace`.
pub const REFINE_CAP: u32 = 1 << 16;

/// Which pyramid: the paper's, or the conservative bound the bilinear surface needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PyramidKind {
    /// Mip 0 is the map; each node the minimum depth of its four children. For `pyramid_trace`.
    Point,
    /// Mip 0 holds the minimum over each texel's 3x3 neighbourhood under this addressing, every
    /// texel centre bilinear interpolation inside the texel can reach. For `bilinear_trace`.
    Conservative(Addressing),
}

/// `trace.wgsl`'s `PyramidInfo`: what its functions need to know about the pyramid. Upload it
/// as (part of) a uniform, or build the WGSL value from your own parameters.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PyramidInfo {
    /// n: the root (mip n) is 1x1; mip 0 is the map padded to powers of two.
    pub levels: i32,
    /// 1: rays that leave [0, 1)^2 miss (terrain); 0: the map tiles.
    pub clamp_to_map: u32,
    /// Hard cap on the steps of any one trace.
    pub iteration_cap: u32,
    /// Hard cap on `bilinear_trace`'s refinement rounds.
    pub refine_cap: u32,
    /// The map's width and height in texels (what uv [0, 1) spans), without the padding.
    pub size: [u32; 2],
    /// Rounds the struct up to 16 bytes, as a uniform's nested struct must be.
    pub _pad: [u32; 2],
}

impl PyramidInfo {
    /// For the pyramid of a `width` x `height` map, read with `addressing`, with the default caps.
    pub fn new(width: u32, height: u32, addressing: Addressing) -> Self {
        Self {
            levels: width
                .next_power_of_two()
                .max(height.next_power_of_two())
                .ilog2() as i32,
            clamp_to_map: u32::from(addressing == Addressing::Clamp),
            iteration_cap: ITERATION_CAP,
            refine_cap: REFINE_CAP,
            size: [width, height],
            _pad: [0; 2],
        }
    }
}

/// A min-depth (max-height) pyramid in an R32Float texture with one mip per level (mip 0 the map
/// padded to powers of two with depth 1, as [`Pyramid`] stores it), built on the
/// caller's device from a [`HeightMap`]; bind [`HeightPyramid::view`] as a `texture_2d<f32>`
/// (unfilterable float) and pass it to `trace.wgsl`'s functions.
pub struct HeightPyramid {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    kind: PyramidKind,
    map_size: (u32, u32),
}

impl HeightPyramid {
    /// The texture's format.
    pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

    /// Builds the pyramid on the CPU and uploads it.
    pub fn build_cpu(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        map: &HeightMap,
        kind: PyramidKind,
    ) -> Self {
        let pyramid = match kind {
            PyramidKind::Point => Pyramid::build(map),
            PyramidKind::Conservative(addressing) => Pyramid::build_conservative(map, addressing),
        };
        Self::upload(device, queue, &pyramid, kind)
    }

    /// Uploads every level of a pyramid built on the CPU; `kind` says which one it is.
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pyramid: &Pyramid,
        kind: PyramidKind,
    ) -> Self {
        let texture = Self::create_texture(device, pyramid.level_size(0));
        for (level, depths) in pyramid.levels.iter().enumerate() {
            let (width, height) = pyramid.level_size(level as u32);
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    mip_level: level as u32,
                    ..texture.as_image_copy()
                },
                bytemuck::cast_slice(depths),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(width * 4),
                    rows_per_image: Some(height),
                },
                wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
            );
        }
        Self::from_texture(texture, kind, (pyramid.width, pyramid.height))
    }

    /// An empty pyramid texture with a full mip chain over a power-of-two `width` x `height` level
    /// 0 (usable as a storage texture, so the compute builder can write it).
    pub(super) fn create_texture(
        device: &wgpu::Device,
        (width, height): (u32, u32),
    ) -> wgpu::Texture {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some("min-depth pyramid"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: width.max(height).ilog2() + 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: Self::FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    }

    /// Wraps a built pyramid `texture` of a `map_size` map.
    pub(super) fn from_texture(
        texture: wgpu::Texture,
        kind: PyramidKind,
        map_size: (u32, u32),
    ) -> Self {
        Self {
            view: texture.create_view(&Default::default()),
            texture,
            kind,
            map_size,
        }
    }

    /// The texture: R32Float, `levels() + 1` mips.
    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    /// A view of all mips, to bind as `texture_2d<f32>`.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// n: the root is mip n (1x1).
    pub fn levels(&self) -> u32 {
        self.texture.mip_level_count() - 1
    }

    /// The map's width and height in texels (mip 0 pads them to powers of two).
    pub fn map_size(&self) -> (u32, u32) {
        self.map_size
    }

    /// Which pyramid this is.
    pub fn kind(&self) -> PyramidKind {
        self.kind
    }

    /// The `PyramidInfo` for tracing this pyramid with `addressing` (for a conservative pyramid,
    /// the addressing it was built for).
    pub fn info(&self, addressing: Addressing) -> PyramidInfo {
        PyramidInfo::new(self.map_size.0, self.map_size.1, addressing)
    }
}
