//! `quadray bench indirect --equal-error`: the light quadtree against RSM sampling at the same
//! error, in the work counts the shaders report (VPL evaluations and texel fetches per shaded
//! pixel, the same on any hardware) and in GPU time, on every bundled scene of the technique at
//! several RSM sizes. The quadtree runs at full resolution and sub-sampled (one gather per
//! `k`^2 pixels, geometry-aware upsampling, recomputed pixels counted), and with a cut per tile
//! (at full resolution, at several error fractions, split by the bound or by the estimated
//! error). RSM sampling is swept
//! over sample counts at full resolution (the paper's baseline) and, as the fair extra row, at
//! each sub-sampling the quadtree uses; its cost at the quadtree's error is interpolated log-log
//! between the two counts whose errors bracket it.

use crate::report::{PlotSpec, Series, Table, line_plot};
use quadray_core::{write_json, write_text};
use quadray_gpu::Gpu;
use quadray_indirect::reference::compare;
use quadray_indirect::scene::scenes_dir;
use quadray_indirect::{
    ClusterSettings, IndirectError, Method, Renderer, Scene, Settings, TileCriterion,
};
use serde::Serialize;
use std::path::Path;

/// The scenes compared: the Cornell box, the bunny and the Buddha in it, the atrium, the leak
/// scene.
const SCENES: [&str; 5] = [
    "cornell.toml",
    "cornell_bunny.toml",
    "cornell_buddha.toml",
    "atrium.toml",
    "leak.toml",
];
/// The quadtree's sub-samplings (1: full resolution), each also RSM sampling's.
const SUBSAMPLES: [u32; 4] = [1, 2, 4, 8];
/// Error fractions of the per-tile cuts compared (full resolution), split by the bound.
const TILE_ERRORS: [f32; 5] = [1.0, 0.5, 0.2, 0.05, 0.02];
/// Error fractions of the per-tile cuts split by the estimated error, which is far below the
/// bound at the same node (BENCHMARKS.md, "Per-tile cuts").
const ESTIMATE_ERRORS: [f32; 6] = [0.01, 0.002, 0.0005, 0.0002, 0.0001, 0.00005];
/// Receiver sharing of the per-tile cuts split by the estimated error (`Settings::tile_share`,
/// 0: off): clusters farther than this many tile extents are gathered at the tile's corners.
const TILE_SHARES: [f32; 3] = [0.0, 2.0, 3.0];
/// The label of the one cut at its default thresholds (the paper's method, quadray's default
/// until the per-tile cuts won at equal error).
const ONE_CUT: &str = "one-cut";

/// The label of [`Method::DEFAULT`] at [`Settings::DEFAULT`] among the per-tile cuts' rows (the
/// sweep holds its criterion, error and sharing).
fn default_label() -> String {
    let s = Settings::DEFAULT;
    let family = tile_family(s.tile_criterion, s.tile_share);
    format!("{family} {}", s.tile_error_or_default())
}
/// RSM sample counts swept, up to where sampling reaches the quadtree's error.
const SAMPLES: [u32; 10] = [16, 64, 216, 512, 1024, 2040, 4096, 8192, 16384, 32768];

/// What to run.
pub struct EqualErrorOptions {
    /// Image side (square).
    pub size: u32,
    /// RSM sides, one comparison per scene each.
    pub rsm_sizes: Vec<u32>,
    /// Timed frames per median (0: counts and errors only).
    pub frames: u32,
    /// The scenes' file stems to run (empty: every bundled scene).
    pub scenes: Vec<String>,
}

impl EqualErrorOptions {
    /// The study's setting: 128x128 images, 256^2 and 512^2 RSMs; quick: 64x64 and 64^2.
    pub fn new(quick: bool, size: Option<u32>, rsm_size: Option<u32>, scenes: Vec<String>) -> Self {
        let rsm_sizes = match (rsm_size, quick) {
            (Some(s), _) => vec![s],
            (None, true) => vec![64],
            (None, false) => vec![256, 512],
        };
        Self {
            size: size.unwrap_or(if quick { 64 } else { 128 }),
            rsm_sizes,
            frames: if quick { 2 } else { 5 },
            scenes,
        }
    }
}

