//! The one cut's indirect shadows from corner receivers ([`crate::Settings::shadow_corners`]):
//! a pass walks from the receiver at every K-th pixel across and down to each cluster of the cut
//! and keeps a bit a cluster (`corners.wgsl`); the cut's gather weighs each cluster by the bits
//! of the corners around a pixel on its surface. The corners' receivers and bits are the cut's
//! group 3.

use crate::contract::{bind_group, layout, storage_buffer, storage_entry, whole};
use crate::gathers::resources::Resources;
use std::sync::OnceLock;

/// The threads of the corners' workgroup (`CORNER_GROUP` in `corners.wgsl`).
const CORNER_GROUP: u32 = 64;

/// The corners' pass and shader part: appended to the cut's shader.
pub(crate) const WGSL: &str = include_str!("corners.wgsl");

/// The corners' receivers and visibility bits, and their bind group.
struct CornerBuffers {
    /// Only the shaders read them.
    _receivers: wgpu::Buffer,
    _bits: wgpu::Buffer,
    group: wgpu::BindGroup,
}

pub(crate) struct ShadowCorners {
    layout: wgpu::BindGroupLayout,
    /// The pass, where the settings test indirect shadows from corners.
    pipeline: Option<wgpu::ComputePipeline>,
    /// Allocated by the first frame that binds them, so that the other methods pay nothing.
    buffers: OnceLock<CornerBuffers>,
    device: wgpu::Device,
}

impl ShadowCorners {
    /// The group's layout, for the cut's pipelines.
    pub fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        layout(
            device,
            "shadow corners",
            &[
                storage_entry::<[f32; 4]>(0, false),
                storage_entry::<u32>(1, false),
            ],
        )
    }

    /// The corners of `res`'s settings over the cut's `layout`, the pass's pipeline from the
    /// cut's shader `own`.
    pub fn new(
        device: &wgpu::Device,
        res: &Resources,
        layout: wgpu::BindGroupLayout,
        own: &[&'static str],
    ) -> Self {
        let pipeline = (res.settings().shadow_corners_or_off() > 0).then(|| {
            let [pipeline] = res.pipelines(
                device,
                "shadow corners",
                own,
                ["shadow_corners"],
                &[&layout],
            );
            pipeline
        });
        Self {
            layout,
            pipeline,
            buffers: OnceLock::new(),
            device: device.clone(),
        }
    }

    /// Binds the group (the cut's pipelines have it in their layout, with corners or without).
    pub fn bind(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        let buffers = self.buffers.get_or_init(|| {
            let s = res.settings();
            let (x, y) = s.shadow_corner_grid();
            let corners = u64::from(x) * u64::from(y);
            let receivers = storage_buffer(&self.device, "shadow corner receivers", corners * 32);
            let words = corners * u64::from(s.shadow_corner_words());
            let bits = storage_buffer(&self.device, "shadow corner bits", words * 4);
            let group = bind_group(
                &self.device,
                "shadow corners",
                &self.layout,
                vec![whole(&receivers), whole(&bits)],
            );
            CornerBuffers {
                _receivers: receivers,
                _bits: bits,
                group,
            }
        });
        pass.set_bind_group(3, &buffers.group, &[]);
    }

    /// Records the corners' walks to the cut's clusters (nothing without corners), the group
    /// bound first.
    pub fn record(&self, pass: &mut wgpu::ComputePass, res: &Resources) {
        self.bind(pass, res);
        if let Some(pipeline) = &self.pipeline {
            let s = res.settings();
            let (x, y) = s.shadow_corner_grid();
            let corners_a_group = CORNER_GROUP / s.shadow_corner_lanes;
            pass.set_pipeline(pipeline);
            res.bind_dispatch(pass, 0, 0);
            pass.dispatch_workgroups(x.div_ceil(corners_a_group), y, 1);
        }
    }
}
