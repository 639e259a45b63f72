//! The output pass: the gather's radiance written into the caller's texture.

use crate::IndirectError;
use crate::contract::{
    OutputTerm, bind_group, compute_pass, compute_pipeline, dispatch_2d, layout, pipeline_layout,
    shader_module, storage_entry, whole,
};
use crate::gathers::gather::Gather;

const WGSL: &str = include_str!("output.wgsl");

/// The WGSL name of a storage-texture format the output pass writes.
fn wgsl_format(format: wgpu::TextureFormat) -> Option<&'static str> {
    match format {
        wgpu::TextureFormat::Rgba32Float => Some("rgba32float"),
        wgpu::TextureFormat::Rgba16Float => Some("rgba16float"),
        wgpu::TextureFormat::Rgba8Unorm => Some("rgba8unorm"),
        _ => None,
    }
}

/// The output pass's shader for a storage format, in order.
pub(crate) fn sources(format: &str) -> [String; 1] {
    [WGSL.replace("OUTPUT_FORMAT", format)]
}

/// Writes linear radiance (rgb, alpha 1) into a texture of the gather's size with
/// `STORAGE_BINDING` usage.
pub struct OutputPass {
    pipeline: wgpu::ComputePipeline,
    group_layout: wgpu::BindGroupLayout,
}

impl OutputPass {
    /// A pass writing `term` into textures of `format`: `Rgba32Float`, `Rgba16Float` or
    /// `Rgba8Unorm` (the last clamps to [0, 1]).
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        term: OutputTerm,
    ) -> Result<Self, IndirectError> {
        let name = wgsl_format(format).ok_or_else(|| {
            IndirectError::Settings(format!(
                "output format {format:?} is not one of Rgba32Float, Rgba16Float, Rgba8Unorm"
            ))
        })?;
        let group_layout = layout(
            device,
            "output",
            &[
                storage_entry::<[f32; 4]>(0, true),
                storage_entry::<[f32; 4]>(1, true),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
            ],
        );
        let [source] = sources(name);
        let module = shader_module(device, "output", &[&source]);
        let pipeline = compute_pipeline(
            device,
            &pipeline_layout(device, &[&group_layout]),
            &module,
            "write_output",
            &[("TERM", f64::from(term as u32))],
        );
        Ok(Self {
            pipeline,
            group_layout,
        })
    }

    /// Records the copy of `gather`'s last radiance into `output` (its bind group is made here:
    /// the output may change every frame).
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        gather: &Gather,
        output: &wgpu::TextureView,
    ) {
        let group = bind_group(
            device,
            "output",
            &self.group_layout,
            vec![
                whole(gather.indirect()),
                whole(gather.direct()),
                wgpu::BindingResource::TextureView(output),
            ],
        );
        let mut pass = compute_pass(encoder, "output", None);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        let s = gather.settings();
        dispatch_2d(&mut pass, s.size.width, s.size.height);
    }
}
