//! The temporal filter ([`crate::Settings::temporal_weight`]): a running average of the indirect
//! light over frames of one method, reprojected through the camera's motion with the G-buffer's
//! positions and normals, points the last frame did not see starting anew. Its group 3: the
//! average as the last filtered frame left it, that frame's view and normals, and this frame's
//! normals.

use crate::contract::{bind_group, dispatch_2d, layout, storage_buffer, storage_entry, whole};
use crate::gathers::resources::Resources;
use crate::method::Method;
use std::sync::{Mutex, PoisonError};

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 1] = [include_str!("temporal.wgsl")];

/// Bytes of a world -> clip matrix, the camera uniform's first field.
const VIEW_PROJ_BYTES: u64 = 64;

pub(crate) struct Temporal {
    blend: wgpu::ComputePipeline,
    /// The average as the last filtered frame left it, read while this frame's is written.
    previous: wgpu::Buffer,
    /// That frame's world -> clip, copied on the GPU from the camera uniform after its blend.
    previous_view_proj: wgpu::Buffer,
    /// Group `k` reads the last frame's normals from normal buffer `k` and writes this frame's
    /// into the other: the two take turns, no copy.
    groups: [wgpu::BindGroup; 2],
    /// What the history holds.
    state: Mutex<History>,
}

#[derive(Clone, Copy)]
struct History {
    /// The method whose frames it averages; `None` when it holds nothing to continue from.
    of: Option<Method>,
    /// The group the next blend binds (the one reading the normals the last blend wrote).
    group: usize,
}

impl Temporal {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let own = layout(
            device,
            "gather temporal",
            &[
                storage_entry::<[f32; 4]>(0, true),
                storage_entry::<[[f32; 4]; 4]>(1, true),
                storage_entry::<[f32; 4]>(2, true),
                storage_entry::<[f32; 4]>(3, false),
            ],
        );
        let [blend] = res.pipelines(
            device,
            "gather temporal",
            &WGSL,
            ["temporal_blend"],
            &[&own],
        );
        let bytes = res.outputs.history.size();
        let previous = storage_buffer(device, "indirect history, last frame", bytes);
        let previous_view_proj = storage_buffer(device, "view of the history", VIEW_PROJ_BYTES);
        let normals = [0, 1].map(|_| storage_buffer(device, "normals of the history", bytes));
        let groups = [0, 1].map(|k| {
            bind_group(
                device,
                "gather temporal",
                &own,
                vec![
                    whole(&previous),
                    whole(&previous_view_proj),
                    whole(&normals[k]),
                    whole(&normals[1 - k]),
                ],
            )
        });
        Self {
            blend,
            previous,
            previous_view_proj,
            groups,
            state: Mutex::new(History { of: None, group: 0 }),
        }
    }

    /// Forgets the average: the next frame starts it anew.
    pub fn reset(&self) {
        self.state().of = None;
    }

    fn state(&self) -> std::sync::MutexGuard<'_, History> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Records, before the pass that blends, the average this frame reads: the last one when
    /// it holds `method`'s frames, else none (every pixel starts anew).
    pub fn record_prepare(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        res: &Resources,
        method: Method,
    ) {
        let history = &res.outputs.history;
        // (the average is copied: it is bound in the frame's group, which every pass shares)
        if self.state().of == Some(method) {
            encoder.copy_buffer_to_buffer(history, 0, &self.previous, 0, history.size());
        } else {
            encoder.clear_buffer(&self.previous, 0, None);
        }
    }

    /// Records the blend of this frame into the average, in a pass that has the groups bound.
    pub fn record_blend(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        pass.set_bind_group(3, &self.groups[self.state().group], &[]);
        pass.set_pipeline(&self.blend);
        let (width, height) = res.size();
        dispatch_2d(pass, width, height);
    }

    /// Records, after the blend, that the average now holds `method`'s frames up to this one,
    /// seen through this frame's camera.
    pub fn record_finish(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        res: &Resources,
        method: Method,
    ) {
        let camera = res.camera();
        encoder.copy_buffer_to_buffer(camera, 0, &self.previous_view_proj, 0, VIEW_PROJ_BYTES);
        let mut state = self.state();
        state.of = Some(method);
        // the next blend reads the normals this one wrote
        state.group = 1 - state.group;
    }
}
