//! The pictures a person looks at: for every bundled map and a few view angles, every method side
//! by side with the error heat maps of the searches; self-shadowing; LOD levels (figure 18).

use quadray_core::image_out::{Rgba8Image, montage};
use quadray_displace::accuracy::{Accuracy, Cost};
use quadray_displace::maps::BUNDLED;
use quadray_displace::pyramid::Addressing;
use quadray_displace::scene::SurfaceKind;
use quadray_displace::{DisplaceError, Lod, Method, Renderer, Settings};
use quadray_gpu::Gpu;
use std::path::{Path, PathBuf};

fn caption(s: &Settings) -> String {
    match s.method {
        Method::Pom | Method::Relief => format!("{} {}-{}", s.method, s.layers.0, s.layers.1),
        Method::Cone => format!("cone {}+{}", s.layers.1, s.binary_steps),
        m => m.to_string(),
    }
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
        progress(bundled.name);
        let map = bundled.load()?;
        let color = bundled.load_color()?;
        let mut renderer = Renderer::new(gpu, &map, color.as_ref(), bundled.surface);
        let addressing = if bundled.surface.wraps() {
            Addressing::Wrap
        } else {
            Addressing::Clamp
        };
        for angle in [35.0, 65.0, 80.0] {
            let base = Settings {
                view_angle_deg: angle,
                width: size,
                height: size,
                ..Default::default()
            };
            let methods = [
                Settings {
                    method: Method::Pyramid,
                    ..base.clone()
                },
                Settings {
                    method: Method::PyramidBilinear,
                    ..base.clone()
                },
                Settings {
                    method: Method::Mesh,
                    ..base.clone()
                },
                Settings {
                    method: Method::Bump,
                    ..base.clone()
                },
                Settings {
                    view_angle_deg: angle,
                    width: size,
                    height: size,
                    ..Settings::bevy_pom()
                },
                Settings {
                    view_angle_deg: angle,
                    width: size,
                    height: size,
                    ..Settings::threejs_relief()
                },
                Settings {
                    view_angle_deg: angle,
                    width: size,
                    height: size,
                    ..Settings::relaxed_cone()
                },
                Settings {
                    method: Method::Parallax,
                    ..base.clone()
                },
            ];
            let mut tiles: Vec<(String, Rgba8Image)> = Vec::new();
            let mut heat: Vec<(String, Rgba8Image)> = Vec::new();
            for s in &methods {
                let frame = renderer.render(gpu, s)?;
                if s.method.traces_rays() && s.method != Method::Bump {
                    let acc = Accuracy::measure(&frame, &map, addressing, s.method.truth());
                    heat.push((
                        format!("{} err {:.1}%", caption(s), acc.wrong_hit_fraction * 100.0),
                        acc.heat_map(),
                    ));
                }
                tiles.push((caption(s), frame.color));
            }
            tiles.extend(heat);
            let path = out.join(format!("{}_{angle:.0}deg.png", bundled.name));
            montage(&tiles, 4).save_png(&path)?;
            written.push(path);
        }
        // A curved mesh whose tangents MikkTSpace generated.
        let mut torus = Renderer::new(gpu, &map, color.as_ref(), SurfaceKind::Torus);
        let at = |s: Settings| Settings {
            view_angle_deg: 50.0,
            width: size,
            height: size,
            ..s
        };
        let mut tiles = Vec::new();
        for s in [
            Settings {
                method: Method::PyramidBilinear,
                shadows: true,
                ..Default::default()
            },
            Settings::bevy_pom(),
            Settings::threejs_relief(),
        ] {
            let s = at(s);
            let frame = torus.render(gpu, &s)?;
            let acc = Accuracy::measure(&frame, &map, Addressing::Wrap, s.method.truth());
            let label = format!(
                "torus {} err {:.1}%",
                caption(&s),
                acc.wrong_hit_fraction * 100.0
            );
            tiles.push((label, frame.color));
        }
        let path = out.join(format!("{}_torus.png", bundled.name));
        montage(&tiles, 3).save_png(&path)?;
        written.push(path);
        // Self-shadowing, and the cost of the search per pixel.
        let s = Settings {
            view_angle_deg: 60.0,
            width: size,
            height: size,
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
