//! Pipelines, render targets and buffers, and the recording of every pass.

use super::{Method, Pass, Settings, Validity};
use crate::IndirectError;
use crate::baselines;
use crate::scene::{Scene, Vertex};
use glam::Vec3;
use quadray_gpu::{Gpu, GpuTimer, cleared_attachment, nearest_depth, texture_2d};
use wgpu::util::DeviceExt;

const FLOAT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Bound on the pyramid's levels (a 1024^2 RSM has 11).
const MAX_LEVELS: u32 = 16;
/// Items (VPLs, clusters, samples) one dispatch of a per-pixel sum covers; longer sums take
/// several dispatches that add up. lavapipe (llvmpipe) silently ends an invocation's loops after
/// 65,535 iterations in all, which cut a 512^2 brute force to the RSM's top rows; on a GPU it
/// keeps each dispatch short. Mirrors `SLICE` in common.wgsl.
const SLICE: u64 = 32768;
/// Nodes one dispatch of a per-level pass covers: each node's cut test climbs up to 10
/// ancestors, so fewer nodes keep it under lavapipe's limit too. Mirrors `LEVEL_SLICE`.
const LEVEL_SLICE: u64 = 2048;
/// Slice uniform slots: enough for level 0 of a 1024^2 RSM in level slices, the longest sum.
const MAX_SLICES: u32 = (1024 * 1024 / LEVEL_SLICE) as u32;

/// Dispatches a sum over `items` takes, `per_slice` items each.
fn slices(items: u64, per_slice: u64) -> u32 {
    items.div_ceil(per_slice).clamp(1, u64::from(MAX_SLICES)) as u32
}

const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];

