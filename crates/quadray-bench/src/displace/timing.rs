//! The paper's timing tables and figures (tables 1 and 2, figures 20 and 21, the pyramid build),
//! the cone map build and today's frame size, each as the rows it measured.

use super::measure::{Bench, Ratios, ms, ratio, ratio_text, traced};
use crate::report::{PlotSpec, Series, Table, line_plot};
use quadray_core::stats::{Summary, time_cpu};
use quadray_displace::accuracy::Cost;
use quadray_displace::cone::ConeMap;
use quadray_displace::heightmap::HeightMap;
use quadray_displace::maps::{BUNDLED, resized};
use quadray_displace::pyramid::Pyramid;
use quadray_displace::scene::SurfaceKind;
use quadray_displace::{
    DisplaceError, Lod, Method, PyramidBuilder, PyramidKind, Renderer, Settings, Size,
};
use quadray_gpu::GpuTimer;
use std::path::Path;

/// `s` with the LOD of section 3.4 chosen from screen-space derivatives.
fn lod_auto(s: Settings) -> Settings {
    Settings {
        lod: Lod::Auto,
        ..s
    }
}

/// The map sides of figure 21 and the pyramid build table.
fn map_sizes(quick: bool) -> &'static [u32] {
    if quick {
        &[256, 512, 1024]
    } else {
        &[256, 512, 1024, 2048, 4096]
    }
}

/// Tables 1 (point vs bilinear) and 2 (POM vs relief vs pyramid) and figure 20 (the displaced
/// mesh), measured in the same renders: the paper's screen size, 256^2 maps.
pub fn tables_1_2_figure_20(
    bench: &mut Bench,
    ratios: &mut Ratios,
) -> Result<Vec<Table>, DisplaceError> {
    let (gpu, paper) = (bench.gpu, bench.paper);
    let mut t1 = Table::new(
        format!("Table 1: point vs bilinear, GPU ms ({paper}x{paper}, 256^2 maps, 60 deg)"),
        &[
            "map (paper row)",
            "pyramid (point)",
            "pyramid-bilinear",
            "bilinear / point",
        ],
    );
    let mut t2 = Table::new(
        format!(
            "Table 2: POM vs relief vs pyramid, GPU ms ({paper}x{paper}, 256^2 maps, 16 layers)"
        ),
        &[
            "map (paper row)",
            "pom-16",
            "relief-16+5",
            "pyramid",
            "pyramid-ascend",
            "pyramid / pom-16",
        ],
    );
    let mut f20 = Table::new(
        format!(
            "Figure 20: displaced mesh (2 x 256^2 triangles) vs pyramid ({paper}x{paper}, one 256^2 tile)"
        ),
        &["map", "method", "GPU ms", "memory (MB)"],
    );
    for b in BUNDLED.iter().filter(|b| b.paper_row != "-") {
        let map = resized(&b.load()?, 256);
        let mut r = Renderer::new(gpu, &map, None, b.surface);
        let mut time = |experiment, method| {
            let s = bench.paper_view(Method::timed(method));
            bench.time(experiment, b.name, &map, &mut r, &s)
        };
        let point = time("table1", Method::Pyramid)?;
        let bilinear = time("table1", Method::PyramidBilinear)?;
        let pom = time("table2", Method::Pom)?;
        let relief = time("table2", Method::Relief)?;
        let ascend = time("table2", Method::PyramidAscend)?;
        let row = format!("{} ({})", b.name, b.paper_row);
        t1.row(vec![
            row.clone(),
            ms(point),
            ms(bilinear),
            ratio_text(ratio(bilinear, point)),
        ]);
        t2.row(vec![
            row,
            ms(pom),
            ms(relief),
            ms(point),
            ms(ascend),
            ratio_text(ratio(point, pom)),
        ]);
        if b.name == "tiles" {
            ratios.pyramid_over_pom16_paper_size = ratio(point, pom);
            // One copy of the map, as in the paper's figure: 2 * 256^2 triangles for the mesh.
            let mut one = Renderer::new(gpu, &map, None, SurfaceKind::Terrain);
            for method in [Method::Pyramid, Method::Mesh] {
                let s = bench.paper_view(method.timed());
                let t = bench.time("figure20", b.name, &map, &mut one, &s)?;
                let mb = one.memory_bytes(method) as f64 / 1e6;
                f20.row(vec![
                    b.name.into(),
                    method.to_string(),
                    ms(t),
                    format!("{mb:.2}"),
                ]);
            }
        }
    }
    Ok(vec![t1, t2, f20])
}

