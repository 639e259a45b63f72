//! `quadray-bevy-gi` as a user runs it without a display (`--screenshot`): the Cornell box glTF
//! through Bevy's loader and renderer, with and without quadray's bounce. That the bounce is the
//! right light is `quadray-bevy`'s `gi.rs` (the plugin against `quadray indirect`); this holds the
//! program: it runs headless, writes its picture at the size asked, and the bounce brightens the
//! room and darkens nothing.

use std::path::Path;
use std::process::Command;

/// Runs the program with `--screenshot DIR/NAME.png --size 64x64 --rsm-size 64` and `extra`,
/// and reads the picture back.
fn screenshot(dir: &Path, name: &str, extra: &[&str]) -> image::RgbaImage {
    let path = dir.join(format!("{name}.png"));
    let run = Command::new(env!("CARGO_BIN_EXE_quadray-bevy-gi"))
        .args(["--screenshot", path.to_str().unwrap()])
        .args(["--size", "64x64", "--rsm-size", "64"])
        .args(extra)
        .output()
        .expect("run quadray-bevy-gi");
    assert!(
        run.status.success(),
        "quadray-bevy-gi {extra:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

#[test]
fn the_gi_program_adds_the_bounce_to_its_headless_picture() {
    let dir = std::env::temp_dir().join(format!("quadray-bevy-gi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Both at once: each mostly waits on its own frames.
    let (lit, unlit) = std::thread::scope(|s| {
        let lit = s.spawn(|| screenshot(&dir, "bounce", &["--method", "reference"]));
        let unlit = s.spawn(|| screenshot(&dir, "no-bounce", &["--no-gi"]));
        (lit.join().unwrap(), unlit.join().unwrap())
    });
    assert_eq!(lit.dimensions(), (64, 64));
    assert_eq!(unlit.dimensions(), (64, 64));
    let luma = |p: &image::Rgba<u8>| p.0[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
    let (mut brighter, mut darker) = (0, 0);
    for (a, b) in lit.pixels().zip(unlit.pixels()) {
        brighter += usize::from(luma(a) > luma(b));
        darker += usize::from(luma(a) < luma(b));
    }
    println!("{brighter} of 4096 pixels brighter with the bounce, {darker} darker");
    // Measured: every pixel (the room fills the picture).
    assert!(brighter >= 3900, "only {brighter} of 4096 pixels brighter");
    assert_eq!(darker, 0, "{darker} pixels darker with the bounce");
}
