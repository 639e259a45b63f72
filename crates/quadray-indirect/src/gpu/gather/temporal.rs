//! The temporal filter: a running average of the indirect light over frames of one method
//! ([`crate::Settings::temporal_weight`]), not reprojected.

use super::resources::Resources;
use crate::gpu::contract::dispatch_2d;
use crate::settings::Method;
use std::sync::{Mutex, PoisonError};

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 1] = [include_str!("temporal.wgsl")];

pub(crate) struct Temporal {
    blend: wgpu::ComputePipeline,
    /// The method whose frames the history averages; `None` when it holds nothing to continue
    /// from.
    history_of: Mutex<Option<Method>>,
}

impl Temporal {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let [blend] = res.pipelines(device, "gather temporal", &WGSL, ["temporal_blend"], &[]);
        Self {
            blend,
            history_of: Mutex::new(None),
        }
    }

    /// Forgets the average: the next frame starts it anew.
    pub fn reset(&self) {
        *self
            .history_of
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = None;
    }

    /// Whether the history holds an average of `method`'s frames to blend this frame into.
    pub fn continues(&self, method: Method) -> bool {
        *self
            .history_of
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            == Some(method)
    }

    /// Records the blend of this frame into the average, in a pass that has the groups bound.
    pub fn record_blend(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        pass.set_pipeline(&self.blend);
        let (width, height) = res.size();
        dispatch_2d(pass, width, height);
    }

    /// Records the start of an average of `method`'s frames from this frame.
    pub fn record_start(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        res: &Resources,
        method: Method,
    ) {
        let o = &res.outputs;
        encoder.copy_buffer_to_buffer(&o.indirect, 0, &o.history, 0, o.indirect.size());
        *self
            .history_of
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = Some(method);
    }
}
