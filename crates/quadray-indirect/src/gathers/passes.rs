//! The paper's per-level passes ([`Method::QuadtreePasses`]): one pass per level of the light
//! quadtree, each pixel adding the level's nodes that the top-down cut rule takes.

use super::resources::Resources;
#[cfg(doc)]
use crate::Method;
use crate::contract::{LEVEL_SLICE, slices};
use crate::light::quadtree::LightQuadtree;
use crate::wgsl;

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 3] = [
    wgsl::CUT_RULE,
    wgsl::GATHER_LEVEL,
    include_str!("passes.wgsl"),
];

pub(crate) struct Passes {
    pipeline: wgpu::ComputePipeline,
}

impl Passes {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let [pipeline] = res.pipelines(device, "gather passes", &WGSL, ["indirect_level"], &[]);
        Self { pipeline }
    }

    /// Clears the indirect light the levels add to (before the pass).
    pub fn record_clear(&self, encoder: &mut wgpu::CommandEncoder, res: &Resources) {
        encoder.clear_buffer(&res.outputs.indirect, 0, None);
    }

    /// Records one pass per level, coarsest first, each in level slices.
    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources, quadtree: &LightQuadtree) {
        pass.set_pipeline(&self.pipeline);
        let levels = quadtree.levels();
        for level in (levels.limit..=levels.start).rev() {
            let nodes = u64::from(quadtree.rsm_size() >> level).pow(2);
            res.sliced(pass, level, slices(nodes, LEVEL_SLICE), res.size());
        }
    }
}
