//! The light-quadtree pass: the RSM packed into a pyramid of clusters (summed flux, weighted
//! means), the validity of every cluster, and the compacted cut. Its buffers are what the gather
//! reads.

use super::contract::{
    ClusterUniform, GpuNode, GpuNodeBounds, LevelSlot, MAX_LEVELS, Slots, bind_group, compute_pass,
    compute_pipeline, dispatch_2d, layout, pipeline_layout, shader_module, storage_buffer,
    storage_entry, tex, texture_entry, uniform_buffer, uniform_entry, whole,
};
use super::rsm::RsmViews;
use super::{ClusterSettings, Validity};
use quadray_gpu::GpuTimer;

pub(crate) const COMMON_WGSL: &str = include_str!("common.wgsl");
pub(crate) const CUT_RULE_WGSL: &str = include_str!("cut_rule.wgsl");
pub(crate) const BOUND_WGSL: &str = include_str!("bound.wgsl");
/// The quadtree pass's shader, in order.
pub(crate) const SOURCES: [&str; 3] = [COMMON_WGSL, CUT_RULE_WGSL, include_str!("cluster.wgsl")];

/// Total nodes of the pyramid of an RSM of side `rsm_size`.
pub(crate) fn node_count(rsm_size: u32) -> u64 {
    level_offset(rsm_size, rsm_size.ilog2() + 1)
}

/// Index of the first node of `level`.
pub(crate) fn level_offset(rsm_size: u32, level: u32) -> u64 {
    (0..level).map(|l| u64::from(rsm_size >> l).pow(2)).sum()
}

