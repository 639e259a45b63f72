//! Whitted ray tracing on a uniform grid with hybrid shadow testing (Eo & Kyung, 1989): the
//! conventional shadow ray, shadow volumes with depth counts carried along every ray segment, the
//! hybrid switch between them with its cost model, and a SAH BVH (and, with the `embree` feature,
//! Intel Embree) as today's baselines.
//!
//! Rooms: [`scene`] (procedural look-alikes of the paper's scenes, TOML scene files), [`grid`]
//! (SEADS, 3DDDA, mailboxes), [`trace`] (the renderer), [`shadow`] (shadow polygons and HST),
//! [`cost`] (equations 1-12 and the micro-benchmarks), [`bvh`], [`bench`] (the paper's tables).
//!
//! Where this departs from the paper, and why:
//! - The depth count counts every polygon between a point and the light, both faces, so it is
//!   exactly the conventional test's answer: silhouette edges (Bergeron's rule) carry weight 1 on
//!   open boundaries and 2 between faces that face the light differently, and a ray refracted
//!   through a polygon adds or removes that polygon ([`shadow`]). Which side of an extruded edge a
//!   polygon lies on comes from how it faces the light and which way it runs along the edge, and
//!   the sides of shadow polygons are tested watertight (the side relation of the ray and the
//!   line from the light through the shared vertex): on a finely meshed model (the bunny) the
//!   plain geometric tests left holes in the volumes.
//! - The paper's switch is kept as written, with one addition: at a self-shadowed point a valid
//!   depth count is carried through (when a ray continues from the point and N_s <= N_th), where
//!   the paper drops it and forces shadow rays on the rest of the ray tree
//!   ([`shadow::LightState::hst_step`]). What a refraction does to the carried state is ours (the
//!   paper leaves it open): through a surface whose far side faces the light, the condition
//!   becomes unknown and the next reflection point takes a shadow ray.
//! - Shadow polygons are extruded to beyond the grid's box (as pentagons, so the far side never cuts
//!   the box) and the grid holds the eye, whose depth count starts every eye ray.
//! - p comes from integral geometry and alpha = n_or / 2 (the relation every row of table 2 obeys);
//!   N_c is sampled from points on the polygons to the lights; C_s is measured per registered
//!   shadow polygon on the scene's own eye-ray segments ([`cost`]).
//! - `--nth auto` is equation 12 with two corrections measured on pilot renders
//!   ([`cost::FollowUp`]); equation 12 as written is reported beside it. The break-even of a
//!   shadow-volume decision and a shadow ray is timed where the choice is made, binned by N_s,
//!   instead of from the mean shadow ray and C_s N_s: HST casts its rays from points deep in the
//!   scene, whose rays cost more than the mean one, and the bucket makes a decision's cost grow
//!   slower than N_s. A timed decision 16 times slower than its bin's median was interrupted and
//!   is left out (one descheduled decision would outweigh a thousand real ones in the mean). And
//!   the follow-up cost of a conventional decision that finds shadow is added (SDF = 0 forces
//!   shadow rays at the later points of the ray tree).
//! - Times are CPU seconds of all threads, as the paper's CPU minutes; the shadow part is split
//!   off with the time-stamp counter around each shading point's shadow decisions. Finding the
//!   cells of a segment that hold shadow polygons is a bit test per cell inside the walk that
//!   finds the hit, so it counts as "other" (the total shows it); summing their N_s and
//!   everything after counts as shadow testing.
//! - Transparent objects must not touch other surfaces (the builtin glasses and vase float a hair
//!   above): a refracted ray passing through two coplanar faces at once would skip one.

pub mod bench;
pub mod bvh;
pub mod cost;
pub mod demo;
#[cfg(feature = "embree")]
pub mod embree;
pub mod geom;
pub mod grid;
pub mod scene;
pub mod shadow;
pub mod trace;

#[cfg(test)]
mod tests;

use cost::{MachineCosts, SceneStats};
use quadray_core::image_out::Rgba8Image;
use scene::Scene;
use serde::Serialize;
use trace::{Prepared, RenderStats, Scheme, Settings};

/// How the HST threshold is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Nth {
    /// Equation 12 from measured machine constants and the scene's statistics.
    Auto,
    Fixed(f32),
}

