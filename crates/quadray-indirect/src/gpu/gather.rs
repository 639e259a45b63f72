//! The gather: deferred shading of the caller's G-buffer from the light quadtree (the compacted
//! cut, or the paper's one pass per level; optionally at low resolution with geometry-aware
//! upsampling), the baselines of the same shape (RSM sampling, the brute force over every VPL),
//! and the direct light of the spot with the RSM depth as shadow map. Writes radiance buffers an
//! [`super::OutputPass`] copies into the caller's texture.

use super::contract::{
    CameraUniform, ClusterUniform, GpuNode, GpuNodeBounds, LEVEL_SLICE, LevelSlot,
    LightTermsUniform, LightUniform, MAX_SLICES, SLICE, ShadeUniform, Slots, bind_group, compute_pass, compute_pipeline, dispatch_2d,
    layout, pipeline_layout, shader_module, slices, storage_buffer, storage_entry, tex,
    texture_entry, uniform_buffer, uniform_entry, whole,
};
use super::gbuffer::{GBufferViews, camera_uniform};
use super::light::Spot;
use super::quadtree::{BOUND_WGSL, COMMON_WGSL, CUT_RULE_WGSL, LightQuadtree};
use super::rsm::{LIGHT_WGSL, RsmViews};
use crate::settings::{Method, Settings, TileCriterion};
use crate::{IndirectError, baselines};
use quadray_gpu::GpuTimer;
use std::cell::{Cell, OnceCell};
use wgpu::util::DeviceExt;

/// The gather's shader, in order.
pub(crate) const SOURCES: [&str; 8] = [
    COMMON_WGSL,
    LIGHT_WGSL,
    include_str!("shade_bindings.wgsl"),
    CUT_RULE_WGSL,
    include_str!("shade.wgsl"),
    BOUND_WGSL,
    include_str!("tiles.wgsl"),
    baselines::WGSL,
];

/// The gather's settings as the shaders read them (written once: a gather's settings are fixed).
fn shade_uniform(s: &Settings) -> ShadeUniform {
    let (low_width, low_height) = s.low_size();
    ShadeUniform {
        sample_count: s.samples,
        subsample: s.subsample,
        low_width,
        low_height,
        normal_agreement: 0.9,
        shadow_steps: s.shadow_steps,
        temporal_weight: s.temporal_weight,
        tile_error: s.tile_error,
        tile_capacity: s.tile_capacity,
        tile_start: s.tile_start_level(),
        tiles_x: s.tiles().0,
        tile_estimate: u32::from(s.tile_criterion == TileCriterion::Estimate),
        tile_share: s.tile_share,
    }
}

/// The per-frame buffers: settings, camera, radiance out, RSM samples, work counts.
struct Outputs {
    shade: wgpu::Buffer,
    camera: wgpu::Buffer,
    indirect: wgpu::Buffer,
    direct: wgpu::Buffer,
    low: wgpu::Buffer,
    samples: wgpu::Buffer,
    /// Per pixel: VPL evaluations, texel fetches, bound evaluations and refused splits of the
    /// last indirect passes (four `u32`).
    counts: wgpu::Buffer,
    /// The temporal filter's running average of the indirect light (one texel without it).
    history: wgpu::Buffer,
}

/// The per-tile cuts' lists and their bind group (group 3).
struct TileLists {
    /// Per tile, the per-tile cut's node indices (`tile_capacity` slots a tile).
    cuts: wgpu::Buffer,
    /// Per tile, the nodes its list holds, the splits refused for want of room, the nodes whose
    /// error it estimated and the VPL evaluations that took (four `u32`).
    sizes: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl TileLists {
    fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, cuts: u64, tiles: u64) -> Self {
        let cuts = storage_buffer(device, "per-tile cuts", cuts);
        let sizes = storage_buffer(device, "per-tile cut sizes", tiles * 16);
        let group = bind_group(
            device,
            "per-tile cuts",
            layout,
            vec![whole(&cuts), whole(&sizes)],
        );
        Self { cuts, sizes, group }
    }
}

impl Outputs {
    fn frame_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        gbuffer: GBufferViews,
    ) -> wgpu::BindGroup {
        bind_group(
            device,
            "gather frame",
            layout,
            vec![
                whole(&self.shade),
                whole(&self.camera),
                tex(gbuffer.position),
                tex(gbuffer.normal),
                tex(gbuffer.albedo),
                whole(&self.indirect),
                whole(&self.direct),
                whole(&self.low),
                whole(&self.samples),
                whole(&self.counts),
                whole(&self.history),
            ],
        )
    }
}

