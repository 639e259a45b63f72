//! The compacted cut ([`Method::Quadtree`]): every pixel sums the light quadtree's cut, at full
//! resolution or sub-sampled.

use super::resources::Resources;
#[cfg(doc)]
use crate::Method;
use crate::contract::{SLICE, slices};
use crate::light::quadtree::LightQuadtree;
use crate::output::upsample::{self, Upsampled};
use crate::wgsl;

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 3] = [wgsl::GATHER_CUT, include_str!("cut.wgsl"), upsample::WGSL];

pub(crate) struct Cut {
    full: wgpu::ComputePipeline,
    pub upsampled: Upsampled,
}

impl Cut {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let [low, reconstruct] = upsample::entries(res.settings());
        let [full, low, reconstruct] = res.pipelines(
            device,
            "gather cut",
            &WGSL,
            ["indirect_cut", low, reconstruct],
            &[],
        );
        Self {
            full,
            upsampled: Upsampled { low, reconstruct },
        }
    }

    /// Dispatches the sum over `quadtree`'s cut takes: a cut partitions the RSM into nodes no
    /// finer than the limit level.
    pub fn slices(quadtree: &LightQuadtree) -> u32 {
        let finest = quadtree.rsm_size() >> quadtree.levels().limit;
        slices(u64::from(finest).pow(2), SLICE)
    }

    /// Records the full-resolution sum.
    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources, quadtree: &LightQuadtree) {
        pass.set_pipeline(&self.full);
        res.sliced(pass, 0, Self::slices(quadtree), res.size());
    }
}
