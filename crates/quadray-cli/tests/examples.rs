//! Each example a user copies draws what the `quadray` binary draws for the same setup: the
//! example's own code (included from its file) against the command line's picture, run as a
//! user would run it.

#[allow(dead_code)] // the example's `main`
#[path = "../../quadray-displace/examples/displaced_quad.rs"]
mod displaced_quad;
#[allow(dead_code)]
#[path = "../../quadray-indirect/examples/gi_gbuffer.rs"]
mod gi_gbuffer;
#[allow(dead_code)]
#[path = "../../quadray-shadows/examples/hst_scene.rs"]
mod hst_scene;

use crate::common::{assets, quadray_ok, scratch};
use quadray_core::image_out::Rgba8Image;
use quadray_indirect::picture::{mean_flip, tone_map};
use std::path::Path;

fn load_png(path: &Path) -> Rgba8Image {
    let image = image::open(path).unwrap().to_rgba8();
    Rgba8Image::from_bytes(image.width(), image.height(), image.as_raw())
}

/// `quadray ARGS --out DIR/NAME.png`, read back.
fn quadray_picture(args: &[&str], dir: &Path, name: &str) -> Rgba8Image {
    let out = dir.join(format!("{name}.png"));
    quadray_ok(&[args, &["--out", out.to_str().unwrap()]].concat());
    load_png(&out)
}

/// `displaced_quad` against `quadray displace --method pyramid --view-angle 60 --azimuth 0
/// --light-azimuth 0 --shadows --size 256x256` on the tile map: mean FLIP at most 0.02 (the
/// example shades with its own simpler shader: the albedo and the normal computed rather than
/// sampled from 8-bit and half-float textures; the surface and the shadows are the same), while
/// the picture without shadows differs by more than twice that.
#[test]
fn displaced_quad_draws_what_quadray_displace_draws() {
    const FLIP_TOLERANCE: f32 = 0.02;
    let gpu = quadray_gpu::Gpu::new().expect("a GPU adapter");
    let map = displaced_quad::tile_map();
    let picture = displaced_quad::render(&gpu.device, &gpu.queue, &map);
    let example = Rgba8Image::from_bytes(picture.width(), picture.height(), picture.as_raw());
    let dir = scratch("displaced-quad");
    let tiles = assets().join("heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png");
    let side = displaced_quad::SIZE.to_string();
    let size = format!("{side}x{side}");
    let args = [
        "displace",
        "--map",
        tiles.to_str().unwrap(),
        "--method",
        "pyramid",
        "--view-angle",
        "60",
        "--azimuth",
        "0",
        "--light-azimuth",
        "0",
        "--size",
        &size,
        // One timed frame: the picture is what is compared.
        "--frames",
        "1",
    ];
    let shadowed = quadray_picture(&[&args[..], &["--shadows"]].concat(), &dir, "shadowed");
    let unshadowed = quadray_picture(&args, &dir, "unshadowed");
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

/// `gi_gbuffer` (its own device, G-buffer and shader, quadray's public passes) against `quadray
/// indirect --scene assets/scenes/example-gi.toml --size 256x256 --rsm-size 128`: the file holds
/// the example's triangles, and the pictures agree to within FLIP noise (mean below 0.005, 99.9%
/// of the pixels within 2 levels), while the picture without the bounce differs.
#[test]
fn gi_gbuffer_draws_what_quadray_indirect_draws() {
    let scene_file = assets().join("scenes/example-gi.toml");
    let file = quadray_indirect::scene::Scene::load(&scene_file).unwrap();
    let built = gi_gbuffer::scene();
    assert_eq!(file.triangles.len(), built.triangles.len());
    for (a, b) in file.triangles.iter().zip(&built.triangles) {
        for (u, v) in a.iter().zip(b) {
            let same =
                |x: [f32; 3], y: [f32; 3]| x.iter().zip(y).all(|(p, q)| (p - q).abs() < 1e-6);
            assert!(
                same(u.position, v.position)
                    && same(u.normal, v.normal)
                    && same(u.albedo, v.albedo),
                "the scene file's triangles are not the example's: {a:?} vs {b:?}"
            );
        }
    }
    let gpu = quadray_gpu::Gpu::new().expect("a GPU adapter");
    let s = gi_gbuffer::settings();
    let (w, h) = (s.size.width, s.size.height);
    let radiance = gi_gbuffer::render(&gpu.device, &gpu.queue).unwrap();
    let rgb: Vec<[f32; 3]> = radiance.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let example = tone_map(w, h, &rgb, 1.0);
    let dir = scratch("gi-gbuffer");
    let size = format!("{w}x{h}");
    let rsm = s.rsm_size.to_string();
    let cli = quadray_picture(
        &[
            "indirect",
            "--scene",
            scene_file.to_str().unwrap(),
            "--size",
            &size,
            "--rsm-size",
            &rsm,
            "--frames",
            "1",
        ],
        &dir,
        "default-method",
    );
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
    assert!(
        close as f64 >= 0.999 * f64::from(w * h),
        "{close} of {} pixels within 2 levels",
        w * h
    );
    // The direct light alone, which the command writes beside its picture.
    let direct = load_png(&dir.join("default-method.direct.png"));
    let without_bounce = mean_flip(&direct, &example);
    assert!(
        without_bounce > 0.02,
        "the bounce adds little: FLIP {without_bounce}"
    );
}

/// `hst_scene` against `quadray raytrace --scene assets/scenes/example-hst.toml` with the
/// example's settings as flags (`--shadows hst --nth 8 --size 320x240 ...`): pixel for pixel, no
/// tolerance (the same polygons, vertices and materials), and not an empty picture.
#[test]
fn hst_scene_draws_what_quadray_raytrace_draws() {
    let example = hst_scene::render(hst_scene::scene().unwrap()).unwrap();
    let dir = scratch("hst-scene");
    let scene_file = assets().join("scenes/example-hst.toml");
    let flags = hst_scene::settings().to_args();
    let args: Vec<&str> = ["raytrace", "--scene", scene_file.to_str().unwrap()]
        .into_iter()
        .chain(flags.iter().map(String::as_str))
        .collect();
    let cli = quadray_picture(&args, &dir, "hst");
    let differing = example
        .pixels
        .iter()
        .zip(&cli.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        (cli.width, cli.height),
        (example.width, example.height),
        "picture sizes"
    );
    assert_eq!(
        differing, 0,
        "pixels differ between the example and quadray raytrace"
    );
    let colours: std::collections::HashSet<_> = example.pixels.iter().collect();
    assert!(colours.len() > 200, "{} colours", colours.len());
}
