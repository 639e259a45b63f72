//! The viewer in a real window: under Xvfb with the software Vulkan driver it draws a few frames
//! with a scripted camera, saves a screenshot and the command line that reproduces it, and that
//! command, run headless by `quadray`, renders the same picture. Beside it the viewer saves the
//! whole window (`.window.png`, for a person to look at) and what of its side panel can be read
//! (`.panel.txt`, from egui's layout): every control whole within the panel or within its
//! scrolling part, and the indirect light's pass timings in view. The viewer runs under the
//! Khronos validation layer: its frames (surface, swapchain, both techniques' passes) print no
//! message.
//!
//! Needs Xvfb (`scripts/setup.sh` installs it) and the `quadray` program built beside the viewer,
//! as `cargo test --workspace` does.

use quadray_gpu::validation;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An Xvfb server on a free display, stopped when dropped.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        let found = std::env::var_os("PATH")
            .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join("Xvfb").is_file()));
        assert!(
            found,
            "Xvfb is not installed: run scripts/setup.sh (it installs xvfb and the X11 libraries)"
        );
        let number = (90..190)
            .find(|n| !Path::new(&format!("/tmp/.X{n}-lock")).exists())
            .expect("a free X display number");
        let child = Command::new("Xvfb")
            .args([
                format!(":{number}").as_str(),
                "-screen",
                "0",
                "1024x768x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start Xvfb");
        let socket = PathBuf::from(format!("/tmp/.X11-unix/X{number}"));
        let deadline = Instant::now() + Duration::from_secs(20);
        while !socket.exists() {
            assert!(Instant::now() < deadline, "Xvfb :{number} did not start");
            std::thread::sleep(Duration::from_millis(100));
        }
        Xvfb {
            child,
            display: format!(":{number}"),
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs `program args` on the display under the Khronos validation layer and waits (at most
/// `limit`) for it to succeed with no message of the layer.
fn run_on(display: &str, program: &Path, args: &[&str], limit: Duration) {
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let log = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("xvfb-{}-{run}.log", std::process::id()));
    let mut command = Command::new(program);
    validation::under_layer(&mut command);
    let mut child = command
        .args(args)
        .env("DISPLAY", display)
        .env_remove("WAYLAND_DISPLAY")
        .env("RUST_LOG", "error")
        .stdout(std::fs::File::create(&log).unwrap())
        .spawn()
        .unwrap_or_else(|e| panic!("start {}: {e}", program.display()));
    let deadline = Instant::now() + limit;
    loop {
        if let Some(status) = child.try_wait().expect("wait for the viewer") {
            assert!(
                status.success(),
                "{} {args:?} failed: {status}",
                program.display()
            );
            let printed = std::fs::read_to_string(&log).unwrap();
            let what = format!("{} {args:?}", program.display());
            if let Err(problem) = validation::LayerReport::parse(&printed).check(&what) {
                panic!("{problem}");
            }
            return;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("{} {args:?} ran past {limit:?}", program.display());
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
        .to_rgb8()
}

/// Not one flat colour: the luminance's standard deviation over the picture.
fn contrast(img: &image::RgbImage) -> f64 {
    let lum: Vec<f64> = img
        .pixels()
        .map(|p| 0.299 * p[0] as f64 + 0.587 * p[1] as f64 + 0.114 * p[2] as f64)
        .collect();
    let mean = lum.iter().sum::<f64>() / lum.len() as f64;
    (lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lum.len() as f64).sqrt()
}

/// The screenshot has `size` and is not blank.
fn assert_screenshot(shot: &Path, size: (u32, u32)) {
    let picture = rgb(shot);
    assert_eq!(picture.dimensions(), size, "{}", shot.display());
    assert!(contrast(&picture) > 10.0, "{} is blank", shot.display());
}

/// The side panel at the window's height (`args` leave it at the default, 560): no widget cut at
/// its sides or below the window outside the scrolling part, and a time (`NAME ... ms`) shown
/// whole for each name in `timed`. The window's picture has the view beside the panel and is not
/// blank.
fn assert_panel_legible(shot: &Path, view: (u32, u32), timed: &[&str]) {
    let window = rgb(&shot.with_extension("window.png"));
    assert!(
        window.width() > view.0 && window.height() >= view.1,
        "the window is {:?} for a view of {view:?}",
        window.dimensions()
    );
    assert!(contrast(&window) > 10.0, "the window's picture is blank");
    let panel = shot.with_extension("panel.txt");
    let report = std::fs::read_to_string(&panel).expect("the panel's report");
    let unreachable: Vec<&str> = report
        .lines()
        .filter(|l| l.starts_with("unreachable "))
        .collect();
    assert!(
        unreachable.is_empty(),
        "{}: widgets no scrolling brings whole into view (x0 y0 x1 y1):\n{}",
        panel.display(),
        unreachable.join("\n")
    );
    let shown: Vec<&str> = report
        .lines()
        .filter_map(|l| l.strip_prefix("shown "))
        .collect();
    for name in timed {
        let time = |s: &&str| s.starts_with(&format!("{name} ")) && s.ends_with(" ms");
        assert!(
            shown.iter().any(time),
            "{}: no time of {name} shown whole",
            panel.display()
        );
    }
}

/// The `quadray` program built beside the viewer.
fn quadray() -> PathBuf {
    let path = Path::new(env!("CARGO_BIN_EXE_quadray-view")).with_file_name("quadray");
    assert!(
        path.is_file(),
        "build `quadray` first (cargo build --release -p quadray-cli; `cargo test --workspace` does)"
    );
    path
}

/// Runs the first line of the screenshot's `.txt` (a `quadray ...` command) with `quadray()`,
/// and returns that line.
fn replay(txt: &Path) -> String {
    let text = std::fs::read_to_string(txt).expect("the screenshot's command line");
    let command = text.lines().next().expect("a command line").to_string();
    let bin = quadray();
    let path = format!(
        "{}:{}",
        bin.parent().expect("target folder").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut sh = Command::new("sh");
    let out = sh.args(["-c", &command]).env("PATH", path).output();
    let out = out.expect("run sh");
    let errors = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "`{command}` failed:\n{errors}");
    command
}

/// Same size and, pixel by pixel, within 2/255 on average with at most 1% of the pixels off by
/// more than 16 (the windowed and headless frames are made by the same code on the same GPU).
fn assert_matches(shot: &Path, headless: &Path) {
    let (a, b) = (rgb(shot), rgb(headless));
    assert_eq!(a.dimensions(), b.dimensions(), "{}", shot.display());
    let (mean, far) = quadray_core::image_out::channel_difference(a.as_raw(), b.as_raw(), 16);
    assert!(
        mean <= 2.0 && far <= 0.01,
        "{} vs {}: mean difference {mean:.2}, {:.2}% far off",
        shot.display(),
        headless.display(),
        far * 100.0
    );
}

/// Runs `program` with `args` (split at spaces) on the display until it saves its screenshot of
/// `size` pixels to `shot`; checks the picture, replays the command line saved beside it and
/// compares the two. Returns that command line.
fn screenshot_matches_replay(
    x: &Xvfb,
    program: &Path,
    args: &str,
    shot: &Path,
    size: (u32, u32),
) -> String {
    let _ = std::fs::remove_file(shot);
    let view_size = format!("{}x{}", size.0, size.1);
    let mut args: Vec<&str> = args.split_whitespace().collect();
    args.extend(["--size", &view_size, "--screenshot", shot.to_str().unwrap()]);
    run_on(&x.display, program, &args, Duration::from_secs(300));
    assert_screenshot(shot, size);
    assert_panel_legible(shot, size, &[]);
    let command = replay(&shot.with_extension("txt"));
    assert_matches(shot, &shot.with_extension("headless.png"));
    command
}

#[test]
fn viewer_screenshots_match_their_headless_command_lines() {
    let x = Xvfb::start();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("xvfb");
    std::fs::create_dir_all(&dir).unwrap();

    // displacement: 3 frames turning 10 degrees each from azimuth 20
    let command = screenshot_matches_replay(
        &x,
        Path::new(env!("CARGO_BIN_EXE_quadray-view")),
        "--technique displace --bundled tiles --method pyramid --view-angle 55 --azimuth 20 \
         --spin 10 --shadows --frames 3",
        &dir.join("displace.png"),
        (160, 120),
    );
    assert!(
        command.contains("--azimuth 40 "),
        "scripted camera not applied: {command}"
    );
    // Bevy's 348x348 map, traced as stored: the replayed command needs no --resample
    let command = screenshot_matches_replay(
        &x,
        Path::new(env!("CARGO_BIN_EXE_quadray-view")),
        "--technique displace --bundled bevy-cube --method pyramid-bilinear --view-angle 70 --frames 1",
        &dir.join("displace-odd.png"),
        (160, 120),
    );
    assert!(!command.contains("--resample"), "{command}");

    // indirect light through `quadray view` on a scene of three lights: the camera turns 5
    // degrees a frame and the second light 30; the command line moves every light by number
    let scene =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/cornell_lights.gltf");
    let command = screenshot_matches_replay(
        &x,
        &quadray(),
        &format!(
            "view --technique indirect --scene {} --rsm-size 32 --spin 5 --light 2 \
             --light-spin 30 --frames 3",
            scene.display()
        ),
        &dir.join("indirect.png"),
        (96, 72),
    );
    // the moved light rebuilt the last frame: the panel shows the time of each of its passes
    let passes = [
        quadray_indirect::Pass::Rsm,
        quadray_indirect::Pass::GBuffer,
        quadray_indirect::Pass::Indirect,
        quadray_indirect::Pass::Direct,
    ];
    let timed: Vec<&str> = passes.iter().map(|p| p.name()).chain(["GPU"]).collect();
    assert_panel_legible(&dir.join("indirect.png"), (96, 72), &timed);
    let loaded = quadray_indirect::Scene::load(&scene).unwrap();
    let second = &loaded.lights[1];
    let given = |flag: &str| {
        let word = command.split(&format!("--light-{flag} 2:")).nth(1)?;
        let v = quadray_core::parse_vec3(word.split_whitespace().next()?).unwrap();
        Some(glam::Vec3::from(v))
    };
    let moved = match (second.position(), second.direction()) {
        (Some(p), None) => given("position").unwrap().distance(p),
        (_, Some(d)) => given("direction")
            .unwrap()
            .normalize()
            .distance(d.normalize()),
        (None, None) => unreachable!("a light has a position or a direction"),
    };
    assert!(moved > 0.1, "light 2 moved {moved} in `{command}`");
    assert!(command.contains("--light-direction 3:"), "{command}");
}