/// One method at one setting: its error and its cost.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// The method's setting ("one-cut", "paper", "tiles E", "estimate E", "estimate+shareF E",
    /// "N samples").
    pub label: String,
    /// One gather per `subsample`^2 pixels (1: full resolution).
    pub subsample: u32,
    /// Relative L1 error of the indirect term against the brute force.
    pub rel_l1: f64,
    /// VPL kernels evaluated per shaded pixel, counted in the shaders.
    pub vpl_evaluations_per_pixel: f64,
    /// Texels and node records read per shaded pixel.
    pub texel_fetches_per_pixel: f64,
    /// Bounds of a cluster's contribution to a tile evaluated per shaded pixel (per-tile cuts).
    pub bound_evaluations_per_pixel: f64,
    /// Median GPU time of a frame with a static light (ms), when timestamps exist.
    pub static_ms: Option<f64>,
}

/// A quadtree setting against RSM sampling at its error.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// The quadtree's point.
    pub quadtree: Point,
    /// Against RSM sampling at full resolution (the paper's baseline).
    pub full_resolution: AtError,
    /// Against RSM sampling sub-sampled as the quadtree is (`None` at full resolution).
    pub same_subsample: Option<AtError>,
}

/// RSM sampling's cost at a quadtree's error, over the quadtree's.
#[derive(Clone, Debug, Serialize)]
pub struct AtError {
    /// RSM samples per pixel that reach the quadtree's error; `None` when no swept count does.
    pub rsm_samples: Option<f64>,
    /// RSM sampling's evaluations per pixel there over the quadtree's.
    pub evaluation_ratio: Option<f64>,
    /// RSM sampling's texel fetches per pixel there over the quadtree's.
    pub fetch_ratio: Option<f64>,
    /// RSM sampling's static-light frame time there over the quadtree's.
    pub time_ratio: Option<f64>,
}

/// One scene at one RSM size.
#[derive(Clone, Debug, Serialize)]
pub struct SceneResult {
    /// The scene's name.
    pub scene: String,
    /// RSM side.
    pub rsm_size: u32,
    /// The quadtree settings, each against RSM sampling.
    pub comparisons: Vec<Comparison>,
    /// RSM sampling at every swept sample count and sub-sampling.
    pub rsm: Vec<Point>,
}

/// Everything measured, as `equal_error.json` holds it.
#[derive(Clone, Debug, Serialize)]
pub struct EqualErrorResults {
    /// The adapter the times were taken on.
    pub adapter: String,
    /// Image side.
    pub size: u32,
    /// Frames per median.
    pub frames: u32,
    /// Per scene and RSM size.
    pub scenes: Vec<SceneResult>,
}

/// `x` at `error` on a curve of (error, x) points whose errors fall as it goes: log-log
/// interpolation between the consecutive points that bracket `error`.
pub(crate) fn at_error(curve: &[(f64, f64)], error: f64) -> Option<f64> {
    curve.windows(2).find_map(|pair| {
        let ((ea, xa), (eb, xb)) = (pair[0], pair[1]);
        if !(ea > error && eb <= error) {
            return None;
        }
        let f = (error.ln() - ea.ln()) / (eb.ln() - ea.ln());
        Some((xa.ln() + f * (xb.ln() - xa.ln())).exp())
    })
}

