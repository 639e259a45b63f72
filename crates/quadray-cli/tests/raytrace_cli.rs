//! The `quadray raytrace` contract: option names, the stats JSON fields the tables read, the demo scene
//! file from the assets, and clear errors (never a panic) on bad input.

use crate::common;

use common::{assets, quadray_refuses, quadray_writes, read_json, scratch};

#[test]
fn raytrace_writes_the_picture_and_the_stats() {
    let dir = scratch("raytrace-ok");
    let (out, stats) = (dir.join("demo.png"), dir.join("demo.json"));
    let scene = assets().join("scenes/shadows-demo.toml");
    quadray_writes(
        &[
            "raytrace",
            "--scene",
            scene.to_str().unwrap(),
            "--shadows",
            "hst",
            "--nth",
            "6",
            "--size",
            "64x48",
            "--depth",
            "4",
            "--check",
        ],
        &out,
        &stats,
    );
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (64, 48));
    let json = read_json(&stats);
    for key in [
        "scheme",
        "width",
        "height",
        "spp",
        "depth",
        "check",
        "polygons",
        "lights",
        "shadow_polygons",
        "grid",
        "times_s",
        "subschemes",
        "nth",
        "p",
        "alpha",
        "disagreements",
        "shading_points",
    ] {
        assert!(json.get(key).is_some(), "stats lack {key}");
    }
    for key in ["preprocess", "shadow_volumes", "shadow", "other", "total"] {
        assert!(json["times_s"][key].as_f64().unwrap() >= 0.0);
    }
    for key in ["sustain", "self_shadow", "shadow_volume", "conventional"] {
        assert!(json["subschemes"][key].as_u64().is_some());
    }
    assert_eq!(json["nth"]["asked"]["fixed"].as_f64(), Some(6.0));
    assert_eq!(json["nth"]["used"].as_f64(), Some(6.0));
    assert_eq!(json["grid"].as_array().unwrap().len(), 3);
    assert_eq!(json["disagreements"].as_u64(), Some(0));
}

#[test]
fn raytrace_bad_input_is_a_clear_error() {
    let dir = scratch("raytrace-bad");
    let bad_scene = dir.join("bad.toml");
    std::fs::write(&bad_scene, "[camera]\neye = [0, 0, 0]\n").unwrap();
    // More lights than the tracer's per-ray state holds: refused by the scene's validation.
    let lights = dir.join("nine-lights.toml");
    let light = "[[lights]]\nposition = [0, 3, 3]\nintensity = [0.1, 0.1, 0.1]\n";
    std::fs::write(
        &lights,
        format!(
            "[camera]\neye = [0, 1, 5]\nlook_at = [0, 0, 0]\nfov_y_deg = 40\n{}\
             [materials.grey]\ndiffuse = [0.5, 0.5, 0.5]\n[[objects]]\nmaterial = \"grey\"\n\
             polygons = [[[-1, 0, -1], [-1, 0, 1], [1, 0, 1]]]\n",
            light.repeat(9)
        ),
    )
    .unwrap();
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (
            &["raytrace", "--builtin", "nope", "--out", out],
            "unknown builtin",
        ),
        (
            &[
                "raytrace",
                "--builtin",
                "stars",
                "--size",
                "0x5",
                "--out",
                out,
            ],
            "--size",
        ),
        (
            &["raytrace", "--builtin", "stars", "--nth=-3", "--out", out],
            "--nth",
        ),
        (
            &[
                "raytrace",
                "--builtin",
                "stars",
                "--shadows",
                "raster",
                "--out",
                out,
            ],
            "unknown shadow scheme",
        ),
        (
            &[
                "raytrace",
                "--scene",
                bad_scene.to_str().unwrap(),
                "--out",
                out,
            ],
            "bad.toml",
        ),
        (
            &[
                "raytrace",
                "--scene",
                lights.to_str().unwrap(),
                "--out",
                out,
            ],
            "nine-lights.toml: 9 lights; 1 to 8",
        ),
    ];
    for (args, why) in cases {
        quadray_refuses(args, why);
    }
}
