//! `quadray bench indirect`: the paper's tables 1-3 on the Cornell box (limit levels, thresholds,
//! RSM sampling at 216/256/2040 samples), error against the brute force for every row, the
//! error-vs-time plot, and the speed ratios (compacted cut vs per-level passes, quadtree vs RSM at
//! equal error). GPU times are medians of timestamp queries; ratios come from one run.

use super::equal_error::at_error;
use crate::report::{PlotSpec, Series, Table, line_plot};
use quadray_core::{write_json, write_text};
use quadray_gpu::Gpu;
use quadray_indirect::reference::compare;
use quadray_indirect::scene::scenes_dir;
use quadray_indirect::{
    ClusterSettings, FrameTiming, IndirectError, Method, Renderer, Scene, Settings, Validity,
};
use serde::Serialize;
use std::path::Path;

pub struct BenchOptions {
    /// 64x64 image and RSM, few frames: seconds on a software rasterizer.
    pub quick: bool,
    /// Image side instead of the default (512, quick 64).
    pub size: Option<u32>,
    /// RSM side instead of the default (512, quick 64).
    pub rsm_size: Option<u32>,
}

/// One measured configuration.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub table: &'static str,
    pub method: Method,
    pub label: String,
    pub clusters: Option<u32>,
    /// Whole frame, light static (pyramid and cut reused), median ms.
    pub static_ms: Option<f64>,
    /// Whole frame, light moving (everything rebuilt), median ms.
    pub moving_ms: Option<f64>,
    pub static_timing: Option<FrameTiming>,
    pub moving_timing: Option<FrameTiming>,
    pub rel_l1: f64,
    pub rmse: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Ratios {
    /// Per limit side: per-level passes time / compacted cut time (indirect pass, static light).
    pub passes_over_cut_indirect: Vec<(u32, Option<f64>)>,
    /// Per limit side: the same for the whole frame with a moving light.
    pub passes_over_cut_moving_frame: Vec<(u32, Option<f64>)>,
    /// Per quadtree row of table 3: quadtree time / RSM-sampling time at the quadtree's error
    /// (static light), the RSM time interpolated log-log between the two sample counts whose
    /// errors bracket it; `None` where no RSM row reaches the quadtree's error.
    pub quadtree_over_rsm_at_equal_error: Vec<EqualError>,
    /// Per quadtree row of table 3: quadtree time / RSM time at 2040 samples (the paper's "same
    /// quality" point), static light; with both errors.
    pub quadtree_over_rsm_2040: Vec<(String, Option<f64>, f64, f64)>,
}

/// A quadtree setting against RSM sampling at the same error.
#[derive(Clone, Debug, Serialize)]
pub struct EqualError {
    pub quadtree: String,
    pub rel_l1: f64,
    /// RSM samples per pixel that give this error (interpolated).
    pub rsm_samples: Option<f64>,
    pub rsm_ms: Option<f64>,
    pub ratio: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchResults {
    pub adapter: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub rsm_size: u32,
    pub frames: u32,
    pub rows: Vec<Row>,
    pub ratios: Ratios,
}

/// The paper's 216, 256 and 2040, and beyond until RSM sampling reaches the quadtree's error.
const RSM_SAMPLES: [u32; 9] = [16, 64, 216, 256, 1024, 2040, 4096, 8192, 16384];
const LIMIT_SIDES: [u32; 3] = [16, 32, 64];
const THRESHOLDS: [(f32, f32); 3] = [(0.45, 0.3), (0.25, 0.6), (0.05, 0.9)];

/// A scene's brute-force indirect light and the frames per median: what every row of it is
/// measured against.
struct Measure {
    brute: Vec<[f32; 3]>,
    frames: u32,
}

impl Measure {
    fn row(
        &self,
        r: &mut Renderer,
        table: &'static str,
        method: Method,
        label: String,
    ) -> Result<Row, IndirectError> {
        let frame = r.render_frame(method)?;
        let clusters = if method.uses_quadtree() {
            r.render(Method::Quadtree, true, false)?;
            Some(r.clusters_in_cut()?)
        } else {
            None
        };
        let e = compare(&frame.indirect, &self.brute);
        let moving = r.time(method, true, self.frames)?;
        let still = r.time(method, false, self.frames)?;
        Ok(Row {
            table,
            method,
            label,
            clusters,
            static_ms: still.as_ref().map(|t| t.total_ms),
            moving_ms: moving.as_ref().map(|t| t.total_ms),
            static_timing: still,
            moving_timing: moving,
            rel_l1: e.rel_l1,
            rmse: e.rmse,
        })
    }