fn measure(
    r: &mut Renderer,
    method: Method,
    label: String,
    brute: &[[f32; 3]],
    frames: u32,
) -> Result<Point, IndirectError> {
    let frame = r.render_frame(method)?;
    let timing = r.time(method, false, frames)?;
    Ok(Point {
        label,
        subsample: r.settings().subsample,
        rel_l1: compare(&frame.indirect, brute).rel_l1,
        vpl_evaluations_per_pixel: frame.counts.vpl_evaluations_per_pixel(),
        texel_fetches_per_pixel: frame.counts.texel_fetches_per_pixel(),
        bound_evaluations_per_pixel: frame.counts.bound_evaluations_per_pixel(),
        static_ms: timing.map(|t| t.total_ms),
    })
}

/// RSM sampling's points at `subsample` (`rsm` holds every sweep) at `quadtree`'s error.
fn at_quadtree_error(quadtree: &Point, rsm: &[Point], subsample: u32) -> AtError {
    let curve = |value: &dyn Fn(&Point) -> Option<f64>| -> Vec<(f64, f64)> {
        rsm.iter()
            .filter(|p| p.subsample == subsample)
            .filter_map(|p| value(p).map(|v| (p.rel_l1, v)))
            .collect()
    };
    let at = |value: &dyn Fn(&Point) -> Option<f64>| at_error(&curve(value), quadtree.rel_l1);
    let ratio = |value: &dyn Fn(&Point) -> Option<f64>| {
        at(value)
            .zip(value(quadtree))
            .filter(|(_, q)| *q > 0.0)
            .map(|(r, q)| r / q)
    };
    let samples = |p: &Point| p.label.trim_end_matches(" samples").parse::<f64>().ok();
    AtError {
        rsm_samples: at(&samples),
        evaluation_ratio: ratio(&|p| Some(p.vpl_evaluations_per_pixel)),
        fetch_ratio: ratio(&|p| Some(p.texel_fetches_per_pixel)),
        time_ratio: ratio(&|p| p.static_ms),
    }
}

fn compare_at_error(quadtree: Point, rsm: &[Point]) -> Comparison {
    Comparison {
        full_resolution: at_quadtree_error(&quadtree, rsm, 1),
        same_subsample: (quadtree.subsample > 1)
            .then(|| at_quadtree_error(&quadtree, rsm, quadtree.subsample)),
        quadtree,
    }
}

/// The bundled scenes of the technique named by file stem (empty: all of them), in [`SCENES`]'s
/// order; an unknown name is refused.
pub(crate) fn bundled_scenes(names: &[String]) -> Result<Vec<Scene>, IndirectError> {
    if let Some(unknown) = names.iter().find(|s| {
        !SCENES
            .iter()
            .any(|f| f.trim_end_matches(".toml") == s.as_str())
    }) {
        return Err(IndirectError::Settings(format!(
            "no bundled scene `{unknown}` (cornell, cornell_bunny, cornell_buddha, atrium, leak)"
        )));
    }
    SCENES
        .into_iter()
        .filter(|file| {
            names.is_empty() || names.iter().any(|s| s == file.trim_end_matches(".toml"))
        })
        .map(|file| Scene::load(&scenes_dir().join(file)).map_err(IndirectError::from))
        .collect()
}

