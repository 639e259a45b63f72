//! The GPU side. Raster passes (`raster.wgsl`): the RSM from the spot and the camera's G-buffer.
//! Compute passes (`cluster.wgsl`): pack the RSM into the quadtree, reduce it level by level, mark
//! valid clusters, compact the cut. Shading (`shade.wgsl`, and the baselines' `baselines.wgsl`):
//! indirect from the cut or the per-level passes, sub-sampled with upsampling, direct light.

mod resources;

use crate::IndirectError;
use crate::baselines;
use crate::scene::Scene;
use quadray_gpu::{Gpu, GpuTimer, read_texture_f32};
use resources::{Buffers, Pipelines, Targets};
use serde::Serialize;
use std::collections::BTreeMap;

/// How the indirect term is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Light quadtree, cut compacted once per light update and looped over per pixel.
    Quadtree,
    /// Light quadtree, the paper's one pass per level.
    QuadtreePasses,
    /// RSM sampling with N Poisson-disk samples (baseline).
    Rsm,
    /// Every VPL (brute force on the GPU).
    Reference,
}

impl Method {
    pub const ALL: [Method; 4] = [
        Method::Quadtree,
        Method::QuadtreePasses,
        Method::Rsm,
        Method::Reference,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Quadtree => "quadtree",
            Method::QuadtreePasses => "quadtree-passes",
            Method::Rsm => "rsm",
            Method::Reference => "reference",
        }
    }

    pub fn uses_quadtree(self) -> bool {
        matches!(self, Method::Quadtree | Method::QuadtreePasses)
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!("unknown method `{s}` (quadtree, quadtree-passes, rsm, reference)")
            })
    }
}

/// Which clusters count as valid (see the spec).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Validity {
    /// The paper's: the 4 children against their mean.
    Local,
    /// Also every child valid.
    Recursive,
}

impl std::str::FromStr for Validity {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "local" => Ok(Validity::Local),
            "recursive" => Ok(Validity::Recursive),
            _ => Err(format!("unknown validity rule `{s}` (local, recursive)")),
        }
    }
}

/// The light quadtree's parameters. Levels are mip levels: 0 is the RSM itself (one VPL per
/// node), each level halves the side.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ClusterSettings {
    pub start_level: u32,
    pub limit_level: u32,
    pub depth_threshold: f32,
    pub normal_threshold: f32,
    pub validity: Validity,
    /// Means weighted by flux luminance (else by texel count).
    pub flux_weighted: bool,
}

impl ClusterSettings {
    /// Defaults for a given RSM: the paper's thresholds (depth 0.05, normal 0.9), start at 8x8 as
    /// in the paper, limit at 64x64 (the paper's level 4; its 32x32 limit leaves about 7% rel. L1
    /// error on the Cornell box, most of it at the limit level), and the recursive rule: on a
    /// 512^2 RSM the local rule leaves 5.1% with 360 clusters, the recursive 3.8% with 633, less
    /// than the local rule reaches with the same time at a finer limit (4.4% with 589).
    pub fn defaults(rsm_size: u32) -> Self {
        Self {
            validity: Validity::Recursive,
            ..Self::with_limit_side(rsm_size, 64)
        }
    }

    /// The paper's settings (local rule) with the limit level where nodes are `side` x `side`
    /// (16, 32, 64 in table 1).
    pub fn with_limit_side(rsm_size: u32, side: u32) -> Self {
        let top = rsm_size.ilog2();
        Self {
            start_level: top.saturating_sub(3),
            limit_level: top.saturating_sub(side.max(1).ilog2()),
            depth_threshold: 0.05,
            normal_threshold: 0.9,
            validity: Validity::Local,
            flux_weighted: true,
        }
    }

    /// Every cluster a single VPL: the cut is the whole RSM.
    pub fn every_vpl(rsm_size: u32) -> Self {
        Self {
            limit_level: 0,
            depth_threshold: 0.0,
            ..Self::defaults(rsm_size)
        }
    }
}

/// Sizes and the parameters of every method.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub rsm_size: u32,
    pub cluster: ClusterSettings,
    /// RSM-sampling samples per pixel.
    pub samples: u32,
    /// Sampling radius as a fraction of the RSM's diagonal.
    pub rsm_radius: f32,
    /// Indirect at one sample per `subsample`^2 pixels (1: full resolution).
    pub subsample: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            rsm_size: 512,
            cluster: ClusterSettings::defaults(512),
            samples: 256,
            rsm_radius: 1.0,
            subsample: 1,
        }
    }
}

