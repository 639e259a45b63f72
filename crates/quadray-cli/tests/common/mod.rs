//! Running the `quadray` binary from the CLI tests.
// Each test binary uses its own part of this module.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

/// Runs `quadray` with `args`, backtraces off so stderr holds just the error.
pub fn quadray(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("run quadray")
}

/// A fresh folder for one test's outputs.
pub fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("quadray-cli-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
