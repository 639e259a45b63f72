//! The paper's cost model (section II, equations 1-12): the cost of a conventional shadow test
//! against the cost of N_s shadow-polygon tests, the threshold N_th where they meet, the machine
//! constants measured by micro-benchmarks and the scene statistics p and alpha.

use crate::SplitMix;
use crate::geom::{Aabb, ConvexPolygon};
use crate::grid::{CellRecord, Grid, Mailbox};
use crate::trace::{COST_BINS, CostBins, Pinhole, Prepared};
use glam::Vec3;
use serde::Serialize;
use std::hint::black_box;

/// Machine constants in nanoseconds (the paper's table 1 has milliseconds on a SUN 3/75).
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct MachineCosts {
    /// One ray / shadow-polygon test.
    pub c_s: f64,
    /// Starting a shadow ray's 3DDDA.
    pub c_i: f64,
    /// One 3DDDA step to the next cell.
    pub c_c: f64,
    /// One ray / object-polygon test.
    pub c_o: f64,
}

/// The scene statistics of the paper's table 2 and what the model derives from them.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct SceneStats {
    pub polygons: usize,
    pub mean_area: f64,
    pub mean_perimeter: f64,
    pub grid: [u32; 3],
    /// Edge of a cube of the cell's volume.
    pub cell_edge: f64,
    /// Mean polygons registered per cell (n_or).
    pub n_or: f64,
    /// New polygons per cell a ray meets: n_or / 2, the relation all four rows of table 2 obey.
    pub alpha: f64,
    /// Chance that a polygon met in a crossed cell blocks the ray.
    pub p: f64,
    /// Mean cells a shadow ray crosses (sampled from points on the polygons to every light).
    pub n_c: f64,
    /// N_o = alpha N_c (eq. 10).
    pub n_o: f64,
    /// C_s measured per registered shadow polygon on this scene (ns), when it has shadow polygons;
    /// equation 12 uses it in place of the per-test C_s.
    pub c_s_per_entry: Option<f64>,
}

/// Equation 11: expected cost of a conventional shadow test.
pub fn conventional_cost(c: &MachineCosts, s: &SceneStats) -> f64 {
    let q = 1.0 - s.p;
    c.c_i + (1.0 - q.powf(s.n_o)) * (c.c_c / (1.0 - q.powf(s.alpha)) + c.c_o / s.p)
}

/// Equation 12: the N_s where the shadow-volume test (C_s N_s, eq. 1) costs as much, with C_s
/// per registered shadow polygon when the scene's was measured.
pub fn predicted_nth(c: &MachineCosts, s: &SceneStats) -> f64 {
    conventional_cost(c, s) / s.c_s_per_entry.unwrap_or(c.c_s)
}

/// What equation 12 leaves out, measured on pilot renders (96 x 72).
///
/// First, in HST's state machine a conventional test that finds shadow also leaves the depth
/// count invalid (SDF = 0), and every later point of that ray tree (not sustained, not
/// self-shadowed) then takes a shadow ray too, until one is lit, even where its N_s is small:
/// `ratio` such forced decisions per free one (N_s above N_th), `forced_ns` their mean N_s (HST
/// at equation 12's N_th).
///
/// Second, equation 12 equates a mean shadow ray with N_s times a mean shadow-polygon test, but
/// neither cost is the mean one where the choice is made. Points reached through many shadow
/// polygons lie far along long segments, deep in the scene, and their shadow rays cross more cells
/// than the mean one; and a long segment meets the same large shadow polygons in cell after cell,
/// which the bucket tests once, so a shadow-volume decision's cost grows slower than N_s. On the
/// look-alikes both push the break-even N_s well above equation 12's. `break_even` is where the
/// two costs meet, measured: HST timed decision by decision with N_th infinite (every decision
/// it can make by shadow volume) and with N_th 0 (every one by shadow ray), both binned by N_s.
/// None when too few decisions were timed.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct FollowUp {
    pub ratio: f64,
    pub forced_ns: f64,
    pub break_even: Option<f64>,
}

/// Fewest timed decisions of a bin the break-even reads.
const PILOT_MIN_DECISIONS: usize = 30;

