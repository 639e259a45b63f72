//! The G-buffer and a light view's RSM as the gather reads them (in either layout), read back
//! for the CPU reference: one pass that writes out what `receiver` and the RSM's reads return.

use super::resources::Resources;
use crate::contract::{
    bind_group, compute_pass, dispatch_2d, layout, storage_buffer, storage_entry, whole,
};
use quadray_gpu::{Gpu, GpuError};

/// The pass's own shader parts, after the shared ones.
pub(crate) const WGSL: [&str; 1] = [include_str!("decode.wgsl")];

/// Three vec4 a pixel or texel, as `decode.wgsl` writes them.
pub(crate) type Decoded = Vec<[[f32; 4]; 3]>;

pub(crate) struct Decode {
    gbuffer: wgpu::ComputePipeline,
    rsm: wgpu::ComputePipeline,
    group_layout: wgpu::BindGroupLayout,
}

impl Decode {
    pub fn new(device: &wgpu::Device, res: &Resources) -> Self {
        let group_layout = layout(device, "decode", &[storage_entry::<[f32; 4]>(0, false)]);
        let [gbuffer, rsm] = res.pipelines(
            device,
            "gather decode",
            &WGSL,
            ["decode_gbuffer", "decode_rsm"],
            &[&group_layout],
        );
        Self {
            gbuffer,
            rsm,
            group_layout,
        }
    }

    /// The G-buffer (`view` None: position, normal, albedo a pixel) or light view `view`'s RSM
    /// (flux, position, normal a texel), read back.
    pub fn read(
        &self,
        gpu: &Gpu,
        res: &Resources,
        view: Option<usize>,
    ) -> Result<Decoded, GpuError> {
        let device = &gpu.device;
        let (width, height) = match view {
            None => res.size(),
            Some(_) => (res.settings().rsm_size, res.settings().rsm_size),
        };
        let texels = u64::from(width) * u64::from(height);
        let decoded = storage_buffer(device, "decoded", texels * 3 * 16);
        let group = bind_group(device, "decode", &self.group_layout, vec![whole(&decoded)]);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = compute_pass(&mut encoder, "decode", None);
            res.bind_groups(&mut pass, view.unwrap_or(0));
            res.bind_dispatch(&mut pass, 0, 0);
            pass.set_bind_group(3, &group, &[]);
            pass.set_pipeline(if view.is_some() {
                &self.rsm
            } else {
                &self.gbuffer
            });
            dispatch_2d(&mut pass, width, height);
        }
        gpu.submit("the decoding of the gather's inputs", encoder.finish());
        let bytes = quadray_gpu::read_buffer(gpu, &decoded)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