/// The shading pipelines and the radiance they write, at one set of sizes.
pub struct Gather {
    settings: Settings,
    indirect_cut: wgpu::ComputePipeline,
    indirect_tiles: wgpu::ComputePipeline,
    indirect_level: wgpu::ComputePipeline,
    indirect_low: wgpu::ComputePipeline,
    upsample: wgpu::ComputePipeline,
    sampled_low: wgpu::ComputePipeline,
    sampled_upsample: wgpu::ComputePipeline,
    direct_light: wgpu::ComputePipeline,
    brute_force: wgpu::ComputePipeline,
    rsm_sampling: wgpu::ComputePipeline,
    temporal_blend: wgpu::ComputePipeline,
    light_layout: wgpu::BindGroupLayout,
    frame_layout: wgpu::BindGroupLayout,
    light: wgpu::Buffer,
    light_terms: wgpu::Buffer,
    outputs: Outputs,
    slots: Slots,
    /// Per light update: the quadtree's settings, the light, the RSM, the quadtree and cut.
    light_group: wgpu::BindGroup,
    /// Per frame: the sizes, the G-buffer and the outputs.
    frame_group: wgpu::BindGroup,
    /// Per dispatch: a level and a slice.
    dispatch_group: wgpu::BindGroup,
    /// The per-tile cuts' lists, allocated by the first frame of [`Method::QuadtreeTiles`] (up
    /// to [`Settings::MAX_TILE_LIST_BYTES`]), so that the other methods pay nothing for them.
    tile_lists: OnceCell<TileLists>,
    /// What group 3 holds until then: lists of one slot.
    no_tile_lists: TileLists,
    tile_layout: wgpu::BindGroupLayout,
    /// To allocate the tile lists when first drawn.
    device: wgpu::Device,
    /// The method whose frames the temporal filter's history averages; `None` when it holds
    /// nothing to continue from.
    history_of: Cell<Option<Method>>,
    /// The camera last set, to restart the (not reprojected) average when it moves.
    camera: Cell<Option<(glam::Mat4, glam::Vec3)>>,
}

