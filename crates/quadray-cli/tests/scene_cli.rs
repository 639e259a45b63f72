//! One scene format for `quadray indirect` and `quadray raytrace`: the bundled glTF scene renders
//! in both (as the TOML Cornell box in `quadray indirect`; lit, shadowed, red left and green
//! right in `quadray raytrace`), and bad scene files are refused with the file named. `quadray
//! scene export` writes the bundled glTF twins of the TOML scenes, which render as the TOML.

use crate::common;

use common::{assets, quadray_ok, quadray_refuses, read_json, scratch};
use std::path::Path;

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().into_rgb8()
}

fn indirect(scene: &Path, out: &Path) {
    quadray_ok(&[
        "indirect",
        "--scene",
        scene.to_str().unwrap(),
        "--size",
        "64x64",
        "--rsm-size",
        "64",
        "--frames",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
}

/// The glTF scene is the Cornell box of `cornell.toml` written as glTF (meshes placed by node
/// transforms, a camera node, a KHR_lights_punctual spot of 1366 cd = 2 W/sr): the pictures
/// agree but for rounding in the vertices, light direction and cone angles.
#[test]
fn indirect_renders_the_gltf_scene_as_its_toml_twin() {
    let dir = scratch("scene-indirect");
    let (from_gltf, from_toml) = (dir.join("gltf.png"), dir.join("toml.png"));
    indirect(&assets().join("scenes/cornell_spot.gltf"), &from_gltf);
    indirect(&assets().join("scenes/cornell.toml"), &from_toml);
    let (a, b) = (rgb(&from_gltf), rgb(&from_toml));
    let (mean, large) = quadray_core::image_out::channel_difference(a.as_raw(), b.as_raw(), 24);
    assert!(
        mean < 1.0 && large < 0.01,
        "mean {mean}, {large} of values off by > 24"
    );
    let lit = a.as_raw().iter().filter(|&&v| v > 128).count();
    assert!(lit > a.as_raw().len() / 20, "the spot lights the floor");
}

#[test]
fn raytrace_renders_the_gltf_scene_lit_and_shadowed() {
    let dir = scratch("scene-raytrace");
    let out = dir.join("gltf.png");
    quadray_ok(&[
        "raytrace",
        "--scene",
        assets().join("scenes/cornell_spot.gltf").to_str().unwrap(),
        "--shadows",
        "hst",
        "--nth",
        "16",
        "--size",
        "64x64",
        "--out",
        out.to_str().unwrap(),
    ]);
    let img = rgb(&out);
    let mean = |x0: u32, x1: u32| {
        let mut sum = [0f64; 3];
        for y in 16..48 {
            for x in x0..x1 {
                for (s, v) in sum.iter_mut().zip(img.get_pixel(x, y).0) {
                    *s += f64::from(v);
                }
            }
        }
        sum
    };
    // The camera looks down -z with +y up: the red wall (x = 0) on the left, the green on the
    // right, so neither the camera nor the materials are mirrored (the bright light and the
    // sRGB encoding narrow the green wall's ratio).
    let (left, right) = (mean(8, 12), mean(52, 56));
    assert!(left[0] > 2.0 * left[1], "left wall {left:?}");
    assert!(right[1] > 1.5 * right[0], "right wall {right:?}");
    let luma: Vec<u32> = img
        .pixels()
        .map(|p| p.0.iter().map(|&c| u32::from(c)).sum())
        .collect();
    // Unlit (ambient only: shadowed, or facing away from the light) and lit surfaces; sRGB
    // lifts the ambient 0.06 to a sum of about 200.
    let dark = luma.iter().filter(|&&l| l < 250).count();
    let bright = luma.iter().filter(|&&l| l > 600).count();
    assert!(
        dark > 100 && bright > 400,
        "{dark} unlit, {bright} lit pixels"
    );
}

#[test]
fn bad_scene_files_are_refused_naming_the_file() {
    let dir = scratch("scene-bad");
    let out = dir.join("x.png");
    let recursive = "malformed/gltf2/RecursiveNodes/RecursiveNodes.gltf";
    let dark = dir.join("dark.toml");
    let cornell = std::fs::read_to_string(assets().join("scenes/cornell.toml")).unwrap();
    let (head, tail) = cornell.split_once("[light]").unwrap();
    let objects = &tail[tail.find("[[mesh]]").unwrap()..];
    std::fs::write(&dark, format!("{head}{objects}")).unwrap();
    let cases = [
        ("raytrace", recursive, "RecursiveNodes.gltf: node"),
        ("indirect", recursive, "RecursiveNodes.gltf: node"),
        // No light at all.
        ("indirect", dark.to_str().unwrap(), "dark.toml: no light"),
        // quadray indirect's builtin meshes.
        (
            "raytrace",
            "scenes/cornell.toml",
            "cornell.toml: object 0: builtin",
        ),
    ];
    for (command, scene, needle) in cases {
        let scene = assets().join(scene);
        let args = [command, "--scene", scene.to_str().unwrap(), "--out"];
        quadray_refuses(&[&args[..], &[out.to_str().unwrap()]].concat(), needle);
    }
}

/// The exposure `quadray` suggests in `stderr`'s warning, if it gave one.
fn suggested_exposure(stderr: &str) -> Option<String> {
    let (_, rest) = stderr.split_once("try --exposure ")?;
    Some(rest.split_whitespace().next()?.to_string())
}

/// A glTF spot of 6 cd (a desk lamp's, where the bundled scene's has 1366): `quadray indirect`
/// renders it nearly black, says so and names an exposure that shows the picture; `quadray
/// raytrace` says the ambient term drowns it (which no exposure changes). The bundled scene
/// draws no warning.
#[test]
fn a_dim_gltf_light_is_reported_with_the_exposure_that_shows_it() {
    let dir = scratch("scene-exposure");
    let bundled = assets().join("scenes/cornell_spot.gltf");
    let text = std::fs::read_to_string(&bundled).unwrap();
    let dim = dir.join("dim.gltf");
    assert!(text.contains("\"intensity\": 1366.0"));
    std::fs::write(
        &dim,
        text.replace("\"intensity\": 1366.0", "\"intensity\": 6.0"),
    )
    .unwrap();
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    let indirect = |scene: &Path| {
        let scene = scene.to_str().unwrap().to_string();
        [
            "indirect",
            "--scene",
            &scene,
            "--size",
            "32x32",
            "--rsm-size",
            "16",
            "--frames",
            "1",
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |args: &[String], extra: &[&str]| {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        quadray_ok(&[&args[..], extra, &["--out", out]].concat())
    };
    assert!(!run(&indirect(&bundled), &[]).contains("WARN"));
    let stderr = run(&indirect(&dim), &[]);
    assert!(stderr.contains("nearly black"), "{stderr}");
    let exposure = suggested_exposure(&stderr).expect("an exposure");
    let stderr = run(&indirect(&dim), &["--exposure", &exposure]);
    assert!(
        suggested_exposure(&stderr).is_none(),
        "{exposure}: {stderr}"
    );
    let lit = rgb(Path::new(out))
        .as_raw()
        .iter()
        .filter(|&&v| v > 128)
        .count();
    assert!(lit > 32, "at --exposure {exposure}: {lit} bright values");

    let raytrace = |scene: &Path| {
        let scene = scene.to_str().unwrap().to_string();
        ["raytrace", "--scene", &scene, "--size", "32x24"]
            .map(String::from)
            .to_vec()
    };
    assert!(!run(&raytrace(&bundled), &[]).contains("WARN"));
    let stderr = run(&raytrace(&dim), &[]);
    assert!(
        stderr.contains("weak against the ambient light"),
        "{stderr}"
    );
}

/// The bundled glTF twins of the sunlit courtyard, the lamplit room and the two rooms joined by a
/// door are what `quadray scene export` writes from their TOML today, byte for byte.
#[test]
fn the_bundled_gltf_twins_are_their_toml_exported() {
    let dir = scratch("scene-export");
    for name in ["courtyard", "lamplit_room", "visibility-door"] {
        let (toml, gltf) = (
            dir.join(format!("{name}.toml")),
            dir.join(format!("{name}.gltf")),
        );
        let scenes = assets().join("scenes");
        // the TOML names no file, so it exports the same from any folder
        std::fs::copy(scenes.join(format!("{name}.toml")), &toml).unwrap();
        quadray_ok(&[
            "scene",
            "export",
            toml.to_str().unwrap(),
            gltf.to_str().unwrap(),
        ]);
        let bundled = std::fs::read(scenes.join(format!("{name}.gltf"))).unwrap();
        assert!(
            std::fs::read(&gltf).unwrap() == bundled,
            "assets/scenes/{name}.gltf is not `quadray scene export` of {name}.toml: export it again"
        );
    }
}

/// `quadray indirect` renders the exported courtyard as its TOML: the same pictures (direct,
/// indirect, combined) to one 8-bit step, and the same work per pixel and error against the
/// brute force. (The point-lit room is held as `Scene`s equal in quadray-indirect's tests: its
/// 18 light views cost seconds here.) In the wide G-buffer and RSM, which carry the scenes' f32
/// values whole: the compact layout rounds normals, albedo and flux to 10-16 bits, and a value
/// the glTF holds a last bit apart can round to the next step in a few texels, which moves the
/// per-tile cuts' refinement of this 16-tile picture (measured: 102.6 against 98.7 evaluations a
/// pixel, the errors within 2e-5 of each other; wide, equal to the last digit).
#[test]
fn indirect_renders_the_exported_courtyard_as_its_toml() {
    let dir = scratch("scene-export-indirect");
    let scenes = assets().join("scenes");
    let render = |file: &str| {
        // courtyard.toml.png, courtyard.gltf.png: one picture each
        let (out, stats) = (
            dir.join(format!("{file}.png")),
            dir.join(format!("{file}.json")),
        );
        quadray_ok(&[
            "indirect",
            "--scene",
            scenes.join(file).to_str().unwrap(),
            "--size",
            "32x32",
            "--rsm-size",
            "16",
            "--gbuffer-layout",
            "wide",
            "--frames",
            "0",
            "--reference",
            "--out",
            out.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ]);
        (out, read_json(&stats))
    };
    let (toml, toml_stats) = render("courtyard.toml");
    let (gltf, gltf_stats) = render("courtyard.gltf");
    for suffix in ["", ".direct", ".indirect"] {
        let picture = |p: &Path| {
            let stem = p.file_stem().unwrap().to_string_lossy();
            rgb(&p.with_file_name(format!("{stem}{suffix}.png")))
        };
        let (a, b) = (picture(&toml), picture(&gltf));
        let (mean, large) = quadray_core::image_out::channel_difference(a.as_raw(), b.as_raw(), 1);
        assert!(
            mean < 0.01 && large == 0.0,
            "courtyard{suffix}: mean {mean}, {large} off by > 1"
        );
    }
    let figure = |stats: &serde_json::Value, path: &str| {
        stats
            .pointer(path)
            .and_then(|v| v.as_f64())
            .unwrap_or_else(|| panic!("{path}"))
    };
    for path in [
        "/vpl_evaluations_per_pixel",
        "/texel_fetches_per_pixel",
        "/error/rel_l1",
        "/error/rmse",
    ] {
        let (a, b) = (figure(&toml_stats, path), figure(&gltf_stats, path));
        assert!(
            (a - b).abs() <= 1e-4 * a.abs(),
            "{path}: {a} from the TOML, {b} from the glTF"
        );
    }
}

/// `quadray scene export` refuses a missing scene, a file it cannot write (not a .gltf) and a
/// builtin mesh no technique has, each with the file named.
#[test]
fn scene_export_refuses_bad_input_naming_the_file() {
    let dir = scratch("scene-export-bad");
    let unknown = dir.join("unknown.toml");
    let courtyard = std::fs::read_to_string(assets().join("scenes/courtyard.toml")).unwrap();
    std::fs::write(
        &unknown,
        format!("{courtyard}\n[[objects]]\nbuiltin = \"sponza\"\n"),
    )
    .unwrap();
    let courtyard = assets().join("scenes/courtyard.toml");
    let (missing, glb, out) = (
        dir.join("missing.toml"),
        dir.join("x.glb"),
        dir.join("x.gltf"),
    );
    let path = |p: &Path| p.to_str().unwrap().to_string();
    for (scene, out, needle) in [
        (path(&missing), path(&out), "missing.toml".to_string()),
        (
            path(&courtyard),
            path(&glb),
            "x.glb: a scene is written as a .gltf".into(),
        ),
        (
            path(&unknown),
            path(&out),
            "unknown.toml: object 11: unknown builtin `sponza`".into(),
        ),
    ] {
        quadray_refuses(&["scene", "export", &scene, &out], &needle);
    }
    assert!(!out.exists() && !glb.exists());
}
