//! The shadow tests the tracer is generic over: at a shading point, is a light hidden? Shadow
//! rays through any [`Occluder`] (grid, BVH, Embree), depth counts carried along every segment
//! (shadow volumes), or the hybrid switch between them (HST). The tracer is compiled once per
//! test, so choosing one costs nothing per ray.

use crate::cost::CostBins;
use crate::grid::{CellRecord, Mailbox};
use crate::occlusion::Occluder;
use crate::shadow::{LightState, ShadowVolumes, Subscheme};
use crate::stats::RenderStats;
use glam::Vec3;
use quadray_core::geom::Ray;

/// One tile's working memory: mailboxes, the cells of the current ray segment and the counts.
pub struct Scratch<R> {
    /// The mailbox of the tracer's closest-hit walks.
    pub(crate) objects: Mailbox,
    /// The working memory of the test's shadow rays.
    pub(crate) rays: R,
    /// The mailbox of shadow-polygon crossing tests.
    pub(crate) shadows: Mailbox,
    /// The ground-truth shadow rays of --check, kept apart so they do not disturb the scheme.
    pub(crate) check: Mailbox,
    /// The cells of the current ray segment that hold shadow polygons.
    pub(crate) occupied: CellRecord,
    /// The tile's counts so far.
    pub(crate) stats: RenderStats,
}

/// A shading point and the ray segment that reached it.
#[derive(Clone, Copy)]
pub struct Arrival {
    /// The segment from the ray's start (`t_min` 0: depth counts take every crossing after it)
    /// to the point (`t_max`).
    pub(crate) segment: Ray,
    /// The point.
    pub(crate) p: Vec3,
    /// The normal on the side the ray arrived from.
    pub(crate) n: Vec3,
    /// The polygon hit.
    pub(crate) polygon: u32,
}

/// What a light's shadow test at a shading point knows: the light, its N_s on the incoming
/// segment, and whether the point faces away from it.
#[derive(Clone, Copy)]
pub struct Decision {
    /// The light's index.
    pub(crate) light: usize,
    /// The shadow polygons of the light registered in the segment's cells (with repeats).
    pub(crate) ns: u32,
    /// From the point to the light.
    pub(crate) to_light: Vec3,
    /// The point faces away from the light.
    pub(crate) self_shadow: bool,
    /// A reflected or refracted ray leaves the point and carries the state on.
    pub(crate) continues: bool,
}

/// A way to decide a light's shadow condition at the tracer's shading points.
pub trait ShadowTest: Sync {
    /// The working memory of the test's shadow rays.
    type Rays: Send;

    /// Fresh working memory for one tile's shadow rays.
    fn rays(&self) -> Self::Rays;

    /// Whether the light of `decision` is hidden at `at`; `state` is what the ray carries for
    /// that light (shadow volumes read and update it).
    fn shadowed(
        &self,
        sc: &mut Scratch<Self::Rays>,
        decision: Decision,
        state: &mut LightState,
        at: &Arrival,
        shadow_eps: f32,
    ) -> bool;
}

/// The conventional test: a shadow ray per light through `O`.
pub struct ShadowRays<O>(pub O);

impl<O: Occluder> ShadowTest for ShadowRays<O> {
    type Rays = O::Scratch;

    fn rays(&self) -> O::Scratch {
        self.0.scratch()
    }

    #[inline]
    fn shadowed(
        &self,
        sc: &mut Scratch<O::Scratch>,
        decision: Decision,
        _: &mut LightState,
        at: &Arrival,
        shadow_eps: f32,
    ) -> bool {
        sc.stats.conventional += 1;
        if decision.self_shadow {
            return true;
        }
        sc.stats.shadow_rays += 1;
        let ray = Ray::segment(at.p, decision.to_light, shadow_eps);
        self.0.occluded(&ray, Some(at.polygon), &mut sc.rays)
    }
}

/// Shadow volumes: the depth count carried along every segment.
pub struct Volumes<'a>(pub &'a ShadowVolumes);

impl ShadowTest for Volumes<'_> {
    type Rays = ();

    fn rays(&self) {}

    #[inline]
    fn shadowed(
        &self,
        sc: &mut Scratch<()>,
        decision: Decision,
        state: &mut LightState,
        at: &Arrival,
        _: f32,
    ) -> bool {
        sc.stats.shadow_volume += 1;
        sc.stats.shadow_polygon_entries += decision.ns as u64;
        let change = self.0.crossings(
            decision.light,
            sc.occupied.cells(),
            &at.segment,
            &mut sc.shadows,
            &mut sc.stats.shadow_polygon_tests,
        );
        state.volume_step(change, decision.self_shadow)
    }
}

/// HST: the depth count where the segment crossed at most `nth` shadow polygons and the count is
/// known, a shadow ray through `O` otherwise (the paper's: the grid).
pub struct Hybrid<'a, O> {
    /// The shadow polygons.
    pub volumes: &'a ShadowVolumes,
    /// The shadow rays.
    pub rays: O,
    /// N_th.
    pub nth: f32,
    /// Time every shadow-volume decision and shadow ray into the render's cost bins.
    pub time_decisions: bool,
}

impl<O: Occluder> ShadowTest for Hybrid<'_, O> {
    type Rays = O::Scratch;

    fn rays(&self) -> O::Scratch {
        self.rays.scratch()
    }

    #[inline]
    fn shadowed(
        &self,
        sc: &mut Scratch<O::Scratch>,
        decision: Decision,
        state: &mut LightState,
        at: &Arrival,
        shadow_eps: f32,
    ) -> bool {
        let Scratch {
            rays,
            shadows,
            occupied,
            stats,
            ..
        } = sc;
        let Decision { light, ns, .. } = decision;
        let nth = self.nth;
        let time = self.time_decisions;
        let mut ray_count = 0;
        let (shadowed, sub) = state.hst_step(
            ns,
            nth,
            decision.self_shadow,
            decision.continues,
            || {
                stats.shadow_polygon_entries += ns as u64;
                timed(time, ns, &mut stats.shadow_volume_costs, || {
                    self.volumes.crossings(
                        light,
                        occupied.cells(),
                        &at.segment,
                        shadows,
                        &mut stats.shadow_polygon_tests,
                    )
                })
            },
            || {
                ray_count += 1;
                timed(time, ns, &mut stats.shadow_ray_costs, || {
                    let ray = Ray::segment(at.p, decision.to_light, shadow_eps);
                    self.rays.occluded(&ray, Some(at.polygon), rays)
                })
            },
        );
        stats.shadow_rays += ray_count;
        // Tallied without branching on the sub-scheme: it changes from one decision to the
        // next, and a jump on it was mispredicted more often than not.
        stats.sustain += (sub == Subscheme::Sustain) as u64;
        stats.self_shadow += (sub == Subscheme::SelfShadow) as u64;
        stats.shadow_volume += (sub == Subscheme::ShadowVolume) as u64;
        let conventional = (sub == Subscheme::Conventional) as u64;
        stats.conventional += conventional;
        let forced = conventional * (ns > 0 && (ns as f32) <= nth) as u64;
        stats.forced_conventional += forced;
        stats.forced_ns += forced * ns as u64;
        shadowed
    }
}

/// `f()`, timed into `bins` as a decision of N_s `ns` when `on`.
#[inline(always)]
fn timed<R>(on: bool, ns: u32, bins: &mut CostBins, f: impl FnOnce() -> R) -> R {
    if !on {
        return f();
    }
    let start = crate::ticks();
    let r = f();
    bins.add(ns, crate::ticks().wrapping_sub(start));
    r
}
