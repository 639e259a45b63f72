//! `scripts/gpu-tables.sh`, the one command that refreshes the GPU tables on a machine with a GPU,
//! tried on whatever adapter the suite has (lavapipe) in its quick mode, so that it still runs
//! the day a GPU comes: the smoke stage's lines, rows of every table (the runs narrowed to a few
//! of each kind), the results packed.

use crate::common::{assert_provenance, built_commit, scratch};
use std::path::Path;
use std::process::Command;

#[test]
fn the_gpu_tables_script_writes_every_table_and_packs_them() {
    let out = scratch("gpu-tables");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let run = Command::new(root.join("scripts/gpu-tables.sh"))
        .args([
            "--quick",
            "--smoke",
            "^indirect-quadtree-tiles$",
            "--runs",
            "^(displace-.*|indirect-(quadtree|quadtree-tiles|quadtree-tiles-wide|rsm|quadtree-interleave-4)|\
             equal-error-cornell-(default|one-cut-interleave-4|rsm-64|rsm-256))$",
            "--budget",
            "0",
            "--bin",
            env!("CARGO_BIN_EXE_quadray"),
        ])
        .arg("--out")
        .arg(&out)
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // the smoke stage, narrowed to one case: a line a pass, the frame as timed last
    for pass in [
        "setup", "rsm", "pyramid", "gbuffer", "indirect", "direct", "timed",
    ] {
        let line = format!("indirect-quadtree-tiles/{pass}: done in ");
        assert!(stdout.contains(&line), "no `{line}` in {stdout}");
    }
    assert!(!stdout.contains("displace-pyramid/"), "{stdout}");
    let folder = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.is_dir())
        .expect("bench/<device>/");
    let summary = std::fs::read_to_string(folder.join("summary.md")).unwrap();
    // the tables say which build and adapter they measured, and so does each stats file
    let heading = summary.lines().next().unwrap();
    assert!(
        heading.ends_with(&format!("(commit {})", built_commit())),
        "{heading}"
    );
    let stats = folder.join("indirect-1080p/quadtree.json");
    assert_provenance(&crate::common::read_json(&stats), true);
    let rows = |section: &str| {
        let (_, rest) = summary.split_once(section).unwrap();
        rest.split("\n## ")
            .next()
            .unwrap()
            .lines()
            .filter(|l| {
                l.starts_with("| ")
                    && !l.starts_with("| method")
                    && !l.starts_with("| run")
                    && !l.starts_with("| scene")
            })
            .count()
    };
    // 5 methods at the quick mode's one angle and pyramid with lod auto; 3 methods, the
    // default one with the wide G-buffer too, and a candidate; at equal error 2 methods against
    // RSM sampling at 2 sample counts, each row with RSM sampling's time at its error or where it
    // lies outside the sweep
    assert_eq!(rows("## Displacement frame"), 6, "{summary}");
    assert_eq!(rows("## Indirect light"), 5, "{summary}");
    assert_eq!(rows("## Equal error"), 4, "{summary}");
    assert!(
        summary.contains("| cornell | one-cut-interleave-4 |")
            && summary.contains("| quadtree-tiles-wide | wide |")
            && summary.contains("| compact |"),
        "{summary}"
    );
    assert!(
        summary.contains("Skipped: bench-indirect"),
        "the budget of 0 s skips the paper tables"
    );
    assert!(out.join("gpu-tables.tar.gz").metadata().unwrap().len() > 1000);
}
