//! The brute force over every VPL of the RSM ([`Method::Reference`], the GPU reference).

use super::resources::Resources;
#[cfg(doc)]
use crate::Method;
use crate::contract::{SLICE, slices};
use crate::wgsl;

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 2] = [wgsl::GATHER_VPLS, include_str!("brute_force.wgsl")];

pub(crate) struct BruteForce {
    pipeline: wgpu::ComputePipeline,
}

impl BruteForce {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let [pipeline] = res.pipelines(device, "gather brute force", &WGSL, ["brute_force"], &[]);
        Self { pipeline }
    }

    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        pass.set_pipeline(&self.pipeline);
        let texels = u64::from(res.settings().rsm_size).pow(2);
        res.sliced(pass, 0, slices(texels, SLICE), res.size());
    }
}