    /// Table 2's rows for one validity rule: each of [`THRESHOLDS`] at the 32^2 limit, labelled
    /// after `scene` ("" for the Cornell box).
    fn threshold_rows(
        &self,
        r: &mut Renderer,
        rsm_size: u32,
        scene: &str,
        validity: Validity,
        progress: &mut dyn FnMut(&str),
    ) -> Result<Vec<Row>, IndirectError> {
        let mut rows = Vec::new();
        for (depth, normal) in THRESHOLDS {
            progress(&format!("table 2: {scene}{depth}/{normal} {validity:?}"));
            r.set_cluster(ClusterSettings {
                depth_threshold: depth,
                normal_threshold: normal,
                validity,
                ..ClusterSettings::with_limit_side(rsm_size, 32)
            })?;
            let label = format!("{scene}depth {depth} normal {normal} {validity:?}, limit 32^2");
            rows.push(self.row(r, "2", Method::Quadtree, label)?);
        }
        Ok(rows)
    }
}

fn ms(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3}"))
}

fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => Some(a / b),
        _ => None,
    }
}

/// The Cornell box's renderer at the benchmark's sizes, its brute force, and the frames per median.
struct Bench<'g> {
    gpu: &'g Gpu,
    scene: Scene,
    base: Settings,
    renderer: Renderer<'g>,
    m: Measure,
}

/// Table 1: the limit level (16^2, 32^2, 64^2 nodes), compacted cut and per-level passes.
fn table1(b: &mut Bench, progress: &mut dyn FnMut(&str)) -> Result<Vec<Row>, IndirectError> {
    let rsm_size = b.base.rsm_size;
    let mut rows = Vec::new();
    for side in LIMIT_SIDES.into_iter().filter(|&s| s < rsm_size) {
        b.renderer
            .set_cluster(ClusterSettings::with_limit_side(rsm_size, side))?;
        for method in [Method::Quadtree, Method::QuadtreePasses] {
            progress(&format!("table 1: limit {side}^2, {}", method.name()));
            rows.push(b.m.row(&mut b.renderer, "1", method, format!("limit {side}^2"))?);
        }
    }
    Ok(rows)
}

/// Table 2: the thresholds under both validity rules on the Cornell box, then the local rule on
/// the Buddha (100k triangles) in the Cornell room.
fn table2(b: &mut Bench, progress: &mut dyn FnMut(&str)) -> Result<Vec<Row>, IndirectError> {
    let mut rows = Vec::new();
    for validity in [Validity::Local, Validity::Recursive] {
        rows.extend(b.m.threshold_rows(
            &mut b.renderer,
            b.base.rsm_size,
            "",
            validity,
            progress,
        )?);
    }
    let buddha = Scene::load(&scenes_dir().join("cornell_buddha.toml"))?;
    let mut rb = Renderer::new(b.gpu, &buddha, b.base.clone())?;
    progress("table 2: Buddha brute force");
    let buddha_brute = rb.render_frame(Method::Reference)?.indirect;
    let mb = Measure {
        brute: buddha_brute,
        frames: b.m.frames,
    };
    rows.extend(mb.threshold_rows(
        &mut rb,
        b.base.rsm_size,
        "Buddha: ",
        Validity::Local,
        progress,
    )?);
    Ok(rows)
}

/// Table 3: the quadtree at limits 16^2 and 32^2 against RSM sampling at every sample count.
fn table3(b: &mut Bench, progress: &mut dyn FnMut(&str)) -> Result<Vec<Row>, IndirectError> {
    let mut rows = Vec::new();
    for side in [16, 32] {
        b.renderer
            .set_cluster(ClusterSettings::with_limit_side(b.base.rsm_size, side))?;
        progress(&format!("table 3: quadtree limit {side}^2"));
        rows.push(b.m.row(
            &mut b.renderer,
            "3",
            Method::Quadtree,
            format!("limit {side}^2"),
        )?);
    }
    for samples in RSM_SAMPLES {
        progress(&format!("table 3: RSM {samples} samples"));
        let mut rs = Renderer::new(
            b.gpu,
            &b.scene,
            Settings {
                samples,
                ..b.base.clone()
            },
        )?;
        rows.push(b.m.row(&mut rs, "3", Method::Rsm, format!("{samples} samples"))?);
    }
    Ok(rows)
}