/// The shadow scheme asked for on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SchemeChoice {
    Conventional,
    Volume,
    Hst,
    Bvh,
    /// Embree occlusion rays; needs the `embree` feature.
    Embree,
}

impl std::str::FromStr for SchemeChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "conventional" => Ok(Self::Conventional),
            "volume" => Ok(Self::Volume),
            "hst" => Ok(Self::Hst),
            "bvh" => Ok(Self::Bvh),
            "embree" if cfg!(feature = "embree") => Ok(Self::Embree),
            "embree" => {
                Err("this quadray was built without Embree (cargo build --features embree)".into())
            }
            _ => Err(format!(
                "unknown shadow scheme {s:?} (conventional, volume, hst, bvh, embree)"
            )),
        }
    }
}

/// One render's parameters.
#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    pub scheme: SchemeChoice,
    pub nth: Nth,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub depth: u32,
    pub check: bool,
    /// Machine constants; measured when `nth` is `Auto` and none are given.
    pub costs: Option<MachineCosts>,
}

/// CPU seconds (all threads), as the paper's table 4 reports CPU minutes.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Times {
    pub preprocess: f64,
    pub shadow: f64,
    pub other: f64,
    pub total: f64,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct Subschemes {
    pub sustain: u64,
    pub self_shadow: u64,
    pub shadow_volume: u64,
    pub conventional: u64,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct NthReport {
    /// What `--nth auto` uses: equation 12 with the pilot's corrections ([`cost::FollowUp`]).
    pub predicted: f64,
    /// Equation 12 as the paper writes it.
    pub equation_12: f64,
    pub follow_up: cost::FollowUp,
    /// None when the scheme has no threshold.
    pub used: Option<f64>,
}

/// The stats JSON of `quadray raytrace --stats`.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    pub scene: String,
    pub scheme: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub depth: u32,
    pub polygons: usize,
    pub lights: usize,
    pub shadow_polygons: usize,
    pub grid: [u32; 3],
    pub times_s: Times,
    /// Clock time of the render alone.
    pub render_wall_s: f64,
    pub subschemes: Subschemes,
    pub nth: NthReport,
    pub p: f64,
    pub alpha: f64,
    pub scene_stats: SceneStats,
    pub machine_costs_ns: MachineCosts,
    pub shading_points: u64,
    pub shadow_decisions: u64,
    /// Present with --check.
    pub disagreements: Option<u64>,
    pub disagreeing_decisions: Option<u64>,
    pub shadow_rays: u64,
    pub shadow_polygon_tests: u64,
    /// Sum of N_s over the decisions that counted crossings (shadow polygons met in cells,
    /// with repeats; the `tests` are those the mailbox let through).
    pub shadow_polygon_entries: u64,
    /// HST's shadow rays taken because of the carried state where N_s was within N_th.
    pub forced_conventional: u64,
}

/// Builds what the scheme needs, predicts N_th and renders.
pub fn run(
    scene: Scene,
    opts: &RunOptions,
    on_tile: &(dyn Fn() + Sync),
) -> (Rgba8Image, RunReport) {
    let prepared = prepare(scene, opts.scheme);
    let costs = opts.costs.unwrap_or_else(cost::calibrate);
    render_prepared(&prepared, opts, &costs, on_tile)
}

/// The preprocessing step alone (grid, and shadow polygons or BVH when the scheme needs them).
pub fn prepare(scene: Scene, scheme: SchemeChoice) -> Prepared {
    let s = match scheme {
        SchemeChoice::Conventional => Scheme::Conventional,
        SchemeChoice::Volume => Scheme::Volume,
        SchemeChoice::Hst => Scheme::Hst { nth: 0.0 },
        SchemeChoice::Bvh => Scheme::Bvh,
        SchemeChoice::Embree => Scheme::Embree,
    };
    Prepared::new(scene, s)
}

