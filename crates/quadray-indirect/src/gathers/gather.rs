//! [`Gather`]: the gather's passes at one set of sizes, picked and ordered by method, over the
//! resources every pass shares.

use super::brute_force::BruteForce;
use super::cut::Cut;
use super::decode::{Decode, Decoded};
use super::passes::Passes;
use super::resources::{Resources, ViewMaps};
use super::rsm_sampling::RsmSampling;
use crate::IndirectError;
use crate::contract::GpuNode;
use crate::contract::compute_pass;
use crate::gbuffer::GBufferViews;
use crate::light::node::node_count;
use crate::light::quadtree::LightQuadtree;
use crate::light::view::LightView;
use crate::method::Method;
use crate::output::temporal::Temporal;
use crate::settings::Settings;
use crate::shadows::occupancy::OccupancyGrid;
use crate::tiles::pass::Tiles;
use quadray_gpu::{Gpu, GpuError, GpuTimer, Limit, LimitNeed};
use std::sync::OnceLock;

/// Every gather pass's whole shader (before the prelude), by name: what the contract test parses.
#[cfg(test)]
pub(crate) fn shaders() -> Vec<(&'static str, Vec<&'static str>)> {
    vec![
        ("gather cut", super::resources::shader(&super::cut::WGSL)),
        (
            "gather passes",
            super::resources::shader(&super::passes::WGSL),
        ),
        (
            "gather tiles",
            super::resources::shader(&crate::tiles::pass::WGSL),
        ),
        (
            "gather tiles split",
            super::resources::shader(&crate::tiles::pass::SPLIT_WGSL),
        ),
        (
            "gather rsm sampling",
            super::resources::shader(&super::rsm_sampling::WGSL),
        ),
        (
            "gather brute force",
            super::resources::shader(&super::brute_force::WGSL),
        ),
        (
            "gather temporal",
            super::resources::shader(&crate::output::temporal::WGSL),
        ),
        (
            "gather decode",
            super::resources::shader(&super::decode::WGSL),
        ),
    ]
}

/// Storage buffers the most demanding pass binds in its compute stage (the contract test counts
/// every shader's).
pub(crate) const STORAGE_BUFFERS_PER_STAGE: u64 = 16;
/// Workgroup memory of the per-tile cuts' kernel in bytes (the contract test sums its variables).
pub(crate) const TILE_WORKGROUP_BYTES: u64 = 15_612;

/// The shading passes and the radiance they write, at one set of sizes.
pub struct Gather {
    res: Resources,
    cut: Cut,
    passes: Passes,
    tiles: Tiles,
    rsm_sampling: RsmSampling,
    brute_force: BruteForce,
    temporal: Temporal,
    /// Made on the first read-back of the inputs (the CPU reference's), not for every gather.
    decode: OnceLock<Decode>,
}

impl Gather {
    /// What the passes of `settings` need of the device's limits, each with the setting or the
    /// pass that needs it; [`Gather::new`] checks them first.
    pub fn limit_needs(settings: &Settings) -> Vec<LimitNeed> {
        let s = settings;
        let size = format!("--size {}x{}", s.size.width, s.size.height);
        let rsm = format!("--rsm-size {}", s.rsm_size);
        let need = |limit, needed, needed_by: &str| LimitNeed {
            limit,
            needed,
            needed_by: needed_by.into(),
        };
        let pixels = u64::from(s.size.width) * u64::from(s.size.height);
        let nodes = node_count(s.rsm_size) * size_of::<GpuNode>() as u64;
        let side = s.size.width.max(s.size.height).into();
        vec![
            need(Limit::TextureDimension2d, side, &size),
            need(Limit::TextureDimension2d, s.rsm_size.into(), &rsm),
            // a vec4 of radiance a pixel
            need(Limit::StorageBufferBindingSize, pixels * 16, &size),
            need(Limit::StorageBufferBindingSize, nodes, &rsm),
            need(
                Limit::StorageBufferBindingSize,
                s.tile_list_bytes(),
                &format!(
                    "{size} with --tile-capacity {}",
                    s.tile_capacity_or_default()
                ),
            ),
            need(
                Limit::StorageBufferBindingSize,
                s.tile_shadow_bytes(),
                &format!(
                    "{size} with --tile-passes {} and --tile-capacity {}",
                    s.tile_passes,
                    s.tile_capacity_or_default()
                ),
            ),
            need(
                Limit::StorageBuffersPerShaderStage,
                STORAGE_BUFFERS_PER_STAGE,
                "the gather passes",
            ),
            need(
                Limit::ComputeWorkgroupStorageSize,
                TILE_WORKGROUP_BYTES,
                "the per-tile cuts (--method quadtree-tiles)",
            ),
        ]
    }

