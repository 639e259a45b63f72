//! The light-quadtree pass: the RSM packed into a pyramid of clusters (summed flux, weighted
//! means), the validity of every cluster, and the compacted cut. Its buffers are what the gather
//! reads.

use crate::contract::{
    ClusterUniform, GpuNode, GpuNodeBounds, LevelSlot, LightUniform, Slots, bind_group,
    compact_constant, compute_pass, compute_pipeline, dispatch_2d, layout, pipeline_layout,
    shader_module, storage_buffer, storage_entry, tex, texture_entry, uniform_buffer,
    uniform_entry, whole,
};
use crate::light::node::{
    CUT_CLASS_SIDE, CutCounts, MAX_LEVELS, cut_class_capacity, level_offset, node_count,
};
use crate::light::rsm::{RSM_READ_WGSL, RsmViews};
use crate::method::GBufferLayout;
use crate::method::Validity;
use crate::settings::{ClusterSettings, Levels};
use crate::wgsl;
use quadray_gpu::GpuTimer;

/// The quadtree pass's shader, in order: `cluster.wgsl` holds its bindings, the accessor the cut
/// rule reads nodes with, and its entry points.
pub(crate) const SOURCES: [&str; 7] = [
    wgsl::NODE,
    wgsl::KERNEL,
    wgsl::LIGHT,
    wgsl::COMPACT,
    wgsl::CUT_RULE,
    RSM_READ_WGSL,
    include_str!("cluster.wgsl"),
];

/// The quadtree over an RSM of a fixed side, and the pipelines that build it and its cut.
pub struct LightQuadtree {
    rsm_size: u32,
    cluster: ClusterSettings,
    /// The layout of the RSM the pipelines read.
    rsm_layout: GBufferLayout,
    /// What a wide RSM's group binds for the light it does not need.
    no_light: wgpu::Buffer,
    pack: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    validity: wgpu::ComputePipeline,
    select_cut: wgpu::ComputePipeline,
    group_layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    nodes: wgpu::Buffer,
    cut: wgpu::Buffer,
    cut_count: wgpu::Buffer,
    bounds: wgpu::Buffer,
    levels: Slots,
    /// Per light update: settings, RSM, nodes and cut.
    group: wgpu::BindGroup,
    /// Per dispatch: the level.
    level_group: wgpu::BindGroup,
}