impl Gather {
    /// The gather of `settings` (sizes, samples, subsampling) reading `quadtree`, the RSM it was
    /// built from and the caller's G-buffer (`settings.width` x `settings.height`).
    pub fn new(
        device: &wgpu::Device,
        settings: &Settings,
        quadtree: &LightQuadtree,
        rsm: RsmViews,
        gbuffer: GBufferViews,
    ) -> Result<Self, IndirectError> {
        settings.validate().map_err(IndirectError::Settings)?;
        let s = settings;
        let compute = wgpu::ShaderStages::COMPUTE;
        let light_layout = layout(
            device,
            "gather light",
            &[
                uniform_entry::<ClusterUniform>(0, compute, false),
                uniform_entry::<LightUniform>(1, compute, false),
                uniform_entry::<LightTermsUniform>(2, compute, false),
                texture_entry(3),
                texture_entry(4),
                texture_entry(5),
                storage_entry::<GpuNode>(6, true),
                storage_entry::<GpuNode>(7, true),
                storage_entry::<u32>(8, true),
                storage_entry::<GpuNodeBounds>(9, true),
            ],
        );
        let frame_layout = layout(
            device,
            "gather frame",
            &[
                uniform_entry::<ShadeUniform>(0, compute, false),
                uniform_entry::<CameraUniform>(1, compute, false),
                texture_entry(2),
                texture_entry(3),
                texture_entry(4),
                storage_entry::<[f32; 4]>(5, false),
                storage_entry::<[f32; 4]>(6, false),
                storage_entry::<[f32; 4]>(7, false),
                storage_entry::<[f32; 4]>(8, true),
                storage_entry::<[u32; 4]>(9, false),
                storage_entry::<[f32; 4]>(10, false),
            ],
        );
        let tile_layout = layout(
            device,
            "per-tile cuts",
            &[
                storage_entry::<u32>(0, false),
                storage_entry::<[u32; 4]>(1, false),
            ],
        );
        let dispatch_layout = layout(
            device,
            "gather dispatch",
            &[
                uniform_entry::<LevelSlot>(0, compute, true),
                uniform_entry::<LevelSlot>(1, compute, true),
            ],
        );
        let module = shader_module(device, "gather", &SOURCES);
        let pipelines = pipeline_layout(
            device,
            &[&light_layout, &frame_layout, &dispatch_layout, &tile_layout],
        );
        let pipeline = |entry| compute_pipeline(device, &pipelines, &module, entry);
        let pixels = u64::from(s.width) * u64::from(s.height);
        let (lw, lh) = s.low_size();
        let samples = baselines::rsm_samples(
            s.samples,
            s.rsm_radius * s.rsm_size as f32 * std::f32::consts::SQRT_2,
            baselines::SAMPLE_SEED,
        );
        let light = uniform_buffer::<LightUniform>(device, "gather light");
        let light_terms = uniform_buffer::<LightTermsUniform>(device, "gather light terms");
        let outputs = Outputs {
            shade: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shade"),
                contents: bytemuck::bytes_of(&shade_uniform(s)),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            camera: uniform_buffer::<CameraUniform>(device, "gather camera"),
            indirect: storage_buffer(device, "indirect", pixels * 16),
            direct: storage_buffer(device, "direct", pixels * 16),
            low: storage_buffer(device, "low-resolution indirect", u64::from(lw * lh) * 16),
            samples: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("rsm samples"),
                contents: bytemuck::cast_slice(&samples),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            counts: storage_buffer(device, "work counts", pixels * 16),
            history: storage_buffer(
                device,
                "indirect history",
                if s.temporal_weight < 1.0 {
                    pixels * 16
                } else {
                    0
                },
            ),
        };
        let slots = Slots::new(device, "gather slots", MAX_SLICES);
        Ok(Self {
            settings: s.clone(),
            indirect_cut: pipeline("indirect_cut"),
            indirect_tiles: pipeline("indirect_tiles"),
            indirect_level: pipeline("indirect_level"),
            indirect_low: pipeline("indirect_low"),
            upsample: pipeline("upsample"),
            sampled_low: pipeline("sampled_low"),
            sampled_upsample: pipeline("sampled_upsample"),
            direct_light: pipeline("direct_light"),
            brute_force: pipeline("brute_force"),
            rsm_sampling: pipeline("rsm_sampling"),
            temporal_blend: pipeline("temporal_blend"),
            light_group: Self::light_group(device, &light_layout, [&light, &light_terms], quadtree, rsm),
            frame_group: outputs.frame_group(device, &frame_layout, gbuffer),
            dispatch_group: bind_group(
                device,
                "gather dispatch",
                &dispatch_layout,
                vec![slots.binding(), slots.binding()],
            ),
            tile_lists: OnceCell::new(),
            no_tile_lists: TileLists::new(device, &tile_layout, 4, 1),
            tile_layout,
            device: device.clone(),
            light_layout,
            frame_layout,
            light,
            light_terms,
            outputs,
            slots,
            history_of: Cell::new(None),
            camera: Cell::new(None),
        })
    }

