//! The scene's base colour textures: every distinct texture of its mesh files at one size, the
//! layers of the one texture array the raster passes sample per fragment (`textures.wgsl`), and
//! the CPU twin of that sampling ([`SceneTextures::sample`]). No mipmaps: a sample reads one
//! texel (nearest) or four (linear) of the texture itself, as glTF's sampler says, so that the
//! GPU and the CPU read the same texels with the same weights.

use glam::{Vec2, Vec3};
use quadray_core::image_out::Rgba8Image;
use quadray_core::mesh::{TextureFilter, TextureSampler, TextureWrap};

/// The most distinct textures a scene may have: the layers of a texture array every WebGPU
/// device offers (`max_texture_array_layers`).
pub const MAX_TEXTURES: usize = 256;

/// The most bytes the scene's texture array may take (its layers at the size of the widest and
/// the tallest texture, 4 bytes a texel).
pub const MAX_TEXTURE_BYTES: u64 = 256 << 20;

/// Bits of a packed [`Vertex::texture`](super::Vertex::texture) that hold the layer; the
/// sampler's filter and wraps lie above them.
const LAYER_BITS: u32 = 16;

/// The layer's bits of a packed texture.
const LAYER_MASK: u32 = (1 << LAYER_BITS) - 1;

/// The layer of packed texture `texture`.
fn layer_of(texture: u32) -> usize {
    (texture & LAYER_MASK) as usize
}

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

/// A texture as the scene takes it.
#[derive(Debug)]
struct Source {
    image: Rgba8Image,
    /// Where it comes from (a mesh file and material, say), for the error of a scene over the
    /// limits.
    origin: String,
}

/// Collects the distinct textures of a scene while its triangles are made, and gives them at one
/// size ([`TextureCollector::textures`]). A scene that changes (the Bevy plugin's) keeps one:
/// a texture's layer stays while it is used, and [`TextureCollector::retain_used`] drops the
/// layers no longer used.
#[derive(Debug, Default)]
pub struct TextureCollector {
    sources: Vec<Source>,
}

impl TextureCollector {
    /// The packed [`Vertex::texture`](super::Vertex::texture) of `image` read through `sampler`:
    /// its layer, a new one where no texture before it has the same texels. `origin` says where
    /// it comes from (a mesh file and material) in the error of a texture over the limits: over
    /// [`MAX_TEXTURES`] distinct textures, or layers (at the size of the widest and the tallest
    /// texture) that would take over [`MAX_TEXTURE_BYTES`]; the collector is then as it was.
    pub fn index(
        &mut self,
        image: &Rgba8Image,
        sampler: TextureSampler,
        origin: &str,
    ) -> Result<u32, String> {
        let layer = match self.sources.iter().position(|s| s.image == *image) {
            Some(layer) => layer,
            None => {
                if self.sources.len() == MAX_TEXTURES {
                    return Err(format!(
                        "{origin}: over {MAX_TEXTURES} distinct base colour textures in the \
                         scene (the layers of one texture array)"
                    ));
                }
                self.sources.push(Source {
                    image: image.clone(),
                    origin: origin.to_string(),
                });
                if let Err(e) = self.check_bytes() {
                    self.sources.pop();
                    return Err(e);
                }
                self.sources.len() - 1
            }
        };
        Ok(pack(layer as u32, sampler))
    }

