//! Whitted ray tracing on a uniform grid with hybrid shadow testing (Eo & Kyung, 1989): the
//! conventional shadow ray, shadow volumes with depth counts carried along every ray segment, the
//! hybrid switch between them with its cost model, and a SAH BVH (and, with the `embree` feature,
//! Intel Embree) as today's baselines.
//!
//! Rooms, from the bottom up: [`settings`] (what a user configures: the one [`Settings`] type
//! that `quadray raytrace`'s flags are), [`scene`] (a scene built in code with [`Scene::new`] and
//! its `add_` methods, procedural look-alikes of the paper's scenes, TOML scene files), [`clip`]
//! (polygon clipping), [`grid`] (SEADS, 3DDDA, mailboxes), [`occlusion`] (the [`Occluder`]
//! interface of shadow rays: the grid, the BVH, `embree`), [`shadow`] (shadow polygons and HST's
//! state machine), [`mod@prepare`] (what a scheme builds before rendering),
//! [`decide`] (the shadow tests the tracer is generic over: shadow rays through any occluder,
//! shadow volumes, HST), [`trace`] (the renderer), [`cost`] (equations 1-12 and the
//! micro-benchmarks; it renders nothing) and [`pilot`] (the pilot renders that calibrate it).
//! Rays, convex polygons and the SAH BVH are [`quadray_core::geom`]'s, shared with the indirect
//! crate's ground truth.
//!
//! A scene built in code and rendered with HST (the whole program is
//! `examples/hst_scene.rs`):
//!
//! ```
//! # use glam::Vec3;
//! # use quadray_shadows::{Camera, Light, Material, Nth, Scene, SchemeChoice, Settings, Size};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! # let (position, target) = (Vec3::new(0.0, 2.0, 4.0), Vec3::ZERO);
//! # let positions = [[-2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 2.0], [2.0, 0.0, -2.0]].map(Vec3::from_array);
//! # let triangle_indices = [0, 1, 2, 0, 2, 3];
//! let mut scene = Scene::new("mine", Camera { position, target, up: Vec3::Y, fov_y_deg: 45.0 });
//! let grey = scene.add_material(Material::matte(Vec3::splat(0.7)));
//! scene.add_light(Light::white(Vec3::new(2.0, 4.0, 2.5), 0.6));
//! scene.add_mesh(&positions, &triangle_indices, grey)?;
//! let settings = Settings { scheme: SchemeChoice::Hst, nth: Nth::Auto, size: Size::new(320, 240),
//!                           ..Settings::DEFAULT };
//! let (image, report) = quadray_shadows::run(scene, &settings, &|| {})?;
//! # assert_eq!((image.width, report.polygons), (320, 2));
//! # Ok(())
//! # }
//! ```
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

#![warn(missing_docs)]

pub mod clip;
pub mod cost;
pub mod decide;
#[cfg(feature = "embree")]
pub mod embree;
pub mod grid;
pub mod occlusion;
pub mod pilot;
pub mod prepare;
pub mod scene;
pub mod settings;
pub mod shadow;
pub mod stats;
pub mod trace;

#[cfg(test)]
mod tests;

use cost::{MachineCosts, SceneStats};
pub use occlusion::Occluder;
pub use prepare::{Prepared, Scheme};
use quadray_core::image_out::Rgba8Image;
pub use quadray_core::settings::Size;
pub use scene::{BuildError, Camera, Light, Material, Scene};
use serde::Serialize;
pub use settings::{Nth, SchemeChoice, Settings};
use stats::RenderStats;
use trace::Job;
pub use trace::{Radiance, Region};

/// CPU seconds (all threads), as the paper's table 4 reports CPU minutes.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Times {
    /// Building the grid and the shadow polygons or BVH.
    pub preprocess: f64,
    /// The part of `preprocess` spent finding and registering the shadow polygons (volume and
    /// HST; 0 for the other schemes).
    pub shadow_volumes: f64,
    /// Deciding shadows at the shading points.
    pub shadow: f64,
    /// Everything else of the render (eye and secondary rays, shading).
    pub other: f64,
    /// Preprocessing and render.
    pub total: f64,
}

#[derive(Clone, Copy, Debug, Serialize)]
/// HST's decisions by sub-scheme (the paper's table 3); the other schemes count theirs as one.
pub struct Subschemes {
    /// The condition carried on unchanged (no shadow polygons on the segment).
    pub sustain: u64,
    /// The point faces away from the light.
    pub self_shadow: u64,
    /// Decided by the depth count.
    pub shadow_volume: u64,
    /// Decided by a shadow ray.
    pub conventional: u64,
}

#[derive(Clone, Copy, Debug, Serialize)]
/// The N_th of a render: predicted, as the paper writes it, and used.
pub struct NthReport {
    /// What the settings asked for ([`Settings::nth`]).
    pub asked: Nth,
    /// What `--nth auto` uses: equation 12 with the pilot's corrections ([`cost::FollowUp`]).
    pub predicted: f64,
    /// Equation 12 as the paper writes it.
    pub equation_12: f64,
    /// The pilot measurements behind `predicted`.
    pub follow_up: cost::FollowUp,
    /// None when the scheme has no threshold.
    pub used: Option<f64>,
}

