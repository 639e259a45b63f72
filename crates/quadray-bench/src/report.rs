//! What every benchmark writes beside its `results.json`: markdown tables and SVG plots made from
//! the same data.

use plotters::prelude::*;
use quadray_core::FileError;
use serde::Serialize;
use std::path::Path;

/// A markdown table with a title.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Table {
    pub title: String,
    pub columns: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new(title: impl Into<String>, columns: &[&str]) -> Self {
        Self {
            title: title.into(),
            columns: columns.iter().map(|c| c.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    pub fn to_markdown(&self) -> String {
        let mut s = format!("### {}\n\n| {} |\n|", self.title, self.columns.join(" | "));
        s += &"---|".repeat(self.columns.len());
        s.push('\n');
        for r in &self.rows {
            s += &format!("| {} |\n", r.join(" | "));
        }
        s
    }
}

/// One line of a plot.
#[derive(Clone, Debug, Serialize)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Axes of a line plot; logarithmic axes need positive values.
pub struct PlotSpec<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub log_x: bool,
    pub log_y: bool,
}

/// Draws `series` as lines with markers into an SVG file.
pub fn line_plot(path: &Path, spec: &PlotSpec, series: &[Series]) -> Result<(), FileError> {
    let err = |e: &dyn std::fmt::Display| FileError::new(path, e);
    let pts = || series.iter().flat_map(|s| s.points.iter().copied());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in pts().filter(|(x, y)| x.is_finite() && y.is_finite()) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        return Err(FileError::new(path, "nothing to plot"));
    }
    let pad = |lo: f64, hi: f64, log: bool| {
        if log {
            (lo.max(1e-9) / 1.5, hi.max(1e-9) * 1.5)
        } else {
            let m = ((hi - lo) * 0.05).max(1e-9);
            (lo - m, hi + m)
        }
    };
    let (x0, x1) = pad(x0, x1, spec.log_x);
    let (y0, y1) = pad(y0.min(0.0_f64.max(y0)), y1, spec.log_y);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| FileError::new(dir, e))?;
    }
    let root = SVGBackend::new(path, (800, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(spec.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60);
    macro_rules! draw {
        ($chart:expr) => {{
            let mut chart = $chart.map_err(|e| err(&e))?;
            chart
                .configure_mesh()
                .x_desc(spec.x_label)
                .y_desc(spec.y_label)
                .draw()
                .map_err(|e| err(&e))?;
            for (i, s) in series.iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                chart
                    .draw_series(LineSeries::new(
                        s.points.iter().copied(),
                        color.stroke_width(2),
                    ))
                    .map_err(|e| err(&e))?
                    .label(&s.name)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], color));
                chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .map_err(|e| err(&e))?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| err(&e))?;
        }};
    }
    match (spec.log_x, spec.log_y) {
        (false, false) => draw!(builder.build_cartesian_2d(x0..x1, y0..y1)),
        (true, false) => draw!(builder.build_cartesian_2d((x0..x1).log_scale(), y0..y1)),
        (false, true) => draw!(builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale())),
        (true, true) => {
            draw!(builder.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale()))
        }
    }
    root.present().map_err(|e| err(&e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_table_has_header_rule_and_rows() {
        let mut t = Table::new("T", &["a", "b"]);
        t.row(vec!["1".into(), "2".into()]);
        assert_eq!(
            t.to_markdown(),
            "### T\n\n| a | b |\n|---|---|\n| 1 | 2 |\n"
        );
    }

    #[test]
    fn plot_writes_an_svg_with_every_series_name() {
        let dir = std::env::temp_dir().join(format!("quadray-plot-{}", std::process::id()));
        let path = dir.join("p.svg");
        let s = |n: &str| Series {
            name: n.into(),
            points: vec![(1.0, 2.0), (10.0, 3.0)],
        };
        let spec = PlotSpec {
            title: "t",
            x_label: "x",
            y_label: "y",
            log_x: true,
            log_y: false,
        };
        line_plot(&path, &spec, &[s("alpha"), s("beta")]).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("alpha") && svg.contains("beta"));
        assert!(line_plot(&path, &spec, &[]).is_err());
    }
}
