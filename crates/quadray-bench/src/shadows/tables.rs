//! The paper's tables 1-4, the summary and figure 6 of `quadray bench shadows`, one function
//! each, from the measurements of [`super::measure`].

use super::measure::{BenchResults, SceneResult};
use crate::report::{PlotSpec, Series, Table, line_plot};
use quadray_core::{FileError, write_json, write_text};
use quadray_shadows::scene::BUILTINS;
use std::path::Path;

fn pct(x: f64, of: f64) -> String {
    format!("{:.0}%", 100.0 * x / of.max(1e-12))
}

fn ms(x: f64) -> String {
    format!("{:.1}", x * 1e3)
}

/// Table 1: the machine constants.
pub fn table1(r: &BenchResults) -> Table {
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
    t1
}

/// Table 2: the scene statistics and the predicted and best N_th.
pub fn table2(r: &BenchResults) -> Table {
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
    t2
}

/// Table 3: HST's sub-schemes at the predicted N_th.
pub fn table3(r: &BenchResults) -> Table {
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
    t3
}

/// Table 4: preprocessing, shadow testing, other and total time of every scheme.
pub fn table4(r: &BenchResults) -> Table {
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
    t4
}

/// HST against the conventional grid test, the BVH and Embree, and the disagreements.
pub fn summary(r: &BenchResults) -> Table {
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
    summary
}

/// Figure 6's data: HST's shadow time against N_th, a column per scene.
pub fn figure6_data(r: &BenchResults) -> Table {
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
    sweep
}

/// The tables above as the markdown of `shadows.md`.
pub fn markdown(r: &BenchResults) -> String {
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
    for table in [
        table1(r),
        table2(r),
        table3(r),
        table4(r),
        summary(r),
        figure6_data(r),
    ] {
        if !md.ends_with("\n\n") {
            md += "\n";
        }
        md += &table.to_markdown();
    }
    md
}

/// Figure 6 of one scene as an SVG: HST's shadow time against N_th, the other schemes flat.
pub fn figure6(path: &Path, s: &SceneResult) -> Result<(), FileError> {
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

/// Writes `results.json`, `shadows.md` and one figure-6 SVG per scene into `out`.
pub fn write(out: &Path, results: &BenchResults) -> Result<(), FileError> {
    write_json(&out.join("results.json"), results)?;
    for s in &results.scenes {
        figure6(&out.join(format!("fig6-{}.svg", s.scene)), s)?;
    }
    write_text(&out.join("shadows.md"), &markdown(results))
}
