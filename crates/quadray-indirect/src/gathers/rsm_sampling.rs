//! RSM sampling ([`Method::Rsm`], the baseline of Dachsbacher & Stamminger 2005): every pixel
//! sums Poisson-disk samples around its projection into the RSM, at full resolution or
//! sub-sampled. The pattern is made in [`crate::gathers::samples`].

use super::resources::Resources;
#[cfg(doc)]
use crate::Method;
use crate::contract::{SLICE, slices};
use crate::output::upsample::{self, Upsampled};
use crate::wgsl;

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 3] = [
    wgsl::GATHER_VPLS,
    include_str!("rsm_sampling.wgsl"),
    upsample::WGSL,
];

pub(crate) struct RsmSampling {
    full: wgpu::ComputePipeline,
    pub upsampled: Upsampled,
}

impl RsmSampling {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let (full, upsampled) = upsample::pipelines(
            device,
            res,
            "gather rsm sampling",
            &WGSL,
            "rsm_sampling",
            &[],
        );
        Self { full, upsampled }
    }

    /// Dispatches the sum over the samples takes.
    pub fn slices(res: &Resources) -> u32 {
        slices(u64::from(res.settings().samples), SLICE)
    }

    /// Records the full-resolution sum.
    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        pass.set_pipeline(&self.full);
        res.sliced(pass, 0, Self::slices(res), res.size());
    }
}
