//! `quadray bench shadows`: the paper's tables 1-4 and figure 6 on the four look-alike scenes,
//! with the SAH BVH as today's baseline. Every time is the median of several renders; methods are
//! compared as ratios within one run.

use crate::cost::{self, MachineCosts, SceneStats};
use crate::scene::{BUILTINS, Scene};
use crate::trace::Prepared;
use crate::{Nth, RunOptions, RunReport, SchemeChoice, prepare, render_prepared};
use quadray_core::FileError;
use quadray_core::bench::{PlotSpec, Series, Table, line_plot, write_json, write_text};
use serde::Serialize;
use std::path::Path;

/// Timings of one scheme on one scene (medians, seconds).
#[derive(Clone, Debug, Serialize)]
pub struct SchemeRow {
    pub scheme: String,
    pub nth: Option<f64>,
    pub preprocess: f64,
    pub shadow: f64,
    pub other: f64,
    pub total: f64,
    pub disagreements: u64,
    pub shading_points: u64,
    pub report: RunReport,
}

/// One point of figure 6.
#[derive(Clone, Debug, Serialize)]
pub struct SweepPoint {
    pub nth: f64,
    pub shadow: f64,
    pub conventional_share: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct SceneResult {
    pub scene: String,
    pub stats: SceneStats,
    /// N_th of `--nth auto`: equation 12 with the pilot's corrections ([`cost::FollowUp`]).
    pub predicted_nth: f64,
    /// Equation 12 as written.
    pub equation_12_nth: f64,
    pub follow_up: cost::FollowUp,
    pub schemes: Vec<SchemeRow>,
    pub sweep: Vec<SweepPoint>,
    /// The sweep's N_th of least shadow time (the predicted one included).
    pub best_nth: f64,
    /// Shadow time at the predicted N_th over the time at the best, the median of the ratios of
    /// [`BenchResults::confirm_rounds`] fresh paired renders (1 when the predicted N_th is the
    /// best). The least of the sweep's medians is the luckiest of them, so holding the predicted
    /// time against it would count that luck against the prediction.
    pub predicted_over_best: f64,
    pub shadow_at_predicted: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchResults {
    pub quick: bool,
    pub width: u32,
    pub height: u32,
    pub depth: u32,
    pub runs: usize,
    /// Paired renders at the predicted and the best N_th per scene.
    pub confirm_rounds: usize,
    pub threads: usize,
    pub costs_ns: MachineCosts,
    pub scenes: Vec<SceneResult>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One scheme prepared for timing: preprocessing times of `runs` preparations, the checked
/// render (disagreements) and the timed renders so far.
struct Contender {
    opts: RunOptions,
    prep: Prepared,
    preprocess: Vec<f64>,
    check: RunReport,
    reports: Vec<RunReport>,
}

impl Contender {
    fn new(scene: &Scene, opts: RunOptions, costs: &MachineCosts, runs: usize) -> Self {
        let mut preprocess = Vec::new();
        let mut prep = None;
        for _ in 0..runs {
            let p = prepare(scene.clone(), opts.scheme);
            preprocess.push(p.preprocess_s);
            prep = Some(p);
        }
        let prep = prep.expect("at least one run");
        let checked = RunOptions {
            check: true,
            ..opts
        };
        let (_, check) = render_prepared(&prep, &checked, costs, &|| {});
        Self {
            opts,
            prep,
            preprocess,
            check,
            reports: Vec::new(),
        }
    }

    fn render(&mut self, costs: &MachineCosts) {
        let report = render_prepared(&self.prep, &self.opts, costs, &|| {}).1;
        self.reports.push(report);
    }

    fn row(&self) -> SchemeRow {
        let pre = median(self.preprocess.clone());
        let shadow = median(self.reports.iter().map(|r| r.times_s.shadow).collect());
        let other = median(self.reports.iter().map(|r| r.times_s.other).collect());
        SchemeRow {
            scheme: self.check.scheme.clone(),
            nth: self.check.nth.used,
            preprocess: pre,
            shadow,
            other,
            total: pre + shadow + other,
            disagreements: self.check.disagreements.unwrap_or(0),
            shading_points: self.check.shading_points,
            report: self.reports[0].clone(),
        }
    }
}

/// The scenes of the benchmark: the four look-alikes, then the Cornell box and the bunny from
/// the repository's assets.
pub fn bench_scenes() -> Result<Vec<Scene>, crate::scene::SceneError> {
    let mut scenes: Vec<Scene> = BUILTINS
        .iter()
        .map(|(name, ..)| Scene::builtin(name).expect("builtin"))
        .collect();
    for file in ASSET_SCENES {
        scenes.push(Scene::load(&crate::scene::assets_dir().join(file))?);
    }
    Ok(scenes)
}

/// Scene files of the benchmark under `assets/`.
pub const ASSET_SCENES: [&str; 2] = ["scenes/shadows-cornell.toml", "scenes/shadows-bunny.toml"];

/// Runs the whole benchmark and writes `results.json`, `shadows.md` and one figure-6 SVG per scene
/// into `out`.
pub fn bench_shadows(
    quick: bool,
    out: &Path,
    progress: &dyn Fn(&str),
) -> Result<BenchResults, FileError> {
    let (width, height, runs) = if quick { (128, 120, 1) } else { (512, 480, 5) };
    let confirm_rounds = 3 * runs;
    let depth = 5;
    let sweep_values: Vec<f64> = if quick {
        vec![0.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0]
    } else {
        vec![
            0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0, 96.0, 128.0,
            192.0, 256.0,
        ]
    };
    let costs = cost::calibrate();
    progress(&format!("machine constants (ns): {costs:?}"));
    let base = RunOptions {
        scheme: SchemeChoice::Conventional,
        nth: Nth::Auto,
        width,
        height,
        spp: 1,
        depth,
        check: false,
        costs: Some(costs),
    };
    let mut scenes = Vec::new();
    let all = bench_scenes().map_err(|e| FileError::new(&e.path, &e.reason))?;
    for scene in all {
        let name = scene.name.clone();
        let mut schemes = vec![
            SchemeChoice::Conventional,
            SchemeChoice::Volume,
            SchemeChoice::Hst,
            SchemeChoice::Bvh,
        ];
        if cfg!(feature = "embree") {
            schemes.push(SchemeChoice::Embree);
        }
        let mut contenders: Vec<Contender> = schemes
            .iter()
            .map(|&scheme| Contender::new(&scene, RunOptions { scheme, ..base }, &costs, runs))
            .collect();
        // Interleaved rounds, so that a busy spell of the machine weighs on every scheme alike.
        for _ in 0..runs {
            for c in &mut contenders {
                c.render(&costs);
            }
        }
        progress(&format!("{name}: schemes"));
        let rows: Vec<SchemeRow> = contenders.iter().map(Contender::row).collect();
        let prep = &contenders[2].prep;
        let stats = *prep.stats();
        let equation_12 = cost::predicted_nth(&costs, &stats);
        let (predicted, follow_up) = prep.predicted_nth(&costs, depth);
        let hst_at = |nth: f64| RunOptions {
            scheme: SchemeChoice::Hst,
            nth: Nth::Fixed(nth as f32),
            ..base
        };
        // Figure 6: the sweep and the predicted N_th, timed in the same interleaved rounds.
        let mut values = sweep_values.clone();
        values.push(predicted);
        let mut times: Vec<Vec<RunReport>> = vec![Vec::new(); values.len()];
        for _ in 0..runs {
            for (&nth, t) in values.iter().zip(&mut times) {
                t.push(render_prepared(prep, &hst_at(nth), &costs, &|| {}).1);
            }
        }
        let mut sweep: Vec<SweepPoint> = values
            .iter()
            .zip(&times)
            .map(|(&nth, reports)| {
                let r = &reports[0];
                SweepPoint {
                    nth,
                    shadow: median(reports.iter().map(|r| r.times_s.shadow).collect()),
                    conventional_share: r.subschemes.conventional as f64
                        / r.shadow_decisions.max(1) as f64,
                }
            })
            .collect();
        let at_predicted = sweep.pop().expect("predicted point");
        progress(&format!("{name}: sweep"));
        let best = sweep
            .iter()
            .chain(std::iter::once(&at_predicted))
            .min_by(|a, b| a.shadow.total_cmp(&b.shadow))
            .expect("sweep");
        let predicted_over_best = if best.nth == predicted {
            1.0
        } else {
            let ratios: Vec<f64> = (0..confirm_rounds)
                .map(|round| {
                    // Alternating which goes first, so that neither always finds the caches warm.
                    let time = |nth| render_prepared(prep, &hst_at(nth), &costs, &|| {}).1;
                    let (p, b) = if round % 2 == 0 {
                        let p = time(predicted);
                        (p, time(best.nth))
                    } else {
                        let b = time(best.nth);
                        (time(predicted), b)
                    };
                    p.times_s.shadow / b.times_s.shadow
                })
                .collect();
            median(ratios)
        };
        progress(&format!("{name}: predicted against best N_th"));
        scenes.push(SceneResult {
            scene: name,
            stats,
            predicted_nth: predicted,
            equation_12_nth: equation_12,
            follow_up,
            best_nth: best.nth,
            predicted_over_best,
            shadow_at_predicted: at_predicted.shadow,
            schemes: rows,
            sweep,
        });
    }
    let results = BenchResults {
        quick,
        width,
        height,
        depth,
        runs,
        confirm_rounds,
        threads: rayon::current_num_threads(),
        costs_ns: costs,
        scenes,
    };
    write_json(&out.join("results.json"), &results)?;
    for s in &results.scenes {
        figure6(&out.join(format!("fig6-{}.svg", s.scene)), s)?;
    }
    write_text(&out.join("shadows.md"), &markdown(&results))?;
    Ok(results)
}

fn figure6(path: &Path, s: &SceneResult) -> Result<(), FileError> {
    let ms = |x: f64| x * 1e3;
    let xmax = s.sweep.last().map_or(1.0, |p| p.nth);
    let flat = |name: &str, y: f64| Series {
        name: name.into(),
        points: vec![(0.0, ms(y)), (xmax, ms(y))],
    };
    let top = s
        .sweep
        .iter()
        .map(|p| p.shadow)
        .chain(s.schemes.iter().map(|r| r.shadow))
        .fold(0.0, f64::max);
    let mut series = vec![
        Series {
            name: "HST".into(),
            points: s.sweep.iter().map(|p| (p.nth, ms(p.shadow))).collect(),
        },
        flat("conventional", s.schemes[0].shadow),
        flat("shadow volume", s.schemes[1].shadow),
        flat("BVH shadow rays", s.schemes[3].shadow),
        Series {
            name: format!("predicted N_th = {:.1}", s.predicted_nth),
            points: vec![
                (s.predicted_nth.min(xmax), 0.0),
                (s.predicted_nth.min(xmax), ms(top)),
            ],
        },
    ];
    if let Some(embree) = s.schemes.get(4) {
        series.push(flat("Embree shadow rays", embree.shadow));
    }
    let title = format!("{}: shadow testing time against N_th", s.scene);
    let spec = PlotSpec {
        title: &title,
        x_label: "N_th",
        y_label: "shadow testing (ms)",
        log_x: false,
        log_y: false,
    };
    line_plot(path, &spec, &series)
}

fn markdown(r: &BenchResults) -> String {
    let pct = |x: f64, of: f64| format!("{:.0}%", 100.0 * x / of.max(1e-12));
    let ms = |x: f64| format!("{:.1}", x * 1e3);
    let mut md = format!(
        "## Hybrid shadow testing (`quadray bench shadows{}`)\n\n{}x{}, recursion depth {}, 1 sample per pixel, median of {} render(s), {} threads. \
         Times are CPU milliseconds of all threads (the paper reports CPU minutes); ratios from one run. \
         Shadow time at the predicted N_th over the best N_th of the sweep: median of {} paired renders.\n\n",
        if r.quick { " --quick" } else { "" },
        r.width,
        r.height,
        r.depth,
        r.runs,
        r.threads,
        r.confirm_rounds
    );
    let c = &r.costs_ns;
    let mut t1 = Table::new(
        "Table 1: machine constants (ns; the paper: 2.00, 2.54, 0.23, 1.88 ms)",
        &["C_s", "C_i", "C_c", "C_o"],
    );
    t1.row(vec![
        format!("{:.1}", c.c_s),
        format!("{:.1}", c.c_i),
        format!("{:.1}", c.c_c),
        format!("{:.1}", c.c_o),
    ]);
    md += &t1.to_markdown();
    let mut t2 = Table::new(
        "Table 2: scene statistics and predicted N_th",
        &[
            "scene",
            "A_avg",
            "L_avg",
            "n_or",
            "N_ot",
            "grid",
            "alpha",
            "p",
            "N_c",
            "N_th eq. 12",
            "break-even N_s (pilot)",
            "forced / free shadow rays",
            "N_th predicted",
            "N_th best (sweep)",
        ],
    );
    for s in &r.scenes {
        let st = &s.stats;
        t2.row(vec![
            s.scene.clone(),
            format!("{:.4}", st.mean_area),
            format!("{:.3}", st.mean_perimeter),
            format!("{:.3}", st.n_or),
            st.polygons.to_string(),
            format!("{}x{}x{}", st.grid[0], st.grid[1], st.grid[2]),
            format!("{:.3}", st.alpha),
            format!("{:.3}", st.p),
            format!("{:.1}", st.n_c),
            format!("{:.2}", s.equation_12_nth),
            s.follow_up
                .break_even
                .map_or("-".into(), |n| format!("{n:.1}")),
            format!("{:.2}", s.follow_up.ratio),
            format!("{:.2}", s.predicted_nth),
            format!("{}", (s.best_nth * 10.0).round() / 10.0),
        ]);
    }
    md += "\n";
    md += &t2.to_markdown();
    let mut t3 = Table::new(
        "Table 3: HST sub-schemes at the predicted N_th (per light and shading point)",
        &[
            "scene",
            "sustain",
            "self-shadow",
            "shadow volume",
            "conventional",
            "total",
        ],
    );
    for s in &r.scenes {
        let sub = &s.schemes[2].report.subschemes;
        let total = (sub.sustain + sub.self_shadow + sub.shadow_volume + sub.conventional) as f64;
        let cell = |n: u64| format!("{n} ({})", pct(n as f64, total));
        t3.row(vec![
            s.scene.clone(),
            cell(sub.sustain),
            cell(sub.self_shadow),
            cell(sub.shadow_volume),
            cell(sub.conventional),
            format!("{total}"),
        ]);
    }
    md += "\n";
    md += &t3.to_markdown();
    let mut t4 = Table::new(
        "Table 4: preprocessing / shadow testing / other / total (ms)",
        &[
            "scene",
            "scheme",
            "preprocess",
            "shadow",
            "other",
            "total",
            "shadow / conventional",
            "total / conventional",
        ],
    );
    for s in &r.scenes {
        let conv = &s.schemes[0];
        for row in &s.schemes {
            let name = match row.nth {
                Some(n) => format!("{} (N_th={:.1})", row.scheme, n),
                None => row.scheme.clone(),
            };
            t4.row(vec![
                s.scene.clone(),
                name,
                format!(
                    "{} ({})",
                    ms(row.preprocess),
                    pct(row.preprocess, row.total)
                ),
                format!("{} ({})", ms(row.shadow), pct(row.shadow, row.total)),
                format!("{} ({})", ms(row.other), pct(row.other, row.total)),
                ms(row.total),
                format!("{:.2}", row.shadow / conv.shadow),
                format!("{:.2}", row.total / conv.total),
            ]);
        }
    }
    md += "\n";
    md += &t4.to_markdown();
    let mut summary = Table::new(
        "Summary: HST against the conventional grid test and the SAH BVH; sameness",
        &[
            "scene",
            "hst/conventional shadow",
            "hst/conventional total",
            "hst/bvh shadow",
            "hst/embree shadow",
            "shadow at predicted / best N_th (paired renders)",
            "disagreements volume",
            "disagreements hst",
            "shading points",
        ],
    );
    let (mut shadow_sum, mut total_sum, mut n) = (0.0, 0.0, 0.0);
    for s in &r.scenes {
        let (conv, vol, hst, bvh) = (&s.schemes[0], &s.schemes[1], &s.schemes[2], &s.schemes[3]);
        if BUILTINS.iter().any(|b| b.0 == s.scene) {
            shadow_sum += hst.shadow / conv.shadow;
            total_sum += hst.total / conv.total;
            n += 1.0;
        }
        summary.row(vec![
            s.scene.clone(),
            format!("{:.2}", hst.shadow / conv.shadow),
            format!("{:.2}", hst.total / conv.total),
            format!("{:.2}", hst.shadow / bvh.shadow),
            s.schemes
                .get(4)
                .map_or("-".into(), |e| format!("{:.2}", hst.shadow / e.shadow)),
            format!("{:.2}", s.predicted_over_best),
            format!(
                "{} ({:.1e})",
                vol.disagreements,
                vol.disagreements as f64 / vol.shading_points as f64
            ),
            format!(
                "{} ({:.1e})",
                hst.disagreements,
                hst.disagreements as f64 / hst.shading_points as f64
            ),
            hst.shading_points.to_string(),
        ]);
    }
    summary.row(vec![
        "mean of the four look-alikes".into(),
        format!("{:.2}", shadow_sum / n),
        format!("{:.2}", total_sum / n),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
    ]);
    md += "\n";
    md += &summary.to_markdown();
    let mut sweep = Table::new(
        "Figure 6 data: HST shadow time (ms) against N_th (fig6-SCENE.svg)",
        &["N_th"],
    );
    sweep
        .columns
        .extend(r.scenes.iter().map(|s| s.scene.clone()));
    if let Some(first) = r.scenes.first() {
        for (i, p) in first.sweep.iter().enumerate() {
            let mut row = vec![format!("{}", p.nth)];
            row.extend(r.scenes.iter().map(|s| ms(s.sweep[i].shadow)));
            sweep.row(row);
        }
    }
    md += "\n";
    md += &sweep.to_markdown();
    md
}
