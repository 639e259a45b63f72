//! `quadray --version` names the commit the program was built from, checked against git's own
//! answer for the checkout the tests run in (every stats file's commit and adapter are checked by
//! `common::quadray_writes`, in each command's test).

use crate::common::built_commit;
use std::path::Path;
use std::process::Command;

/// git's answer in the workspace, when git is there.
fn git(args: &[&str]) -> Option<String> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
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

/// What the build should have named: the commit given in `QUADRAY_COMMIT`, else git's `HEAD`,
/// `-modified` when the sources differ from it, else `unknown`.
fn expected_commit() -> String {
    if let Ok(given) = std::env::var("QUADRAY_COMMIT")
        && !given.trim().is_empty()
    {
        return given.trim().to_string();
    }
    let Some(head) = git(&["rev-parse", "HEAD"]) else {
        return "unknown".into();
    };
    let changed = git(&[
        "status",
        "--porcelain",
        "--untracked-files=no",
        "--",
        "crates",
        "Cargo.toml",
        "Cargo.lock",
    ])
    .expect("git status");
    if changed.is_empty() {
        head
    } else {
        format!("{head}-modified")
    }
}

#[test]
fn the_version_names_the_commit_the_program_was_built_from() {
    assert_eq!(built_commit(), expected_commit());
}