/// Every table, the ratios between them, and `results.md`, `results.json` and the error-vs-time
/// plot in `out`.
pub fn run(
    gpu: &Gpu,
    out: &Path,
    options: BenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<BenchResults, IndirectError> {
    let scene = Scene::cornell();
    let (default_size, frames) = if options.quick { (64, 3) } else { (512, 30) };
    let size = options.size.unwrap_or(default_size);
    let rsm_size = options.rsm_size.unwrap_or(default_size);
    let base = Settings::sized(size, size, rsm_size);
    let mut renderer = Renderer::new(gpu, &scene, base.clone())?;
    progress("brute force");
    let brute = renderer.render_frame(Method::Reference)?.indirect;
    let mut b = Bench {
        gpu,
        scene,
        base,
        renderer,
        m: Measure { brute, frames },
    };
    let mut rows = table1(&mut b, &mut progress)?;
    rows.extend(table2(&mut b, &mut progress)?);
    rows.extend(table3(&mut b, &mut progress)?);
    let ratios = ratios(&rows);
    let results = BenchResults {
        adapter: gpu.describe(),
        scene: b.scene.name.clone(),
        width: size,
        height: size,
        rsm_size,
        frames,
        rows,
        ratios,
    };
    write_outputs(out, &results)?;
    Ok(results)
}

fn ratios(rows: &[Row]) -> Ratios {
    let find = |table: &str, method: Method, label: &str| {
        rows.iter()
            .find(|r| r.table == table && r.method == method && r.label == label)
    };
    let indirect_ms = |r: &Row| {
        r.static_timing
            .as_ref()
            .and_then(|t| t.passes.get("indirect").copied())
    };
    let mut passes_over_cut_indirect = Vec::new();
    let mut passes_over_cut_moving_frame = Vec::new();
    for side in LIMIT_SIDES {
        let label = format!("limit {side}^2");
        if let (Some(cut), Some(passes)) = (
            find("1", Method::Quadtree, &label),
            find("1", Method::QuadtreePasses, &label),
        ) {
            passes_over_cut_indirect.push((side, ratio(indirect_ms(passes), indirect_ms(cut))));
            passes_over_cut_moving_frame.push((side, ratio(passes.moving_ms, cut.moving_ms)));
        }
    }
    let rsm: Vec<&Row> = rows.iter().filter(|r| r.method == Method::Rsm).collect();
    let quadtree_over_rsm_at_equal_error = rows
        .iter()
        .filter(|r| r.table == "3" && r.method == Method::Quadtree)
        .map(|q| {
            let at = rsm_at_error(&rsm, q.rel_l1);
            EqualError {
                quadtree: q.label.clone(),
                rel_l1: q.rel_l1,
                rsm_samples: at.map(|(samples, _)| samples),
                rsm_ms: at.map(|(_, ms)| ms),
                ratio: ratio(q.static_ms, at.map(|(_, ms)| ms)),
            }
        })
        .collect();
    let rsm_2040 = rsm.iter().find(|r| r.label == "2040 samples");
    let quadtree_over_rsm_2040 = rows
        .iter()
        .filter(|r| r.table == "3" && r.method == Method::Quadtree)
        .filter_map(|q| {
            rsm_2040.map(|r| {
                (
                    q.label.clone(),
                    ratio(q.static_ms, r.static_ms),
                    q.rel_l1,
                    r.rel_l1,
                )
            })
        })
        .collect();
    Ratios {
        quadtree_over_rsm_2040,
        passes_over_cut_indirect,
        passes_over_cut_moving_frame,
        quadtree_over_rsm_at_equal_error,
    }
}

/// Samples and static-light time at which RSM sampling's error falls to `error`: log-log
/// interpolation between the consecutive sample counts (rows in increasing order) that bracket it.
fn rsm_at_error(rsm: &[&Row], error: f64) -> Option<(f64, f64)> {
    let curve = |value: &dyn Fn(&Row) -> Option<f64>| -> Option<Vec<(f64, f64)>> {
        rsm.iter().map(|r| Some((r.rel_l1, value(r)?))).collect()
    };
    let samples = curve(&|r| r.label.trim_end_matches(" samples").parse::<f64>().ok())?;
    let times = curve(&|r| r.static_ms)?;
    Some((at_error(&samples, error)?, at_error(&times, error)?))
}

fn write_outputs(out: &Path, results: &BenchResults) -> Result<(), IndirectError> {
    let titles = [
        (
            "1",
            "Table 1: limit level (depth 0.05, normal 0.9, local rule)",
        ),
        (
            "2",
            "Table 2: thresholds (limit 32^2; Cornell box, then the Buddha)",
        ),
        ("3", "Table 3: quadtree vs RSM sampling"),
    ];
    let mut md = format!(
        "## Indirect light, Cornell box, {}x{} image, {}^2 RSM, {} frames per median ({})\n\n",
        results.width, results.height, results.rsm_size, results.frames, results.adapter
    );
    for (table, title) in titles {
        let mut t = Table::new(
            title,
            &[
                "method",
                "setting",
                "clusters",
                "static ms",
                "moving ms",
                "rel L1",
                "RMSE",
            ],
        );
        for r in results.rows.iter().filter(|r| r.table == table) {
            t.row(vec![
                r.method.name().into(),
                r.label.clone(),
                r.clusters.map_or("-".into(), |c| c.to_string()),
                ms(r.static_ms),
                ms(r.moving_ms),
                format!("{:.4}", r.rel_l1),
                format!("{:.3e}", r.rmse),
            ]);
        }
        md += &t.to_markdown();
        md.push('\n');
    }
    md += &format!(
        "### Ratios\n\n```json\n{}\n```\n",
        serde_json::to_string_pretty(&results.ratios).unwrap_or_default()
    );
    write_text(&out.join("results.md"), &md)?;
    write_json(&out.join("results.json"), results)?;
    let series = |name: &str, keep: &dyn Fn(&Row) -> bool| Series {
        name: name.into(),
        points: results
            .rows
            .iter()
            .filter(|r| keep(r))
            .filter_map(|r| r.static_ms.map(|t| (t, r.rel_l1)))
            .collect(),
    };
    let all = [
        series("quadtree, limit levels", &|r| {
            r.table == "1" && r.method == Method::Quadtree
        }),
        series("quadtree-passes, limit levels", &|r| {
            r.table == "1" && r.method == Method::QuadtreePasses
        }),
        series("quadtree, thresholds (Cornell)", &|r| {
            r.table == "2" && !r.label.starts_with("Buddha")
        }),
        series("RSM sampling", &|r| r.method == Method::Rsm),
    ];
    let plotted: Vec<Series> = all.into_iter().filter(|s| !s.points.is_empty()).collect();
    if !plotted.is_empty() {
        line_plot(
            &out.join("error_vs_time.svg"),
            &PlotSpec {
                title: "Indirect light: error against time (static light)",
                x_label: "GPU ms per frame",
                y_label: "rel. L1 error of the indirect term",
                log_x: true,
                log_y: true,
            },
            &plotted,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rsm_row(samples: u32, rel_l1: f64, ms: f64) -> Row {
        Row {
            table: "3",
            method: Method::Rsm,
            label: format!("{samples} samples"),
            clusters: None,
            static_ms: Some(ms),
            moving_ms: None,
            static_timing: None,
            moving_timing: None,
            rel_l1,
            rmse: 0.0,
        }
    }

    #[test]
    fn rsm_time_at_an_error_is_interpolated_log_log_between_the_bracketing_rows() {
        // error halves and time quadruples with every 4x the samples
        let rows = [
            rsm_row(100, 0.2, 1.0),
            rsm_row(400, 0.1, 4.0),
            rsm_row(1600, 0.05, 16.0),
        ];
        let rsm: Vec<&Row> = rows.iter().collect();
        let (samples, ms) = rsm_at_error(&rsm, 0.1).unwrap();
        assert!((samples - 400.0).abs() < 1e-9 && (ms - 4.0).abs() < 1e-9);
        // half way in log error between 0.1 and 0.05: half way in log time
        let (samples, ms) = rsm_at_error(&rsm, (0.1f64 * 0.05).sqrt()).unwrap();
        assert!((samples - 800.0).abs() < 1e-6, "{samples}");
        assert!((ms - 8.0).abs() < 1e-9, "{ms}");
        assert!(rsm_at_error(&rsm, 0.01).is_none());
        assert!(rsm_at_error(&rsm, 0.5).is_none());
    }
}