/// Renders an already prepared scene.
pub fn render_prepared(
    prep: &Prepared,
    opts: &RunOptions,
    costs: &MachineCosts,
    on_tile: &(dyn Fn() + Sync),
) -> (Rgba8Image, RunReport) {
    let stats = *prep.stats();
    let equation_12 = cost::predicted_nth(costs, &stats);
    let (predicted, follow_up) = prep.predicted_nth(costs, opts.depth);
    let used = match opts.nth {
        Nth::Auto => predicted,
        Nth::Fixed(n) => n as f64,
    };
    let scheme = match opts.scheme {
        SchemeChoice::Conventional => Scheme::Conventional,
        SchemeChoice::Volume => Scheme::Volume,
        SchemeChoice::Hst => Scheme::Hst { nth: used as f32 },
        SchemeChoice::Bvh => Scheme::Bvh,
        SchemeChoice::Embree => Scheme::Embree,
    };
    let settings = Settings {
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        depth: opts.depth,
        scheme,
        check: opts.check,
        time_decisions: false,
    };
    let (image, r) = trace::render(prep, settings, on_tile);
    let nth = NthReport {
        predicted,
        equation_12,
        follow_up,
        used: match scheme {
            Scheme::Hst { nth } => Some(nth as f64),
            _ => None,
        },
    };
    (image, report(prep, &settings, &r, &stats, costs, nth))
}

fn report(
    prep: &Prepared,
    settings: &Settings,
    r: &RenderStats,
    stats: &SceneStats,
    costs: &MachineCosts,
    nth: NthReport,
) -> RunReport {
    let shadow = r.shadow_cpu_s();
    RunReport {
        scene: prep.scene.name.clone(),
        scheme: settings.scheme.name().into(),
        width: settings.width,
        height: settings.height,
        spp: settings.spp,
        depth: settings.depth,
        polygons: prep.polygons.len(),
        lights: prep.scene.lights.len(),
        shadow_polygons: prep.volumes.as_ref().map_or(0, |v| v.polygon_count()),
        grid: prep.grid.res,
        times_s: Times {
            preprocess: prep.preprocess_s,
            shadow,
            other: r.render_cpu_s - shadow,
            total: prep.preprocess_s + r.render_cpu_s,
        },
        render_wall_s: r.render_wall_s,
        subschemes: Subschemes {
            sustain: r.sustain,
            self_shadow: r.self_shadow,
            shadow_volume: r.shadow_volume,
            conventional: r.conventional,
        },
        nth,
        p: stats.p,
        alpha: stats.alpha,
        scene_stats: *stats,
        machine_costs_ns: *costs,
        shading_points: r.shading_points,
        shadow_decisions: r.shadow_decisions,
        disagreements: settings.check.then_some(r.disagreements),
        disagreeing_decisions: settings.check.then_some(r.disagreeing_decisions),
        shadow_rays: r.shadow_rays,
        shadow_polygon_tests: r.shadow_polygon_tests,
        shadow_polygon_entries: r.shadow_polygon_entries,
        forced_conventional: r.forced_conventional,
    }
}

/// A small deterministic generator (SplitMix64) for sampling and tests.
pub struct SplitMix(pub u64);

impl SplitMix {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A cheap monotonic tick counter for splitting a thread's time between parts of its work (the
/// shadow tests and the rest, per shading point): the time-stamp counter on x86-64 (a few ns per
/// read, against about 20 ns for a clock call, which would otherwise weigh on every scheme's shadow
/// time alike), nanoseconds of a monotonic clock elsewhere. Only ratios of ticks are used.
#[inline]
pub fn ticks() -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: RDTSC has no preconditions on x86-64.
        unsafe { std::arch::x86_64::_rdtsc() }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
        START
            .get_or_init(std::time::Instant::now)
            .elapsed()
            .as_nanos() as u64
    }
}

/// CPU time of this process, all threads, in seconds.
pub fn process_cpu_s() -> f64 {
    cpu_clock_s(CpuClock::Process)
}

/// CPU time of the calling thread, in seconds.
pub fn thread_cpu_s() -> f64 {
    cpu_clock_s(CpuClock::Thread)
}

enum CpuClock {
    Process,
    Thread,
}

#[cfg(unix)]
fn cpu_clock_s(which: CpuClock) -> f64 {
    let id = match which {
        CpuClock::Process => libc::CLOCK_PROCESS_CPUTIME_ID,
        CpuClock::Thread => libc::CLOCK_THREAD_CPUTIME_ID,
    };
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime only writes the timespec we pass.
    let ok = unsafe { libc::clock_gettime(id, &mut t) } == 0;
    if ok {
        t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
    } else {
        0.0
    }
}

/// Without CPU clocks, clock time since the first call.
#[cfg(not(unix))]
fn cpu_clock_s(_: CpuClock) -> f64 {
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_secs_f64()
}