fn scene_result(
    gpu: &Gpu,
    scene: &Scene,
    base: Settings,
    frames: u32,
    progress: &mut dyn FnMut(&str),
) -> Result<SceneResult, IndirectError> {
    let name = format!("{} {}^2", scene.name, base.rsm_size);
    progress(&format!("{name}: brute force"));
    let brute = Renderer::new(gpu, scene, base.clone())?
        .render_frame(Method::Reference)?
        .indirect;
    let mut quadtree = Vec::new();
    for subsample in SUBSAMPLES {
        let mut r = Renderer::new(
            gpu,
            scene,
            Settings {
                subsample,
                ..base.clone()
            },
        )?;
        for (label, cluster) in [
            (ONE_CUT, ClusterSettings::DEFAULT),
            ("paper", ClusterSettings::with_limit_side(base.rsm_size, 32)),
        ] {
            progress(&format!("{name}: quadtree {label}, subsample {subsample}"));
            r.set_cluster(cluster)?;
            quadtree.push(measure(
                &mut r,
                Method::Quadtree,
                label.into(),
                &brute,
                frames,
            )?);
        }
    }
    let tile_runs = TILE_ERRORS
        .map(|e| (TileCriterion::Bound, e, 0.0))
        .into_iter()
        .chain(
            TILE_SHARES
                .into_iter()
                .flat_map(|share| ESTIMATE_ERRORS.map(|e| (TileCriterion::Estimate, e, share))),
        );
    for (tile_criterion, tile_error, tile_share) in tile_runs {
        let label = format!("{} {tile_error}", tile_family(tile_criterion, tile_share));
        progress(&format!("{name}: per-tile cuts, {label}"));
        let mut r = Renderer::new(
            gpu,
            scene,
            Settings {
                tile_error: Some(tile_error),
                tile_criterion,
                tile_share,
                ..base.clone()
            },
        )?;
        quadtree.push(measure(
            &mut r,
            Method::QuadtreeTiles,
            label,
            &brute,
            frames,
        )?);
    }
    let mut rsm: Vec<Point> = Vec::new();
    for subsample in SUBSAMPLES {
        // past the best error of the quadtree settings compared with this sweep there is
        // nothing more to interpolate (full resolution is compared with every setting)
        let best = quadtree
            .iter()
            .filter(|p| subsample == 1 || p.subsample == subsample)
            .map(|p| p.rel_l1)
            .fold(f64::MAX, f64::min);
        let mut last = f64::MAX;
        for samples in SAMPLES {
            if last <= best {
                break;
            }
            progress(&format!(
                "{name}: RSM {samples} samples, subsample {subsample}"
            ));
            let mut rs = Renderer::new(
                gpu,
                scene,
                Settings {
                    samples,
                    subsample,
                    ..base.clone()
                },
            )?;
            let label = format!("{samples} samples");
            let point = measure(&mut rs, Method::Rsm, label, &brute, frames)?;
            last = point.rel_l1;
            rsm.push(point);
        }
    }
    Ok(SceneResult {
        scene: scene.name.clone(),
        rsm_size: base.rsm_size,
        comparisons: quadtree
            .into_iter()
            .map(|q| compare_at_error(q, &rsm))
            .collect(),
        rsm,
    })
}

/// Every scene at every RSM size; writes `equal_error.md`, `.json` and the error-vs-evaluations
/// plot into `out`.
pub fn run(
    gpu: &Gpu,
    out: &Path,
    options: &EqualErrorOptions,
    mut progress: impl FnMut(&str),
) -> Result<EqualErrorResults, IndirectError> {
    let mut scenes = Vec::new();
    for scene in bundled_scenes(&options.scenes)? {
        for &rsm_size in &options.rsm_sizes {
            let base = Settings::sized(options.size, options.size, rsm_size);
            scenes.push(scene_result(
                gpu,
                &scene,
                base,
                options.frames,
                &mut progress,
            )?);
        }
    }
    let results = EqualErrorResults {
        adapter: gpu.describe(),
        size: options.size,
        frames: options.frames,
        scenes,
    };
    write_outputs(out, &results)?;
    Ok(results)
}

fn fixed(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |v| format!("{v:.digits$}"))
}

fn write_outputs(out: &Path, results: &EqualErrorResults) -> Result<(), IndirectError> {
    let md = [
        defaults_table(results),
        comparison_table(results),
        sweep_table(results),
    ]
    .map(|t| t.to_markdown())
    .join("\n");
    write_text(&out.join("equal_error.md"), &md)?;
    write_json(&out.join("equal_error.json"), results)?;
    let series: Vec<Series> = results.scenes.iter().flat_map(scene_series).collect();
    line_plot(
        &out.join("equal_error.svg"),
        &PlotSpec {
            title: "Indirect light: error against VPL evaluations per pixel",
            x_label: "VPL evaluations per shaded pixel",
            y_label: "rel. L1 error of the indirect term",
            log_x: true,
            log_y: true,
        },
        &series,
    )?;
    Ok(())
}