/// The quadtree over an RSM of a fixed side, and the pipelines that build it and its cut.
pub struct LightQuadtree {
    rsm_size: u32,
    cluster: ClusterSettings,
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
    /// settings `cluster` (check them with [`super::Settings::validate`]).
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
                storage_entry::<u32>(6, false),
                storage_entry::<GpuNodeBounds>(7, false),
            ],
        );
        let level_layout = layout(
            device,
            "quadtree level",
            &[uniform_entry::<LevelSlot>(0, compute, true)],
        );
        let module = shader_module(device, "quadtree", &SOURCES);
        let pipelines = pipeline_layout(device, &[&group_layout, &level_layout]);
        let pipeline = |entry| compute_pipeline(device, &pipelines, &module, entry);
        let node_size = size_of::<GpuNode>() as u64;
        let params = uniform_buffer::<ClusterUniform>(device, "cluster settings");
        let nodes = storage_buffer(device, "nodes", node_count(rsm_size) * node_size);
        // a cut partitions the RSM: at most one cluster per texel
        let cut = storage_buffer(device, "cut", u64::from(rsm_size).pow(2) * node_size);
        let cut_count = storage_buffer(device, "cut count", 4);
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
        let buffers = [&params, &nodes, &cut, &cut_count, &bounds];
        let group = Self::rsm_group(device, &group_layout, buffers, rsm);
        let quadtree = Self {
            rsm_size,
            cluster,
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

    /// The group of `buffers` (settings, nodes, cut, cut count, node bounds) and `rsm`.
    fn rsm_group(
        device: &wgpu::Device,
        group_layout: &wgpu::BindGroupLayout,
        buffers: [&wgpu::Buffer; 5],
        rsm: RsmViews,
    ) -> wgpu::BindGroup {
        let [params, nodes, cut, cut_count, bounds] = buffers;
        bind_group(
            device,
            "quadtree",
            group_layout,
            vec![
                whole(params),
                tex(rsm.flux),
                tex(rsm.position),
                tex(rsm.normal),
                whole(nodes),
                whole(cut),
                whole(cut_count),
                whole(bounds),
            ],
        )
    }

    /// Reads another RSM of the same side from now on (when the caller's RSM textures change).
    pub fn bind_rsm(&mut self, device: &wgpu::Device, rsm: RsmViews) {
        let buffers = [
            &self.params,
            &self.nodes,
            &self.cut,
            &self.cut_count,
            &self.bounds,
        ];
        self.group = Self::rsm_group(device, &self.group_layout, buffers, rsm);
    }

    /// New settings for the next build and cut (check them with [`super::Settings::validate`]).
    pub fn set_cluster(&mut self, queue: &wgpu::Queue, cluster: ClusterSettings) {
        self.cluster = cluster;
        self.write_cluster(queue);
    }

    fn write_cluster(&self, queue: &wgpu::Queue) {
        let c = &self.cluster;
        queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&ClusterUniform {
                rsm_size: self.rsm_size,
                levels: self.rsm_size.ilog2() + 1,
                start_level: c.start_level,
                limit_level: c.limit_level,
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
    /// levels limit..start, atomic append.
    pub fn record_cut(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<(&GpuTimer, u32)>) {
        encoder.clear_buffer(&self.cut_count, 0, None);
        let c = &self.cluster;
        let nodes = level_offset(self.rsm_size, c.start_level + 1)
            - level_offset(self.rsm_size, c.limit_level);
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

    pub(crate) fn params(&self) -> &wgpu::Buffer {
        &self.params
    }

    /// Every node, finest level first: [`GpuNode`]s.
    pub(crate) fn nodes(&self) -> &wgpu::Buffer {
        &self.nodes
    }

    /// The compacted cut's clusters ([`GpuNode`]s, `normal.w` the node's index as bits).
    pub(crate) fn cut(&self) -> &wgpu::Buffer {
        &self.cut
    }

    /// How many clusters the cut holds (one `u32`).
    pub(crate) fn cut_count(&self) -> &wgpu::Buffer {
        &self.cut_count
    }

    /// Every node's box and normal cone ([`GpuNodeBounds`]), as the nodes.
    pub(crate) fn bounds(&self) -> &wgpu::Buffer {
        &self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::super::contract::{
        bind_group, compute_pipeline, layout, pipeline_layout, shader_module, storage_buffer,
        storage_entry, whole,
    };
    use super::{BOUND_WGSL, COMMON_WGSL};
    use crate::gpu::{Receiver, Vpl};
    use crate::reference::brute_force;
    use glam::Vec3;
    use quadray_core::random::SplitMix;
    use wgpu::util::DeviceExt;

    /// `node_bound`'s inputs (one case), and the entry point that evaluates it per case.
    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct BoundCase {
        flux: [f32; 4],
        /// the node's box (w of lo: its cone's cosine) and cone axis
        node_lo: [f32; 4],
        node_hi: [f32; 4],
        node_axis: [f32; 4],
        /// the receivers' box (w of lo: their cone's cosine), cone axis (w: r_min)
        lo: [f32; 4],
        hi: [f32; 4],
        axis: [f32; 4],
    }

    const ENTRY: &str = "
struct BoundCase { flux: vec4<f32>, node_lo: vec4<f32>, node_hi: vec4<f32>, node_axis: vec4<f32>,
    lo: vec4<f32>, hi: vec4<f32>, axis: vec4<f32> }
@group(0) @binding(0) var<storage, read> cases: array<BoundCase>;
@group(0) @binding(1) var<storage, read_write> bound: array<f32>;
@compute @workgroup_size(64)
fn bound_cases(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x < arrayLength(&cases)) {
        let c = cases[id.x];
        bound[id.x] = node_bound(c.flux.rgb, NodeBounds(c.node_lo, c.node_hi), c.node_axis.xyz,
            c.lo.xyz, c.hi.xyz, c.axis.xyz, c.lo.w, c.axis.w);
    }
}
";

    fn bounds_on_the_gpu(cases: &[BoundCase]) -> Vec<f32> {
        let gpu = quadray_gpu::Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
        let d = &gpu.device;
        let group_layout = layout(
            d,
            "bound cases",
            &[
                storage_entry::<BoundCase>(0, true),
                storage_entry::<f32>(1, false),
            ],
        );
        let module = shader_module(d, "bound cases", &[COMMON_WGSL, BOUND_WGSL, ENTRY]);
        let pipeline = compute_pipeline(
            d,
            &pipeline_layout(d, &[&group_layout]),
            &module,
            "bound_cases",
        );
        let input = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("bound cases"),
            contents: bytemuck::cast_slice(cases),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let output = storage_buffer(d, "bounds", cases.len() as u64 * 4);
        let group = bind_group(
            d,
            "bound cases",
            &group_layout,
            vec![whole(&input), whole(&output)],
        );
        let mut encoder = d.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
        }
        gpu.queue.submit([encoder.finish()]);
        let bytes = quadray_gpu::read_buffer(&gpu, &output).unwrap();
        bytemuck::pod_collect_to_vec(&bytes)
    }

    struct Random(SplitMix);

    impl Random {
        fn unit(&mut self) -> f32 {
            self.0.next_f32()
        }
        fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
            Vec3::new(self.unit(), self.unit(), self.unit()) * (hi - lo) + lo
        }
        fn direction(&mut self) -> Vec3 {
            loop {
                let v = self.vec(-1.0, 1.0);
                if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                    return v.normalize();
                }
            }
        }
        /// A unit vector at `angle` or less from `axis`, often exactly at it (the cone's rim).
        fn within(&mut self, axis: Vec3, angle: f32) -> Vec3 {
            let across = axis
                .cross(self.direction())
                .normalize_or(axis.any_orthonormal_vector());
            let turn = if self.unit() < 0.3 {
                angle
            } else {
                angle * self.unit()
            };
            axis * turn.cos() + across * turn.sin()
        }
        /// A box, flat along one axis a third of the time (a wall), and a point in it.
        fn box_around(&mut self, centre: Vec3, size: f32) -> (Vec3, Vec3) {
            let mut half = self.vec(0.0, size);
            if self.unit() < 0.33 {
                half[(self.unit() * 3.0) as usize % 3] = 0.0;
            }
            (centre - half, centre + half)
        }
        fn inside(&mut self, (lo, hi): (Vec3, Vec3)) -> Vec3 {
            lo + (hi - lo) * self.vec(0.0, 1.0)
        }
    }

    fn luminance(c: [f32; 3]) -> f32 {
        0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    }

    #[test]
    fn the_node_bound_is_at_least_the_exact_irradiance_at_any_receiver_of_the_box() {
        let mut rng = Random(SplitMix(7));
        let (cases, per_case) = (512, 24);
        let mut all = Vec::new();
        let mut exact = Vec::new();
        for case in 0..cases {
            // near boxes (overlapping, within r_min) and far ones, narrow and wide cones
            let spread = if case % 2 == 0 { 0.6 } else { 3.0 };
            let centres = [rng.vec(-spread, spread), rng.vec(-spread, spread)];
            let node_box = rng.box_around(centres[0], 0.4);
            let receiver_box = rng.box_around(centres[1], 0.4);
            let node_axis = rng.direction();
            let receiver_axis = rng.direction();
            let angles = [0.0, 0.3, 1.2, 2.0];
            let node_angle = angles[case % 4];
            let receiver_angle = angles[(case / 4) % 4];
            let r_min = [0.01, 0.2][(case / 16) % 2];
            let vpls: Vec<Vpl> = (0..per_case)
                .map(|_| Vpl {
                    flux: rng.vec(0.0, 1.0).into(),
                    position: rng.inside(node_box).into(),
                    normal: rng.within(node_axis, node_angle).into(),
                })
                .collect();
            let receivers: Vec<Option<Receiver>> = (0..per_case)
                .map(|_| {
                    Some(Receiver {
                        position: rng.inside(receiver_box).into(),
                        normal: rng.within(receiver_axis, receiver_angle).into(),
                        // radiance albedo / pi * E is then the irradiance E
                        albedo: [std::f32::consts::PI; 3],
                    })
                })
                .collect();
            let irradiance = brute_force(&vpls, &receivers, r_min);
            exact.push(irradiance.into_iter().map(luminance).fold(0.0, f32::max));
            let flux = vpls.iter().fold(Vec3::ZERO, |s, v| s + Vec3::from(v.flux));
            all.push(BoundCase {
                flux: flux.extend(0.0).into(),
                node_lo: node_box.0.extend(node_angle.cos()).into(),
                node_hi: node_box.1.extend(0.0).into(),
                node_axis: node_axis.extend(0.0).into(),
                lo: receiver_box.0.extend(receiver_angle.cos()).into(),
                hi: receiver_box.1.extend(0.0).into(),
                axis: receiver_axis.extend(r_min).into(),
            });
        }
        let bounds = bounds_on_the_gpu(&all);
        let mut tightness = Vec::new();
        for (i, (&bound, &exact)) in bounds.iter().zip(&exact).enumerate() {
            assert!(
                bound >= exact * (1.0 - 1e-4),
                "case {i}: bound {bound} < exact {exact}"
            );
            if exact > 0.0 {
                tightness.push(exact / bound);
            }
        }
        // the bound follows the light: it is not a constant over the cases
        tightness.sort_by(f32::total_cmp);
        let median = tightness[tightness.len() / 2];
        let zero = bounds.iter().filter(|&&b| b == 0.0).count();
        println!(
            "{} of {cases} cases lit; exact / bound median {median:.3}; {zero} bounds 0",
            tightness.len()
        );
        assert!(
            median > 0.03,
            "bound too loose: median exact / bound {median}"
        );
        assert!(zero > 0, "no case told back-facing nodes apart");
    }
}
