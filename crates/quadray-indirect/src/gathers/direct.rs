//! The spot's direct light on the G-buffer, shadowed by the RSM depth as a shadow map.

use super::resources::Resources;
use crate::contract::dispatch_2d;

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 1] = [include_str!("direct.wgsl")];

pub(crate) struct Direct {
    pipeline: wgpu::ComputePipeline,
}

impl Direct {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let [pipeline] = res.pipelines(device, "gather direct", &WGSL, ["direct_light"], &[]);
        Self { pipeline }
    }

    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        res.bind_dispatch(pass, 0, 0);
        pass.set_pipeline(&self.pipeline);
        let (width, height) = res.size();
        dispatch_2d(pass, width, height);
    }
}
