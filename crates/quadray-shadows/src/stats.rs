//! Counts and times of one render, summed over its tiles.

use crate::cost::CostBins;
use serde::Serialize;

/// Counts and times of one render.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RenderStats {
    /// Points where rays hit a polygon and were shaded.
    pub shading_points: u64,
    /// Shading points times lights.
    pub shadow_decisions: u64,
    /// Shading points where some light's condition differs from the conventional test (--check).
    pub disagreements: u64,
    /// Decisions (point, light) that differ from the conventional test (--check).
    pub disagreeing_decisions: u64,
    /// Decisions that carried the condition on unchanged (HST; the other schemes count
    /// theirs as conventional or shadow volume).
    pub sustain: u64,
    /// Points facing away from the light.
    pub self_shadow: u64,
    /// Decisions by depth count.
    pub shadow_volume: u64,
    /// Decisions by shadow ray.
    pub conventional: u64,
    /// Ray / shadow-polygon crossing tests.
    pub shadow_polygon_tests: u64,
    /// Sum of N_s over the decisions that counted crossings.
    pub shadow_polygon_entries: u64,
    /// HST's conventional decisions made because of the carried state (the count invalid and the
    /// condition shadowed or unknown) where N_s alone would have chosen the shadow volume, and
    /// their N_s summed.
    pub forced_conventional: u64,
    /// (See `forced_conventional`.)
    pub forced_ns: u64,
    /// Shadow rays cast.
    pub shadow_rays: u64,
    /// Ticks ([`crate::ticks`]) the tiles' threads spent deciding shadows, and in the tiles.
    pub shadow_ticks: u64,
    /// (See `shadow_ticks`.)
    pub tile_ticks: u64,
    /// With [`crate::trace::Job::time_decisions`]: HST's shadow-volume decisions (the
    /// crossing tests) and its shadow rays, timed and binned by N_s.
    pub shadow_volume_costs: CostBins,
    /// (See `shadow_volume_costs`.)
    pub shadow_ray_costs: CostBins,
    /// Clock time of the render.
    pub render_wall_s: f64,
    /// CPU time of the render, all threads (what the paper's CPU minutes measure; unlike clock
    /// time it is not inflated by other processes on a shared machine).
    pub render_cpu_s: f64,
}

impl RenderStats {
    pub(crate) fn add(&mut self, o: &RenderStats) {
        self.shading_points += o.shading_points;
        self.shadow_decisions += o.shadow_decisions;
        self.disagreements += o.disagreements;
        self.disagreeing_decisions += o.disagreeing_decisions;
        self.sustain += o.sustain;
        self.self_shadow += o.self_shadow;
        self.shadow_volume += o.shadow_volume;
        self.conventional += o.conventional;
        self.shadow_polygon_tests += o.shadow_polygon_tests;
        self.shadow_polygon_entries += o.shadow_polygon_entries;
        self.forced_conventional += o.forced_conventional;
        self.forced_ns += o.forced_ns;
        self.shadow_rays += o.shadow_rays;
        self.shadow_ticks += o.shadow_ticks;
        self.tile_ticks += o.tile_ticks;
        self.shadow_volume_costs.merge(&o.shadow_volume_costs);
        self.shadow_ray_costs.merge(&o.shadow_ray_costs);
    }

    /// CPU time of shadow testing: the render's CPU time split in the threads' proportion.
    pub fn shadow_cpu_s(&self) -> f64 {
        if self.tile_ticks > 0 {
            self.render_cpu_s * self.shadow_ticks as f64 / self.tile_ticks as f64
        } else {
            0.0
        }
    }
}