    /// The gather of `settings` (sizes, samples, subsampling) summing the light views whose
    /// `maps` (each an RSM and the quadtree built from it, all RSMs in one layout) it reads, on
    /// the caller's G-buffer (`settings.size`; a compact one needs [`Gather::set_camera`]). The
    /// layouts are the views' own: [`Settings::gbuffer_layout`] is the one quadray's passes write.
    pub fn new(
        device: &wgpu::Device,
        settings: &Settings,
        maps: &[ViewMaps],
        gbuffer: GBufferViews,
    ) -> Result<Self, IndirectError> {
        settings.validate().map_err(IndirectError::Settings)?;
        if maps.is_empty() {
            return Err(IndirectError::Settings(
                "a gather needs a light view".into(),
            ));
        }
        if maps.iter().any(|m| m.rsm.layout() != maps[0].rsm.layout()) {
            return Err(IndirectError::Settings(
                "a gather reads its light views' RSMs in one layout".into(),
            ));
        }
        quadray_gpu::check_limits(&device.limits(), "the device", &Self::limit_needs(settings))?;
        let res = Resources::new(device, settings, maps, gbuffer);
        Ok(Self {
            cut: Cut::new(device, &res),
            passes: Passes::new(device, &res),
            tiles: Tiles::new(device, &res),
            rsm_sampling: RsmSampling::new(device, &res),
            brute_force: BruteForce::new(device, &res),
            temporal: Temporal::new(device, &res),
            decode: OnceLock::new(),
            res,
        })
    }

    /// Reads other quadtrees or RSMs from now on (when the caller's RSM textures change), one
    /// a light view as at [`Gather::new`].
    ///
    /// # Panics
    /// With another number of views, or RSMs in another layout, than the gather was made for.
    pub fn bind_maps(&mut self, device: &wgpu::Device, maps: &[ViewMaps]) {
        self.reset_history();
        self.res.bind_maps(device, maps);
    }

    /// How many light views the gather sums.
    pub fn view_count(&self) -> usize {
        self.res.view_count()
    }

    /// Shades another G-buffer of the same size from now on (when the caller's targets change).
    ///
    /// # Panics
    /// With a G-buffer in another layout than the gather was made for.
    pub fn bind_gbuffer(&mut self, device: &wgpu::Device, gbuffer: GBufferViews) {
        self.reset_history();
        self.res.bind_gbuffer(device, gbuffer);
    }

    /// Walks the scene's occupancy `grid` for indirect shadows from now on, instead of marching
    /// the camera's and the light's depth maps (a gather starts without one). A grid updated
    /// since the last ([`OccupancyGrid::add`], [`OccupancyGrid::remove`]) is uploaded in the
    /// rows of its words that changed; where it outgrew its texture, the frame's bind group is
    /// made anew, hence the G-buffer's views.
    pub fn set_occupancy(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        grid: &OccupancyGrid,
        gbuffer: GBufferViews,
    ) {
        self.res.set_occupancy(device, queue, grid, gbuffer);
    }

    /// Sets the light views (per light update), in the order of the maps, and the clamp `r_min`
    /// of the VPL kernel's 1/r^4 (world units).
    ///
    /// # Panics
    /// With another number of views than the gather was made for.
    pub fn set_lights(&self, queue: &wgpu::Queue, lights: &[LightView], r_min: f32) {
        self.res.set_lights(queue, lights, r_min);
    }

    /// Sets the camera the G-buffer is rendered from (`view_proj`: world -> clip, `eye`: its
    /// position): indirect shadows read the G-buffer as a depth map, and the temporal filter
    /// reprojects its average from the last filtered frame's camera to this one.
    pub fn set_camera(&self, queue: &wgpu::Queue, view_proj: glam::Mat4, eye: glam::Vec3) {
        self.res.set_camera(queue, view_proj, eye);
    }

    /// Forgets the temporal filter's average: the next frame starts it anew (when what the
    /// frames show changes other than by the light moving, e.g. new cluster settings).
    pub fn reset_history(&self) {
        self.temporal.reset();
    }

