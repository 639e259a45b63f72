//! The ray-traced pictures of `quadray demo`: every benchmark scene (the four look-alikes, the
//! Cornell box, the bunny) with conventional shadow rays and with HST side by side, and where their
//! pixels differ.

use super::measure::bench_scenes;
use quadray_core::FileError;
use quadray_core::image_out::{heat_map, montage};
use quadray_shadows::{
    BuildError, Scene, SchemeChoice, Settings, Size, cost, prepare, render_prepared,
};
use std::path::{Path, PathBuf};

/// A pixel difference this large (of 255, largest channel) is white in the heat map.
const DIFFERENCE_WHITE: f32 = 32.0;

/// Renders every scene `size` pixels wide in the paper's 512:480 aspect and writes one montage
/// per scene into `out`: conventional, HST at the predicted N_th (with the shading points whose
/// shadow condition differs from the conventional test), and the pixel difference.
pub fn render_demo(
    out: &Path,
    size: u32,
    mut progress: impl FnMut(&str),
) -> Result<Vec<PathBuf>, FileError> {
    let scenes = bench_scenes().map_err(|e| FileError::new(&e.path, &e.reason))?;
    progress("machine constants");
    let costs = cost::calibrate();
    let (width, height) = (size, (size * 15 / 16).max(1));
    // One calibration for every render: `quadray_shadows::run` would measure it each time.
    let run = |scene: Scene, scheme, check| -> Result<_, BuildError> {
        let settings = Settings {
            scheme,
            size: Size::new(width, height),
            check,
            ..Settings::DEFAULT
        };
        let prep = prepare(scene, scheme)?;
        Ok(render_prepared(&prep, &settings, &costs, &|| {}))
    };
    let mut files = Vec::new();
    for scene in scenes {
        let name = scene.name.clone();
        progress(&format!("{name}: conventional"));
        let invalid = |e: quadray_shadows::BuildError| FileError::new(Path::new(&name), e);
        let (conventional, c) =
            run(scene.clone(), SchemeChoice::Conventional, false).map_err(invalid)?;
        progress(&format!("{name}: hst"));
        let (hst, h) = run(scene, SchemeChoice::Hst, true).map_err(invalid)?;
        let difference: Vec<f32> = conventional
            .pixels
            .iter()
            .zip(&hst.pixels)
            .map(|(a, b)| (0..3).map(|i| a[i].abs_diff(b[i])).max().unwrap_or(0) as f32)
            .collect();
        let differing = difference.iter().filter(|&&d| d > 0.0).count();
        let picture = montage(
            &[
                (
                    format!("conventional, shadow {:.2} s", c.times_s.shadow),
                    conventional,
                ),
                (
                    format!(
                        "HST (N_th {:.0}), shadow {:.2} s",
                        h.nth.used.unwrap_or(h.nth.predicted),
                        h.times_s.shadow
                    ),
                    hst,
                ),
                (
                    format!(
                        "differ: {differing} pixels, {} of {} points",
                        h.disagreements.unwrap_or(0),
                        h.shading_points
                    ),
                    heat_map(width, height, &difference, DIFFERENCE_WHITE),
                ),
            ],
            3,
        );
        let path = out.join(format!("{name}.png"));
        picture.save_png(&path)?;
        files.push(path);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::super::measure::ASSET_SCENES;
    use quadray_shadows::scene::BUILTINS;

    /// The demo writes one montage per benchmark scene: three captioned tiles side by side.
    #[test]
    fn the_demo_writes_a_montage_per_scene() {
        let out = std::env::temp_dir().join(format!("quadray-shadows-demo-{}", std::process::id()));
        let files = super::render_demo(&out, 48, |_| {}).unwrap();
        assert_eq!(files.len(), BUILTINS.len() + ASSET_SCENES.len());
        for f in &files {
            let picture = image::open(f).unwrap();
            assert!(
                picture.width() > 3 * 48 && picture.height() > 45,
                "{}",
                f.display()
            );
        }
        std::fs::remove_dir_all(&out).unwrap();
    }
}
