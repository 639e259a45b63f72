//! The commit `quadray` is built from, for `quadray --version` and every stats file: the
//! `QUADRAY_COMMIT` variable where it is set (a build from a copy without git's history: a
//! container, a machine the sources were copied to), else git's `HEAD`, with `-modified` when the
//! sources differ from it, else `unknown`. Only this crate has the script, so a new commit
//! rebuilds the `quadray` program and nothing below it.

use std::path::PathBuf;
use std::process::Command;

/// What the binary is built from: the workspace's crates and the locked dependencies.
const SOURCES: [&str; 3] = ["crates", "Cargo.toml", "Cargo.lock"];

fn main() {
    println!("cargo:rerun-if-env-changed=QUADRAY_COMMIT");
    let commit = match std::env::var("QUADRAY_COMMIT") {
        Ok(given) if !given.trim().is_empty() => given.trim().to_string(),
        _ => from_git().unwrap_or_else(|| "unknown".into()),
    };
    println!("cargo:rustc-env=QUADRAY_COMMIT={commit}");
}

/// Runs git in the workspace; its output without the line end, when it succeeds.
fn git(args: &[&str]) -> Option<String> {
    let workspace = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR")?).join("../..");
    let out = Command::new("git")
        .arg("-C")
        .arg(workspace)
        .args(args)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// `HEAD`'s commit, `-modified` when a tracked source differs from it; the script runs again when
/// `HEAD` moves (a checkout, a commit, packed refs) or a source changes.
fn from_git() -> Option<String> {
    let head = git(&["rev-parse", "HEAD"])?;
    let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
    watched.extend(git(&["symbolic-ref", "-q", "HEAD"]));
    for name in watched {
        let path = git(&["rev-parse", "--path-format=absolute", "--git-path", &name]);
        // a path that is not there would make Cargo run the script at every build
        if let Some(path) = path.filter(|p| std::path::Path::new(p).exists()) {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    let top = git(&["rev-parse", "--show-toplevel"])?;
    for source in SOURCES {
        println!("cargo:rerun-if-changed={top}/{source}");
    }
    let changed = git(&["status", "--porcelain", "--untracked-files=no", "--"]
        .into_iter()
        .chain(SOURCES)
        .collect::<Vec<_>>())?;
    Some(if changed.is_empty() {
        head
    } else {
        format!("{head}-modified")
    })
}
