//! What quadray's techniques share: image input (held to one size limit) and output, error heat
//! maps, medians of timings, the JSON and text files the programs write, the mesh loader (OBJ,
//! glTF, PLY) the renderers share, the CPU ray tracing geometry ([`geom`]: rays, convex polygons,
//! a SAH BVH) and the random generator ([`random`]).

pub mod geom;
pub mod image_in;
pub mod image_out;
pub mod mesh;
pub mod random;
pub mod scene;
pub mod settings;
pub mod stats;

use serde::Serialize;
use std::path::{Path, PathBuf};
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

/// The `FromStr` of a named choice (a method, a convention, ...): the one of `all` whose `name` is
/// `s`, else an error that says what `s` was meant to be and lists the names.
pub fn parse_named<T: Copy>(
    s: &str,
    all: &[T],
    name: impl Fn(T) -> &'static str,
    what: &str,
) -> Result<T, String> {
    all.iter().copied().find(|&t| name(t) == s).ok_or_else(|| {
        let names: Vec<_> = all.iter().map(|&t| name(t)).collect();
        format!("unknown {what} `{s}` (one of: {})", names.join(", "))
    })
}

/// Writes `value` as pretty JSON (stats and results files), creating the folder.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<(), FileError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| FileError::new(path, e))?;
    write_text(path, &text)
}

/// Writes `text` to `path`, creating the folder.
pub fn write_text(path: &Path, text: &str) -> Result<(), FileError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| FileError::new(dir, e))?;
    }
    std::fs::write(path, text).map_err(|e| FileError::new(path, e))
}

/// Parses `X,Y,Z` (a point or direction on a command line); every coordinate must be finite.
pub fn parse_vec3(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|v| v.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}` is not X,Y,Z"))?;
    match parts[..] {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok([x, y, z]),
        _ => Err(format!("`{s}` is not X,Y,Z with finite numbers")),
    }
}

/// Parses an image size written `WxH` (command lines).
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    parse_pair(s, 'x', "WxH")
}

/// Parses two whole numbers split by `separator`; `form` names them in the error (`MIN,MAX`).
pub fn parse_pair(s: &str, separator: char, form: &str) -> Result<(u32, u32), String> {
    let wrong = || format!("`{s}` is not {form}");
    let (a, b) = s.split_once(separator).ok_or_else(wrong)?;
    let n = |v: &str| v.trim().parse::<u32>().map_err(|_| wrong());
    Ok((n(a)?, n(b)?))
}

/// Logging for quadray's programs: `RUST_LOG` when set, else warnings, to stderr.
#[cfg(feature = "logging")]
pub fn init_logging() {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
}
