//! Geometry-aware reconstruction, for the methods that gather at low resolution or interleaved
//! ([`crate::Method::subsamples`]): their sum at one sample per `subsample`^2 pixels, or at every
//! pixel one of `interleave`^2 parts of it, then each pixel interpolated (or its window's parts
//! rejoined) from the samples on its surface, or recomputed from the whole sum.

use crate::gathers::resources::Resources;
use crate::settings::Settings;

/// The low-resolution and upsampling passes; appended to a method's shader, which defines
/// `fn gathered_irradiance(r: Receiver, part: vec2<u32>) -> vec3<f32>`, a part of its slice of
/// the sum.
pub(crate) const WGSL: &str = include_str!("upsample.wgsl");

/// The entry points `upsample.wgsl` adds to a method's shader for `settings`: the
/// low-resolution samples', and the reconstruction's (interleaved sampling's rejoin, or the
/// upsampling).
pub(crate) fn entries(settings: &Settings) -> [&'static str; 2] {
    let reconstruct = if settings.interleave > 1 {
        "rejoin"
    } else {
        "upsample"
    };
    ["indirect_low", reconstruct]
}

/// A sub-sampled method's pipelines from its shader `own` (with [`WGSL`]) over the shared groups
/// and `own_groups`: its full-resolution sum's entry point `full`, and the two of [`entries`].
pub(crate) fn pipelines(
    device: &wgpu::Device,
    res: &Resources,
    label: &str,
    own: &[&'static str],
    full: &str,
    own_groups: &[&wgpu::BindGroupLayout],
) -> (wgpu::ComputePipeline, Upsampled) {
    let [low, reconstruct] = entries(res.settings());
    let [full, low, reconstruct] =
        res.pipelines(device, label, own, [full, low, reconstruct], own_groups);
    (full, Upsampled { low, reconstruct })
}

/// A sub-sampled method's two pipelines, made from its shader with [`WGSL`] and [`entries`].
pub(crate) struct Upsampled {
    pub low: wgpu::ComputePipeline,
    /// The upsampling, or interleaved sampling's rejoin ([`entries`]).
    pub reconstruct: wgpu::ComputePipeline,
}

impl Upsampled {
    /// Records the low-resolution samples, the sum in `slices` slices.
    pub fn record_low(&self, pass: &mut wgpu::ComputePass, res: &Resources, slices: u32) {
        pass.set_pipeline(&self.low);
        res.sliced(pass, 0, slices, res.settings().low_size());
    }

    /// Records the upsampling, or interleaved sampling's rejoin: where it recomputes a pixel it
    /// sums the same as the low-resolution samples, in the same slices.
    pub fn record_upsample(&self, pass: &mut wgpu::ComputePass, res: &Resources, slices: u32) {
        pass.set_pipeline(&self.reconstruct);
        res.sliced(pass, 0, slices, res.size());
    }
}