impl Settings {
    /// Refuses sizes and parameters that would make no picture or an absurd amount of work.
    pub fn validate(&self) -> Result<(), String> {
        let s = self;
        if !(1..=8192).contains(&s.width) || !(1..=8192).contains(&s.height) {
            return Err(format!("size {}x{} is outside 1..8192", s.width, s.height));
        }
        // 1024^2 VPLs make a 67 MB quadtree, within every adapter's storage-buffer limit
        if !s.rsm_size.is_power_of_two() || !(4..=1024).contains(&s.rsm_size) {
            return Err(format!(
                "RSM size {} must be a power of two in 4..1024",
                s.rsm_size
            ));
        }
        let top = s.rsm_size.ilog2();
        let c = &s.cluster;
        if c.start_level > top || c.limit_level > c.start_level {
            return Err(format!(
                "levels must satisfy limit ({}) <= start ({}) <= {top} (the 1x1 level of a {} RSM)",
                c.limit_level, c.start_level, s.rsm_size
            ));
        }
        if !(c.depth_threshold.is_finite() && c.depth_threshold >= 0.0) {
            return Err(format!(
                "depth threshold {} must be >= 0",
                c.depth_threshold
            ));
        }
        if !(c.normal_threshold.is_finite() && (-1.0..=1.0).contains(&c.normal_threshold)) {
            return Err(format!(
                "normal threshold {} is outside [-1, 1]",
                c.normal_threshold
            ));
        }
        if !(1..=65536).contains(&s.samples) {
            return Err(format!("{} samples is outside 1..65536", s.samples));
        }
        if !(s.rsm_radius.is_finite() && s.rsm_radius > 0.0 && s.rsm_radius <= 1.0) {
            return Err(format!("RSM radius {} is outside (0, 1]", s.rsm_radius));
        }
        if !(1..=64).contains(&s.subsample) {
            return Err(format!("subsample {} is outside 1..64", s.subsample));
        }
        Ok(())
    }
}

/// The timed passes, in `GpuTimer` order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pass {
    Rsm,
    Pyramid,
    Validity,
    Cut,
    GBuffer,
    Indirect,
    Upsample,
    Direct,
}

impl Pass {
    pub const ALL: [Pass; 8] = [
        Pass::Rsm,
        Pass::Pyramid,
        Pass::Validity,
        Pass::Cut,
        Pass::GBuffer,
        Pass::Indirect,
        Pass::Upsample,
        Pass::Direct,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Pass::Rsm => "rsm",
            Pass::Pyramid => "pyramid",
            Pass::Validity => "validity",
            Pass::Cut => "cut",
            Pass::GBuffer => "gbuffer",
            Pass::Indirect => "indirect",
            Pass::Upsample => "upsample",
            Pass::Direct => "direct",
        }
    }
}

/// Median GPU time per pass (ms) over some frames; `total_ms` is the sum of the medians.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameTiming {
    pub passes: BTreeMap<&'static str, f64>,
    pub total_ms: f64,
    pub frames: u32,
}

/// One frame read back: linear radiance per pixel, row-major, top row first.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub indirect: Vec<[f32; 3]>,
    pub direct: Vec<[f32; 3]>,
    /// Pixels the upsampler recomputed at full resolution.
    pub recomputed: u32,
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CutNode {
    pub level: u32,
    pub x: u32,
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
    pub flux: [f32; 3],
    pub position: [f32; 3],
    pub normal: [f32; 3],
}

/// A G-buffer texel (the CPU reference's receivers); `None` where the camera sees nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub albedo: [f32; 3],
}

/// Everything one scene needs on the GPU at one set of sizes.
pub struct Renderer<'g> {
    gpu: &'g Gpu,
    settings: Settings,
    pipelines: Pipelines,
    targets: Targets,
    buffers: Buffers,
    vertex_count: u32,
    /// A timer for all passes; `None` when the adapter has no timestamp queries.
    timer: GpuTimer,
}