    fn light_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        [light, terms]: [&wgpu::Buffer; 2],
        quadtree: &LightQuadtree,
        rsm: RsmViews,
    ) -> wgpu::BindGroup {
        bind_group(
            device,
            "gather light",
            layout,
            vec![
                whole(quadtree.params()),
                whole(light),
                whole(terms),
                tex(rsm.flux),
                tex(rsm.position),
                tex(rsm.normal),
                whole(quadtree.nodes()),
                whole(quadtree.cut()),
                whole(quadtree.cut_count()),
                whole(quadtree.bounds()),
            ],
        )
    }

    /// Reads another quadtree or RSM from now on (when the caller's RSM textures change).
    pub fn bind_rsm(&mut self, device: &wgpu::Device, quadtree: &LightQuadtree, rsm: RsmViews) {
        self.reset_history();
        let buffers = [&self.light, &self.light_terms];
        self.light_group = Self::light_group(device, &self.light_layout, buffers, quadtree, rsm);
    }

    /// Shades another G-buffer of the same size from now on (when the caller's targets change).
    pub fn bind_gbuffer(&mut self, device: &wgpu::Device, gbuffer: GBufferViews) {
        self.reset_history();
        self.frame_group = self
            .outputs
            .frame_group(device, &self.frame_layout, gbuffer);
    }

    /// Sets the light (per light update) and the clamp `r_min` of the VPL kernel's 1/r^4
    /// (world units).
    pub fn set_light(&self, queue: &wgpu::Queue, spot: &Spot, r_min: f32) {
        queue.write_buffer(&self.light, 0, bytemuck::bytes_of(&spot.uniform()));
        let terms = spot.terms(&self.settings, r_min);
        queue.write_buffer(&self.light_terms, 0, bytemuck::bytes_of(&terms));
    }

    /// Sets the camera the G-buffer is rendered from (`view_proj`: world -> clip, `eye`: its
    /// position): indirect shadows read the G-buffer as a depth map. A camera that moves
    /// restarts the temporal filter's average.
    pub fn set_camera(&self, queue: &wgpu::Queue, view_proj: glam::Mat4, eye: glam::Vec3) {
        if self.camera.replace(Some((view_proj, eye))) != Some((view_proj, eye)) {
            self.reset_history();
        }
        let s = &self.settings;
        let camera = camera_uniform(view_proj, eye, (s.width, s.height));
        queue.write_buffer(&self.outputs.camera, 0, bytemuck::bytes_of(&camera));
    }

    /// Binds the light's, the frame's and the tile lists' groups (the lists allocated first if
    /// `method` draws them).
    fn bind_groups(&self, pass: &mut wgpu::ComputePass, method: Option<Method>) {
        pass.set_bind_group(0, &self.light_group, &[]);
        pass.set_bind_group(1, &self.frame_group, &[]);
        let lists = if method == Some(Method::QuadtreeTiles) {
            self.tile_lists.get_or_init(|| {
                let (tx, ty) = self.settings.tiles();
                let tiles = u64::from(tx) * u64::from(ty);
                let cuts = self.settings.tile_list_bytes();
                TileLists::new(&self.device, &self.tile_layout, cuts, tiles)
            })
        } else {
            self.tile_lists.get().unwrap_or(&self.no_tile_lists)
        };
        pass.set_bind_group(3, &lists.group, &[]);
    }

    fn bind(&self, pass: &mut wgpu::ComputePass, level: u32, slice: u32) {
        pass.set_bind_group(
            2,
            &self.dispatch_group,
            &[self.slots.offset(level), self.slots.offset(slice)],
        );
    }

    /// Forgets the temporal filter's average: the next frame starts it anew (when what the
    /// frames show changes other than by the light moving, e.g. new cluster settings).
    pub fn reset_history(&self) {
        self.history_of.set(None);
    }

    /// Records the indirect light of `method` (after `quadtree`'s build, and its cut for
    /// [`Method::Quadtree`]) into `timer`'s `indirect` and `upsample` slots; with a temporal
    /// weight below 1 (not for the brute force) the frame is then averaged with the last ones,
    /// in the last of those slots.
    pub fn record_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        method: Method,
        quadtree: &LightQuadtree,
        timer: Option<(&GpuTimer, u32, u32)>,
    ) {
        let s = &self.settings;
        let c = quadtree.cluster();
        let subsampled = method.subsamples() && s.subsample > 1;
        let rsm_texels = u64::from(s.rsm_size).pow(2);
        // a cut partitions the RSM into nodes no finer than the limit level
        let cut_slices = slices(u64::from(s.rsm_size >> c.limit_level).pow(2), SLICE);
        let sample_slices = slices(u64::from(s.samples), SLICE);
        // the sub-sampled passes: their low-resolution and upsampling pipelines, and slices
        let (low, upsample, low_slices) = if method == Method::Rsm {
            (&self.sampled_low, &self.sampled_upsample, sample_slices)
        } else {
            (&self.indirect_low, &self.upsample, cut_slices)
        };
        let filtered = s.temporal_weight < 1.0 && method != Method::Reference;
        let blend = filtered && self.history_of.get() == Some(method);
        if method == Method::QuadtreePasses {
            encoder.clear_buffer(&self.outputs.indirect, 0, None);
        }
        encoder.clear_buffer(&self.outputs.counts, 0, None);
        {
            let stamps = timer.and_then(|(t, slot, _)| t.compute_pass(slot));
            let mut pass = compute_pass(encoder, "indirect", stamps);
            self.bind_groups(&mut pass, Some(method));
            // the sum over `items` in slices; the first slice writes, the others add
            let sliced = |pass: &mut wgpu::ComputePass, level: u32, count: u32, w, h| {
                for slice in 0..count {
                    self.bind(pass, level, slice);
                    dispatch_2d(pass, w, h);
                }
            };
            let (w, h) = (s.width, s.height);
            match method {
                _ if subsampled => {
                    pass.set_pipeline(low);
                    let (lw, lh) = s.low_size();
                    sliced(&mut pass, 0, low_slices, lw, lh);
                }
                Method::Quadtree => {
                    pass.set_pipeline(&self.indirect_cut);
                    sliced(&mut pass, 0, cut_slices, w, h);
                }
                Method::QuadtreeTiles => {
                    // one workgroup a tile; a list of at most TILE_FRONTIER nodes fits a slice
                    pass.set_pipeline(&self.indirect_tiles);
                    self.bind(&mut pass, 0, 0);
                    let (tx, ty) = s.tiles();
                    pass.dispatch_workgroups(tx, ty, 1);
                }
                Method::QuadtreePasses => {
                    pass.set_pipeline(&self.indirect_level);
                    for level in (c.limit_level..=c.start_level).rev() {
                        let nodes = u64::from(s.rsm_size >> level).pow(2);
                        sliced(&mut pass, level, slices(nodes, LEVEL_SLICE), w, h);
                    }
                }
                Method::Rsm => {
                    pass.set_pipeline(&self.rsm_sampling);
                    sliced(&mut pass, 0, sample_slices, w, h);
                }
                Method::Reference => {
                    pass.set_pipeline(&self.brute_force);
                    sliced(&mut pass, 0, slices(rsm_texels, SLICE), w, h);
                }
            }
            if blend && !subsampled {
                self.record_blend(&mut pass);
            }
        }
        if subsampled {
            // where the upsampler recomputes a pixel it sums the same as the low-resolution
            // samples, in the same slices
            let stamps = timer.and_then(|(t, _, slot)| t.compute_pass(slot));
            let mut pass = compute_pass(encoder, "upsample", stamps);
            self.bind_groups(&mut pass, Some(method));
            pass.set_pipeline(upsample);
            for slice in 0..low_slices {
                self.bind(&mut pass, 0, slice);
                dispatch_2d(&mut pass, s.width, s.height);
            }
            if blend {
                self.record_blend(&mut pass);
            }
        }
        if filtered && !blend {
            // the average starts from this frame
            let size = self.outputs.indirect.size();
            encoder.copy_buffer_to_buffer(
                &self.outputs.indirect,
                0,
                &self.outputs.history,
                0,
                size,
            );
            self.history_of.set(Some(method));
        }
    }

    /// The temporal filter, in a pass that has the groups bound.
    fn record_blend(&self, pass: &mut wgpu::ComputePass) {
        pass.set_pipeline(&self.temporal_blend);
        dispatch_2d(pass, self.settings.width, self.settings.height);
    }

    /// Records the direct light of the spot, shadowed by the RSM depth, into `timer`'s `slot`.
    pub fn record_direct(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<(&GpuTimer, u32)>,
    ) {
        let stamps = timer.and_then(|(t, slot)| t.compute_pass(slot));
        let mut pass = compute_pass(encoder, "direct", stamps);
        self.bind_groups(&mut pass, None);
        self.bind(&mut pass, 0, 0);
        pass.set_pipeline(&self.direct_light);
        dispatch_2d(&mut pass, self.settings.width, self.settings.height);
    }

    /// The settings the gather was built or last reconfigured with.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Indirect radiance per pixel, row-major: rgb, and w = 1 where the upsampler recomputed it.
    pub(crate) fn indirect(&self) -> &wgpu::Buffer {
        &self.outputs.indirect
    }

    /// Direct radiance per pixel, row-major (rgb, w = 1 where the G-buffer has geometry).
    pub(crate) fn direct(&self) -> &wgpu::Buffer {
        &self.outputs.direct
    }

    /// Per pixel, the last indirect passes' VPL evaluations, texel fetches, bound evaluations and
    /// refused splits (`[u32; 4]`).
    pub(crate) fn counts(&self) -> &wgpu::Buffer {
        &self.outputs.counts
    }

    /// The last per-tile cuts, `None` before the first frame of [`Method::QuadtreeTiles`]: per
    /// tile, its node indices (`tile_capacity` `u32` slots a tile), and its list's length,
    /// refused splits, nodes estimated and the estimates' VPL evaluations (`[u32; 4]`).
    pub(crate) fn tile_lists(&self) -> Option<(&wgpu::Buffer, &wgpu::Buffer)> {
        self.tile_lists.get().map(|t| (&t.cuts, &t.sizes))
    }
}
