//! The scene's base colour textures: every distinct texture of its mesh files at one size, the
//! layers of the one texture array the raster passes sample per fragment (`textures.wgsl`), and
//! the CPU twin of that sampling ([`SceneTextures::sample`]). No mipmaps: a sample reads one
//! texel (nearest) or four (linear) of the texture itself, as glTF's sampler says, so that the
//! GPU and the CPU read the same texels with the same weights.

use glam::{Vec2, Vec3};
use quadray_core::image_out::Rgba8Image;
use quadray_core::mesh::{TextureFilter, TextureSampler, TextureWrap};
use std::path::Path;

/// The most distinct textures a scene may have: the layers of a texture array every WebGPU
/// device offers (`max_texture_array_layers`).
pub const MAX_TEXTURES: usize = 256;

/// The most bytes the scene's texture array may take (its layers at the size of the widest and
/// the tallest texture, 4 bytes a texel).
pub const MAX_TEXTURE_BYTES: u64 = 256 << 20;

/// Bits of a packed [`Vertex::texture`](super::Vertex::texture) that hold the layer; the
/// sampler's filter and wraps lie above them.
const LAYER_BITS: u32 = 16;

/// The scene's base colour textures, as sRGB bytes (decoded when sampled, as the GPU's
/// `Rgba8UnormSrgb` decodes them), every layer `width` x `height`: a texture of another size is
/// resized to it (nearest texel) when the scene loads, and both the GPU and the CPU sample the
/// resized texels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneTextures {
    /// Texels a row of every layer.
    pub width: u32,
    /// Rows of every layer.
    pub height: u32,
    /// Each layer's texels, row-major, top row first.
    pub layers: Vec<Vec<[u8; 4]>>,
}

/// A texture of a mesh file as the scene takes it.
#[derive(Debug)]
struct Source {
    image: Rgba8Image,
    /// The mesh file and material it comes from, for the error of a scene over the limits.
    origin: String,
}

/// Collects the distinct textures of a scene's mesh files while their triangles are made, then
/// resizes them to one size ([`TextureCollector::finish`]).
#[derive(Debug, Default)]
pub(super) struct TextureCollector {
    sources: Vec<Source>,
}

impl TextureCollector {
    /// The packed texture index of `image` read through `sampler` (material `material` of mesh
    /// file `file`): its layer, a new one where no texture before it has the same texels.
    pub fn index(
        &mut self,
        image: &Rgba8Image,
        sampler: TextureSampler,
        file: &Path,
        material: &str,
    ) -> Result<u32, String> {
        let layer = match self.sources.iter().position(|s| s.image == *image) {
            Some(layer) => layer,
            None => {
                if self.sources.len() == MAX_TEXTURES {
                    return Err(format!(
                        "{}: material `{material}`: over {MAX_TEXTURES} distinct base colour \
                         textures in the scene (the layers of one texture array)",
                        file.display()
                    ));
                }
                self.sources.push(Source {
                    image: image.clone(),
                    origin: format!("{} (material `{material}`)", file.display()),
                });
                self.sources.len() - 1
            }
        };
        Ok(pack(layer as u32, sampler))
    }

    /// Every texture resized to the width of the widest and the height of the tallest; an error
    /// names the files of those two when the layers would take over [`MAX_TEXTURE_BYTES`].
    pub fn finish(self) -> Result<SceneTextures, String> {
        let widest = self.sources.iter().max_by_key(|s| s.image.width);
        let tallest = self.sources.iter().max_by_key(|s| s.image.height);
        let (Some(widest), Some(tallest)) = (widest, tallest) else {
            return Ok(SceneTextures::default());
        };
        let (width, height) = (widest.image.width, tallest.image.height);
        let bytes = u64::from(width) * u64::from(height) * 4 * self.sources.len() as u64;
        if bytes > MAX_TEXTURE_BYTES {
            return Err(format!(
                "{} base colour textures at {width}x{height} (the widest: {}; the tallest: {}) \
                 take {} MiB, over quadray indirect's limit of {} MiB: use fewer or smaller \
                 textures",
                self.sources.len(),
                widest.origin,
                tallest.origin,
                bytes >> 20,
                MAX_TEXTURE_BYTES >> 20
            ));
        }
        Ok(SceneTextures {
            width,
            height,
            layers: self
                .sources
                .iter()
                .map(|s| resized(&s.image, width, height))
                .collect(),
        })
    }
}