/// What a user gets without choosing, and the paper's one cut, against RSM sampling.
fn defaults_table(results: &EqualErrorResults) -> Table {
    let default = default_label();
    let mut defaults = Table::new(
        format!(
            "The default method ({}, {default}) and the one cut against RSM sampling at equal \
             error, full resolution",
            Method::DEFAULT
        ),
        &[
            "scene",
            "RSM",
            "method",
            "rel L1",
            "evals/px",
            "RSM samples at that error",
            "evals ratio",
            "time ratio",
        ],
    );
    for s in &results.scenes {
        for (name, label) in [("default", default.as_str()), (ONE_CUT, ONE_CUT)] {
            let found = s
                .comparisons
                .iter()
                .find(|c| c.quadtree.label == label && c.quadtree.subsample == 1);
            if let Some(c) = found {
                let (q, full) = (&c.quadtree, &c.full_resolution);
                defaults.row(vec![
                    s.scene.clone(),
                    format!("{}^2", s.rsm_size),
                    name.into(),
                    format!("{:.4}", q.rel_l1),
                    format!("{:.1}", q.vpl_evaluations_per_pixel),
                    fixed(full.rsm_samples, 0),
                    fixed(full.evaluation_ratio, 2),
                    fixed(full.time_ratio, 2),
                ]);
            }
        }
    }
    defaults
}

/// Every quadtree row against RSM sampling at full resolution and at its own sub-sampling.
fn comparison_table(results: &EqualErrorResults) -> Table {
    let mut table = Table::new(
        format!(
            "Quadtree vs RSM sampling at equal error, {0}x{0} image ({1}, {2} frames per median)",
            results.size, results.adapter, results.frames
        ),
        &[
            "scene",
            "RSM",
            "quadtree",
            "subsample",
            "rel L1",
            "evals/px",
            "bounds/px",
            "fetches/px",
            "ms",
            "RSM samples at that error",
            "evals ratio",
            "fetches ratio",
            "time ratio",
            "same-subsample RSM samples",
            "evals ratio",
            "time ratio",
        ],
    );
    for s in &results.scenes {
        for c in &s.comparisons {
            let (q, full, same) = (&c.quadtree, &c.full_resolution, &c.same_subsample);
            let same = |value: &dyn Fn(&AtError) -> Option<f64>, digits| {
                fixed(same.as_ref().and_then(value), digits)
            };
            table.row(vec![
                s.scene.clone(),
                format!("{}^2", s.rsm_size),
                q.label.clone(),
                q.subsample.to_string(),
                format!("{:.4}", q.rel_l1),
                format!("{:.1}", q.vpl_evaluations_per_pixel),
                format!("{:.1}", q.bound_evaluations_per_pixel),
                format!("{:.0}", q.texel_fetches_per_pixel),
                fixed(q.static_ms, 2),
                fixed(full.rsm_samples, 0),
                fixed(full.evaluation_ratio, 2),
                fixed(full.fetch_ratio, 2),
                fixed(full.time_ratio, 2),
                same(&|a| a.rsm_samples, 0),
                same(&|a| a.evaluation_ratio, 2),
                same(&|a| a.time_ratio, 2),
            ]);
        }
    }
    table
}

