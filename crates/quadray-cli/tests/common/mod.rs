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

/// Runs `quadray` with `args` and `--out out --stats stats` and checks that it succeeded and that
/// the stats say what they measured: the call of each command's test that writes everything.
pub fn quadray_writes(args: &[&str], out: &Path, stats: &Path) {
    let (out, stats_path) = (out.to_str().unwrap(), stats.to_str().unwrap());
    quadray_ok(&[args, &["--out", out, "--stats", stats_path]].concat());
    assert_provenance(&read_json(stats), args[0] != "raytrace");
}

/// The commit `quadray --version` names (`quadray 0.1.0 (commit C)`).
pub fn built_commit() -> String {
    let version = quadray_ok_stdout(&["--version"]);
    let (_, commit) = version
        .trim()
        .strip_suffix(')')
        .and_then(|v| v.split_once(" (commit "))
        .unwrap_or_else(|| panic!("no commit in `quadray --version`: {version}"));
    commit.to_string()
}

/// `stats` name the commit `quadray --version` names and, from a command that ran on the GPU
/// (`on_gpu`), the adapter `quadray adapter` names; the ray tracer's, which run on the CPU, none.
pub fn assert_provenance(stats: &serde_json::Value, on_gpu: bool) {
    static ADAPTER: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    let provenance = &stats["provenance"];
    assert_eq!(provenance["commit"], built_commit().as_str(), "{stats}");
    let adapter = &provenance["adapter"];
    if !on_gpu {
        assert!(adapter.is_null(), "{provenance}");
        return;
    }
    let described = ADAPTER.get_or_init(|| quadray_ok_stdout(&["adapter"]).trim().to_string());
    for field in ["name", "backend", "driver", "driver_info", "device_type"] {
        assert!(
            adapter[field].is_string(),
            "no adapter {field}: {provenance}"
        );
    }
    let name = adapter["name"].as_str().unwrap();
    let backend = adapter["backend"].as_str().unwrap();
    assert!(
        described.starts_with(&format!("{name} ({backend}, ")),
        "the stats' adapter {adapter} is not `quadray adapter`'s {described}"
    );
}

/// Runs `quadray` with `args`, checks that it succeeded and returns what it printed.
fn quadray_ok_stdout(args: &[&str]) -> String {
    let run = quadray(args);
    assert!(
        run.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    String::from_utf8_lossy(&run.stdout).into_owned()
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
