//! The three kinds of light and several at once: a point light's six cube faces and the sun's
//! orthographic map hold the light's whole flux, the direct light of each kind is the analytic
//! value at every pixel, every method sums several lights as the sum of each alone, and the GPU
//! brute force over all their VPLs is the CPU's.

use glam::Vec3;
use quadray_gpu::Gpu;
use quadray_indirect::reference::{brute_force, compare, direct_truth, shadow_mismatch};
use quadray_indirect::scene::scenes_dir;
use quadray_indirect::{Method, Renderer, Scene, Settings};
use std::f32::consts::PI;

fn gpu() -> Gpu {
    Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)")
}

const CAMERA: &str = "[camera]\nposition = [0.5, 0.5, 2.4]\ntarget = [0.5, 0.5, 0.0]\n\
                      fov_y_deg = 39.0\n";
const SPOT: &str = "[[lights]]\nposition = [0.5, 0.97, 0.85]\ndirection = [-0.25, -1.0, -0.55]\n\
                    cone_deg = 55.0\nfalloff_deg = 15.0\nintensity = [2.0, 2.0, 2.0]\n";
const POINT: &str = "[[lights]]\nposition = [0.7, 0.8, 0.6]\nintensity = [0.5, 0.4, 0.3]\n";
const SUN: &str = "[[lights]]\ndirection = [0.3, -1.0, -0.6]\nintensity = [1.5, 1.5, 1.2]\n";

/// The Cornell box lit by `lights` (TOML `[[lights]]` entries).
fn cornell(lights: &str) -> Scene {
    Scene::parse(
        &format!("{CAMERA}{lights}[[objects]]\nbuiltin = \"cornell\"\n"),
        "lights",
    )
    .unwrap()
}

fn flux_sum(r: &Renderer) -> Vec3 {
    r.read_vpls()
        .unwrap()
        .iter()
        .map(|v| Vec3::from(v.flux))
        .sum()
}

/// A point light in the middle of a closed box of albedo 0.5: its six faces' VPLs together
/// reflect half of its 4 pi I (the texels' solid angles sum to the sphere's), and each face a
/// sixth of that.
#[test]
fn a_point_light_s_six_faces_hold_its_whole_flux() {
    let gpu = gpu();
    let scene = Scene::parse(
        &format!(
            "{CAMERA}[[lights]]\nposition = [0.5, 0.5, 0.5]\nintensity = [1.0, 2.0, 3.0]\n\
             [[objects]]\nbox = {{ min = [0, 0, 0], max = [1, 1, 1] }}\nalbedo = [0.5, 0.5, 0.5]\n"
        ),
        "closed",
    )
    .unwrap();
    let mut r = Renderer::new(&gpu, &scene, Settings::sized(16, 16, 64)).unwrap();
    assert_eq!(r.view_count(), 6);
    r.render_frame(Method::Reference).unwrap();
    let vpls = r.read_vpls().unwrap();
    assert_eq!(
        vpls.len(),
        6 * 64 * 64,
        "every texel of every face sees a wall"
    );
    let total = flux_sum(&r);
    let expected = 0.5 * 4.0 * PI * Vec3::new(1.0, 2.0, 3.0);
    println!("point light: {total} of {expected}");
    assert!(
        (total / expected - 1.0).abs().max_element() < 2e-3,
        "{total} vs {expected}"
    );
    let per_face = vpls
        .chunks(64 * 64)
        .map(|face| face.iter().map(|v| v.flux[0]).sum::<f32>())
        .collect::<Vec<_>>();
    for face in per_face {
        assert!((face / (expected.x / 6.0) - 1.0).abs() < 2e-3, "{face}");
    }
}

