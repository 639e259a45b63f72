//! The workspace's example programs, built for a test and run as a user runs them
//! (`cargo run --example NAME`), rather than their source compiled into the test.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The executable of the workspace's example `name`, built the first time a test of this binary
/// asks for one (every example at once) by `cargo build --workspace --examples` in the profile the
/// running test was built with: the same features as `cargo test --workspace`, so the libraries
/// that test built are reused. Panics with cargo's output where the build fails.
pub fn example_program(name: &str) -> PathBuf {
    static BUILT: OnceLock<Result<Vec<(String, PathBuf)>, String>> = OnceLock::new();
    let built = BUILT.get_or_init(build_examples).as_ref();
    let examples = built.unwrap_or_else(|e| panic!("{e}"));
    examples
        .iter()
        .find(|(example, _)| example == name)
        .map(|(_, program)| program.clone())
        .unwrap_or_else(|| panic!("no example `{name}` in the workspace"))
}

/// The workspace root: this crate lives in `crates/`.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every example of the workspace, (name, executable), built by cargo.
fn build_examples() -> Result<Vec<(String, PathBuf)>, String> {
    let test = std::env::current_exe().map_err(|e| format!("the test's own path: {e}"))?;
    // a test runs from `target/PROFILE/deps/`; cargo names the dev profile's folder `debug`
    let folder = test
        .parent()
        .and_then(Path::parent)
        .and_then(Path::file_name)
        .and_then(|f| f.to_str())
        .ok_or_else(|| format!("no profile folder above {}", test.display()))?;
    let profile = if folder == "debug" { "dev" } else { folder };
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let manifest = workspace().join("Cargo.toml");
    let output = Command::new(cargo)
        .args(["build", "--workspace", "--examples", "--profile", profile])
        .arg("--manifest-path")
        .arg(&manifest)
        .arg("--message-format=json-render-diagnostics")
        .output()
        .map_err(|e| format!("running cargo: {e}"))?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        return Err(format!("cargo build --examples failed:\n{stderr}"));
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    let mut examples = Vec::new();
    for line in stdout.lines() {
        let Ok(message) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        let target = &message["target"];
        let is_example = target["kind"]
            .as_array()
            .is_some_and(|kinds| kinds.iter().any(|k| k == "example"));
        if let (true, Some(name), Some(program)) = (
            is_example,
            target["name"].as_str(),
            message["executable"].as_str(),
        ) {
            examples.push((name.to_string(), PathBuf::from(program)));
        }
    }
    Ok(examples)
}
