//! Reading pictures (height maps, albedo images, mesh textures): the size is read from the header
//! and held to quadray's own limit before a texel is decoded.

use image::{DynamicImage, ImageDecoder, ImageReader};
use std::io::{BufRead, Cursor, Seek};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The largest side of an image quadray reads: wgpu's default `max_texture_dimension_2d`, so
/// whatever is read can be uploaded whole (8192^2 floats are 256 MiB, a height map's pyramid a
/// third more).
pub const MAX_SIDE: u32 = 8192;

/// What a decoder may allocate: a [`MAX_SIDE`]^2 image of four f32 channels (the widest texel),
/// so that an image within the limit never meets the image crate's own 512 MiB default.
const MAX_DECODED_BYTES: u64 = MAX_SIDE as u64 * MAX_SIDE as u64 * 16;

/// Why an image was refused; every message names the file.
#[derive(Debug, Error)]
pub enum ImageReadError {
    #[error("{}: cannot read the image: {reason}", path.display())]
    Unreadable { path: PathBuf, reason: String },
    #[error(
        "{}: the image is {width}x{height}, over quadray's limit of {MAX_SIDE}x{MAX_SIDE}",
        path.display()
    )]
    TooLarge {
        path: PathBuf,
        width: u32,
        height: u32,
    },
}

/// Decodes the image file at `path` (its format guessed from its bytes).
pub fn open(path: &Path) -> Result<DynamicImage, ImageReadError> {
    let reader = ImageReader::open(path).map_err(|e| unreadable(path, e))?;
    decode(path, reader)
}

/// Decodes an image held in memory (a texture inside a glTF file); `path` names it in errors.
pub fn from_memory(path: &Path, bytes: &[u8]) -> Result<DynamicImage, ImageReadError> {
    decode(path, ImageReader::new(Cursor::new(bytes)))
}

fn decode<R: BufRead + Seek>(
    path: &Path,
    reader: ImageReader<R>,
) -> Result<DynamicImage, ImageReadError> {
    let mut reader = reader
        .with_guessed_format()
        .map_err(|e| unreadable(path, e))?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MAX_DECODED_BYTES);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(|e| unreadable(path, e))?;
    let (width, height) = decoder.dimensions();
    check_size(path, width, height)?;
    DynamicImage::from_decoder(decoder).map_err(|e| unreadable(path, e))
}

/// Both sides within [`MAX_SIDE`] (for images that arrive by other means, too: an engine's
/// asset loader); `path` names the image in the error.
pub fn check_size(path: &Path, width: u32, height: u32) -> Result<(), ImageReadError> {
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(ImageReadError::TooLarge {
            path: path.to_owned(),
            width,
            height,
        });
    }
    Ok(())
}

fn unreadable(path: &Path, reason: impl ToString) -> ImageReadError {
    ImageReadError::Unreadable {
        path: path.to_owned(),
        reason: reason.to_string(),
    }
}
