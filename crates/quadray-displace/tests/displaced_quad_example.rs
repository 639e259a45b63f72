//! The example a user copies runs, and draws what `quadray displace` draws for the same setup:
//! `--method pyramid --view-angle 60 --azimuth 0 --light-azimuth 0 --shadows --size 256x256` on the
//! tile map.

#[path = "../examples/displaced_quad.rs"]
#[allow(dead_code)] // its main
mod example;

use quadray_core::image_out::Rgba8Image;
use quadray_displace::scene::{SurfaceKind, View};
use quadray_displace::{Method, Renderer, Settings, Size};
use quadray_gpu::Gpu;

/// Mean FLIP error the example's picture may differ by: its shading approximates quadray's (the
/// albedo and the normal computed in the shader rather than sampled from 8-bit and half-float
/// textures), the traced surface and the shadows are the same.
const FLIP_TOLERANCE: f32 = 0.02;

fn flip_mean(a: &[u8], b: &[u8], side: u32) -> f32 {
    let rgb = |px: &[u8]| -> Vec<u8> { px.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let image = |px| nv_flip::FlipImageRgb8::with_data(side, side, &rgb(px));
    let map = nv_flip::flip(image(a), image(b), nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&map).mean()
}

#[test]
fn the_example_draws_what_quadray_displace_draws() {
    let gpu = Gpu::new().expect("a GPU adapter");
    let map = example::tile_map();
    let picture = example::render(&gpu.device, &gpu.queue, &map);
    let settings = Settings {
        method: Method::Pyramid,
        view_angle_deg: 60.0,
        azimuth_deg: 0.0,
        light_azimuth_deg: 0.0,
        shadows: true,
        size: Size::new(example::SIZE, example::SIZE),
        ..Default::default()
    };
    let view = View::of(SurfaceKind::Wall, &settings);
    assert!(view.eye.distance(example::EYE) < 1e-5, "{}", view.eye);
    assert!(view.light.distance(example::LIGHT) < 1e-5, "{}", view.light);
    let mut renderer = Renderer::new(&gpu, &map, None, SurfaceKind::Wall);
    let quadray = renderer.render(&gpu, &settings).unwrap().color;
    let unshadowed = Settings {
        shadows: false,
        ..settings.clone()
    };
    let without_shadows = renderer.render(&gpu, &unshadowed).unwrap().color;
    let side = example::SIZE;
    let flip = flip_mean(picture.as_raw(), quadray.pixels.as_flattened(), side);
    let save = |name: &str, img: &Rgba8Image| {
        let dir = std::env::temp_dir().join("quadray-displaced-quad");
        std::fs::create_dir_all(&dir).unwrap();
        img.save_png(&dir.join(name)).unwrap();
    };
    if flip > FLIP_TOLERANCE {
        save("quadray.png", &quadray);
        save(
            "example.png",
            &Rgba8Image::from_bytes(side, side, picture.as_raw()),
        );
    }
    assert!(
        flip <= FLIP_TOLERANCE,
        "example vs quadray displace: FLIP mean {flip} > {FLIP_TOLERANCE}"
    );
    // The comparison sees a difference as small as the self-shadows.
    let shadows = flip_mean(
        picture.as_raw(),
        without_shadows.pixels.as_flattened(),
        side,
    );
    eprintln!("FLIP mean: example vs quadray {flip}, vs quadray without shadows {shadows}");
    assert!(
        shadows > 2.0 * FLIP_TOLERANCE,
        "without shadows FLIP mean is only {shadows}"
    );
}
