//! What the core test files share: the bundled assets and a scratch directory per test.

use std::path::{Path, PathBuf};

const ASSETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets");

pub fn asset(relative: &str) -> PathBuf {
    Path::new(ASSETS).join(relative)
}

/// A fresh directory for one test's files, under the test binary's own folder.
pub fn scratch(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(env!("CARGO_CRATE_NAME"))
        .join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
