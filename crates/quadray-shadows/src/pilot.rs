//! The pilot measurements that calibrate the cost model on a prepared scene: its statistics
//! (p, alpha, N_c, C_s per registered shadow polygon) and the small renders of [`FollowUp`]. It
//! sits above the tracer it runs and the equations it feeds ([`crate::cost`]).

use crate::cost::{
    FollowUp, MachineCosts, SceneStats, break_even, extended_nth, median_ns, predicted_nth,
};
use crate::grid::{CellRecord, Grid, Mailbox};
use crate::prepare::{Prepared, Scheme};
use crate::settings::{Nth, SchemeChoice, Settings};
use crate::trace::{Job, Pinhole, render};
use glam::Vec3;
use quadray_core::geom::{ConvexPolygon, Ray};
use quadray_core::random::SplitMix;
use quadray_core::settings::Size;
use std::hint::black_box;

impl Prepared {
    /// The cost model's scene statistics (measured once, so every render of this preparation
    /// predicts the same N_th).
    pub fn stats(&self) -> &SceneStats {
        self.stats.get_or_init(|| scene_stats(self))
    }

    /// The N_th HST uses with `--nth auto`: equation 12 with the measured break-even and the
    /// follow-up cost of a conventional decision ([`FollowUp`]), measured once on pilot renders
    /// of recursion `depth` (without shadow polygons: equation 12 as written).
    pub fn predicted_nth(&self, costs: &MachineCosts, depth: u32) -> (f64, FollowUp) {
        let stats = self.stats();
        let equation_12 = predicted_nth(costs, stats);
        let follow_up = *self
            .follow_up
            .get_or_init(|| follow_up(self, equation_12, depth));
        (extended_nth(costs, stats, &follow_up), follow_up)
    }
}

/// The pilot renders of [`FollowUp`]; zero without shadow polygons.
pub fn follow_up(prep: &Prepared, nth: f64, depth: u32) -> FollowUp {
    if prep.volumes.is_none() {
        return FollowUp::default();
    }
    let pilot = |nth: f32, time_decisions| {
        // Every field named: a new setting's default must not move the prediction unseen.
        let job = Job {
            settings: Settings {
                scheme: SchemeChoice::Hst,
                nth: Nth::Fixed(nth),
                size: Size::new(96, 72),
                spp: 1,
                depth,
                check: false,
            },
            scheme: Scheme::Hst { nth },
            time_decisions,
        };
        render(prep, job, &|| {}).1
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
                .partition_point(|&c| c < rng.next_f32() as f64 * total)
                .min(polygons.len() - 1);
            let poly = polygons[pick];
            // A point inside the convex polygon: random convex weights of its vertices.
            let w: Vec<f32> = poly
                .vertices
                .iter()
                .map(|_| rng.next_f32() + 1e-3)
                .collect();
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
            grid.walk(&Ray::new(point, to / dist, 0.0, dist), |_, _, _| {
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
    let eye = prep.scene.camera.position;
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
            let hit = prep.grid_occluder().closest_hit(
                &Ray::new(eye, d, prep.eps, f32::INFINITY),
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
                change += volumes.crossings(
                    l,
                    occupied,
                    &Ray::new(eye, *d, 0.0, *t),
                    &mut mailbox,
                    &mut tests,
                );
            }
        }
        black_box(change);
    }))
}