/// The pilot renders of [`FollowUp`]; zero without shadow polygons.
pub fn follow_up(prep: &Prepared, nth: f64, depth: u32) -> FollowUp {
    if prep.volumes.is_none() {
        return FollowUp::default();
    }
    let pilot = |nth: f32, time_decisions| {
        let settings = crate::trace::Settings {
            width: 96,
            height: 72,
            spp: 1,
            depth,
            scheme: crate::trace::Scheme::Hst { nth },
            check: false,
            time_decisions,
        };
        crate::trace::render(prep, settings, &|| {}).1
    };
    // This one also warms the caches for the timed ones.
    let r = pilot(nth as f32, false);
    let free = r.conventional.saturating_sub(r.forced_conventional);
    let (volume, rays) = (pilot(f32::INFINITY, true), pilot(0.0, true));
    FollowUp {
        ratio: r.forced_conventional as f64 / free.max(1) as f64,
        forced_ns: r.forced_ns as f64 / r.forced_conventional.max(1) as f64,
        break_even: break_even(&volume.shadow_volume_costs, &rays.shadow_ray_costs),
    }
}

/// The N_s where shadow-volume decisions start to cost more than shadow rays: interpolated
/// between the mean N_s of the last bin where they cost less and the first where they cost more;
/// the top of the last bin timed when they cost less everywhere.
pub(crate) fn break_even(volume: &CostBins, rays: &CostBins) -> Option<f64> {
    let mut below: Option<(f64, f64)> = None;
    for b in 1..COST_BINS {
        let (Some((ns, v)), Some((_, r))) = (
            volume.mean(b, PILOT_MIN_DECISIONS),
            rays.mean(b, PILOT_MIN_DECISIONS),
        ) else {
            continue;
        };
        let excess = v - r;
        if excess > 0.0 {
            // From the origin (no polygons cost nothing) when the first bin already costs more.
            let (ns0, e0) = below.unwrap_or((0.0, -r));
            return Some(ns0 + (ns - ns0) * -e0 / (excess - e0));
        }
        below = Some((ns, excess));
    }
    below.map(|(ns, _)| ns.max(1.0).log2().ceil().exp2().max(ns))
}

/// N_th with the pilot's corrections: choosing a shadow ray at a point costs C_cv, and with the
/// measured `ratio` that many forced shadow rays more, each in place of a shadow-volume test of
/// about `forced_ns` polygons: C_s N_th = C_cv (1 + ratio) - ratio C_s forced_ns. C_cv / C_s is
/// the pilot's measured break-even where it has one, equation 12's otherwise.
pub fn extended_nth(c: &MachineCosts, s: &SceneStats, f: &FollowUp) -> f64 {
    let cv_over_s = f.break_even.unwrap_or_else(|| predicted_nth(c, s));
    (cv_over_s * (1.0 + f.ratio) - f.ratio * f.forced_ns).max(0.0)
}

/// Scene statistics from the polygons and the grid.
///
/// p comes from integral geometry: among random lines that meet a polygon's neighbourhood of
/// cells (the polygon swept by a cell, K + C), the share that meets the polygon is the ratio of mean
/// projected areas, (2A/4) / (S(K+C)/4), and for a flat polygon of area A and perimeter L and a cube
/// cell of edge h the mean surface of K + C is 2A + 6h^2 + (3 pi / 4) L h.
pub fn scene_stats(prep: &Prepared) -> SceneStats {
    let live: Vec<&ConvexPolygon> = prep
        .polygons
        .iter()
        .filter(|p| !p.is_degenerate())
        .collect();
    let n = live.len().max(1) as f64;
    let mean_area = live.iter().map(|p| p.area() as f64).sum::<f64>() / n;
    let mean_perimeter = live.iter().map(|p| p.perimeter() as f64).sum::<f64>() / n;
    let g = &prep.grid;
    let cell_edge = (g.cell_size.x as f64 * g.cell_size.y as f64 * g.cell_size.z as f64).cbrt();
    let n_or = prep.cells.registrations() as f64 / g.cell_count() as f64;
    let alpha = n_or / 2.0;
    let (a, l, h) = (mean_area, mean_perimeter, cell_edge);
    let p =
        (2.0 * a / (2.0 * a + 6.0 * h * h + 0.75 * std::f64::consts::PI * l * h)).clamp(1e-6, 1.0);
    let c_s_per_entry = shadow_entry_cost(prep);
    let n_c = mean_shadow_ray_cells(
        &live,
        g,
        &prep
            .scene
            .lights
            .iter()
            .map(|l| l.position)
            .collect::<Vec<_>>(),
    );
    SceneStats {
        polygons: prep.polygons.len(),
        mean_area,
        mean_perimeter,
        grid: g.res,
        cell_edge,
        n_or,
        alpha,
        p,
        n_c,
        n_o: alpha * n_c,
        c_s_per_entry,
    }
}

