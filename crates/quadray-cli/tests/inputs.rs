//! Every command's parameters are bounded and its output paths checked before any work: the
//! refusal names the parameter, its value and its range, writes nothing and makes no folder; the
//! files a scene refers to are read only inside its folder unless `--allow-outside-paths` says
//! otherwise; a bare mesh file is refused with what to give instead.

use crate::common::{assets, quadray_refuses, scratch};
use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `quadray` with `args` and checks that it is refused within seconds (an input let through
/// would start the work: `--frames 1000000` runs for hours) with `needle` in its error and no
/// panic; returns the exit code.
fn refused_before_the_work(args: &[&str], needle: &str) -> Option<i32> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > Duration::from_secs(30) {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("{args:?}: still running after 30 s, not refused");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    assert!(!status.success(), "{args:?} succeeded");
    assert!(
        stderr.contains(needle),
        "{args:?}: `{needle}` not in {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    status.code()
}

/// A glTF scene whose one buffer is `uri` (a triangle's 36 bytes), without a camera.
fn gltf_with_buffer(path: &Path, uri: &str) {
    std::fs::write(path, quadray_test_support::gltf::triangle_with_buffer(uri)).unwrap();
}

#[test]
fn bad_inputs_are_refused_before_any_work() {
    let dir = scratch("inputs");
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    let missing_dir = dir.join("no-such-folder");
    let in_missing = missing_dir.join("x.png");
    let in_missing = in_missing.to_str().unwrap();
    let cornell = assets().join("scenes/cornell.toml");
    let cornell = cornell.to_str().unwrap();
    let mesh = assets().join("meshes/cornell_box/cornell_box.obj");
    let mesh = mesh.to_str().unwrap();
    let map = assets().join("heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png");
    let map = map.to_str().unwrap();
    let not_a_scene = "cornell_box.obj: a mesh file, not a scene: give a scene that places it";
    let folder_missing = format!("the folder {} does not exist", missing_dir.display());
    let cases: Vec<(Vec<&str>, String)> =
        vec![
        (
            vec!["indirect", "--out", out, "--method", "quadtree", "--interleave", "3"],
            "indirect-light options: interleave 3 must be a power of two".into(),
        ),
        (
            vec!["indirect", "--out", out, "--frames", "1000000"],
            "invalid value '1000000' for '--frames <FRAMES>': 1000000 is outside 0..=1000".into(),
        ),
        (
            vec!["indirect", "--out", "noext"],
            "invalid value 'noext' for '--out <OUT>': the format is chosen by the name's ending: \
             one of .png"
                .into(),
        ),
        (
            vec!["indirect", "--out", in_missing],
            format!("invalid value '{in_missing}' for '--out <OUT>': {folder_missing}"),
        ),
        (
            vec!["indirect", "--out", out, "--stats", in_missing],
            folder_missing.clone(),
        ),
        (
            vec!["indirect", "--out", out, "--camera-position", "1e30,0,0"],
            "invalid value '1e30,0,0' for '--camera-position <CAMERA_POSITION>': x = 1e30 is \
             outside the limit |coordinate| <= 1e7"
                .into(),
        ),
        (
            vec!["indirect", "--out", out, "--camera-target", "0,0,-2e7"],
            "z = -2e7 is outside the limit |coordinate| <= 1e7".into(),
        ),
        (
            vec!["indirect", "--out", out, "--light-position", "1:0,1e8,0"],
            "invalid value '1:0,1e8,0' for '--light-position <LIGHT_POSITION>': y = 1e8 is \
             outside the limit |coordinate| <= 1e7"
                .into(),
        ),
        (
            vec!["indirect", "--out", out, "--camera-orbit", "200"],
            "'--camera-orbit <DEG>': 200 is outside -180..=180".into(),
        ),
        (
            vec!["indirect", "--out", out, "--scene", mesh],
            not_a_scene.into(),
        ),
        (
            vec!["raytrace", "--out", out, "--scene", mesh],
            not_a_scene.into(),
        ),
        (
            vec!["raytrace", "--out", "noext", "--scene", cornell],
            "--out noext: the format is chosen by the name's ending: one of .png, .exr".into(),
        ),
        (
            vec!["raytrace", "--out", in_missing, "--scene", cornell],
            folder_missing.clone(),
        ),
        (
            vec!["displace", "--map", map, "--out", out, "--frames", "0"],
            "'--frames <FRAMES>': 0 is outside 1..=10000".into(),
        ),
        (
            vec!["displace", "--map", map, "--out", "x.jpg"],
            "one of .png".into(),
        ),
        (
            vec!["scene", "export", cornell, "/nonexistent_dir/x.gltf"],
            "invalid value '/nonexistent_dir/x.gltf' for '<OUT>': the folder /nonexistent_dir \
             does not exist"
                .into(),
        ),
    ];
    for (args, needle) in cases {
        // clap's refusal at parse time, or quadray's before the GPU is opened
        let code = refused_before_the_work(&args, &needle);
        assert!(matches!(code, Some(1 | 2)), "{args:?}: exit code {code:?}");
    }
    assert!(!Path::new(out).exists() && !missing_dir.exists());
    assert!(!Path::new("/nonexistent_dir").exists());
}

/// A glTF buffer reached by `..` or an absolute path is refused by name; `--allow-outside-paths`
/// reads it (the scene then fails later: it has no camera).
#[test]
fn files_outside_the_scene_s_folder_are_read_only_when_allowed() {
    let dir = scratch("outside");
    let folder = dir.join("scene");
    std::fs::create_dir_all(&folder).unwrap();
    let triangle: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let outside = dir.join("outside.bin");
    std::fs::write(&outside, triangle).unwrap();
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    for uri in [
        "../outside.bin",
        "../../../../../../../../etc/passwd",
        outside.to_str().unwrap(),
    ] {
        let scene = folder.join("scene.gltf");
        gltf_with_buffer(&scene, uri);
        let scene = scene.to_str().unwrap();
        let refusal = format!(
            "scene.gltf: refers to `{uri}`, outside the folder {}: files are read only inside \
             the scene's folder (--allow-outside-paths reads it)",
            folder.display()
        );
        for command in ["indirect", "raytrace"] {
            quadray_refuses(&[command, "--scene", scene, "--out", out], &refusal);
        }
        if uri != "../../../../../../../../etc/passwd" {
            let allowed = [
                "indirect",
                "--allow-outside-paths",
                "--scene",
                scene,
                "--out",
                out,
            ];
            quadray_refuses(&allowed, "scene.gltf: no camera");
        }
    }
}
