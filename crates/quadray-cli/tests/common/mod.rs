//! Running the `quadray` binary from the CLI tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

/// Runs `quadray` with `args` in the folder `dir`, backtraces off so stderr holds just the error.
fn quadray_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadray"))
        .current_dir(dir)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("run quadray")
}

fn quadray(args: &[&str]) -> Output {
    quadray_in(Path::new("."), args)
}

/// Runs `quadray` with `args`, checks that it succeeded and returns what it wrote to stderr
/// (warnings).
pub fn quadray_ok(args: &[&str]) -> String {
    quadray_ok_in(Path::new("."), args)
}

/// [`quadray_ok`] run in the folder `dir` (the workspace root, where the documentation writes its
/// command lines).
pub fn quadray_ok_in(dir: &Path, args: &[&str]) -> String {
    let run = quadray_in(dir, args);
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    assert!(run.status.success(), "{args:?}: {stderr}");
    stderr
}

/// Runs `quadray` with `args` and `--out out --stats stats` and checks that it succeeded: the
/// call of each command's test that writes everything.
pub fn quadray_writes(args: &[&str], out: &Path, stats: &Path) {
    let (out, stats) = (out.to_str().unwrap(), stats.to_str().unwrap());
    quadray_ok(&[args, &["--out", out, "--stats", stats]].concat());
}

/// Runs `quadray` with `args` and checks that it failed with an error that mentions `needle`
/// (and no panic); returns the exit code.
pub fn quadray_refuses(args: &[&str], needle: &str) -> Option<i32> {
    let run = quadray(args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "{args:?} succeeded");
    assert!(
        stderr.contains(needle),
        "{args:?}: `{needle}` not in {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    run.status.code()
}

/// The stats file a run wrote.
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap();
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A fresh folder for one test's outputs.
pub fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("quadray-cli-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
