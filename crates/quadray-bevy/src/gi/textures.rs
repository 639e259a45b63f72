//! The `StandardMaterial`s' base colour textures in the indirect light's scene: each image read
//! once on the CPU as Bevy decodes it (sRGB bytes), a layer of quadray's texture array
//! (`quadray_indirect::scene::TextureCollector`, shared by identical images), its sampler as the
//! image's descriptor says. The layers stay while used; the array is made anew (and uploaded by
//! the render world) only when the set of textures changes.

use bevy::asset::RenderAssetUsages;
use bevy::image::{ImageAddressMode, ImageFilterMode, ImageSampler, ImageSamplerDescriptor};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use quadray_core::image_in::MAX_SIDE;
use quadray_core::image_out::Rgba8Image;
use quadray_core::mesh::{TextureFilter, TextureSampler, TextureWrap};
use quadray_indirect::scene::{
    MAX_TEXTURE_BYTES, Relayering, SceneTextures, TextureCollector, Vertex,
};
use std::sync::Arc;

/// The scene's base colour textures, kept across updates.
pub(super) struct BaseColours {
    collector: TextureCollector,
    /// Each image asked for: its packed texture, or `None` (not loaded yet; or not readable on
    /// the CPU, or over the limits, which was warned once).
    read: HashMap<AssetId<Image>, Option<u32>>,
    /// The images refused because the layers were full (their count or bytes): read again once
    /// layers are dropped.
    refused_full: HashSet<AssetId<Image>>,
    /// The layers changed since [`BaseColours::publish`].
    changed: bool,
    /// The layers the render world uploads.
    pub(super) textures: Arc<SceneTextures>,
    /// Counts the changes to [`Self::textures`].
    pub(super) generation: u64,
    /// What `ImageSampler::Default` stands for: the app's `ImagePlugin::default_sampler`
    /// (Bevy's linear default until the plugin is finished).
    pub(super) default_sampler: ImageSamplerDescriptor,
}

impl Default for BaseColours {
    fn default() -> Self {
        Self {
            collector: TextureCollector::default(),
            read: HashMap::default(),
            refused_full: HashSet::default(),
            changed: false,
            textures: Arc::default(),
            generation: 0,
            default_sampler: ImageSamplerDescriptor::linear(),
        }
    }
}

impl BaseColours {
    /// Forgets image `id` (loaded, changed or removed): read again when next asked for.
    pub fn forget(&mut self, id: AssetId<Image>) {
        self.read.remove(&id);
    }

    /// Forgets every image: each read again when next asked for (after a pause in which their
    /// events went unread).
    pub fn forget_all(&mut self) {
        self.read.clear();
    }

    /// The packed texture ([`Vertex::texture`]) of `texture`, read the first time it is asked
    /// for once loaded; `None` until it loads, and where it cannot be read on the CPU or is over
    /// quadray's limits (with a warning naming it, once).
    pub fn packed(
        &mut self,
        images: &Assets<Image>,
        assets: &AssetServer,
        texture: &Handle<Image>,
    ) -> Option<u32> {
        if let Some(packed) = self.read.get(&texture.id()) {
            return *packed;
        }
        let image = images.get(texture)?;
        let name = || {
            assets
                .get_path(texture.id())
                .map_or_else(|| format!("{:?}", texture.id()), |p| p.to_string())
        };
        let bytes = u64::from(image.width()) * u64::from(image.height()) * 4;
        let packed = if image.width().max(image.height()) > MAX_SIDE {
            Err(format!(
                "it is {}x{}, over quadray's limit of {MAX_SIDE}x{MAX_SIDE}",
                image.width(),
                image.height()
            ))
        } else if bytes > MAX_TEXTURE_BYTES {
            Err(format!(
                "it takes {} MiB, over quadray indirect's limit of {} MiB for all the textures",
                bytes >> 20,
                MAX_TEXTURE_BYTES >> 20
            ))
        } else if let Some(texels) = srgb_texels(image) {
            let before = self.collector.len();
            let packed = self.collector.index(
                &texels,
                sampler_of(&image.sampler, &self.default_sampler),
                &name(),
            );
            self.changed |= self.collector.len() != before;
            if packed.is_err() {
                self.refused_full.insert(texture.id());
            }
            packed
        } else {
            Err(
                "it cannot be read on the CPU (no CPU-side data: RenderAssetUsages without \
                 MAIN_WORLD; or a format Image::get_color_at does not read)"
                    .into(),
            )
        };
        let packed = packed
            .inspect_err(|e| {
                warn!(
                    "quadray indirect light: the base colour texture {} is left out of the RSM, \
                     which takes its material's base colour alone: {e}",
                    name()
                );
            })
            .ok();
        self.read.insert(texture.id(), packed);
        packed
    }

