//! What quadray's techniques share: image output and error heat maps, medians of timings, and the
//! results files (JSON, markdown, SVG plots) every benchmark writes, and the mesh loader (OBJ, glTF,
//! PLY) the renderers share.

pub mod bench;
pub mod image_out;
pub mod mesh;
pub mod stats;

use std::path::PathBuf;
use thiserror::Error;

/// An I/O failure with the file it concerns.
#[derive(Debug, Error)]
#[error("{path}: {reason}")]
pub struct FileError {
    pub path: PathBuf,
    pub reason: String,
}

impl FileError {
    pub fn new(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        Self {
            path: path.into(),
            reason: reason.to_string(),
        }
    }
}
