//! Accuracy against the CPU ground truth: every method by view angle on every bundled map, and
//! how many POM layers match the pyramid.

use super::measure::{AccuracyRow, Bench, Ratios, fixed_layers, ms, ratio, ratio_text, traced};
use crate::report::{PlotSpec, Series, Table, line_plot};
use quadray_displace::accuracy::{Accuracy, Cost};
use quadray_displace::heightmap::HeightMap;
use quadray_displace::maps::{BUNDLED, resized};
use quadray_displace::{DisplaceError, Method, Renderer, Settings, Size};
use std::path::Path;

/// Wrong-hit fraction and texel fetches per pixel by view angle, every method, every bundled map:
/// two tables and one plot (accuracy_MAP.svg in `out`) per map, and every measurement as a row.
pub fn by_view_angle(
    bench: &Bench,
    out: &Path,
) -> Result<(Vec<Table>, Vec<AccuracyRow>), DisplaceError> {
    let (gpu, quick) = (bench.gpu, bench.quick);
    let mut tables = Vec::new();
    let acc_size = if quick { 128 } else { 256 };
    let angles: &[f32] = if quick {
        &[0.0, 45.0, 70.0, 85.0]
    } else {
        &[0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0]
    };
    let candidates = traced(Method::shown);
    let mut accuracy = Vec::new();
    for b in &BUNDLED {
        let map = b.load()?;
        let mut r = Renderer::new(gpu, &map, None, b.surface);
        let mut columns = vec!["method".to_string()];
        columns.extend(angles.iter().map(|a| format!("{a:.0} deg")));
        let mut table = Table {
            title: format!(
                "Wrong-hit fraction by view angle: {} ({}x{} map, {acc_size}x{acc_size})",
                b.name, map.width, map.height
            ),
            columns: columns.clone(),
            rows: vec![],
        };
        let mut fetch_table = Table {
            title: format!(
                "Texel fetches per pixel by view angle: {} ({}x{} map, {acc_size}x{acc_size})",
                b.name, map.width, map.height
            ),
            columns,
            rows: vec![],
        };
        let mut series = Vec::new();
        for c in &candidates {
            let truth = c.method.truth().expect("a traced method");
            let mut row = vec![c.caption()];
            let mut fetch_row = vec![c.caption()];
            let mut points = Vec::new();
            for &angle in angles {
                let s = Settings {
                    view_angle_deg: angle,
                    size: Size::new(acc_size, acc_size),
                    ..c.clone()
                };
                let frame = r.render(gpu, &s)?;
                let acc = Accuracy::measure(&frame, &map, b.surface, &s, truth);
                let cost = Cost::of(&frame);
                row.push(format!("{:.4}", acc.wrong_hit_fraction));
                fetch_row.push(format!("{:.1}", cost.texel_fetches_per_pixel));
                points.push((f64::from(angle), acc.wrong_hit_fraction));
                accuracy.push(AccuracyRow {
                    map: b.name.into(),
                    method: c.caption(),
                    view_angle_deg: angle,
                    wrong_hit_fraction: acc.wrong_hit_fraction,
                    mean_error_texels: acc.mean_error_texels,
                    covered: acc.covered,
                    mean_iterations: cost.mean_iterations,
                    texel_fetches_per_pixel: cost.texel_fetches_per_pixel,
                    iteration_cap_hits: cost.iteration_cap_hits,
                });
            }
            table.row(row);
            fetch_table.row(fetch_row);
            series.push(Series {
                name: c.caption(),
                points,
            });
        }
        tables.push(table);
        tables.push(fetch_table);
        line_plot(
            &out.join(format!("accuracy_{}.svg", b.name)),
            &PlotSpec {
                title: &format!("Wrong hits by view angle: {}", b.name),
                x_label: "view angle (degrees from the normal)",
                y_label: "wrong-hit fraction",
                log_x: false,
                log_y: false,
            },
            &series,
        )?;
    }
    Ok((tables, accuracy))
}

/// How many POM layers match the pyramid on the sharp map at a grazing angle, and at what cost
/// (plot: pom_layers.svg in `out`).
pub fn pom_layers_to_match(
    bench: &mut Bench,
    tiles: &HeightMap,
    out: &Path,
    ratios: &mut Ratios,
) -> Result<Table, DisplaceError> {
    let (gpu, paper) = (bench.gpu, bench.paper);
    let map = resized(tiles, 256);
    let mut r = Renderer::new(gpu, &map, None, BUNDLED[0].surface);
    let grazing = |s: Settings| Settings {
        size: Size::new(paper, paper),
        view_angle_deg: 80.0,
        ..s
    };
    let measure = |r: &mut Renderer, s: &Settings| -> Result<f64, DisplaceError> {
        let frame = r.render(gpu, s)?;
        let truth = s.method.truth().expect("a traced method");
        Ok(Accuracy::measure(&frame, &map, BUNDLED[0].surface, s, truth).wrong_hit_fraction)
    };
    let pyramid_settings = grazing(Method::Pyramid.timed());
    let pyramid_wrong = measure(&mut r, &pyramid_settings)?;
    let pyramid_time = bench.time("pom-match", "tiles", &map, &mut r, &pyramid_settings)?;
    let target = pyramid_wrong.max(0.001);
    let mut t = Table::new(
        format!(
            "POM layers vs accuracy and time (tiles 256^2, {paper}x{paper}, 80 deg); pyramid: {pyramid_wrong:.4} wrong, {} ms",
            ms(pyramid_time)
        ),
        &[
            "layers",
            "wrong-hit fraction",
            "GPU ms",
            "pom / pyramid time",
        ],
    );
    let mut points = Vec::new();
    for layers in [16, 32, 64, 128, 256, 512, 1024, 2048, 4096] {
        let s = grazing(fixed_layers(Method::Pom, layers));
        let wrong = measure(&mut r, &s)?;
        let time = bench.time("pom-match", "tiles", &map, &mut r, &s)?;
        points.push((f64::from(layers), wrong));
        t.row(vec![
            layers.to_string(),
            format!("{wrong:.4}"),
            ms(time),
            ratio_text(ratio(time, pyramid_time)),
        ]);
        ratios.pom_most_layers = Some((layers, wrong, ratio(time, pyramid_time)));
        if wrong <= target {
            ratios.pom_layers_to_match = Some(layers);
            ratios.pom_matched_over_pyramid = ratio(time, pyramid_time);
            break;
        }
    }
    line_plot(
        &out.join("pom_layers.svg"),
        &PlotSpec {
            title: "POM wrong hits by layer count (tiles, 80 deg)",
            x_label: "layers",
            y_label: "wrong-hit fraction",
            log_x: true,
            log_y: false,
        },
        &[
            Series {
                name: "pom".into(),
                points,
            },
            Series {
                name: "pyramid".into(),
                points: vec![(16.0, pyramid_wrong), (1024.0, pyramid_wrong)],
            },
        ],
    )?;
    Ok(t)
}