/// `image` at `width` x `height`, each texel the source texel its centre falls in.
fn resized(image: &Rgba8Image, width: u32, height: u32) -> Vec<[u8; 4]> {
    if (image.width, image.height) == (width, height) {
        return image.pixels.clone();
    }
    let source = |x: u32, n: u32, from: u32| {
        ((2 * u64::from(x) + 1) * u64::from(from) / (2 * u64::from(n))) as u32
    };
    (0..height)
        .flat_map(|y| {
            let row = source(y, height, image.height) * image.width;
            (0..width).map(move |x| image.pixels[(row + source(x, width, image.width)) as usize])
        })
        .collect()
}

/// A layer and the sampler it is read through, packed into a [`Vertex::texture`](super::Vertex::texture)
/// (`textures.wgsl`'s `unpacked_sampler` reads it): the layer in the low [`LAYER_BITS`], then
/// one bit of filter (1: nearest) and two bits of each wrap (0 repeat, 1 clamp to edge, 2
/// mirrored repeat).
fn pack(layer: u32, sampler: TextureSampler) -> u32 {
    let wrap = |w: TextureWrap| match w {
        TextureWrap::Repeat => 0,
        TextureWrap::ClampToEdge => 1,
        TextureWrap::MirroredRepeat => 2,
    };
    let nearest = u32::from(sampler.filter == TextureFilter::Nearest);
    layer
        | nearest << LAYER_BITS
        | wrap(sampler.wrap_u) << (LAYER_BITS + 1)
        | wrap(sampler.wrap_v) << (LAYER_BITS + 3)
}

/// Texel `i` of a row or column of `n` under `wrap` (as `textures.wgsl`'s `wrapped`).
fn wrapped(i: i32, n: i32, wrap: u32) -> i32 {
    match wrap {
        1 => i.clamp(0, n - 1),
        2 => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
        _ => i.rem_euclid(n),
    }
}