/// Mean number of cells walked from area-weighted random points on the polygons to each light.
/// `count` area-weighted random points on the polygons.
fn surface_points(polygons: &[&ConvexPolygon], count: usize, rng: &mut SplitMix) -> Vec<Vec3> {
    let mut cumulative = Vec::with_capacity(polygons.len());
    let mut total = 0.0;
    for p in polygons {
        total += p.area() as f64;
        cumulative.push(total);
    }
    (0..count)
        .map(|_| {
            let pick = cumulative
                .partition_point(|&c| c < rng.unit() as f64 * total)
                .min(polygons.len() - 1);
            let poly = polygons[pick];
            // A point inside the convex polygon: random convex weights of its vertices.
            let w: Vec<f32> = poly.vertices.iter().map(|_| rng.unit() + 1e-3).collect();
            let ws: f32 = w.iter().sum();
            poly.vertices
                .iter()
                .zip(&w)
                .map(|(v, w)| *v * (w / ws))
                .sum::<Vec3>()
        })
        .collect()
}

/// Mean number of cells walked from area-weighted random points on the polygons to each light.
fn mean_shadow_ray_cells(polygons: &[&ConvexPolygon], grid: &Grid, lights: &[Vec3]) -> f64 {
    if polygons.is_empty() || lights.is_empty() {
        return 0.0;
    }
    let points = surface_points(polygons, 2000, &mut SplitMix(7));
    let mut cells = 0u64;
    for &point in &points {
        for &light in lights {
            let to = light - point;
            let dist = to.length();
            grid.walk(point, to / dist, 0.0, dist, |_, _, _| {
                cells += 1;
                false
            });
        }
    }
    cells as f64 / (points.len() * lights.len()) as f64
}

/// C_s as equation 1 uses it, measured on the scene's own shadow polygons: CPU time per shadow
/// polygon registered in a crossed cell. N_s counts a polygon once per cell it is registered in,
/// and the bucket (mailbox) tests it only once per segment, so most entries cost a mailbox check
/// rather than a ray test. Timed on the segments the tracer meets most, eye rays to their first
/// hit (a 64 x 48 grid of them): how many cells a segment crosses and how long it runs through
/// shadow volumes decide the mix of checks and tests. None without shadow polygons.
fn shadow_entry_cost(prep: &Prepared) -> Option<f64> {
    let volumes = prep.volumes.as_ref()?;
    let eye = prep.scene.camera.eye;
    let pinhole = Pinhole::new(&prep.scene.camera, 64, 48);
    let mut objects = Mailbox::new(prep.polygons.len());
    // (direction, length, occupied cells, lights with shadow polygons in them): HST counts
    // crossings only for a light whose N_s is not 0 (else it sustains), so only those are timed.
    let mut segments: Vec<(Vec3, f32, Vec<u32>, Vec<usize>)> = Vec::new();
    let mut entries = 0u64;
    let mut occupied = CellRecord::new(&prep.grid);
    for y in 0..48 {
        for x in 0..64 {
            let d = pinhole.dir(x as f32 + 0.5, y as f32 + 0.5);
            occupied.clear();
            let hit = prep.grid.closest_hit(
                &prep.cells,
                &prep.polygons,
                eye,
                d,
                prep.eps,
                f32::INFINITY,
                None,
                &mut objects,
                Some((volumes.occupied_cells(), &mut occupied)),
            );
            if let Some(h) = hit {
                let ns = volumes.counts(occupied.cells());
                let lights: Vec<usize> = (0..volumes.lights.len()).filter(|&l| ns[l] > 0).collect();
                entries += lights.iter().map(|&l| ns[l] as u64).sum::<u64>();
                segments.push((d, h.t, occupied.cells().to_vec(), lights));
            }
        }
    }
    if entries == 0 {
        return None;
    }
    let mut mailbox = Mailbox::new(volumes.max_per_light());
    let mut tests = 0;
    Some(median_ns(entries as usize, || {
        let mut change = 0;
        for (d, t, occupied, lights) in &segments {
            for &l in lights {
                change +=
                    volumes.crossings(l, occupied, eye, *d, 0.0, *t, &mut mailbox, &mut tests);
            }
        }
        black_box(change);
    }))
}

