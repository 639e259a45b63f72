//! The pictures a person looks at: for every bundled map and a few view angles, every method side
//! by side with the error heat maps of the searches; self-shadowing; LOD levels (figure 18).

use quadray_core::image_out::{Rgba8Image, montage};
use quadray_displace::accuracy::{Accuracy, Cost, GroundTruth};
use quadray_displace::cone::ConeMap;
use quadray_displace::maps::BUNDLED;
use quadray_displace::reference::Surface;
use quadray_displace::scene::SurfaceKind;
use quadray_displace::{DisplaceError, Lod, Method, Renderer, Settings, Size};
use quadray_gpu::Gpu;
use std::path::{Path, PathBuf};

/// The ground truth of a method that searches the height field: an error heat map of it shows
/// where the search went wrong (bump mapping's hits are the flat surface's; the mesh is
/// rasterised).
fn searched_truth(method: Method) -> Option<Surface> {
    method.truth().filter(|_| method.describe().searches)
}

/// Renders the demo into `out` (side `size` pixels per picture); returns the files written.
pub fn render_demo(
    gpu: &Gpu,
    out: &Path,
    size: u32,
    mut progress: impl FnMut(&str),
) -> Result<Vec<PathBuf>, DisplaceError> {
    let mut written = Vec::new();
    for bundled in &BUNDLED {
        let name = bundled.name;
        progress(&format!("{name}: loading"));
        let map = bundled.load()?;
        let color = bundled.load_color()?;
        let mut renderer = Renderer::new(gpu, &map, color.as_ref(), bundled.surface);
        // one cone map for the surface and the torus where both address the map alike
        let cones = ConeMap::build(&map, bundled.surface.addressing());
        renderer.set_cone_map(gpu, &cones, None)?;
        for angle in [35.0, 65.0, 80.0] {
            progress(&format!("{name}: every method at {angle:.0} degrees"));
            let methods = Method::ALL.map(|m| Settings {
                view_angle_deg: angle,
                size: Size::new(size, size),
                ..m.shown()
            });
            let mut tiles: Vec<(String, Rgba8Image)> = Vec::new();
            let mut heat: Vec<(String, Rgba8Image)> = Vec::new();
            // each truth surface traced once a view, for every method that searches it
            let mut truths: Vec<(Surface, GroundTruth)> = Vec::new();
            for s in &methods {
                let frame = renderer.render(gpu, s)?;
                if let Some(truth) = searched_truth(s.method) {
                    let traced = match truths.iter().position(|(t, _)| *t == truth) {
                        Some(i) => &truths[i].1,
                        None => {
                            let traced = GroundTruth::trace(&map, bundled.surface, s, truth);
                            &truths.push_mut((truth, traced)).1
                        }
                    };
                    let acc = traced.measure(&frame);
                    heat.push((
                        format!("{} err {:.1}%", s.caption(), acc.wrong_hit_fraction * 100.0),
                        acc.heat_map(),
                    ));
                }
                tiles.push((s.caption(), frame.color));
            }
            tiles.extend(heat);
            let path = out.join(format!("{}_{angle:.0}deg.png", bundled.name));
            montage(&tiles, 4).save_png(&path)?;
            written.push(path);
        }
        // A curved mesh whose tangents MikkTSpace generated.
        progress(&format!("{name}: a torus"));
        let mut torus = Renderer::new(gpu, &map, color.as_ref(), SurfaceKind::Torus);
        if SurfaceKind::Torus.addressing() == bundled.surface.addressing() {
            torus.set_cone_map(gpu, &cones, None)?;
        }
        let mut tiles = Vec::new();
        for (method, truth) in Method::ALL
            .into_iter()
            .filter_map(|m| Some((m, searched_truth(m)?)))
        {
            let s = Settings {
                view_angle_deg: 50.0,
                size: Size::new(size, size),
                shadows: true,
                ..method.shown()
            };
            let frame = torus.render(gpu, &s)?;
            let acc = Accuracy::measure(&frame, &map, SurfaceKind::Torus, &s, truth);
            let label = format!(
                "torus {} err {:.1}%",
                s.caption(),
                acc.wrong_hit_fraction * 100.0
            );
            tiles.push((label, frame.color));
        }
        let path = out.join(format!("{}_torus.png", bundled.name));
        montage(&tiles, 4).save_png(&path)?;
        written.push(path);
        // Self-shadowing, and the cost of the search per pixel.
        progress(&format!("{name}: self-shadowing"));
        let s = Settings {
            view_angle_deg: 60.0,
            size: Size::new(size, size),
            ..Default::default()
        };
        let plain = renderer.render(gpu, &s)?;
        let shadowed = renderer.render(
            gpu,
            &Settings {
                shadows: true,
                ..s.clone()
            },
        )?;
        let bilinear_shadowed = renderer.render(
            gpu,
            &Settings {
                shadows: true,
                method: Method::PyramidBilinear,
                ..s.clone()
            },
        )?;
        let iterations = Cost::heat_map(&plain, 64.0);
        let tiles = vec![
            ("pyramid".to_string(), plain.color),
            ("pyramid + shadows".to_string(), shadowed.color),
            ("bilinear + shadows".to_string(), bilinear_shadowed.color),
            ("iterations (0..64)".to_string(), iterations),
        ];
        let path = out.join(format!("{}_shadows.png", bundled.name));
        montage(&tiles, 4).save_png(&path)?;
        written.push(path);
        // Figure 18: the finest level the traversal may reach, coarser and coarser.
        progress(&format!("{name}: levels of detail"));
        let top = map.levels();
        let lods: Vec<(String, Rgba8Image)> = [
            Lod::Auto,
            Lod::Level(0),
            Lod::Level(2),
            Lod::Level(3),
            Lod::Level(4),
            Lod::Level(5),
        ]
        .into_iter()
        .filter(|l| !matches!(l, Lod::Level(k) if *k > top))
        .map(|lod| {
            let frame = renderer.render(
                gpu,
                &Settings {
                    lod,
                    view_angle_deg: 70.0,
                    ..s.clone()
                },
            )?;
            let name = match lod {
                Lod::Auto => "lod auto".to_string(),
                Lod::Level(k) => format!("finest level {k}"),
            };
            Ok((name, frame.color))
        })
        .collect::<Result<_, DisplaceError>>()?;
        let path = out.join(format!("{}_lod.png", bundled.name));
        montage(&lods, 3).save_png(&path)?;
        written.push(path);
    }
    Ok(written)
}
