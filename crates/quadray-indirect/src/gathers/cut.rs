//! The compacted cut ([`Method::Quadtree`]): every pixel sums the light quadtree's cut, at full
//! resolution or sub-sampled, with indirect shadows from the pixel or from corner receivers
//! ([`ShadowCorners`]).

use super::resources::Resources;
#[cfg(doc)]
use crate::Method;
use crate::contract::{SLICE, slices};
use crate::light::quadtree::LightQuadtree;
use crate::output::upsample::{self, Upsampled};
use crate::shadows::corners::{self, ShadowCorners};
use crate::wgsl;

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 4] = [
    wgsl::GATHER_CUT,
    include_str!("cut.wgsl"),
    upsample::WGSL,
    corners::WGSL,
];

pub(crate) struct Cut {
    full: wgpu::ComputePipeline,
    pub upsampled: Upsampled,
    /// Group 3 of every pipeline here.
    pub corners: ShadowCorners,
}

impl Cut {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let corners_layout = ShadowCorners::layout(device);
        let (full, upsampled) = upsample::pipelines(
            device,
            res,
            "gather cut",
            &WGSL,
            "indirect_cut",
            &[&corners_layout],
        );
        Self {
            full,
            upsampled,
            corners: ShadowCorners::new(device, res, corners_layout, &WGSL),
        }
    }

    /// Dispatches the sum over `quadtree`'s cut takes: a cut partitions the RSM into nodes no
    /// finer than the limit level.
    pub fn slices(quadtree: &LightQuadtree) -> u32 {
        let finest = quadtree.rsm_size() >> quadtree.levels().limit;
        slices(u64::from(finest).pow(2), SLICE)
    }

    /// Records the corners' walks, then the sum: at full resolution, or where the settings
    /// reconstruct the picture its low-resolution samples.
    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources, quadtree: &LightQuadtree) {
        self.corners.record(pass, res);
        if res.settings().reconstructs(crate::Method::Quadtree) {
            self.upsampled.record_low(pass, res, Self::slices(quadtree));
        } else {
            pass.set_pipeline(&self.full);
            res.sliced(pass, 0, Self::slices(quadtree), res.size());
        }
    }
}