    /// Drops the layers that no packed texture of `used` (every object's) reads; returns what
    /// the packed textures kept become, where one was dropped, and the images refused while the
    /// layers were full, forgotten so that they are read again when next asked for.
    pub fn drop_unused(
        &mut self,
        used: impl IntoIterator<Item = u32>,
    ) -> Option<(Relayering, HashSet<AssetId<Image>>)> {
        let moved = self.collector.retain_used(used)?;
        let refused = std::mem::take(&mut self.refused_full);
        for id in &refused {
            self.read.remove(id);
        }
        self.read.retain(|_, packed| match packed {
            Some(p) => {
                *p = moved.packed(*p);
                *p != Vertex::UNTEXTURED
            }
            None => true,
        });
        self.changed = true;
        Some((moved, refused))
    }

    /// Ends an update: the textures made anew where the layers changed.
    pub fn publish(&mut self) {
        if std::mem::take(&mut self.changed) {
            self.textures = Arc::new(self.collector.textures());
            self.generation += 1;
        }
    }
}

/// The image's texels as sRGB bytes, as Bevy decodes its format (an 8-bit sRGB image's bytes as
/// they are; another format through `Image::get_color_at`); `None` for an image not kept in the
/// main world (its data is there only until Bevy first extracts it: taken never, rather than
/// depending on which frame asks), without CPU-side data, of a format `get_color_at` does not
/// read, or of more than one layer.
fn srgb_texels(image: &Image) -> Option<Rgba8Image> {
    if !image.asset_usage.contains(RenderAssetUsages::MAIN_WORLD) {
        return None;
    }
    let (width, height) = (image.width(), image.height());
    let data = image.data.as_ref()?;
    if width == 0 || height == 0 || image.texture_descriptor.size.depth_or_array_layers != 1 {
        return None;
    }
    let count = width as usize * height as usize;
    let pixels = if image.texture_descriptor.format == TextureFormat::Rgba8UnormSrgb {
        bytemuck::cast_slice::<u8, [u8; 4]>(data.get(..4 * count)?).to_vec()
    } else {
        let mut pixels = Vec::with_capacity(count);
        for y in 0..height {
            for x in 0..width {
                let colour = image.get_color_at(x, y).ok()?;
                pixels.push(Srgba::from(colour).to_u8_array());
            }
        }
        pixels
    };
    Some(Rgba8Image {
        width,
        height,
        pixels,
    })
}

/// Bevy's sampler as quadray's: its magnification filter (quadray reads no mipmaps) and its
/// wraps, a border clamp as a clamp to the edge. `ImageSampler::Default` is the app's
/// `ImagePlugin::default_sampler`, `default`.
fn sampler_of(sampler: &ImageSampler, default: &ImageSamplerDescriptor) -> TextureSampler {
    let descriptor = match sampler {
        ImageSampler::Descriptor(d) => d,
        ImageSampler::Default => default,
    };
    let wrap = |mode| match mode {
        ImageAddressMode::Repeat => TextureWrap::Repeat,
        ImageAddressMode::MirrorRepeat => TextureWrap::MirroredRepeat,
        ImageAddressMode::ClampToEdge | ImageAddressMode::ClampToBorder => TextureWrap::ClampToEdge,
    };
    TextureSampler {
        filter: match descriptor.mag_filter {
            ImageFilterMode::Nearest => TextureFilter::Nearest,
            ImageFilterMode::Linear => TextureFilter::Linear,
        },
        wrap_u: wrap(descriptor.address_mode_u),
        wrap_v: wrap(descriptor.address_mode_v),
    }
}
