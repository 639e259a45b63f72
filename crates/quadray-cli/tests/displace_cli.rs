//! The `quadray displace` contract other tools rely on: option names, the stats JSON fields, the
//! heat map beside the output, and clear errors (never a panic) on bad input.

use crate::common;

use common::{assets, quadray_refuses, quadray_writes, read_json, scratch};

#[test]
fn displace_writes_the_picture_the_stats_and_the_error_map() {
    let dir = scratch("displace-ok");
    let map = assets().join("heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png");
    let out = dir.join("tiles.png");
    let stats = dir.join("tiles.json");
    quadray_writes(
        &[
            "displace",
            "--map",
            map.to_str().unwrap(),
            "--method",
            "pom",
            "--layers",
            "1,16",
            "--view-angle",
            "80",
            "--size",
            "96x64",
            "--frames",
            "3",
            "--reference",
        ],
        &out,
        &stats,
    );
    let json = read_json(&stats);
    for field in [
        "method",
        "width",
        "height",
        "map",
        "view_angle_deg",
        "gpu_time_ms",
        "frames",
        "iteration_cap_hits",
        "wrong_hit_fraction",
    ] {
        assert!(json.get(field).is_some(), "stats lack `{field}`: {json}");
    }
    assert_eq!(json["method"], "pom");
    assert_eq!(
        (json["width"].as_u64(), json["height"].as_u64()),
        (Some(96), Some(64))
    );
    // Bevy's POM at 80 degrees on the sharp tile map is wrong on a large share of pixels.
    assert!(
        json["wrong_hit_fraction"].as_f64().unwrap() > 0.05,
        "{json}"
    );
    let picture = image::open(&out).unwrap();
    assert_eq!((picture.width(), picture.height()), (96, 64));
    assert!(dir.join("tiles.error.png").exists());
}

#[test]
fn odd_sized_maps_are_traced_as_stored_without_resample() {
    let dir = scratch("displace-odd");
    let map = assets().join("heightmaps/bevy_parallax/cube_depth.png");
    let (out, stats) = (dir.join("bevy.png"), dir.join("bevy.json"));
    quadray_writes(
        &[
            "displace",
            "--map",
            map.to_str().unwrap(),
            "--convention",
            "depth",
            "--view-angle",
            "60",
            "--size",
            "64x64",
            "--frames",
            "1",
            "--reference",
        ],
        &out,
        &stats,
    );
    let json = read_json(&stats);
    assert_eq!(json["map_size"], serde_json::json!([348, 348]), "{json}");
    assert!(
        json["wrong_hit_fraction"].as_f64().unwrap() <= 0.001,
        "{json}"
    );
}

#[test]
fn bad_input_gets_a_clear_error_and_no_panic() {
    let dir = scratch("displace-bad");
    let out = dir.join("x.png");
    let tiles = assets().join("heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png");
    let too_wide = dir.join("too_wide.png");
    image::GrayImage::new(8193, 1).save(&too_wide).unwrap();
    let text = assets().join("SOURCES.md");
    // clap refuses a setting outside its limits and an unknown method (2), quadray the rest (1)
    let cases: Vec<(Vec<&str>, &str, i32)> = vec![
        (vec!["--map", too_wide.to_str().unwrap()], "8193x1", 1),
        (vec!["--map", text.to_str().unwrap()], "SOURCES.md", 1),
        (vec!["--map", "/nonexistent/map.png"], "map.png", 1),
        (
            vec!["--map", tiles.to_str().unwrap(), "--view-angle", "95"],
            "95 is outside 0..=89",
            2,
        ),
        (
            vec!["--map", tiles.to_str().unwrap(), "--depth-scale", "NaN"],
            "NaN is outside (0, 10]",
            2,
        ),
        (
            vec!["--map", tiles.to_str().unwrap(), "--size", "0x10"],
            "size 0x10",
            2,
        ),
        (
            vec!["--map", tiles.to_str().unwrap(), "--layers", "9,3"],
            "layers 9,3",
            2,
        ),
        (
            vec!["--map", tiles.to_str().unwrap(), "--method", "steep"],
            "possible values: pyramid,",
            2,
        ),
        (
            vec![
                "--map",
                tiles.to_str().unwrap(),
                "--surface",
                "torus",
                "--method",
                "mesh",
            ],
            "curved",
            1,
        ),
    ];
    for (args, expected, code) in cases {
        let mut all = vec!["displace", "--out", out.to_str().unwrap(), "--frames", "1"];
        if !args.contains(&"--size") {
            all.extend(["--size", "32x32"]);
        }
        all.extend(args.iter().copied());
        assert_eq!(quadray_refuses(&all, expected), Some(code), "{args:?}");
    }
}