const COMMON: &str = include_str!("common.wgsl");
const LIGHT: &str = include_str!("light.wgsl");
const CUT_RULE: &str = include_str!("cut_rule.wgsl");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightUniform {
    view_proj: [[f32; 4]; 4],
    position: [f32; 4],
    direction: [f32; 4],
    intensity: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RasterUniform {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    texel: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ClusterUniform {
    rsm_size: u32,
    levels: u32,
    start_level: u32,
    limit_level: u32,
    recursive: u32,
    flux_weighted: u32,
    depth_threshold: f32,
    normal_threshold: f32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadeUniform {
    width: u32,
    height: u32,
    r_min: f32,
    sample_count: u32,
    subsample: u32,
    low_width: u32,
    low_height: u32,
    depth_bias: f32,
    normal_agreement: f32,
    plane_agreement: f32,
    pad: [u32; 2],
}

fn low_size(settings: &Settings) -> (u32, u32) {
    (
        settings.width.div_ceil(settings.subsample),
        settings.height.div_ceil(settings.subsample),
    )
}

fn float_target(
    gpu: &Gpu,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    texture_2d(
        gpu,
        label,
        size,
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    )
}

/// The RSM (flux, position + depth, normal) and the G-buffer (position, normal, albedo).
pub(super) struct Targets {
    pub rsm: [wgpu::Texture; 3],
    rsm_depth: wgpu::Texture,
    pub gbuffer: [wgpu::Texture; 3],
    gbuffer_depth: wgpu::Texture,
}

impl Targets {
    pub fn new(gpu: &Gpu, s: &Settings) -> Self {
        let rsm = (s.rsm_size, s.rsm_size);
        let screen = (s.width, s.height);
        Self {
            rsm: ["rsm flux", "rsm position", "rsm normal"]
                .map(|l| float_target(gpu, l, rsm, FLOAT_FORMAT)),
            rsm_depth: float_target(gpu, "rsm depth", rsm, DEPTH_FORMAT),
            gbuffer: ["g position", "g normal", "g albedo"]
                .map(|l| float_target(gpu, l, screen, FLOAT_FORMAT)),
            gbuffer_depth: float_target(gpu, "g depth", screen, DEPTH_FORMAT),
        }
    }
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

fn storage_buffer(gpu: &Gpu, label: &str, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn uniform_buffer(gpu: &Gpu, label: &str, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Total nodes of the pyramid of an RSM of side `rsm_size`.
pub(super) fn node_count(rsm_size: u32) -> u64 {
    (0..=rsm_size.ilog2())
        .map(|l| u64::from(rsm_size >> l).pow(2))
        .sum()
}

/// Index of the first node of `level`.
pub(super) fn level_offset(rsm_size: u32, level: u32) -> u64 {
    (0..level).map(|l| u64::from(rsm_size >> l).pow(2)).sum()
}

/// Uniforms, the scene's vertices, the quadtree and cut, the per-pixel outputs, and the bind
/// groups tying them to the targets.
pub(super) struct Buffers {
    vertices: wgpu::Buffer,
    light: wgpu::Buffer,
    raster_rsm: wgpu::Buffer,
    raster_camera: wgpu::Buffer,
    cluster: wgpu::Buffer,
    shade: wgpu::Buffer,
    /// One `level` per uniform slot, bound with a dynamic offset.
    level_stride: u32,
    pub nodes: wgpu::Buffer,
    pub cut: wgpu::Buffer,
    pub cut_count: wgpu::Buffer,
    pub indirect: wgpu::Buffer,
    pub direct: wgpu::Buffer,
    rsm_group: wgpu::BindGroup,
    camera_group: wgpu::BindGroup,
    cluster_group: wgpu::BindGroup,
    shade_group: wgpu::BindGroup,
}

impl Buffers {
    pub fn new(
        gpu: &Gpu,
        scene: &Scene,
        s: &Settings,
        samples: &[[f32; 4]],
        pipelines: &Pipelines,
        targets: &Targets,
    ) -> Self {
        let d = &gpu.device;
        let vertices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vertices"),
            contents: bytemuck::cast_slice(&scene.triangles),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let light = uniform_buffer(gpu, "light", size_of::<LightUniform>() as u64);
        let raster_rsm = uniform_buffer(gpu, "raster rsm", size_of::<RasterUniform>() as u64);
        let raster_camera = uniform_buffer(gpu, "raster camera", size_of::<RasterUniform>() as u64);
        let cluster = uniform_buffer(gpu, "cluster", size_of::<ClusterUniform>() as u64);
        let shade = uniform_buffer(gpu, "shade", size_of::<ShadeUniform>() as u64);
        let level_stride = d.limits().min_uniform_buffer_offset_alignment.max(16);
        // uniform slots holding 0, 1, 2, ..., one bound per dispatch with a dynamic offset
        let slots = |label, count: u32| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &(0..count)
                    .flat_map(|i| {
                        let mut slot = vec![0u8; level_stride as usize];
                        slot[..4].copy_from_slice(&i.to_le_bytes());
                        slot
                    })
                    .collect::<Vec<u8>>(),
                usage: wgpu::BufferUsages::UNIFORM,
            })
        };
        let levels = slots("levels", MAX_LEVELS);
        let slice_slots = slots("slices", MAX_SLICES);
        let nodes = storage_buffer(gpu, "nodes", node_count(s.rsm_size) * 48);
        // a cut partitions the RSM: at most one cluster per texel
        let cut = storage_buffer(gpu, "cut", u64::from(s.rsm_size).pow(2) * 48);
        let cut_count = storage_buffer(gpu, "cut count", 4);
        let pixels = u64::from(s.width) * u64::from(s.height);
        let indirect = storage_buffer(gpu, "indirect", pixels * 16);
        let direct = storage_buffer(gpu, "direct", pixels * 16);
        let (lw, lh) = low_size(s);
        let low = storage_buffer(gpu, "low-resolution indirect", u64::from(lw * lh) * 16);
        let samples_buffer = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("rsm samples"),
            contents: bytemuck::cast_slice(samples),
            usage: wgpu::BufferUsages::STORAGE,
        });

        fn whole(b: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
            b.as_entire_binding()
        }
        let slot_binding = |buffer| {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset: 0,
                size: wgpu::BufferSize::new(16),
            })
        };
        let level_binding = || slot_binding(&levels);
        let raster_group = |uniform: &wgpu::Buffer| {
            d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("raster"),
                layout: &pipelines.raster_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: whole(&light),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: whole(uniform),
                    },
                ],
            })
        };
        let rsm_views = targets.rsm.each_ref().map(view);
        let g_views = targets.gbuffer.each_ref().map(view);
        fn tex(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::TextureView(v)
        }
        fn entries(list: Vec<wgpu::BindingResource<'_>>) -> Vec<wgpu::BindGroupEntry<'_>> {
            list.into_iter()
                .enumerate()
                .map(|(i, resource)| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource,
                })
                .collect()
        }
        let cluster_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cluster"),
            layout: &pipelines.cluster_layout,
            entries: &entries(vec![
                whole(&cluster),
                level_binding(),
                tex(&rsm_views[0]),
                tex(&rsm_views[1]),
                tex(&rsm_views[2]),
                whole(&nodes),
                whole(&cut),
                whole(&cut_count),
            ]),
        });
        let shade_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shade"),
            layout: &pipelines.shade_layout,
            entries: &entries(vec![
                whole(&cluster),
                whole(&shade),
                level_binding(),
                whole(&light),
                tex(&g_views[0]),
                tex(&g_views[1]),
                tex(&g_views[2]),
                tex(&rsm_views[0]),
                tex(&rsm_views[1]),
                tex(&rsm_views[2]),
                whole(&nodes),
                whole(&cut),
                whole(&cut_count),
                whole(&indirect),
                whole(&direct),
                whole(&low),
                whole(&samples_buffer),
                slot_binding(&slice_slots),
            ]),
        });
        let buffers = Self {
            rsm_group: raster_group(&raster_rsm),
            camera_group: raster_group(&raster_camera),
            vertices,
            light,
            raster_rsm,
            raster_camera,
            cluster,
            shade,
            level_stride,
            nodes,
            cut,
            cut_count,
            indirect,
            direct,
            cluster_group,
            shade_group,
        };
        buffers.write_scene(gpu, scene, s);
        buffers
    }

    /// Light, cameras and per-frame constants.
    pub fn write_scene(&self, gpu: &Gpu, scene: &Scene, s: &Settings) {
        let q = &gpu.queue;
        let l = &scene.light;
        let extent = scene.extent();
        let cone = l.cone_deg.to_radians();
        let light_view_proj = scene.light_view_proj().to_cols_array_2d();
        let dir = Vec3::from(l.direction).normalize();
        let [x, y, z] = l.position;
        q.write_buffer(
            &self.light,
            0,
            bytemuck::bytes_of(&LightUniform {
                view_proj: light_view_proj,
                position: [x, y, z, 1.0 / extent],
                direction: [dir.x, dir.y, dir.z, cone.cos()],
                intensity: [
                    l.intensity[0],
                    l.intensity[1],
                    l.intensity[2],
                    (cone - l.falloff_deg.to_radians()).cos(),
                ],
            }),
        );
        let texel_side = 2.0 * cone.tan() / s.rsm_size as f32;
        q.write_buffer(
            &self.raster_rsm,
            0,
            bytemuck::bytes_of(&RasterUniform {
                view_proj: light_view_proj,
                eye: [x, y, z, 1.0],
                texel: [texel_side * texel_side, 0.0, 0.0, 0.0],
            }),
        );
        let [ex, ey, ez] = scene.camera.position;
        q.write_buffer(
            &self.raster_camera,
            0,
            bytemuck::bytes_of(&RasterUniform {
                view_proj: scene
                    .camera_view_proj(s.width as f32 / s.height as f32)
                    .to_cols_array_2d(),
                eye: [ex, ey, ez, 1.0],
                texel: [0.0; 4],
            }),
        );
        let (low_width, low_height) = low_size(s);
        q.write_buffer(
            &self.shade,
            0,
            bytemuck::bytes_of(&ShadeUniform {
                width: s.width,
                height: s.height,
                r_min: scene.r_min,
                sample_count: s.samples,
                subsample: s.subsample,
                low_width,
                low_height,
                // a few shadow-map texels' worth of depth at the far side of the scene
                depth_bias: 0.005 + 3.0 * texel_side * scene.light_far() / extent,
                normal_agreement: 0.9,
                plane_agreement: 0.02 * extent,
                pad: [0; 2],
            }),
        );
        self.write_cluster(gpu, s);
    }

    pub fn write_cluster(&self, gpu: &Gpu, s: &Settings) {
        let c = &s.cluster;
        gpu.queue.write_buffer(
            &self.cluster,
            0,
            bytemuck::bytes_of(&ClusterUniform {
                rsm_size: s.rsm_size,
                levels: s.rsm_size.ilog2() + 1,
                start_level: c.start_level,
                limit_level: c.limit_level,
                recursive: u32::from(c.validity == Validity::Recursive),
                flux_weighted: u32::from(c.flux_weighted),
                depth_threshold: c.depth_threshold,
                normal_threshold: c.normal_threshold,
            }),
        );
    }

    fn read_bytes(&self, gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>, IndirectError> {
        Ok(quadray_gpu::read_buffer(gpu, buffer)?)
    }

    pub fn read_vec4(
        &self,
        gpu: &Gpu,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<[f32; 4]>, IndirectError> {
        Ok(bytemuck::pod_collect_to_vec(&self.read_bytes(gpu, buffer)?))
    }

    pub fn read_u32(&self, gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u32>, IndirectError> {
        Ok(bytemuck::pod_collect_to_vec(&self.read_bytes(gpu, buffer)?))
    }

    fn level_offset(&self, level: u32) -> u32 {
        level * self.level_stride
    }

    /// The shading group's dynamic offsets: the level's slot, then the slice's.
    fn shade_offsets(&self, level: u32, slice: u32) -> [u32; 2] {
        [self.level_offset(level), slice * self.level_stride]
    }
}

/// Every pipeline and the layouts they share.
pub(super) struct Pipelines {
    raster_layout: wgpu::BindGroupLayout,
    cluster_layout: wgpu::BindGroupLayout,
    shade_layout: wgpu::BindGroupLayout,
    rsm: wgpu::RenderPipeline,
    gbuffer: wgpu::RenderPipeline,
    pack: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    validity: wgpu::ComputePipeline,
    select_cut: wgpu::ComputePipeline,
    indirect_cut: wgpu::ComputePipeline,
    indirect_level: wgpu::ComputePipeline,
    indirect_low: wgpu::ComputePipeline,
    upsample: wgpu::ComputePipeline,
    direct_light: wgpu::ComputePipeline,
    brute_force: wgpu::ComputePipeline,
    rsm_sampling: wgpu::ComputePipeline,
}

fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    dynamic: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn dispatch_2d(pass: &mut wgpu::ComputePass, width: u32, height: u32) {
    pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
}

impl Pipelines {
    pub fn new(gpu: &Gpu) -> Self {
        let d = &gpu.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let raster_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raster"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT, false),
                uniform_entry(1, wgpu::ShaderStages::VERTEX_FRAGMENT, false),
            ],
        });
        let cluster_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cluster"),
            entries: &[
                uniform_entry(0, compute, false),
                uniform_entry(1, compute, true),
                texture_entry(2),
                texture_entry(3),
                texture_entry(4),
                storage_entry(5, false),
                storage_entry(6, false),
                storage_entry(7, false),
            ],
        });
        let mut shade_entries = vec![
            uniform_entry(0, compute, false),
            uniform_entry(1, compute, false),
            uniform_entry(2, compute, true),
            uniform_entry(3, compute, false),
        ];
        shade_entries.extend((4..10).map(texture_entry));
        shade_entries.extend([
            storage_entry(10, true),
            storage_entry(11, true),
            storage_entry(12, true),
            storage_entry(13, false),
            storage_entry(14, false),
            storage_entry(15, false),
            storage_entry(16, true),
            uniform_entry(17, compute, true),
        ]);
        let shade_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade"),
            entries: &shade_entries,
        });
        let module = |label: &str, parts: &[&str]| {
            d.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(parts.concat().into()),
            })
        };
        let raster_module = module("raster", &[LIGHT, include_str!("raster.wgsl")]);
        let cluster_module = module("cluster", &[COMMON, CUT_RULE, include_str!("cluster.wgsl")]);
        let shade_module = module(
            "shade",
            &[
                COMMON,
                LIGHT,
                include_str!("shade_bindings.wgsl"),
                CUT_RULE,
                include_str!("shade.wgsl"),
                baselines::WGSL,
            ],
        );
        let layout = |group: &wgpu::BindGroupLayout| {
            d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(group)],
                immediate_size: 0,
            })
        };
        let raster_pipeline_layout = layout(&raster_layout);
        let raster = |fragment: &str| {
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fragment),
                layout: Some(&raster_pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &raster_module,
                    entry_point: Some("vertex"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &VERTEX_ATTRIBUTES,
                    })],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(nearest_depth(DEPTH_FORMAT)),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &raster_module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[
                        Some(FLOAT_FORMAT.into()),
                        Some(FLOAT_FORMAT.into()),
                        Some(FLOAT_FORMAT.into()),
                    ],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let cluster_pipeline_layout = layout(&cluster_layout);
        let shade_pipeline_layout = layout(&shade_layout);
        let compute_pipeline =
            |pl: &wgpu::PipelineLayout, module: &wgpu::ShaderModule, entry: &str| {
                d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(pl),
                    module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
            };
        let cluster = |entry| compute_pipeline(&cluster_pipeline_layout, &cluster_module, entry);
        let shade = |entry| compute_pipeline(&shade_pipeline_layout, &shade_module, entry);
        Self {
            rsm: raster("rsm"),
            gbuffer: raster("gbuffer"),
            pack: cluster("pack"),
            reduce: cluster("reduce"),
            validity: cluster("validity"),
            select_cut: cluster("select_cut"),
            indirect_cut: shade("indirect_cut"),
            indirect_level: shade("indirect_level"),
            indirect_low: shade("indirect_low"),
            upsample: shade("upsample"),
            direct_light: shade("direct_light"),
            brute_force: shade("brute_force"),
            rsm_sampling: shade("rsm_sampling"),
            raster_layout,
            cluster_layout,
            shade_layout,
        }
    }

    /// Rasterises the scene into the RSM (`Pass::Rsm`) or the G-buffer (`Pass::GBuffer`).
    pub fn raster(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        which: Pass,
        t: &Targets,
        b: &Buffers,
        vertex_count: u32,
        timer: Option<&GpuTimer>,
    ) {
        let (pipeline, group, colors, depth) = match which {
            Pass::Rsm => (&self.rsm, &b.rsm_group, &t.rsm, &t.rsm_depth),
            Pass::GBuffer => (&self.gbuffer, &b.camera_group, &t.gbuffer, &t.gbuffer_depth),
            other => unreachable!("{} is no raster pass", other.name()),
        };
        let views = colors.each_ref().map(view);
        let depth_view = view(depth);
        let attachments = views
            .each_ref()
            .map(|v| cleared_attachment(v, wgpu::Color::TRANSPARENT));
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("raster"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.and_then(|t| t.render_pass(which as u32)),
            ..Default::default()
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.set_vertex_buffer(0, b.vertices.slice(..));
        pass.draw(0..vertex_count, 0..1);
    }

    fn compute_pass<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        pass: Pass,
        timer: Option<&GpuTimer>,
    ) -> wgpu::ComputePass<'e> {
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: timer.and_then(|t| t.compute_pass(pass as u32)),
        })
    }

    /// Pyramid (pack + one reduce per level) and validity (one dispatch per level, finest first,
    /// so the recursive rule sees its children's verdicts).
    pub fn build_quadtree(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        b: &Buffers,
        s: &Settings,
        timer: Option<&GpuTimer>,
    ) {
        let top = s.rsm_size.ilog2();
        {
            let mut pass = Self::compute_pass(encoder, "pyramid", Pass::Pyramid, timer);
            pass.set_pipeline(&self.pack);
            pass.set_bind_group(0, &b.cluster_group, &[b.level_offset(0)]);
            dispatch_2d(&mut pass, s.rsm_size, s.rsm_size);
            pass.set_pipeline(&self.reduce);
            for level in 1..=top {
                pass.set_bind_group(0, &b.cluster_group, &[b.level_offset(level)]);
                dispatch_2d(&mut pass, s.rsm_size >> level, s.rsm_size >> level);
            }
        }
        let mut pass = Self::compute_pass(encoder, "validity", Pass::Validity, timer);
        pass.set_pipeline(&self.validity);
        for level in 1..=top {
            pass.set_bind_group(0, &b.cluster_group, &[b.level_offset(level)]);
            dispatch_2d(&mut pass, s.rsm_size >> level, s.rsm_size >> level);
        }
    }

    /// The compacted cut: one thread per node of the levels limit..start, atomic append.
    pub fn select_cut(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        b: &Buffers,
        s: &Settings,
        timer: Option<&GpuTimer>,
    ) {
        encoder.clear_buffer(&b.cut_count, 0, None);
        let c = &s.cluster;
        let nodes =
            level_offset(s.rsm_size, c.start_level + 1) - level_offset(s.rsm_size, c.limit_level);
        let mut pass = Self::compute_pass(encoder, "cut", Pass::Cut, timer);
        pass.set_pipeline(&self.select_cut);
        pass.set_bind_group(0, &b.cluster_group, &[b.level_offset(0)]);
        pass.dispatch_workgroups(nodes.div_ceil(256) as u32, 1, 1);
    }

    pub fn shade_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        b: &Buffers,
        s: &Settings,
        method: Method,
        timer: Option<&GpuTimer>,
    ) {
        let subsampled = method == Method::Quadtree && s.subsample > 1;
        let rsm_texels = u64::from(s.rsm_size).pow(2);
        // a cut partitions the RSM into nodes no finer than the limit level
        let cut_slices = slices(u64::from(s.rsm_size >> s.cluster.limit_level).pow(2), SLICE);
        if method == Method::QuadtreePasses {
            encoder.clear_buffer(&b.indirect, 0, None);
        }
        {
            let mut pass = Self::compute_pass(encoder, "indirect", Pass::Indirect, timer);
            // the sum over `items` in slices; the first slice writes, the others add
            let sliced = |pass: &mut wgpu::ComputePass, level: u32, count: u32, w, h| {
                for slice in 0..count {
                    pass.set_bind_group(0, &b.shade_group, &b.shade_offsets(level, slice));
                    dispatch_2d(pass, w, h);
                }
            };
            let (w, h) = (s.width, s.height);
            match method {
                Method::Quadtree if subsampled => {
                    pass.set_pipeline(&self.indirect_low);
                    let (lw, lh) = low_size(s);
                    sliced(&mut pass, 0, cut_slices, lw, lh);
                }
                Method::Quadtree => {
                    pass.set_pipeline(&self.indirect_cut);
                    sliced(&mut pass, 0, cut_slices, w, h);
                }
                Method::QuadtreePasses => {
                    pass.set_pipeline(&self.indirect_level);
                    let c = &s.cluster;
                    for level in (c.limit_level..=c.start_level).rev() {
                        let nodes = u64::from(s.rsm_size >> level).pow(2);
                        sliced(&mut pass, level, slices(nodes, LEVEL_SLICE), w, h);
                    }
                }
                Method::Rsm => {
                    pass.set_pipeline(&self.rsm_sampling);
                    sliced(&mut pass, 0, slices(u64::from(s.samples), SLICE), w, h);
                }
                Method::Reference => {
                    pass.set_pipeline(&self.brute_force);
                    sliced(&mut pass, 0, slices(rsm_texels, SLICE), w, h);
                }
            }
        }
        if subsampled {
            // where the upsampler recomputes a pixel it sums the cut, in the same slices
            let mut pass = Self::compute_pass(encoder, "upsample", Pass::Upsample, timer);
            pass.set_pipeline(&self.upsample);
            for slice in 0..cut_slices {
                pass.set_bind_group(0, &b.shade_group, &b.shade_offsets(0, slice));
                dispatch_2d(&mut pass, s.width, s.height);
            }
        }
    }

    pub fn shade_direct(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        b: &Buffers,
        s: &Settings,
        timer: Option<&GpuTimer>,
    ) {
        let mut pass = Self::compute_pass(encoder, "direct", Pass::Direct, timer);
        pass.set_bind_group(0, &b.shade_group, &b.shade_offsets(0, 0));
        pass.set_pipeline(&self.direct_light);
        dispatch_2d(&mut pass, s.width, s.height);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_cover_the_longest_sums_that_settings_allow() {
        // the largest RSM's VPLs (brute force, a cut of single VPLs), its finest level in level
        // slices (per-level passes), the most RSM samples: never clamped by the slot count
        let vpls = 1024u64 * 1024;
        for (items, per_slice) in [(vpls, SLICE), (vpls, LEVEL_SLICE), (65536, SLICE)] {
            let n = slices(items, per_slice);
            assert!(
                u64::from(n) * per_slice >= items,
                "{items} in {n} x {per_slice}"
            );
            assert!(n <= MAX_SLICES);
        }
        assert_eq!(slices(0, SLICE), 1, "an empty sum still writes its zeros");
        assert_eq!(slices(SLICE + 1, SLICE), 2);
    }
}