    /// Records the indirect light of `method`, summed over the light views (after each view's
    /// `quadtrees` build, and its cut for [`Method::Quadtree`]; one a view, in the order of the
    /// maps) into `timer`'s `indirect` and `upsample` slots; with a temporal weight below 1 (not
    /// for the brute force) the frame is then averaged with the last ones, in the last of those
    /// slots.
    ///
    /// # Panics
    /// With another number of quadtrees than the gather has views.
    pub fn record_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        method: Method,
        quadtrees: &[&LightQuadtree],
        timer: Option<(&GpuTimer, u32, u32)>,
    ) {
        let res = &self.res;
        assert_eq!(
            quadtrees.len(),
            res.view_count(),
            "one quadtree a light view"
        );
        let s = res.settings();
        // the sub-sampled and interleaved methods: their passes, and the slices of their sum
        let upsampled = match method {
            Method::Quadtree => Some(&self.cut.upsampled),
            Method::Rsm => Some(&self.rsm_sampling.upsampled),
            _ => None,
        }
        .filter(|_| s.reconstructs(method));
        let slices = |quadtree| match method {
            Method::Quadtree => Cut::slices(quadtree),
            _ => RsmSampling::slices(res),
        };
        let filtered = s.temporal_weight < 1.0 && method != Method::Reference;
        if filtered {
            self.temporal.record_prepare(encoder, res, method);
        }
        if method == Method::QuadtreePasses {
            self.passes.record_clear(encoder, res);
        }
        encoder.clear_buffer(&res.outputs.counts, 0, None);
        {
            let stamps = timer.and_then(|(t, slot, _)| t.compute_pass(slot));
            let mut pass = compute_pass(encoder, "indirect", stamps);
            for (view, &quadtree) in quadtrees.iter().enumerate() {
                res.bind_groups(&mut pass, view);
                match (method, upsampled) {
                    (Method::Quadtree, _) => self.cut.record(&mut pass, res, quadtree),
                    (_, Some(upsampled)) => upsampled.record_low(&mut pass, res, slices(quadtree)),
                    (Method::QuadtreeTiles, None) => self.tiles.record(&mut pass, res),
                    (Method::QuadtreePasses, None) => self.passes.record(&mut pass, res, quadtree),
                    (Method::Rsm, None) => self.rsm_sampling.record(&mut pass, res),
                    (Method::Reference, None) => self.brute_force.record(&mut pass, res),
                }
            }
            if method == Method::QuadtreeTiles {
                self.tiles.record_deblock(&mut pass, res);
            }
            if filtered && upsampled.is_none() {
                self.temporal.record_blend(&mut pass, res);
            }
        }
        if let Some(upsampled) = upsampled {
            let stamps = timer.and_then(|(t, _, slot)| t.compute_pass(slot));
            let mut pass = compute_pass(encoder, "upsample", stamps);
            if method == Method::Quadtree {
                self.cut.corners.bind(&mut pass, res);
            }
            for (view, &quadtree) in quadtrees.iter().enumerate() {
                res.bind_groups(&mut pass, view);
                upsampled.record_upsample(&mut pass, res, slices(quadtree));
            }
            if filtered {
                self.temporal.record_blend(&mut pass, res);
            }
        }
        if filtered {
            self.temporal.record_finish(encoder, res, method);
        }
    }

    /// The G-buffer as the passes read it (on `gpu`, the gather's device), row-major: position
    /// (w: 1 where geometry is seen), normal, albedo a pixel.
    pub(crate) fn read_gbuffer(&self, gpu: &Gpu) -> Result<Decoded, GpuError> {
        self.decoder(gpu).read(gpu, &self.res, None)
    }

    /// Light view `view`'s RSM as the passes read it, row-major: flux, position (w: depth along
    /// the light's axis), normal (w: 1 where the light sees geometry) a texel.
    pub(crate) fn read_rsm(&self, gpu: &Gpu, view: usize) -> Result<Decoded, GpuError> {
        self.decoder(gpu).read(gpu, &self.res, Some(view))
    }

    fn decoder(&self, gpu: &Gpu) -> &Decode {
        self.decode
            .get_or_init(|| Decode::new(&gpu.device, &self.res))
    }

    /// The settings the gather was built with.
    pub fn settings(&self) -> &Settings {
        self.res.settings()
    }

    /// Indirect radiance per pixel, row-major, `[f32; 4]`: rgb, and w = 1 where the upsampler
    /// recomputed it. Valid after [`Gather::record_indirect`]; a renderer composites it itself
    /// or through an [`crate::OutputPass`].
    pub fn indirect(&self) -> &wgpu::Buffer {
        &self.res.outputs.indirect
    }

    /// Direct radiance per pixel, row-major (rgb, w = 1 where the G-buffer has geometry), as a
    /// [`crate::DirectLight`] writes it.
    pub(crate) fn direct(&self) -> &wgpu::Buffer {
        &self.res.outputs.direct
    }

    /// The resources every pass shares, for the passes outside the gather (the direct light).
    pub(crate) fn resources(&self) -> &Resources {
        &self.res
    }

    /// Per pixel, the last indirect passes' VPL evaluations, texel fetches, bound evaluations and
    /// refused splits (`[u32; 4]`).
    pub fn counts(&self) -> &wgpu::Buffer {
        &self.res.outputs.counts
    }

    /// The last per-tile cuts, `None` before the first frame of [`Method::QuadtreeTiles`]: per
    /// tile, its node indices (`tile_capacity` `u32` slots a tile), and its list's length,
    /// refused splits, nodes estimated and the estimates' VPL evaluations (`[u32; 4]`).
    pub(crate) fn tile_lists(&self) -> Option<(&wgpu::Buffer, &wgpu::Buffer)> {
        self.tiles.lists()
    }
}
