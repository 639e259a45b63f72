//! The measurements of `quadray bench shadows`: every scheme on the four look-alike scenes and
//! the two asset scenes, the N_th sweep of figure 6 and the paired renders that hold the
//! predicted N_th against the best. Every time is the median of several renders; methods are
//! compared as ratios within one run.

use quadray_core::FileError;
use quadray_shadows::cost::{self, MachineCosts, SceneStats};
use quadray_shadows::scene::{BUILTINS, Scene, SceneError, assets_dir};
use quadray_shadows::{
    Nth, Prepared, RunReport, SchemeChoice, Settings, Size, prepare, render_prepared,
};
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
    settings: Settings,
    prep: Prepared,
    preprocess: Vec<f64>,
    check: RunReport,
    reports: Vec<RunReport>,
}

impl Contender {
    fn new(
        scene: &Scene,
        settings: Settings,
        costs: &MachineCosts,
        runs: usize,
    ) -> Result<Self, FileError> {
        let mut preprocess = Vec::new();
        let mut prep = None;
        for _ in 0..runs {
            let p = prepare(scene.clone(), settings.scheme)
                .map_err(|e| FileError::new(Path::new(&scene.name), e))?;
            preprocess.push(p.preprocess_s);
            prep = Some(p);
        }
        let prep = prep.expect("at least one run");
        let checked = Settings {
            check: true,
            ..settings
        };
        let (_, check) = render_prepared(&prep, &checked, costs, &|| {});
        Ok(Self {
            settings,
            prep,
            preprocess,
            check,
            reports: Vec::new(),
        })
    }

    fn render(&mut self, costs: &MachineCosts) {
        let report = render_prepared(&self.prep, &self.settings, costs, &|| {}).1;
        self.reports.push(report);
    }

    fn row(&self) -> SchemeRow {
        let pre = median(self.preprocess.clone());
        let shadow = median(self.reports.iter().map(|r| r.times_s.shadow).collect());
        let other = median(self.reports.iter().map(|r| r.times_s.other).collect());
        SchemeRow {
            scheme: self.check.settings.scheme.to_string(),
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
pub fn bench_scenes() -> Result<Vec<Scene>, SceneError> {
    let mut scenes: Vec<Scene> = BUILTINS
        .iter()
        .map(|(name, ..)| Scene::builtin(name).expect("builtin"))
        .collect();
    for file in ASSET_SCENES {
        scenes.push(Scene::load(&assets_dir().join(file))?);
    }
    Ok(scenes)
}

/// Scene files of the benchmark under `assets/`.
pub const ASSET_SCENES: [&str; 2] = ["scenes/shadows-cornell.toml", "scenes/shadows-bunny.toml"];

/// Runs the whole benchmark (`quick`: small pictures, one render a measurement).
pub fn measure(quick: bool, progress: &dyn Fn(&str)) -> Result<BenchResults, FileError> {
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
    let base = Settings {
        scheme: SchemeChoice::Conventional,
        size: Size::new(width, height),
        depth,
        ..Settings::DEFAULT
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
            .map(|&scheme| Contender::new(&scene, Settings { scheme, ..base }, &costs, runs))
            .collect::<Result<_, _>>()?;
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
        let hst_at = |nth: f64| Settings {
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
    Ok(results)
}
