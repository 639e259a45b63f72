//! Geometry-aware upsampling, for the methods that gather at low resolution
//! ([`crate::Method::subsamples`]): their sum at one sample per `subsample`^2 pixels, then each
//! pixel interpolated from the samples on its surface or recomputed at full resolution.

use crate::gathers::resources::Resources;

/// The low-resolution and upsampling passes; appended to a method's shader, which defines
/// `fn gathered_irradiance(r: Receiver) -> vec3<f32>`, its slice of the sum.
pub(crate) const WGSL: &str = include_str!("upsample.wgsl");

/// The entry points `upsample.wgsl` adds to a method's shader.
pub(crate) const ENTRIES: [&str; 2] = ["indirect_low", "upsample"];

/// A sub-sampled method's two pipelines, made from its shader with [`WGSL`] and [`ENTRIES`].
pub(crate) struct Upsampled {
    pub low: wgpu::ComputePipeline,
    pub upsample: wgpu::ComputePipeline,
}

impl Upsampled {
    /// Records the low-resolution samples, the sum in `slices` slices.
    pub fn record_low(&self, pass: &mut wgpu::ComputePass, res: &Resources, slices: u32) {
        pass.set_pipeline(&self.low);
        res.sliced(pass, 0, slices, res.settings().low_size());
    }

    /// Records the upsampling: where it recomputes a pixel it sums the same as the
    /// low-resolution samples, in the same slices.
    pub fn record_upsample(&self, pass: &mut wgpu::ComputePass, res: &Resources, slices: u32) {
        pass.set_pipeline(&self.upsample);
        res.sliced(pass, 0, slices, res.size());
    }
}