    /// An error naming the widest and the tallest texture when the layers at their size take
    /// over [`MAX_TEXTURE_BYTES`].
    fn check_bytes(&self) -> Result<(), String> {
        let widest = self.sources.iter().max_by_key(|s| s.image.width);
        let tallest = self.sources.iter().max_by_key(|s| s.image.height);
        let (Some(widest), Some(tallest)) = (widest, tallest) else {
            return Ok(());
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
        Ok(())
    }

    /// How many layers the textures take.
    pub fn len(&self) -> usize {
        self.sources.len()
    }

    /// Whether no texture was collected.
    pub fn is_empty(&self) -> bool {
        self.sources.is_empty()
    }

    /// Drops the layers that no packed texture of `used` reads, keeping the others in order;
    /// `None` where every layer is used, else what each packed texture becomes
    /// ([`Relayering::packed`]).
    pub fn retain_used(&mut self, used: impl IntoIterator<Item = u32>) -> Option<Relayering> {
        let mut kept = vec![false; self.sources.len()];
        for texture in used {
            if let Some(k) = kept.get_mut(layer_of(texture)) {
                *k = true;
            }
        }
        if kept.iter().all(|k| *k) {
            return None;
        }
        let mut next = 0;
        let layers = kept
            .iter()
            .map(|&k| {
                k.then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        let mut kept = kept.into_iter();
        self.sources.retain(|_| kept.next() == Some(true));
        Some(Relayering { layers })
    }

    /// Every texture resized to the width of the widest and the height of the tallest.
    pub fn textures(&self) -> SceneTextures {
        let width = self.sources.iter().map(|s| s.image.width).max();
        let height = self.sources.iter().map(|s| s.image.height).max();
        let (Some(width), Some(height)) = (width, height) else {
            return SceneTextures::default();
        };
        SceneTextures {
            width,
            height,
            layers: self
                .sources
                .iter()
                .map(|s| resized(&s.image, width, height))
                .collect(),
        }
    }
}

/// The layers a [`TextureCollector::retain_used`] moved or dropped.
#[derive(Debug)]
pub struct Relayering {
    /// Each layer before: its layer now, or `None` where dropped.
    layers: Vec<Option<u32>>,
}

impl Relayering {
    /// What packed texture `texture` (of a layer kept) is now, with the same sampler;
    /// [`Vertex::UNTEXTURED`](super::Vertex::UNTEXTURED) where its layer was dropped (or it had
    /// none).
    pub fn packed(&self, texture: u32) -> u32 {
        // (an untextured vertex's layer bits are past every layer)
        match self.layers.get(layer_of(texture)).copied().flatten() {
            Some(layer) => (texture & !LAYER_MASK) | layer,
            None => super::Vertex::UNTEXTURED,
        }
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
        let layer = &self.layers[layer_of(texture)];
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
        let index = collector.index(&image(2, 1, texels), sampler, "a").unwrap();
        (collector.textures(), index)
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
        let sampler = TextureSampler::default();
        let first = collector.index(&red, sampler, "floor.gltf (a)").unwrap();
        assert_eq!(
            collector.index(&red, sampler, "floor.gltf (b)").unwrap(),
            first
        );
        collector.index(&wide, sampler, "floor.gltf (c)").unwrap();
        let textures = collector.textures();
        assert_eq!((textures.width, textures.height), (4, 1));
        assert_eq!(textures.layers[0], vec![[255, 0, 0, 255]; 4]);
        // one texture as wide as the limit, one as tall: the array would be both, 512 MiB
        let mut collector = TextureCollector::default();
        let side = quadray_core::image_in::MAX_SIDE;
        let row = image(side, 1, vec![[0; 4]; side as usize]);
        let column = image(1, side, vec![[1; 4]; side as usize]);
        collector.index(&row, sampler, "floor.gltf (row)").unwrap();
        let err = collector
            .index(&column, sampler, "wall.gltf (column)")
            .unwrap_err();
        assert!(
            err.contains("floor.gltf") && err.contains("wall.gltf") && err.contains("512 MiB"),
            "{err}"
        );
        assert_eq!(collector.len(), 1, "the refused texture is not kept");
        let mut collector = TextureCollector::default();
        let err = (0..=MAX_TEXTURES)
            .map(|i| {
                let texel = [i as u8, (i >> 8) as u8, 0, 255];
                collector.index(&image(1, 1, vec![texel]), sampler, "floor.gltf (m)")
            })
            .find_map(Result::err)
            .expect("one over the limit");
        assert!(err.contains("floor.gltf") && err.contains("256"), "{err}");
    }

    #[test]
    fn unused_layers_are_dropped_and_the_others_renumbered() {
        let texel = |c: u8| image(1, 1, vec![[c, c, c, 255]]);
        let nearest = TextureSampler {
            filter: TextureFilter::Nearest,
            ..TextureSampler::default()
        };
        let mut collector = TextureCollector::default();
        let a = collector.index(&texel(10), nearest, "a").unwrap();
        let b = collector.index(&texel(20), nearest, "b").unwrap();
        let c = collector
            .index(&texel(30), TextureSampler::default(), "c")
            .unwrap();
        assert!(collector.retain_used([a, b, c]).is_none());
        let moved = collector.retain_used([c, a]).expect("b dropped");
        assert_eq!(collector.len(), 2);
        assert_eq!(moved.packed(a), a);
        assert_eq!(moved.packed(b), super::super::Vertex::UNTEXTURED);
        assert_eq!(
            moved.packed(super::super::Vertex::UNTEXTURED),
            super::super::Vertex::UNTEXTURED
        );
        // c now reads layer 1, through its own sampler still
        let textures = collector.textures();
        assert_eq!(
            textures.sample(moved.packed(c), Vec2::splat(0.5)),
            Vec3::splat(srgb_to_linear(30))
        );
        assert_eq!(
            moved.packed(c),
            collector
                .index(&texel(30), TextureSampler::default(), "c")
                .unwrap()
        );
    }
}