/// The stats JSON of `quadray raytrace --stats`.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// The scene's name.
    pub scene: String,
    /// What was rendered: the settings' own fields (scheme, width, height, spp, depth, check;
    /// the N_th asked for is `nth.asked`).
    #[serde(flatten)]
    pub settings: Settings,
    /// Polygons of the scene.
    pub polygons: usize,
    /// Point lights.
    pub lights: usize,
    /// Shadow polygons of all lights (volume and HST).
    pub shadow_polygons: usize,
    /// The grid's resolution.
    pub grid: [u32; 3],
    /// CPU seconds by part.
    pub times_s: Times,
    /// Clock time of the render alone.
    pub render_wall_s: f64,
    /// Decisions by sub-scheme.
    pub subschemes: Subschemes,
    /// N_th predicted and used.
    pub nth: NthReport,
    /// The cost model's p ([`SceneStats::p`]).
    pub p: f64,
    /// The cost model's alpha ([`SceneStats::alpha`]).
    pub alpha: f64,
    /// All of the cost model's scene statistics.
    pub scene_stats: SceneStats,
    /// The machine constants used.
    pub machine_costs_ns: MachineCosts,
    /// Points where rays hit a polygon and were shaded.
    pub shading_points: u64,
    /// Shading points times lights.
    pub shadow_decisions: u64,
    /// Present with --check.
    pub disagreements: Option<u64>,
    /// Decisions (point, light) that differ from the conventional test; present with --check.
    pub disagreeing_decisions: Option<u64>,
    /// Shadow rays cast.
    pub shadow_rays: u64,
    /// Ray / shadow-polygon crossing tests.
    pub shadow_polygon_tests: u64,
    /// Sum of N_s over the decisions that counted crossings (shadow polygons met in cells,
    /// with repeats; the `tests` are those the mailbox let through).
    pub shadow_polygon_entries: u64,
    /// HST's shadow rays taken because of the carried state where N_s was within N_th.
    pub forced_conventional: u64,
}

/// Checks the scene, builds what the scheme needs, measures the machine constants
/// ([`cost::calibrate`]), predicts N_th and renders. `on_tile` is called after each finished
/// block of 16x16 pixels: a progress bar's hook, not a setting (it changes nothing rendered).
pub fn run(
    scene: Scene,
    settings: &Settings,
    on_tile: &(dyn Fn() + Sync),
) -> Result<(Rgba8Image, RunReport), BuildError> {
    let prepared = prepare(scene, settings.scheme)?;
    Ok(render_prepared(
        &prepared,
        settings,
        &cost::calibrate(),
        on_tile,
    ))
}

/// The shadow test `choice` names, HST with threshold `nth`.
fn scheme(choice: SchemeChoice, nth: f32) -> Scheme {
    match choice {
        SchemeChoice::Conventional => Scheme::Conventional,
        SchemeChoice::Volume => Scheme::Volume,
        SchemeChoice::Hst => Scheme::Hst { nth },
        SchemeChoice::Bvh => Scheme::Bvh,
        SchemeChoice::Embree => Scheme::Embree,
    }
}

/// The preprocessing step alone (grid, and shadow polygons or BVH when the scheme needs them),
/// after checking the scene ([`Scene::validate`]).
pub fn prepare(scene: Scene, choice: SchemeChoice) -> Result<Prepared, BuildError> {
    scene.validate()?;
    Ok(Prepared::new(scene, scheme(choice, 0.0)))
}

/// Renders an already prepared scene with the machine constants `costs` (measured once by
/// [`cost::calibrate`] and shared by a series of renders).
pub fn render_prepared(
    prep: &Prepared,
    settings: &Settings,
    costs: &MachineCosts,
    on_tile: &(dyn Fn() + Sync),
) -> (Rgba8Image, RunReport) {
    let full = Region::full(settings.size.width, settings.size.height);
    let (radiance, report) = render_prepared_region(prep, settings, costs, full, on_tile);
    (radiance.to_rgba8(1.0), report)
}

/// [`render_prepared`] of one rectangle of the image, as radiance ([`trace::render_region`]):
/// the report's counts and times are the region's.
pub fn render_prepared_region(
    prep: &Prepared,
    settings: &Settings,
    costs: &MachineCosts,
    region: Region,
    on_tile: &(dyn Fn() + Sync),
) -> (Radiance, RunReport) {
    let stats = *prep.stats();
    let equation_12 = cost::predicted_nth(costs, &stats);
    let (predicted, follow_up) = prep.predicted_nth(costs, settings.depth);
    let used = match settings.nth {
        Nth::Auto => predicted,
        Nth::Fixed(n) => n as f64,
    };
    let job = Job {
        settings: *settings,
        scheme: scheme(settings.scheme, used as f32),
        time_decisions: false,
    };
    let (image, r) = trace::render_region(prep, job, region, on_tile);
    let nth = NthReport {
        asked: settings.nth,
        predicted,
        equation_12,
        follow_up,
        used: match job.scheme {
            Scheme::Hst { nth } => Some(nth as f64),
            _ => None,
        },
    };
    (image, report(prep, settings, &r, &stats, costs, nth))
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
        settings: *settings,
        polygons: prep.polygons.len(),
        lights: prep.scene.lights.len(),
        shadow_polygons: prep.volumes.as_ref().map_or(0, |v| v.polygon_count()),
        grid: prep.grid.res,
        times_s: Times {
            preprocess: prep.preprocess_s,
            shadow_volumes: prep.shadow_volumes_s,
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

/// CPU time of this process, all threads, in seconds (0 where the clock cannot be read).
pub fn process_cpu_s() -> f64 {
    cpu_time::ProcessTime::try_now().map_or(0.0, |t| t.as_duration().as_secs_f64())
}

/// CPU time of the calling thread, in seconds (0 where the clock cannot be read).
pub fn thread_cpu_s() -> f64 {
    cpu_time::ThreadTime::try_now().map_or(0.0, |t| t.as_duration().as_secs_f64())
}
