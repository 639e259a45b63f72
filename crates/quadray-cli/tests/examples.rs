//! Each example a user copies draws what the `quadray` binary draws for the same setup: the
//! example built and run as a program, as a user runs it, against the picture of the `quadray`
//! command line its own documentation gives.

use crate::common::{quadray_ok_in, scratch};
use quadray_core::image_out::Rgba8Image;
use quadray_indirect::picture::mean_flip;
use quadray_test_support::examples::{example_program, workspace};
use std::path::Path;
use std::process::Command;

fn load_png(path: &Path) -> Rgba8Image {
    let image = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8();
    Rgba8Image::from_bytes(image.width(), image.height(), image.as_raw())
}

/// The picture of example `name` (`crates/PACKAGE/examples/NAME.rs`), run as a program that writes
/// it into `dir`.
fn example_picture(name: &str, dir: &Path) -> Rgba8Image {
    let out = dir.join(format!("example-{name}.png"));
    let run = Command::new(example_program(name))
        .arg(&out)
        .output()
        .unwrap_or_else(|e| panic!("running example {name}: {e}"));
    let log = String::from_utf8_lossy(&run.stdout) + String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "example {name}: {log}");
    load_png(&out)
}

/// The `quadray` command line the example's documentation says draws its picture: the words
/// between "`quadray " and the next backtick in its `//!` comment, the command's name first.
fn documented_command(package: &str, name: &str) -> Vec<String> {
    let file = workspace().join(format!("crates/{package}/examples/{name}.rs"));
    let source = std::fs::read_to_string(&file).unwrap();
    let doc: Vec<&str> = source
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(str::trim)
        .collect();
    let doc = doc.join(" ");
    let start = doc
        .find("`quadray ")
        .unwrap_or_else(|| panic!("{}: no `quadray ...` command in its doc", file.display()));
    let command = &doc[start + "`quadray ".len()..];
    let end = command.find('`').expect("a closing backtick");
    command[..end]
        .split_whitespace()
        .map(String::from)
        .collect()
}

/// `quadray ARGS [--frames 1] --out DIR/NAME.png` run from the workspace root (where the
/// examples' command lines are written), read back; one timed frame where the command times
/// frames: the picture is what is compared.
fn quadray_picture(args: &[String], dir: &Path, name: &str) -> Rgba8Image {
    let out = dir.join(format!("{name}.png"));
    let timed = ["displace", "indirect"].contains(&args[0].as_str());
    let argv: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .chain(
            if timed {
                ["--frames", "1"].as_slice()
            } else {
                &[]
            }
            .iter()
            .copied(),
        )
        .chain(["--out", out.to_str().unwrap()])
        .collect();
    quadray_ok_in(&workspace(), &argv);
    load_png(&out)
}

/// `displaced_quad` against the `quadray displace` line of its doc on the tile map: mean FLIP at
/// most 0.02 (the example shades with its own simpler shader: the albedo and the normal computed
/// rather than sampled from 8-bit and half-float textures; the surface and the shadows are the
/// same), while the picture without `--shadows` differs by more than twice that.
#[test]
fn displaced_quad_draws_what_quadray_displace_draws() {
    const FLIP_TOLERANCE: f32 = 0.02;
    let dir = scratch("displaced-quad");
    let example = example_picture("displaced_quad", &dir);
    let command = documented_command("quadray-displace", "displaced_quad");
    assert_eq!(command[0], "displace");
    assert!(command.iter().any(|w| w == "--shadows"), "{command:?}");
    let shadowed = quadray_picture(&command, &dir, "shadowed");
    let without: Vec<String> = command.into_iter().filter(|w| w != "--shadows").collect();
    let unshadowed = quadray_picture(&without, &dir, "unshadowed");
    let flip = mean_flip(&shadowed, &example);
    let without_shadows = mean_flip(&unshadowed, &example);
    println!("example vs quadray displace: FLIP {flip}; without shadows {without_shadows}");
    assert!(
        flip <= FLIP_TOLERANCE,
        "example vs quadray displace: mean FLIP {flip} > {FLIP_TOLERANCE} (pictures in {})",
        dir.display()
    );
    assert!(
        without_shadows > 2.0 * FLIP_TOLERANCE,
        "the comparison does not see the shadows: FLIP {without_shadows} without them"
    );
}

/// `gi_gbuffer` (its own device, G-buffer and shader, quadray's public passes) against the
/// `quadray indirect --scene assets/scenes/example-gi.toml ...` line of its doc: the file holds
/// the example's triangles, so the pictures agree to within FLIP noise (mean below 0.005, 99.9% of
/// the pixels within 2 levels), while the picture without the bounce differs.
#[test]
fn gi_gbuffer_draws_what_quadray_indirect_draws() {
    let dir = scratch("gi-gbuffer");
    let example = example_picture("gi_gbuffer", &dir);
    let command = documented_command("quadray-indirect", "gi_gbuffer");
    assert_eq!(command[0], "indirect");
    let cli = quadray_picture(&command, &dir, "default-method");
    assert_eq!((cli.width, cli.height), (example.width, example.height));
    let flip = mean_flip(&cli, &example);
    let close = cli
        .pixels
        .iter()
        .zip(&example.pixels)
        .filter(|(a, b)| a.iter().zip(b.iter()).all(|(x, y)| x.abs_diff(*y) <= 2))
        .count();
    println!("example vs quadray indirect: mean FLIP {flip}, {close} pixels within 2 levels");
    assert!(
        flip < 0.005,
        "mean FLIP {flip} (pictures in {})",
        dir.display()
    );
    let pixels = example.pixels.len();
    assert!(
        close as f64 >= 0.999 * pixels as f64,
        "{close} of {pixels} pixels within 2 levels"
    );
    // The direct light alone, which the command writes beside its picture.
    let direct = load_png(&dir.join("default-method.direct.png"));
    let without_bounce = mean_flip(&direct, &example);
    assert!(
        without_bounce > 0.02,
        "the bounce adds little: FLIP {without_bounce}"
    );
}

/// `hst_scene` against the `quadray raytrace --scene assets/scenes/example-hst.toml ...` line of
/// its doc: pixel for pixel, no tolerance (the same polygons, vertices and materials), and not an
/// empty picture.
#[test]
fn hst_scene_draws_what_quadray_raytrace_draws() {
    let dir = scratch("hst-scene");
    let example = example_picture("hst_scene", &dir);
    let command = documented_command("quadray-shadows", "hst_scene");
    assert_eq!(command[0], "raytrace");
    let cli = quadray_picture(&command, &dir, "hst");
    assert_eq!(
        (cli.width, cli.height),
        (example.width, example.height),
        "picture sizes"
    );
    let differing = example
        .pixels
        .iter()
        .zip(&cli.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "pixels differ between the example and quadray raytrace"
    );
    let colours: std::collections::HashSet<_> = example.pixels.iter().collect();
    assert!(colours.len() > 200, "{} colours", colours.len());
}