impl LightQuadtree {
    /// A quadtree over `rsm` (textures of side `rsm_size`, a power of two, the RSM's side) with the
    /// settings `cluster` (check them with [`crate::Settings::validate`]).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        rsm_size: u32,
        cluster: ClusterSettings,
        rsm: RsmViews,
    ) -> Self {
        let compute = wgpu::ShaderStages::COMPUTE;
        let group_layout = layout(
            device,
            "quadtree",
            &[
                uniform_entry::<ClusterUniform>(0, compute, false),
                texture_entry(1),
                texture_entry(2),
                texture_entry(3),
                storage_entry::<GpuNode>(4, false),
                storage_entry::<GpuNode>(5, false),
                storage_entry::<CutCounts>(6, false),
                storage_entry::<GpuNodeBounds>(7, false),
                uniform_entry::<LightUniform>(8, compute, false),
            ],
        );
        let level_layout = layout(
            device,
            "quadtree level",
            &[uniform_entry::<LevelSlot>(0, compute, true)],
        );
        let module = shader_module(device, "quadtree", &SOURCES);
        let pipelines = pipeline_layout(device, &[&group_layout, &level_layout]);
        let rsm_layout = rsm.layout();
        let constants = [compact_constant("COMPACT_RSM", rsm_layout)];
        let pipeline = |entry| compute_pipeline(device, &pipelines, &module, entry, &constants);
        let node_size = size_of::<GpuNode>() as u64;
        let params = uniform_buffer::<ClusterUniform>(device, "cluster settings");
        let nodes = storage_buffer(device, "nodes", node_count(rsm_size) * node_size);
        let classes = u64::from(CUT_CLASS_SIDE).pow(2);
        let cut = storage_buffer(
            device,
            "cut",
            classes * cut_class_capacity(rsm_size) * node_size,
        );
        let cut_count = storage_buffer(device, "cut count", (classes + 1) * 4);
        let bounds = storage_buffer(
            device,
            "node bounds",
            node_count(rsm_size) * size_of::<GpuNodeBounds>() as u64,
        );
        let levels = Slots::new(device, "levels", MAX_LEVELS);
        let level_group = bind_group(
            device,
            "quadtree level",
            &level_layout,
            vec![levels.binding()],
        );
        let no_light = uniform_buffer::<LightUniform>(device, "quadtree no light");
        let buffers = [&params, &nodes, &cut, &cut_count, &bounds, &no_light];
        let group = Self::rsm_group(device, &group_layout, buffers, rsm);
        let quadtree = Self {
            rsm_size,
            cluster,
            rsm_layout,
            no_light,
            pack: pipeline("pack"),
            reduce: pipeline("reduce"),
            validity: pipeline("validity"),
            select_cut: pipeline("select_cut"),
            group_layout,
            params,
            nodes,
            cut,
            cut_count,
            bounds,
            levels,
            group,
            level_group,
        };
        quadtree.write_cluster(queue);
        quadtree
    }

    /// The group of `buffers` (settings, nodes, cut, cut count, node bounds, and the light a
    /// wide RSM does not need) and `rsm`.
    fn rsm_group(
        device: &wgpu::Device,
        group_layout: &wgpu::BindGroupLayout,
        buffers: [&wgpu::Buffer; 6],
        rsm: RsmViews,
    ) -> wgpu::BindGroup {
        let [params, nodes, cut, cut_count, bounds, no_light] = buffers;
        let [flux, position, normal] = rsm.textures();
        let light = match rsm {
            RsmViews::Compact { light, .. } => light,
            RsmViews::Wide { .. } => no_light,
        };
        bind_group(
            device,
            "quadtree",
            group_layout,
            vec![
                whole(params),
                tex(flux),
                tex(position),
                tex(normal),
                whole(nodes),
                whole(cut),
                whole(cut_count),
                whole(bounds),
                whole(light),
            ],
        )
    }

    /// Reads another RSM of the same side from now on (when the caller's RSM textures change).
    ///
    /// # Panics
    /// With an RSM in another layout than the one the quadtree was made for.
    pub fn bind_rsm(&mut self, device: &wgpu::Device, rsm: RsmViews) {
        assert_eq!(
            rsm.layout(),
            self.rsm_layout,
            "the quadtree reads the RSM layout it was made for"
        );
        let buffers = [
            &self.params,
            &self.nodes,
            &self.cut,
            &self.cut_count,
            &self.bounds,
            &self.no_light,
        ];
        self.group = Self::rsm_group(device, &self.group_layout, buffers, rsm);
    }

    /// New settings for the next build and cut (check them with [`crate::Settings::validate`]).
    pub fn set_cluster(&mut self, queue: &wgpu::Queue, cluster: ClusterSettings) {
        self.cluster = cluster;
        self.write_cluster(queue);
    }

    fn write_cluster(&self, queue: &wgpu::Queue) {
        let c = &self.cluster;
        let levels = self.levels();
        queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&ClusterUniform {
                rsm_size: self.rsm_size,
                levels: self.rsm_size.ilog2() + 1,
                start_level: levels.start,
                limit_level: levels.limit,
                recursive: u32::from(c.validity == Validity::Recursive),
                flux_weighted: u32::from(c.flux_weighted),
                depth_threshold: c.depth_threshold,
                normal_threshold: c.normal_threshold,
            }),
        );
    }

    /// Records the pyramid (pack + one reduce per level) into `timer`'s `pyramid` slot and the
    /// validity (one dispatch per level, finest first, so the recursive rule sees its children's
    /// verdicts) into its `validity` slot.
    pub fn record_build(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<(&GpuTimer, u32, u32)>,
    ) {
        let top = self.rsm_size.ilog2();
        let side = |level: u32| self.rsm_size >> level;
        {
            let stamps = timer.and_then(|(t, slot, _)| t.compute_pass(slot));
            let mut pass = compute_pass(encoder, "pyramid", stamps);
            pass.set_bind_group(0, &self.group, &[]);
            pass.set_pipeline(&self.pack);
            pass.set_bind_group(1, &self.level_group, &[self.levels.offset(0)]);
            dispatch_2d(&mut pass, side(0), side(0));
            pass.set_pipeline(&self.reduce);
            for level in 1..=top {
                pass.set_bind_group(1, &self.level_group, &[self.levels.offset(level)]);
                dispatch_2d(&mut pass, side(level), side(level));
            }
        }
        let stamps = timer.and_then(|(t, _, slot)| t.compute_pass(slot));
        let mut pass = compute_pass(encoder, "validity", stamps);
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_pipeline(&self.validity);
        for level in 1..=top {
            pass.set_bind_group(1, &self.level_group, &[self.levels.offset(level)]);
            dispatch_2d(&mut pass, side(level), side(level));
        }
    }

    /// Records the compacted cut (after [`Self::record_build`]): one thread per node of the
    /// levels limit..start, atomic append to its class's segment.
    pub fn record_cut(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<(&GpuTimer, u32)>) {
        encoder.clear_buffer(&self.cut_count, 0, None);
        let levels = self.levels();
        let nodes = level_offset(self.rsm_size, levels.start + 1)
            - level_offset(self.rsm_size, levels.limit);
        let stamps = timer.and_then(|(t, slot)| t.compute_pass(slot));
        let mut pass = compute_pass(encoder, "cut", stamps);
        pass.set_pipeline(&self.select_cut);
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_bind_group(1, &self.level_group, &[self.levels.offset(0)]);
        pass.dispatch_workgroups(nodes.div_ceil(256) as u32, 1, 1);
    }

    /// Side of the RSM the quadtree was built for; its levels follow from it.
    pub fn rsm_size(&self) -> u32 {
        self.rsm_size
    }

    /// The parameters the next cut is made with.
    pub fn cluster(&self) -> ClusterSettings {
        self.cluster
    }

    /// The levels the cut spans ([`ClusterSettings::levels`] on this quadtree's RSM).
    pub fn levels(&self) -> Levels {
        self.cluster.levels(self.rsm_size)
    }

    /// The pyramid's parameters (a `ClusterParams` uniform of [`crate::wgsl::NODE`]): for an
    /// engine's own passes over the quadtree, as the Bevy plugin's cut view.
    pub fn params(&self) -> &wgpu::Buffer {
        &self.params
    }

    /// Every node, finest level first: a `Node` array of [`crate::wgsl::NODE`] (for an engine's
    /// own passes, as [`Self::params`]).
    pub fn nodes(&self) -> &wgpu::Buffer {
        &self.nodes
    }

    /// The compacted cut's clusters ([`GpuNode`]s, `normal.w` the node's index as bits), a
    /// segment of [`cut_class_capacity`] a class.
    pub(crate) fn cut(&self) -> &wgpu::Buffer {
        &self.cut
    }

    /// How many clusters the last cut holds (its first `u32`, copyable: for a read-back or a
    /// profiler's counter), then how many each of its classes holds (`CUT_CLASS_SIDE`^2 more).
    pub fn cut_count(&self) -> &wgpu::Buffer {
        &self.cut_count
    }

    /// Every node's box and normal cone ([`GpuNodeBounds`]), as the nodes.
    pub(crate) fn bounds(&self) -> &wgpu::Buffer {
        &self.bounds
    }
}