impl<'g> Renderer<'g> {
    pub fn new(gpu: &'g Gpu, scene: &Scene, settings: Settings) -> Result<Self, IndirectError> {
        settings.validate().map_err(IndirectError::Settings)?;
        let pipelines = gpu.checked(|| Pipelines::new(gpu))?;
        let targets = gpu.checked(|| Targets::new(gpu, &settings))?;
        let samples = baselines::rsm_samples(
            settings.samples,
            settings.rsm_radius * settings.rsm_size as f32 * std::f32::consts::SQRT_2,
            0x5eed,
        );
        let buffers =
            gpu.checked(|| Buffers::new(gpu, scene, &settings, &samples, &pipelines, &targets))?;
        Ok(Self {
            gpu,
            vertex_count: (scene.triangles.len() * 3) as u32,
            timer: GpuTimer::new(gpu, Pass::ALL.len() as u32),
            settings,
            pipelines,
            targets,
            buffers,
        })
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Moves the camera and the light to the scene's (its geometry must be the one the renderer
    /// was made with); the next frame must `rebuild` if the light moved.
    pub fn set_view(&mut self, scene: &Scene) {
        self.buffers.write_scene(self.gpu, scene, &self.settings);
    }

    /// Changes the quadtree's parameters; the next frame with `rebuild` uses them.
    pub fn set_cluster(&mut self, cluster: ClusterSettings) -> Result<(), IndirectError> {
        let settings = Settings {
            cluster,
            ..self.settings.clone()
        };
        settings.validate().map_err(IndirectError::Settings)?;
        self.settings = settings;
        self.buffers.write_cluster(self.gpu, &self.settings);
        Ok(())
    }

    /// Renders one frame of `method`. With `rebuild` the light-dependent work (RSM, pyramid,
    /// validity, cut) is redone, as when the light moves; without it those buffers are reused.
    /// With `timed` the passes' GPU times are recorded.
    pub fn render(
        &mut self,
        method: Method,
        rebuild: bool,
        timed: bool,
    ) -> Result<(), IndirectError> {
        let gpu = self.gpu;
        let run = self.passes_run(method, rebuild);
        gpu.checked(|| {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let timer = timed.then_some(&self.timer);
            let p = &self.pipelines;
            let t = &self.targets;
            let b = &self.buffers;
            if run.contains(&Pass::Rsm) {
                p.raster(&mut encoder, Pass::Rsm, t, b, self.vertex_count, timer);
            }
            if run.contains(&Pass::Pyramid) {
                p.build_quadtree(&mut encoder, b, &self.settings, timer);
            }
            if run.contains(&Pass::Cut) {
                p.select_cut(&mut encoder, b, &self.settings, timer);
            }
            p.raster(&mut encoder, Pass::GBuffer, t, b, self.vertex_count, timer);
            p.shade_indirect(&mut encoder, b, &self.settings, method, timer);
            p.shade_direct(&mut encoder, b, &self.settings, timer);
            if let Some(timer) = timer {
                timer.resolve(&mut encoder);
            }
            gpu.queue.submit([encoder.finish()]);
        })?;
        if timed {
            self.timer.collect(gpu)?;
        }
        Ok(())
    }

    /// The passes a frame of `method` records (the timer's slots of the others hold stale times).
    pub fn passes_run(&self, method: Method, rebuild: bool) -> Vec<Pass> {
        let mut passes = Vec::new();
        if rebuild {
            passes.push(Pass::Rsm);
            if method.uses_quadtree() {
                passes.extend([Pass::Pyramid, Pass::Validity]);
            }
            if method == Method::Quadtree {
                passes.push(Pass::Cut);
            }
        }
        passes.extend([Pass::GBuffer, Pass::Indirect, Pass::Direct]);
        if method == Method::Quadtree && self.settings.subsample > 1 {
            passes.push(Pass::Upsample);
        }
        passes
    }

    /// Renders `frames` timed frames of `method` (rebuilding the light's buffers each frame with
    /// `rebuild`) and returns the median GPU time of each pass; `None` without timestamp queries.
    pub fn time(
        &mut self,
        method: Method,
        rebuild: bool,
        frames: u32,
    ) -> Result<Option<FrameTiming>, IndirectError> {
        self.timer.clear();
        for _ in 0..frames {
            self.render(method, rebuild, true)?;
        }
        if !self.timer.enabled() || frames == 0 {
            return Ok(None);
        }
        let run = self.passes_run(method, rebuild);
        let passes: BTreeMap<&'static str, f64> = Pass::ALL
            .into_iter()
            .zip(self.timer.summaries())
            .filter(|(p, _)| run.contains(p))
            .filter_map(|(p, s)| s.map(|s| (p.name(), s.median_ms)))
            .collect();
        Ok(Some(FrameTiming {
            total_ms: passes.values().sum(),
            passes,
            frames,
        }))
    }

    pub fn has_timestamps(&self) -> bool {
        self.timer.enabled()
    }

    /// Renders one frame of `method` from scratch, untimed, and reads it back.
    pub fn render_frame(&mut self, method: Method) -> Result<Frame, IndirectError> {
        self.render(method, true, false)?;
        self.read_frame()
    }

    /// The last frame's indirect and direct light.
    pub fn read_frame(&self) -> Result<Frame, IndirectError> {
        let indirect = self.buffers.read_vec4(self.gpu, &self.buffers.indirect)?;
        let direct = self.buffers.read_vec4(self.gpu, &self.buffers.direct)?;
        let rgb = |v: &[[f32; 4]]| v.iter().map(|p| [p[0], p[1], p[2]]).collect();
        Ok(Frame {
            width: self.settings.width,
            height: self.settings.height,
            recomputed: indirect.iter().filter(|p| p[3] > 0.5).count() as u32,
            indirect: rgb(&indirect),
            direct: rgb(&direct),
        })
    }

    /// Number of clusters in the compacted cut (after a `Quadtree` frame with rebuild).
    pub fn clusters_in_cut(&self) -> Result<u32, IndirectError> {
        let count = self.buffers.read_u32(self.gpu, &self.buffers.cut_count)?;
        Ok(count[0])
    }

    /// The clusters of the compacted cut (after a `Quadtree` frame with rebuild), in no order.
    pub fn read_cut(&self) -> Result<Vec<CutNode>, IndirectError> {
        let count = self.clusters_in_cut()? as usize;
        let clusters = self.buffers.read_vec4(self.gpu, &self.buffers.cut)?;
        // three vec4 a cluster; the normal's w holds the node's index
        Ok(clusters
            .chunks_exact(3)
            .take(count)
            .map(|c| CutNode::at(self.settings.rsm_size, c[2][3].to_bits()))
            .collect())
    }

    /// The RSM's flux per texel, row-major (what the cut clusters).
    pub fn read_rsm_flux(&self) -> Result<Vec<[f32; 3]>, IndirectError> {
        let flux = read_texture_f32(self.gpu, &self.targets.rsm[0], 0, 4)?;
        Ok(flux.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect())
    }

    /// The quadtree as built: per node (flux rgb + texel count, position + depth, normal +
    /// validity), finest level first.
    pub fn read_nodes(&self) -> Result<Vec<[[f32; 4]; 3]>, IndirectError> {
        let flat = self.buffers.read_vec4(self.gpu, &self.buffers.nodes)?;
        Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// The RSM's VPLs (texels that see geometry), for the CPU reference.
    pub fn read_vpls(&self) -> Result<Vec<Vpl>, IndirectError> {
        let read = |tex: &wgpu::Texture| read_texture_f32(self.gpu, tex, 0, 4);
        let flux = read(&self.targets.rsm[0])?;
        let pos = read(&self.targets.rsm[1])?;
        let normal = read(&self.targets.rsm[2])?;
        Ok((0..flux.len() / 4)
            .filter(|i| normal[i * 4 + 3] > 0.5)
            .map(|i| Vpl {
                flux: [flux[i * 4], flux[i * 4 + 1], flux[i * 4 + 2]],
                position: [pos[i * 4], pos[i * 4 + 1], pos[i * 4 + 2]],
                normal: [normal[i * 4], normal[i * 4 + 1], normal[i * 4 + 2]],
            })
            .collect())
    }

    /// The G-buffer, for the CPU reference.
    pub fn read_receivers(&self) -> Result<Vec<Option<Receiver>>, IndirectError> {
        let read = |tex: &wgpu::Texture| read_texture_f32(self.gpu, tex, 0, 4);
        let pos = read(&self.targets.gbuffer[0])?;
        let normal = read(&self.targets.gbuffer[1])?;
        let albedo = read(&self.targets.gbuffer[2])?;
        let v3 = |v: &[f32], i: usize| [v[i * 4], v[i * 4 + 1], v[i * 4 + 2]];
        Ok((0..pos.len() / 4)
            .map(|i| {
                (pos[i * 4 + 3] > 0.5).then(|| Receiver {
                    position: v3(&pos, i),
                    normal: v3(&normal, i),
                    albedo: v3(&albedo, i),
                })
            })
            .collect())
    }
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