/// Figure 21: GPU time against map size (and its plot, figure21_map_size.svg in `out`).
pub fn figure_21(
    bench: &mut Bench,
    tiles: &HeightMap,
    out: &Path,
    ratios: &mut Ratios,
) -> Result<Table, DisplaceError> {
    let (gpu, paper, sizes) = (bench.gpu, bench.paper, map_sizes(bench.quick));
    let mut f21 = Table::new(
        format!("Figure 21: GPU ms by map size ({paper}x{paper}, tiles, 60 deg)"),
        &[
            "map size",
            "pyramid",
            "pyramid-ascend",
            "pyramid lod-auto",
            "pyramid / at 256^2",
            "lod-auto / at 256^2",
        ],
    );
    let variants = [
        Method::Pyramid.timed(),
        Method::PyramidAscend.timed(),
        lod_auto(Method::Pyramid.timed()),
    ];
    let mut f21_series: Vec<Series> = variants
        .iter()
        .map(|s| Series {
            name: s.caption(),
            points: vec![],
        })
        .collect();
    let mut at_256 = [None; 3];
    for &size in sizes {
        let map = resized(tiles, size);
        let mut r = Renderer::new(gpu, &map, None, BUNDLED[0].surface);
        let mut times = [None; 3];
        for (k, s) in variants.iter().enumerate() {
            times[k] = bench.time(
                "figure21",
                "tiles",
                &map,
                &mut r,
                &bench.paper_view(s.clone()),
            )?;
            if let Some(t) = times[k] {
                f21_series[k].points.push((f64::from(size), t));
            }
        }
        if size == 256 {
            at_256 = times;
        }
        if size == 4096 {
            ratios.pyramid_4096_over_256 = ratio(times[0], at_256[0]);
            ratios.pyramid_lod_auto_4096_over_256 = ratio(times[2], at_256[2]);
        }
        let r = |k: usize| ratio_text(ratio(times[k], at_256[k]));
        f21.row(vec![
            format!("{size}^2"),
            ms(times[0]),
            ms(times[1]),
            ms(times[2]),
            r(0),
            r(2),
        ]);
    }
    if f21_series.iter().all(|s| !s.points.is_empty()) {
        let spec = PlotSpec {
            title: "GPU time by map size (figure 21)",
            x_label: "map side (texels)",
            y_label: "GPU ms",
            log_x: true,
            log_y: false,
        };
        line_plot(&out.join("figure21_map_size.svg"), &spec, &f21_series)?;
    }
    Ok(f21)
}

/// Section 3.1: building the pyramid, on the CPU (the paper: 2.3 ms for 256^2) and on the GPU.
pub fn pyramid_build(bench: &Bench, tiles: &HeightMap) -> Result<Table, DisplaceError> {
    let (gpu, frames, sizes) = (bench.gpu, bench.frames, map_sizes(bench.quick));
    let mut build = Table::new(
        "Pyramid build (section 3.1): CPU ms (median, one thread) and GPU ms (compute, timestamps)",
        &["map size", "CPU", "GPU"],
    );
    let builder = PyramidBuilder::new(&gpu.device);
    for &size in sizes {
        let map = resized(tiles, size);
        let (_, cpu) = time_cpu(frames, || Pyramid::build(&map));
        let mut timer = GpuTimer::new(gpu, 1);
        for _ in 0..frames {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let kind = PyramidKind::Point;
            let writes = timer.compute_pass(0);
            builder.record(&gpu.device, &gpu.queue, &mut encoder, &map, kind, writes);
            timer.resolve(&mut encoder);
            gpu.submit(
                format!("the pyramid build of a {size}^2 map"),
                encoder.finish(),
            );
            timer.collect(gpu)?;
        }
        let gpu_ms = timer.summaries()[0].map(|t| t.median_ms);
        build.row(vec![
            format!("{size}^2"),
            format!("{:.3}", cpu.median_ms),
            ms(gpu_ms),
        ]);
    }
    Ok(build)
}

