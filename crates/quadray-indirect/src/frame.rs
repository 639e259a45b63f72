//! What a frame reads back: the radiance, the work the shaders counted, the timings, the cut's
//! clusters, and the VPLs and receivers the CPU reference takes. Plain values, no GPU.

use serde::Serialize;
use std::collections::BTreeMap;

/// Two receivers lie on one surface only where their normals' dot exceeds this (upsampling,
/// corner sharing, deblocking).
pub(crate) const NORMAL_AGREEMENT: f32 = 0.9;

/// The timed passes, in `GpuTimer` order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pass {
    /// The reflective shadow map from the spot.
    Rsm,
    /// The quadtree's levels: VPL means and spreads, coarser level from finer.
    Pyramid,
    /// Each node's validity under the thresholds.
    Validity,
    /// The cut: the valid clusters that replace the VPLs.
    Cut,
    /// The camera's G-buffer.
    GBuffer,
    /// The gather: each (sub-sampled) pixel sums the cut or its VPL samples.
    Indirect,
    /// Sub-sampled indirect light brought to full resolution.
    Upsample,
    /// Each light view's shadow map for the direct light (the sun's fitted to the camera).
    ShadowMap,
    /// The lights' direct light on the G-buffer, through the shadow maps.
    Direct,
}

impl Pass {
    /// Every pass, in the order a frame records them.
    pub const ALL: [Pass; 9] = [
        Pass::Rsm,
        Pass::Pyramid,
        Pass::Validity,
        Pass::Cut,
        Pass::GBuffer,
        Pass::Indirect,
        Pass::Upsample,
        Pass::ShadowMap,
        Pass::Direct,
    ];

    /// The pass's key in [`FrameTiming::passes`] and the stats JSON.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Rsm => "rsm",
            Pass::Pyramid => "pyramid",
            Pass::Validity => "validity",
            Pass::Cut => "cut",
            Pass::GBuffer => "gbuffer",
            Pass::Indirect => "indirect",
            Pass::Upsample => "upsample",
            Pass::ShadowMap => "shadow-map",
            Pass::Direct => "direct",
        }
    }
}

/// Median GPU time per pass (ms) over some frames; `total_ms` is the sum of the medians.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameTiming {
    /// Median ms of each pass the method ran, by [`Pass::name`].
    pub passes: BTreeMap<&'static str, f64>,
    /// Sum of the passes' medians, ms.
    pub total_ms: f64,
    /// Frames the medians are taken over.
    pub frames: u32,
}

/// One frame read back: linear radiance per pixel, row-major, top row first.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One-bounce indirect radiance, what the methods differ in.
    pub indirect: Vec<[f32; 3]>,
    /// The lights' direct radiance, the same for every method.
    pub direct: Vec<[f32; 3]>,
    /// Pixels the upsampler recomputed at full resolution.
    pub recomputed: u32,
    /// The work the indirect passes did, counted in the shaders.
    pub counts: WorkCounts,
}

/// The work of a frame's indirect passes, counted by the shaders themselves: hardware-independent
/// figures to compare methods by. Every dispatch's work is counted, so a sum split into slices
/// reads the G-buffer once per slice, and the sub-sampled quadtree counts its low-resolution
/// samples and the pixels the upsampler recomputed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct WorkCounts {
    /// Pixels where the G-buffer has geometry: the ones shaded, what the means are over.
    pub shaded_pixels: u32,
    /// VPL kernels evaluated (a cluster counts one, an RSM sample one where its texel is a
    /// VPL), over all pixels.
    pub vpl_evaluations: u64,
    /// Reads of G-buffer texels, RSM texels, quadtree node records and low-resolution samples,
    /// over all pixels.
    pub texel_fetches: u64,
    /// Upper bounds of a node's contribution to a tile evaluated (per-tile cuts), over all
    /// tiles.
    pub bound_evaluations: u64,
    /// Splits a per-tile cut refused because the tile's list was full, over all tiles.
    pub refused_splits: u64,
}

impl WorkCounts {
    /// Mean VPL evaluations per shaded pixel.
    pub fn vpl_evaluations_per_pixel(&self) -> f64 {
        self.vpl_evaluations as f64 / f64::from(self.shaded_pixels.max(1))
    }

    /// Mean texel fetches per shaded pixel.
    pub fn texel_fetches_per_pixel(&self) -> f64 {
        self.texel_fetches as f64 / f64::from(self.shaded_pixels.max(1))
    }

    /// Mean bound evaluations per shaded pixel.
    pub fn bound_evaluations_per_pixel(&self) -> f64 {
        self.bound_evaluations as f64 / f64::from(self.shaded_pixels.max(1))
    }
}

impl Frame {
    /// Direct plus indirect radiance.
    pub fn combined(&self) -> Vec<[f32; 3]> {
        self.direct
            .iter()
            .zip(&self.indirect)
            .map(|(d, i)| std::array::from_fn(|c| d[c] + i[c]))
            .collect()
    }
}

/// A cluster of the cut: its level (0 = one RSM texel) and its node's column and row there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct CutNode {
    /// Quadtree level, 0 being the RSM itself.
    pub level: u32,
    /// Column of the node at its level.
    pub x: u32,
    /// Row of the node at its level.
    pub y: u32,
}

impl CutNode {
    /// The node at `index` of the pyramid of an RSM of side `rsm_size` (finest level first).
    pub fn at(rsm_size: u32, mut index: u32) -> Self {
        let mut level = 0;
        while level < rsm_size.ilog2() && index >= (rsm_size >> level).pow(2) {
            index -= (rsm_size >> level).pow(2);
            level += 1;
        }
        let side = rsm_size >> level;
        Self {
            level,
            x: index % side,
            y: index / side,
        }
    }
}

/// A VPL as the RSM stores it (the CPU reference's input).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    /// Flux the VPL's surface reflects (W).
    pub flux: [f32; 3],
    /// World position.
    pub position: [f32; 3],
    /// Unit normal facing the light.
    pub normal: [f32; 3],
}

/// A G-buffer texel (the CPU reference's receivers); `None` where the camera sees nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    /// World position.
    pub position: [f32; 3],
    /// Unit normal facing the camera.
    pub normal: [f32; 3],
    /// Diffuse albedo the gathered light is multiplied by.
    pub albedo: [f32; 3],
}

#[cfg(test)]
mod tests {
    use super::CutNode;

    #[test]
    fn cut_nodes_are_found_from_their_pyramid_index() {
        let size = 16u32;
        let mut index = 0;
        for level in 0..=size.ilog2() {
            let side = size >> level;
            for y in 0..side {
                for x in 0..side {
                    assert_eq!(CutNode::at(size, index), CutNode { level, x, y });
                    index += 1;
                }
            }
        }
    }
}
