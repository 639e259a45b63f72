//! `quadray bench indirect`: the paper's tables 1-3 on the Cornell box (limit levels, thresholds,
//! RSM sampling at 216/256/2040 samples), error against the brute force for every row, the
//! error-vs-time plot, and the speed ratios (compacted cut vs per-level passes, quadtree vs RSM at
//! equal error). GPU times are medians of timestamp queries; ratios come from one run.

use crate::gpu::{ClusterSettings, FrameTiming, Method, Renderer, Settings, Validity};
use crate::reference::compare;
use crate::{IndirectError, Scene};
use quadray_core::bench::{PlotSpec, Series, Table, line_plot, write_json, write_text};
use quadray_gpu::Gpu;
use serde::Serialize;
use std::path::Path;

pub struct BenchOptions {
    /// 64x64 image and RSM, few frames: seconds on a software rasterizer.
    pub quick: bool,
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
    /// Per quadtree row of table 3: quadtree time / time of the cheapest RSM row with no more
    /// error (static light); `None` where no RSM row reaches the quadtree's error.
    pub quadtree_over_rsm_at_equal_error: Vec<(String, Option<f64>)>,
    /// Per quadtree row of table 3: quadtree time / RSM time at 2040 samples (the paper's "same
    /// quality" point), static light; with both errors.
    pub quadtree_over_rsm_2040: Vec<(String, Option<f64>, f64, f64)>,
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

const RSM_SAMPLES: [u32; 6] = [16, 64, 216, 256, 1024, 2040];
const LIMIT_SIDES: [u32; 3] = [16, 32, 64];
const THRESHOLDS: [(f32, f32); 3] = [(0.45, 0.3), (0.25, 0.6), (0.05, 0.9)];

struct Measure<'a> {
    brute: &'a [[f32; 3]],
    frames: u32,
}

impl Measure<'_> {
    fn row(
        &self,
        r: &mut Renderer,
        table: &'static str,
        method: Method,
        label: String,
    ) -> Result<Row, IndirectError> {
        r.render(method, true, false)?;
        let frame = r.read_frame()?;
        let clusters = if method.uses_quadtree() {
            r.render(Method::Quadtree, true, false)?;
            Some(r.clusters_in_cut()?)
        } else {
            None
        };
        let e = compare(&frame.indirect, self.brute);
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

pub fn run(
    gpu: &Gpu,
    out: &Path,
    options: BenchOptions,
    mut progress: impl FnMut(&str),
) -> Result<BenchResults, IndirectError> {
    let scene = Scene::cornell();
    let (size, rsm_size, frames) = if options.quick {
        (64, 64, 3)
    } else {
        (512, 512, 30)
    };
    let base = Settings {
        width: size,
        height: size,
        rsm_size,
        cluster: ClusterSettings::defaults(rsm_size),
        ..Settings::default()
    };
    let mut r = Renderer::new(gpu, &scene, base.clone())?;
    progress("brute force");
    r.render(Method::Reference, true, false)?;
    let brute = r.read_frame()?.indirect;
    let m = Measure {
        brute: &brute,
        frames,
    };
    let mut rows = Vec::new();
    for side in LIMIT_SIDES.into_iter().filter(|&s| s < rsm_size) {
        r.set_cluster(ClusterSettings::with_limit_side(rsm_size, side))?;
        for method in [Method::Quadtree, Method::QuadtreePasses] {
            progress(&format!("table 1: limit {side}^2, {}", method.name()));
            rows.push(m.row(&mut r, "1", method, format!("limit {side}^2"))?);
        }
    }
    for validity in [Validity::Local, Validity::Recursive] {
        for (depth, normal) in THRESHOLDS {
            progress(&format!("table 2: {depth}/{normal} {validity:?}"));
            r.set_cluster(ClusterSettings {
                depth_threshold: depth,
                normal_threshold: normal,
                validity,
                ..ClusterSettings::with_limit_side(rsm_size, 32)
            })?;
            let label = format!("depth {depth} normal {normal} {validity:?}, limit 32^2");
            rows.push(m.row(&mut r, "2", Method::Quadtree, label)?);
        }
    }
    // Table 2's second scene: the Buddha (100k triangles) in the Cornell room.
    let buddha = Scene::load(&crate::scene::scenes_dir().join("cornell_buddha.toml"))?;
    let mut rb = Renderer::new(gpu, &buddha, base.clone())?;
    progress("table 2: Buddha brute force");
    rb.render(Method::Reference, true, false)?;
    let buddha_brute = rb.read_frame()?.indirect;
    let mb = Measure {
        brute: &buddha_brute,
        frames,
    };
    for (depth, normal) in THRESHOLDS {
        progress(&format!("table 2: Buddha {depth}/{normal}"));
        rb.set_cluster(ClusterSettings {
            depth_threshold: depth,
            normal_threshold: normal,
            ..ClusterSettings::with_limit_side(rsm_size, 32)
        })?;
        let label = format!("Buddha: depth {depth} normal {normal} Local, limit 32^2");
        rows.push(mb.row(&mut rb, "2", Method::Quadtree, label)?);
    }
    for side in [16, 32] {
        r.set_cluster(ClusterSettings::with_limit_side(rsm_size, side))?;
        progress(&format!("table 3: quadtree limit {side}^2"));
        rows.push(m.row(&mut r, "3", Method::Quadtree, format!("limit {side}^2"))?);
    }
    for samples in RSM_SAMPLES {
        progress(&format!("table 3: RSM {samples} samples"));
        let mut rs = Renderer::new(
            gpu,
            &scene,
            Settings {
                samples,
                ..base.clone()
            },
        )?;
        rows.push(m.row(&mut rs, "3", Method::Rsm, format!("{samples} samples"))?);
    }
    let ratios = ratios(&rows);
    let results = BenchResults {
        adapter: gpu.describe(),
        scene: scene.name.clone(),
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
            let cheapest = rsm
                .iter()
                .filter(|r| r.rel_l1 <= q.rel_l1)
                .filter_map(|r| r.static_ms)
                .min_by(f64::total_cmp);
            (q.label.clone(), ratio(q.static_ms, cheapest))
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