/// The sun on a square of ground of albedo 0.8, at an angle: the map's VPLs reflect 0.8 E A cos.
#[test]
fn the_sun_s_map_holds_the_flux_it_casts_on_the_ground() {
    let gpu = gpu();
    let scene = Scene::parse(
        &format!(
            "{CAMERA}[[lights]]\ndirection = [0.6, -1.0, 0.3]\nintensity = [2.0, 2.0, 2.0]\n\
             [[objects]]\npolygons = [[[-1, 0, 2], [3, 0, 2], [3, 0, -2], [-1, 0, -2]]]\n\
             albedo = [0.8, 0.8, 0.8]\n"
        ),
        "ground",
    )
    .unwrap();
    let mut r = Renderer::new(&gpu, &scene, Settings::sized(16, 16, 256)).unwrap();
    assert_eq!(r.view_count(), 1);
    r.render_frame(Method::Reference).unwrap();
    let total = flux_sum(&r).x;
    let cos = 1.0 / Vec3::new(0.6, -1.0, 0.3).length();
    let expected = 0.8 * 2.0 * 16.0 * cos;
    println!("sun: {total} of {expected}");
    // the ground's edges cross texels: a texel's worth of its outline
    assert!(
        (total / expected - 1.0).abs() < 0.002,
        "{total} vs {expected}"
    );
}

/// Direct light at every pixel of a floor: a point light's I cos / d^2 from whichever face sees
/// the pixel (no pixel lit twice or missed where faces meet), the sun's E cos.
#[test]
fn direct_light_is_the_analytic_value_at_every_pixel() {
    let gpu = gpu();
    let floor = "[[objects]]\npolygons = [[[-1, 0, 2], [2, 0, 2], [2, 0, -1], [-1, 0, -1]]]\n\
                 albedo = [0.5, 0.5, 0.5]\n";
    let camera = "[camera]\nposition = [0.5, 1.5, 1.8]\ntarget = [0.5, 0.0, 0.3]\nfov_y_deg = 60\n";
    let point = Vec3::new(0.5, 0.4, 0.5);
    let sun = Vec3::new(0.3, -1.0, -0.6);
    for (light, analytic) in [
        (
            "[[lights]]\nposition = [0.5, 0.4, 0.5]\nintensity = [1.0, 1.0, 1.0]\n",
            Box::new(move |x: Vec3, n: Vec3| {
                let to = point - x;
                n.dot(to.normalize()).max(0.0) / to.length_squared()
            }) as Box<dyn Fn(Vec3, Vec3) -> f32>,
        ),
        (
            "[[lights]]\ndirection = [0.3, -1.0, -0.6]\nintensity = [1.0, 1.0, 1.0]\n",
            Box::new(move |_: Vec3, n: Vec3| n.dot(-sun.normalize()).max(0.0)),
        ),
    ] {
        let scene = Scene::parse(&format!("{camera}{light}{floor}"), "floor").unwrap();
        let mut r = Renderer::new(&gpu, &scene, Settings::sized(64, 64, 128)).unwrap();
        let frame = r.render_frame(Method::Reference).unwrap();
        let receivers = r.read_receivers().unwrap();
        let mut checked = 0;
        for (direct, receiver) in frame.direct.iter().zip(&receivers) {
            let Some(receiver) = receiver else { continue };
            let (x, n) = (Vec3::from(receiver.position), Vec3::from(receiver.normal));
            // the floor's albedo as the G-buffer holds it (0.5 in 10 bits: 512 / 1023)
            let expected = receiver.albedo[0] / PI * analytic(x, n);
            assert!(
                (direct[0] - expected).abs() <= 1e-4 * expected.max(1e-3),
                "{light}at {x}: {} where {expected}",
                direct[0]
            );
            checked += 1;
        }
        assert!(checked > 2000, "{checked} pixels see the floor");
    }
}

/// The sunlit courtyard's direct shadows (the roof's, the walls', the bench's) at 128x64 are the
/// traced ones but at a few pixels of their edges: the sun's shadow map is fitted to what the
/// camera sees and sized for the picture, not the 16^2 RSM (whose depth as the shadow map left
/// 16% of the lit pixels' shadows wrong, staircases of a metre a step).
#[test]
fn the_courtyard_s_direct_shadows_are_the_traced_ones() {
    let gpu = gpu();
    let scene = Scene::load(&scenes_dir().join("courtyard.toml")).unwrap();
    let settings = Settings {
        samples: 16,
        ..Settings::sized(128, 64, 16)
    };
    let mut r = Renderer::new(&gpu, &scene, settings.clone()).unwrap();
    let frame = r.render_frame(Method::Rsm).unwrap();
    let truth = direct_truth(&r.read_receivers().unwrap(), &scene, settings.max_lights);
    let wrong = shadow_mismatch(&frame.direct, &truth);
    println!(
        "courtyard: {:.2}% of the lit pixels' direct shadows wrong",
        100.0 * wrong
    );
    assert!(wrong < 0.02, "{:.2}% wrong", 100.0 * wrong);
}