/// Measures the machine constants with micro-benchmarks on synthetic polygons and grids; each is
/// the median of several timed batches.
pub fn calibrate() -> MachineCosts {
    let mut rng = SplitMix(1);
    let mut random_polygon = |sides: usize| {
        let c = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 4.0 - 2.0;
        let (u, v) = (
            Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize(),
            Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5),
        );
        let v = u.cross(v).normalize();
        let r = 0.3 + rng.unit();
        ConvexPolygon::new(
            (0..sides)
                .map(|i| {
                    let a = i as f32 / sides as f32 * std::f32::consts::TAU;
                    c + (u * a.cos() + v * a.sin()) * r
                })
                .collect(),
        )
    };
    // Objects are triangles and quads; shadow polygons are the extruded pentagons.
    let objects: Vec<ConvexPolygon> = (0..256).map(|i| random_polygon(3 + i % 2)).collect();
    let shadows: Vec<ConvexPolygon> = (0..256).map(|_| random_polygon(5)).collect();
    let rays: Vec<(Vec3, Vec3)> = (0..256)
        .map(|_| {
            let o = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 6.0 - 3.0;
            let d = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize();
            (o, d)
        })
        .collect();
    let per_test = |polys: &[ConvexPolygon]| {
        let mut mailbox = Mailbox::new(polys.len());
        median_ns(polys.len() * rays.len(), || {
            let mut hits = 0u32;
            for &(o, d) in &rays {
                mailbox.next_ray();
                for (i, p) in polys.iter().enumerate() {
                    if mailbox.first_visit(i as u32) {
                        hits += p.intersect(o, d, 0.0, 10.0).is_some() as u32;
                    }
                }
            }
            black_box(hits);
        })
    };
    let c_o = per_test(&objects);
    let c_s = per_test(&shadows);
    let grid = Grid::with_resolution(
        Aabb {
            min: Vec3::splat(-3.0),
            max: Vec3::splat(3.0),
        },
        [48, 48, 48],
    );
    let c_i = median_ns(rays.len(), || {
        for &(o, d) in &rays {
            grid.walk(o, d, 0.0, 100.0, |c, _, _| black_box(c) != u32::MAX);
        }
    });
    let mut steps = 0usize;
    grid.walk(
        Vec3::splat(-2.99),
        Vec3::ONE.normalize(),
        0.0,
        100.0,
        |_, _, _| {
            steps += 1;
            false
        },
    );
    let walk_all = median_ns(rays.len(), || {
        for _ in 0..rays.len() {
            grid.walk(
                Vec3::splat(-2.99),
                Vec3::ONE.normalize(),
                0.0,
                100.0,
                |c, _, _| black_box(c) == u32::MAX,
            );
        }
    });
    let c_c = ((walk_all - c_i) / steps.max(1) as f64).max(0.01);
    MachineCosts { c_s, c_i, c_c, c_o }
}

/// Median over batches of the time per operation of `f`, which performs `ops` operations.
/// Timed in this thread's CPU time, so neither other processes nor idle-spinning worker threads
/// sharing the cores inflate it.
fn median_ns(ops: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut samples: Vec<f64> = (0..15)
        .map(|_| {
            let start = crate::thread_cpu_s();
            f();
            (crate::thread_cpu_s() - start) * 1e9 / ops as f64
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}
