//! The `gi_gbuffer` example (its own device, G-buffer and shader, quadray's public passes)
//! against quadray's own render of the same scene, the path `quadray indirect` takes.

#[path = "../examples/gi_gbuffer.rs"]
#[allow(dead_code)]
mod example;

use quadray_gpu::Gpu;
use quadray_indirect::picture::{mean_flip, tone_map};
use quadray_indirect::{Method, Renderer};

#[test]
fn gi_gbuffer_example_matches_quadrays_own_render() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let s = example::settings();
    let (w, h) = (s.size.width, s.size.height);
    let radiance = example::render(&gpu.device, &gpu.queue).unwrap();
    let rgb: Vec<[f32; 3]> = radiance.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let picture = tone_map(w, h, &rgb, 1.0);

    let mut renderer = Renderer::new(&gpu, &example::scene(), s.clone()).unwrap();
    let frame = renderer.render_frame(Method::Quadtree).unwrap();
    let quadray = tone_map(w, h, &frame.combined(), 1.0);
    let direct_only = tone_map(w, h, &frame.direct, 1.0);

    // Same passes, same inputs: the pictures agree to within FLIP noise (tolerance 0.005 mean).
    let flip = mean_flip(&quadray, &picture);
    println!("example vs quadray: mean FLIP {flip}");
    assert!(flip < 0.005, "mean FLIP {flip}");
    let close = quadray
        .pixels
        .iter()
        .zip(&picture.pixels)
        .filter(|(a, b)| a.iter().zip(b.iter()).all(|(x, y)| x.abs_diff(*y) <= 2))
        .count();
    assert!(
        close as f64 >= 0.999 * f64::from(w * h),
        "{close} of {} pixels within 2 levels",
        w * h
    );
    // and the bounce is there: without it the picture is visibly darker
    let without_bounce = mean_flip(&direct_only, &picture);
    assert!(
        without_bounce > 0.02,
        "indirect adds little: {without_bounce}"
    );
}