/// Three lights, one of each kind: every method's indirect light and the direct light are the
/// sums of each light's alone (the first light view writes, the others add, in every pass: the
/// sub-sampled cut's upsampling too), frame after frame on the same renderers.
#[test]
fn several_lights_light_as_the_sum_of_each_alone() {
    let gpu = gpu();
    let settings = Settings {
        samples: 32,
        ..Settings::sized(48, 48, 32)
    };
    let all = cornell(&format!("{SPOT}{POINT}{SUN}"));
    let alone = [SPOT, POINT, SUN].map(cornell);
    let subsampled = Settings {
        subsample: 2,
        ..settings.clone()
    };
    // one renderer a scene and setting, every method on it (a renderer's pipelines are the
    // frame's costliest part on lavapipe)
    let cases = [
        (settings, &Method::ALL[..]),
        (subsampled, &[Method::Quadtree][..]),
    ];
    for (settings, methods) in cases {
        let renderer = |scene: &Scene| Renderer::new(&gpu, scene, settings.clone()).unwrap();
        let mut together_renderer = renderer(&all);
        let mut alone_renderers = alone.each_ref().map(renderer);
        let mut first_direct: Option<Vec<[f32; 3]>> = None;
        for &method in methods {
            let together = together_renderer.render_frame(method).unwrap();
            // each frame's direct light is the frame's own: nothing of the last frame's is left
            let first = first_direct.get_or_insert_with(|| together.direct.clone());
            let e = compare(&together.direct, first);
            assert!(
                e.rel_l1 < 1e-6,
                "{method}: direct light unlike the first frame's: {e:?}"
            );
            let (mut indirect, mut direct) =
                (vec![[0.0f32; 3]; 48 * 48], vec![[0.0f32; 3]; 48 * 48]);
            for r in &mut alone_renderers {
                let f = r.render_frame(method).unwrap();
                for (sum, (i, d)) in indirect
                    .iter_mut()
                    .zip(direct.iter_mut())
                    .zip(f.indirect.iter().zip(&f.direct))
                {
                    for c in 0..3 {
                        sum.0[c] += i[c];
                        sum.1[c] += d[c];
                    }
                }
            }
            let what = format!("{method}, subsample {}", settings.subsample);
            let e = compare(&together.indirect, &indirect);
            println!("{what}: indirect {e:?}");
            assert!(e.rel_l1 < 1e-5, "{what}: indirect {e:?}");
            let e = compare(&together.direct, &direct);
            assert!(e.rel_l1 < 1e-6, "{what}: direct {e:?}");
        }
    }
}

/// The GPU brute force over the VPLs of a spot, a point light and the sun is the CPU's, and the
/// default method stays near it.
#[test]
fn the_gpu_brute_force_over_every_light_s_vpls_matches_the_cpu() {
    let gpu = gpu();
    let scene = cornell(&format!("{SPOT}{POINT}{SUN}"));
    let mut r = Renderer::new(&gpu, &scene, Settings::sized(48, 48, 32)).unwrap();
    assert_eq!(r.view_count(), 1 + 6 + 1);
    let image = r.render_frame(Method::Reference).unwrap().indirect;
    let vpls = r.read_vpls().unwrap();
    assert!(vpls.len() > 6 * 32 * 32, "{} VPLs", vpls.len());
    let cpu = brute_force(&vpls, &r.read_receivers().unwrap(), scene.r_min);
    let e = compare(&image, &cpu);
    println!("GPU vs CPU brute force, three lights: {e:?}");
    assert!(e.rel_l1 < 1e-5 && e.rel_max < 1e-4, "{e:?}");
    let default = r.render_frame(Method::DEFAULT).unwrap().indirect;
    let e = compare(&default, &cpu);
    println!("default method vs CPU brute force, three lights: {e:?}");
    assert!(e.rel_l1 < 0.05, "{e:?}");
}
