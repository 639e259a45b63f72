//! The paper's cost model (section II, equations 1-12): the cost of a conventional shadow test
//! against the cost of N_s shadow-polygon tests, the threshold N_th where they meet, the machine
//! constants measured by micro-benchmarks, and the measured decision costs the pilot renders
//! ([`crate::pilot`]) bin. Nothing here renders.

use crate::grid::{Grid, Mailbox};
use glam::Vec3;
use quadray_core::geom::{Aabb, ConvexPolygon, Ray};
use quadray_core::random::SplitMix;
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
    /// N_ot: polygons of the scene.
    pub polygons: usize,
    /// A_avg: mean area of the (non-degenerate) polygons.
    pub mean_area: f64,
    /// L_avg: their mean perimeter.
    pub mean_perimeter: f64,
    /// The grid's resolution.
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
    /// Forced conventional decisions per free one.
    pub ratio: f64,
    /// Mean N_s of the forced decisions.
    pub forced_ns: f64,
    /// The measured N_s where a shadow-volume decision costs as much as a shadow ray.
    pub break_even: Option<f64>,
}

/// Fewest timed decisions of a bin the break-even reads.
const PILOT_MIN_DECISIONS: usize = 30;

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

/// Measures the machine constants with micro-benchmarks on synthetic polygons and grids; each is
/// the median of several timed batches.
pub fn calibrate() -> MachineCosts {
    let mut rng = SplitMix(1);
    let mut random_polygon = |sides: usize| {
        let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
        let (u, v) = (
            Vec3::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            )
            .normalize(),
            Vec3::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            ),
        );
        let v = u.cross(v).normalize();
        let r = 0.3 + rng.next_f32();
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
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - 3.0;
            let d = Vec3::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            )
            .normalize();
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
            grid.walk(&Ray::new(o, d, 0.0, 100.0), |c, _, _| {
                black_box(c) != u32::MAX
            });
        }
    });
    let mut steps = 0usize;
    let diagonal = Ray::new(Vec3::splat(-2.99), Vec3::ONE.normalize(), 0.0, 100.0);
    grid.walk(&diagonal, |_, _, _| {
        steps += 1;
        false
    });
    let walk_all = median_ns(rays.len(), || {
        for _ in 0..rays.len() {
            grid.walk(&diagonal, |c, _, _| black_box(c) == u32::MAX);
        }
    });
    let c_c = ((walk_all - c_i) / steps.max(1) as f64).max(0.01);
    MachineCosts { c_s, c_i, c_c, c_o }
}

/// Median over batches of the time per operation of `f`, which performs `ops` operations.
/// Timed in this thread's CPU time, so neither other processes nor idle-spinning worker threads
/// sharing the cores inflate it.
pub(crate) fn median_ns(ops: usize, mut f: impl FnMut()) -> f64 {
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

/// Number of [`CostBins`].
pub const COST_BINS: usize = 12;

/// A timed decision that took this many times its bin's median was interrupted (the thread was
/// descheduled or served an interrupt): one such decision of a millisecond would outweigh a
/// thousand real ones in the bin's mean.
const INTERRUPTED: u64 = 16;

/// Timed decisions, read by N_s in bins: bin 0 holds N_s = 0, bin b N_s in `[2^(b-1), 2^b)`,
/// the last all above.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct CostBins {
    /// (N_s, ticks) of each decision.
    samples: Vec<(u32, u64)>,
}

impl CostBins {
    /// Notes a decision of N_s `ns` that took `ticks`.
    pub fn add(&mut self, ns: u32, ticks: u64) {
        self.samples.push((ns, ticks));
    }

    pub(crate) fn merge(&mut self, o: &CostBins) {
        self.samples.extend_from_slice(&o.samples);
    }

    fn bin(ns: u32) -> usize {
        ((u32::BITS - ns.leading_zeros()) as usize).min(COST_BINS - 1)
    }

    /// Mean N_s and mean ticks of bin `b`'s decisions, if it has at least `min` of them, the
    /// interrupted ones left out.
    pub fn mean(&self, b: usize, min: usize) -> Option<(f64, f64)> {
        let bin: Vec<(u32, u64)> = self
            .samples
            .iter()
            .copied()
            .filter(|&(ns, _)| Self::bin(ns) == b)
            .collect();
        if bin.len() < min.max(1) {
            return None;
        }
        let mut ticks: Vec<u64> = bin.iter().map(|&(_, t)| t).collect();
        let half = ticks.len() / 2;
        let limit = INTERRUPTED * *ticks.select_nth_unstable(half).1;
        let kept: Vec<&(u32, u64)> = bin.iter().filter(|&&(_, t)| t <= limit).collect();
        let n = kept.len() as f64;
        Some((
            kept.iter().map(|&&(ns, _)| ns as f64).sum::<f64>() / n,
            kept.iter().map(|&&(_, t)| t as f64).sum::<f64>() / n,
        ))
    }
}