/// RSM sampling's sweep over sample counts and sub-samplings.
fn sweep_table(results: &EqualErrorResults) -> Table {
    let mut sweep = Table::new(
        "RSM sampling sweep",
        &[
            "scene",
            "RSM",
            "subsample",
            "samples",
            "rel L1",
            "evals/px",
            "fetches/px",
            "ms",
        ],
    );
    for s in &results.scenes {
        for p in &s.rsm {
            sweep.row(vec![
                s.scene.clone(),
                format!("{}^2", s.rsm_size),
                p.subsample.to_string(),
                p.label.trim_end_matches(" samples").into(),
                format!("{:.4}", p.rel_l1),
                format!("{:.0}", p.vpl_evaluations_per_pixel),
                format!("{:.0}", p.texel_fetches_per_pixel),
                fixed(p.static_ms, 2),
            ]);
        }
    }
    sweep
}

/// A scene's lines of error against VPL evaluations: RSM sampling and the one cut at each
/// sub-sampling, the per-tile cuts a line for each criterion and sharing.
fn scene_series(s: &SceneResult) -> Vec<Series> {
    let mut series = Vec::new();
    let points = |ps: &mut dyn Iterator<Item = &Point>| {
        ps.map(|p| (p.vpl_evaluations_per_pixel, p.rel_l1))
            .collect()
    };
    for k in SUBSAMPLES {
        let at = |p: &&Point| p.subsample == k;
        series.push(Series {
            name: format!("{} {}^2 RSM sampling, subsample {k}", s.scene, s.rsm_size),
            points: points(&mut s.rsm.iter().filter(at)),
        });
        series.push(Series {
            name: format!("{} {}^2 quadtree, subsample {k}", s.scene, s.rsm_size),
            points: points(
                &mut s
                    .comparisons
                    .iter()
                    .map(|c| &c.quadtree)
                    .filter(at)
                    // the one cut (`ONE_CUT`, "paper"); the per-tile cuts follow
                    .filter(|p| !p.label.contains(' ')),
            ),
        });
    }
    // the per-tile cuts (full resolution), a line for each criterion and sharing
    let mut families: Vec<&str> = Vec::new();
    for c in &s.comparisons {
        if let Some((family, _)) = c.quadtree.label.rsplit_once(' ')
            && !families.contains(&family)
        {
            families.push(family);
        }
    }
    for family in families {
        let of = |p: &&Point| p.label.rsplit_once(' ').is_some_and(|(f, _)| f == family);
        series.push(Series {
            name: format!("{} {}^2 per-tile cuts, {family}", s.scene, s.rsm_size),
            points: points(&mut s.comparisons.iter().map(|c| &c.quadtree).filter(of)),
        });
    }
    series
}

/// The name of the per-tile cuts' rows of a criterion and sharing, before their error
/// fraction: "tiles" (the bound), "estimate", "estimate+share2".
fn tile_family(criterion: TileCriterion, share: f32) -> String {
    match (criterion, share > 0.0) {
        (TileCriterion::Bound, _) => "tiles".into(),
        (TileCriterion::Estimate, false) => "estimate".into(),
        (TileCriterion::Estimate, true) => format!("estimate+share{share}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sweep_measures_the_default_method() {
        let s = Settings::DEFAULT;
        assert_eq!(Method::DEFAULT, Method::QuadtreeTiles);
        assert_eq!(s.tile_criterion, TileCriterion::Estimate);
        assert!(TILE_SHARES.contains(&s.tile_share));
        assert!(ESTIMATE_ERRORS.contains(&s.tile_error_or_default()));
        assert_eq!(default_label(), "estimate+share2 0.002");
    }

    #[test]
    fn a_value_at_an_error_is_interpolated_log_log_between_the_bracketing_points() {
        // error halves with every 4x the value
        let curve = [(0.2, 100.0), (0.1, 400.0), (0.05, 1600.0)];
        assert!((at_error(&curve, 0.1).unwrap() - 400.0).abs() < 1e-9);
        let mid = at_error(&curve, (0.1f64 * 0.05).sqrt()).unwrap();
        assert!((mid - 800.0).abs() < 1e-6, "{mid}");
        assert!(at_error(&curve, 0.01).is_none());
        assert!(at_error(&curve, 0.5).is_none());
    }
}
