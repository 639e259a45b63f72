//! Tiles and frames as work items: each item runs as its own `quadray` process with its index in
//! the variable Kubernetes (Indexed Job) or Slurm (job array) sets, and `quadray merge` must give
//! back, bit for bit, what one process renders; bad tile sets are refused by name.

use crate::common;

use common::{quadray_ok, quadray_refuses, scratch};
use std::path::Path;
use std::process::Command;

/// A small scene and image, so that a dozen processes take a second or two.
const SCENE: [&str; 10] = [
    "raytrace",
    "--builtin",
    "stars",
    "--size",
    "40x30",
    "--spp",
    "2",
    "--nth",
    "4",
    "--check",
];

/// Runs `quadray` with `args` as the scheduler would: `variable` set to `index`, the other unset.
fn work_item(args: &[&str], variable: &str, index: u32) {
    let mut run = Command::new(env!("CARGO_BIN_EXE_quadray"));
    for v in ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"] {
        run.env_remove(v);
    }
    let out = run
        .args(args)
        .env(variable, index.to_string())
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("run quadray");
    assert!(
        out.status.success(),
        "{variable}={index} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn same_bytes(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} differs from {}", a.display(), b.display());
}

/// `a` and `b` are the same PNG, and not one colour (the merge of blank tiles would match a
/// blank render too).
fn same_picture(a: &Path, b: &Path) {
    same_bytes(a, b);
    let picture = image::open(a).unwrap().to_rgba8();
    let first = picture.get_pixel(0, 0);
    assert!(
        picture.pixels().any(|p| p != first),
        "{} is one colour",
        a.display()
    );
}

#[test]
fn tiles_from_a_slurm_array_merge_into_the_one_process_render() {
    let dir = scratch("tiles-slurm");
    let s = |p: &str| dir.join(p).to_str().unwrap().to_string();
    quadray_ok(
        &[
            &SCENE[..],
            &["--out", &s("one.png"), "--stats", &s("one.json")],
        ]
        .concat(),
    );
    quadray_ok(&[&SCENE[..], &["--out", &s("one.exr")]].concat());
    let tiles = s("tiles");
    let item = [&SCENE[..], &["--tiles", "3", "--out", &tiles]].concat();
    for i in 0..3 {
        work_item(&item, "SLURM_ARRAY_TASK_ID", i);
    }
    quadray_ok(&["merge", &s("tiles"), "--out", &s("merged.png")]);
    quadray_ok(&["merge", &s("tiles"), "--out", &s("merged.exr")]);
    same_picture(&dir.join("one.png"), &dir.join("merged.png"));
    same_bytes(&dir.join("one.exr"), &dir.join("merged.exr"));
    // Each item's stats lie beside its tile; together they count the one render's points.
    let points: u64 = (0..3)
        .map(|t| {
            let json = common::read_json(&dir.join(format!("tiles/frame0000-tile000{t}.json")));
            json["shading_points"].as_u64().unwrap()
        })
        .sum();
    let one = common::read_json(&dir.join("one.json"));
    assert_eq!(Some(points), one["shading_points"].as_u64());

    // A missing tile, a duplicate and a tile of other settings are named.
    let tile = |t: u32| s(&format!("tiles/frame0000-tile000{t}.exr"));
    quadray_refuses(
        &["merge", &tile(0), &tile(2), "--out", &s("x.png")],
        "frame 0 tile 1",
    );
    std::fs::copy(tile(1), s("copy.exr")).unwrap();
    quadray_refuses(
        &["merge", &s("tiles"), &s("copy.exr"), "--out", &s("x.png")],
        "duplicate",
    );
    let other_dir = s("other");
    let other = [
        &SCENE[..],
        &["--tiles", "3", "--tile", "1", "--out", &other_dir],
    ]
    .concat();
    let other = other
        .iter()
        .map(|a| if *a == "4" { "5" } else { a })
        .collect::<Vec<_>>();
    quadray_ok(&other);
    quadray_refuses(
        &[
            "merge",
            &tile(0),
            &s("other/frame0000-tile0001.exr"),
            &tile(2),
            "--out",
            &s("x.png"),
        ],
        "other settings (--shadows hst --nth 5",
    );
    quadray_refuses(&["merge", &s("one.png"), "--out", &s("x.png")], "one.png");
}

#[test]
fn a_turntable_from_a_kubernetes_indexed_job_merges_frame_by_frame() {
    let dir = scratch("tiles-k8s");
    let s = |p: &str| dir.join(p).to_str().unwrap().to_string();
    let job = [&SCENE[..], &["--orbit", "35", "--frames", "1..3"]].concat();
    let tiles = s("tiles");
    let item = [&job[..], &["--tiles", "2", "--out", &tiles]].concat();
    for i in 0..4 {
        work_item(&item, "JOB_COMPLETION_INDEX", i);
    }
    quadray_ok(&["merge", &s("tiles"), "--out", &s("turn.png")]);
    // The job's options with --frame F (it overrides --frames) render frame F in one process.
    for frame in ["1", "2"] {
        let one = s(&format!("one{frame}.png"));
        quadray_ok(&[&job[..], &["--frame", frame, "--out", &one]].concat());
        same_picture(Path::new(&one), &dir.join(format!("turn.000{frame}.png")));
    }
    // The frames differ: the camera did turn.
    assert_ne!(
        std::fs::read(s("turn.0001.png")).unwrap(),
        std::fs::read(s("turn.0002.png")).unwrap()
    );
}

#[test]
fn work_items_need_a_valid_index_and_one_nth() {
    let dir = scratch("tiles-bad");
    let out = dir.join("t");
    let item = [
        &SCENE[..],
        &["--tiles", "2", "--out", out.to_str().unwrap()],
    ]
    .concat();
    quadray_refuses(&[&item[..], &["--tile", "2"]].concat(), "out of range 0..2");
    let auto: Vec<&str> = item
        .iter()
        .map(|a| if *a == "4" { "auto" } else { a })
        .collect();
    quadray_refuses(&[&auto[..], &["--tile", "0"]].concat(), "--print-nth");
    let too_many = [&SCENE[..], &["--tiles", "31", "--tile", "0", "--out", "t"]].concat();
    quadray_refuses(&too_many, "--tiles 31");
    let mut no_index = Command::new(env!("CARGO_BIN_EXE_quadray"));
    for v in ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"] {
        no_index.env_remove(v);
    }
    let refused = no_index.args(&item).output().unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && stderr.contains("a work item index is needed"));
    let nth = Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args([
            "raytrace",
            "--builtin",
            "stars",
            "--size",
            "40x30",
            "--print-nth",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&nth.stdout);
    assert!(text.trim().parse::<f32>().is_ok_and(|n| n > 0.0), "{text}");
}