/// Relaxed cone stepping's preprocessing at 1024^2, 2048^2 and 4096^2: the cone map built on the
/// CPU (all cores), median seconds of a few builds (each takes seconds: no warm-up build).
pub fn cone_build(bench: &Bench, tiles: &HeightMap) -> Result<Table, DisplaceError> {
    let runs = if bench.quick { 3 } else { 5 };
    let mut build = Table::new(
        format!(
            "Cone map build (relaxed cones, tiles, wrapped): CPU seconds, median of {runs}, {} threads",
            rayon::current_num_threads()
        ),
        &["map size", "seconds", "p10", "p90"],
    );
    let addressing = BUNDLED[0].surface.addressing();
    for size in [1024, 2048, 4096] {
        let map = resized(tiles, size);
        let mut seconds: Vec<f64> = (0..runs)
            .map(|_| {
                let start = std::time::Instant::now();
                ConeMap::build(&map, addressing);
                start.elapsed().as_secs_f64()
            })
            .collect();
        // Summary names its fields in ms; here they hold the samples' unit, seconds.
        let s = Summary::from_samples(&mut seconds).expect("at least one run");
        build.row(vec![
            format!("{size}^2"),
            format!("{:.2}", s.median_ms),
            format!("{:.2}", s.p10_ms),
            format!("{:.2}", s.p90_ms),
        ]);
    }
    Ok(build)
}

/// Today's frame: 1920x1080 with a 1024^2 map (480x270 when quick): GPU time at 60 degrees, and
/// the hardware-independent cost (iterations, texel fetches per pixel) by view angle.
pub fn todays_frame(
    bench: &mut Bench,
    tiles: &HeightMap,
    ratios: &mut Ratios,
) -> Result<Vec<Table>, DisplaceError> {
    let gpu = bench.gpu;
    let (w, h) = if bench.quick {
        (480, 270)
    } else {
        (1920, 1080)
    };
    let mut r = Renderer::new(gpu, tiles, None, BUNDLED[0].surface);
    let today = |s: Settings| Settings {
        size: Size::new(w, h),
        view_angle_deg: 60.0,
        ..s
    };
    let mut columns = traced(Method::timed);
    columns.push(lod_auto(Method::Pyramid.timed()));
    let mut times = Vec::new();
    for s in &columns {
        times.push(bench.time("today", "tiles", tiles, &mut r, &today(s.clone()))?);
    }
    let time_of = |wanted: &Settings| {
        let k = columns.iter().position(|s| s == wanted);
        times[k.expect("a column")]
    };
    let pom = time_of(&Method::Pom.timed());
    let over_pom = [
        time_of(&Method::Pyramid.timed()),
        time_of(&lod_auto(Method::Pyramid.timed())),
    ]
    .map(|t| ratio(t, pom));
    ratios.pyramid_over_pom16_today = over_pom[0];
    ratios.pyramid_lod_auto_over_pom16_today = over_pom[1];
    let mut header: Vec<String> = columns.iter().map(Settings::caption).collect();
    let pom_caption = Method::Pom.timed().caption();
    header.extend([
        format!("pyramid / {pom_caption}"),
        format!("lod-auto / {pom_caption}"),
    ]);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let mut t = Table::new(
        format!("Today's frame: {w}x{h}, tiles 1024^2, 60 deg, GPU ms"),
        &header,
    );
    let mut row: Vec<String> = times.iter().map(|&t| ms(t)).collect();
    row.extend(over_pom.map(ratio_text));
    t.row(row);
    let angles = [0.0, 45.0, 60.0, 70.0, 85.0];
    let mut angle_columns = vec!["method".to_string()];
    angle_columns.extend(angles.map(|a| format!("{a:.0} deg")));
    let mut cost = Table {
        title: format!(
            "Today's frame: mean iterations / texel fetches per pixel by view angle ({w}x{h}, tiles 1024^2)"
        ),
        columns: angle_columns,
        rows: vec![],
    };
    for s in &columns {
        let mut row = vec![s.caption()];
        for angle in angles {
            let s = Settings {
                view_angle_deg: angle,
                ..today(s.clone())
            };
            let c = Cost::of(&r.render(gpu, &s)?);
            row.push(format!(
                "{:.1} / {:.1}",
                c.mean_iterations, c.texel_fetches_per_pixel
            ));
        }
        cost.row(row);
    }
    Ok(vec![t, cost])
}