/// An sRGB-encoded channel in linear light (the decoding of an `*Srgb` texture format).
fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl SceneTextures {
    /// The linear RGB of packed texture `texture` at `uv` ((0, 0) the top-left corner), as the
    /// raster passes sample it (`textures.wgsl`'s `base_colour`): one where the vertex has no
    /// texture ([`Vertex::UNTEXTURED`](super::Vertex::UNTEXTURED)).
    pub fn sample(&self, texture: u32, uv: Vec2) -> Vec3 {
        if texture == super::Vertex::UNTEXTURED {
            return Vec3::ONE;
        }
        let layer = &self.layers[(texture & ((1 << LAYER_BITS) - 1)) as usize];
        let nearest = (texture >> LAYER_BITS) & 1 == 1;
        let (wrap_u, wrap_v) = (
            (texture >> (LAYER_BITS + 1)) & 3,
            (texture >> (LAYER_BITS + 3)) & 3,
        );
        let (w, h) = (self.width as i32, self.height as i32);
        let texel = |x: i32, y: i32| {
            let p = layer[(wrapped(y, h, wrap_v) * w + wrapped(x, w, wrap_u)) as usize];
            Vec3::new(
                srgb_to_linear(p[0]),
                srgb_to_linear(p[1]),
                srgb_to_linear(p[2]),
            )
        };
        let at = uv * Vec2::new(self.width as f32, self.height as f32);
        if nearest {
            let i = at.floor();
            return texel(i.x as i32, i.y as i32);
        }
        let x = at - 0.5;
        let i = x.floor();
        let f = x - i;
        // (float to integer saturates and integer addition wraps, as in WGSL)
        let (x0, y0) = (i.x as i32, i.y as i32);
        let (x1, y1) = (x0.wrapping_add(1), y0.wrapping_add(1));
        let mix = |a: Vec3, b: Vec3, t: f32| a * (1.0 - t) + b * t;
        let top = mix(texel(x0, y0), texel(x1, y0), f.x);
        let bottom = mix(texel(x0, y1), texel(x1, y1), f.x);
        mix(top, bottom, f.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, pixels: Vec<[u8; 4]>) -> Rgba8Image {
        Rgba8Image {
            width,
            height,
            pixels,
        }
    }

    /// A 2x1 texture, black then white, through each filter and wrap.
    fn black_white(filter: TextureFilter, wrap: TextureWrap) -> (SceneTextures, u32) {
        let mut collector = TextureCollector::default();
        let texels = vec![[0, 0, 0, 255], [255, 255, 255, 255]];
        let sampler = TextureSampler {
            filter,
            wrap_u: wrap,
            wrap_v: wrap,
        };
        let index = collector
            .index(&image(2, 1, texels), sampler, Path::new("a.gltf"), "m")
            .unwrap();
        (collector.finish().unwrap(), index)
    }

    #[test]
    fn samples_follow_the_filter_and_the_wrap() {
        use TextureFilter::{Linear, Nearest};
        use TextureWrap::{ClampToEdge, MirroredRepeat, Repeat};
        let cases = [
            // between the texel centres (u 0.25 and 0.75): halfway in linear light
            (Linear, Repeat, 0.5, 0.5),
            (Linear, Repeat, 0.375, 0.25),
            // at the left edge: the texel beyond it is the last (repeat), the first (clamp,
            // mirrored)
            (Linear, Repeat, 0.0, 0.5),
            (Linear, ClampToEdge, 0.0, 0.0),
            (Linear, MirroredRepeat, 0.0, 0.0),
            (Nearest, Repeat, 0.49, 0.0),
            (Nearest, Repeat, 0.51, 1.0),
            (Nearest, Repeat, 1.0, 0.0),
            (Nearest, ClampToEdge, 1.0, 1.0),
            (Nearest, ClampToEdge, -7.0, 0.0),
            (Nearest, MirroredRepeat, 1.0, 1.0),
            (Nearest, MirroredRepeat, 1.6, 0.0),
            (Nearest, Repeat, -0.25, 1.0),
        ];
        for (filter, wrap, u, expected) in cases {
            let (textures, index) = black_white(filter, wrap);
            let got = textures.sample(index, Vec2::new(u, 0.5));
            assert!(
                got.abs_diff_eq(Vec3::splat(expected), 1e-6),
                "{filter:?} {wrap:?} at u {u}: {got}"
            );
        }
        assert_eq!(
            SceneTextures::default().sample(super::super::Vertex::UNTEXTURED, Vec2::ZERO),
            Vec3::ONE
        );
    }

    #[test]
    fn textures_are_shared_resized_and_bounded() {
        let red = image(1, 1, vec![[255, 0, 0, 255]]);
        let wide = image(4, 1, vec![[0, 0, 255, 255]; 4]);
        let mut collector = TextureCollector::default();
        let file = Path::new("floor.gltf");
        let sampler = TextureSampler::default();
        let first = collector.index(&red, sampler, file, "a").unwrap();
        assert_eq!(collector.index(&red, sampler, file, "b").unwrap(), first);
        collector.index(&wide, sampler, file, "c").unwrap();
        let textures = collector.finish().unwrap();
        assert_eq!((textures.width, textures.height), (4, 1));
        assert_eq!(textures.layers[0], vec![[255, 0, 0, 255]; 4]);
        // one texture as wide as the limit, one as tall: the array is both, 512 MiB
        let mut collector = TextureCollector::default();
        let side = quadray_core::image_in::MAX_SIDE;
        let row = image(side, 1, vec![[0; 4]; side as usize]);
        let column = image(1, side, vec![[1; 4]; side as usize]);
        collector.index(&row, sampler, file, "row").unwrap();
        collector
            .index(&column, sampler, Path::new("wall.gltf"), "column")
            .unwrap();
        let err = collector.finish().unwrap_err();
        assert!(
            err.contains("floor.gltf") && err.contains("wall.gltf") && err.contains("512 MiB"),
            "{err}"
        );
        let mut collector = TextureCollector::default();
        let err = (0..=MAX_TEXTURES)
            .map(|i| {
                let texel = [i as u8, (i >> 8) as u8, 0, 255];
                collector.index(&image(1, 1, vec![texel]), sampler, file, "m")
            })
            .find_map(Result::err)
            .expect("one over the limit");
        assert!(err.contains("floor.gltf") && err.contains("256"), "{err}");
    }
}
