//! The surface render pass: quadray's wall, terrain, photo and torus (and the displaced-mesh
//! baseline) drawn with any method by `surface.wgsl`, which is composed after the generated method
//! constants, `trace.wgsl` and `cone.wgsl`. Bindings by how often they change: group 0 per frame (the camera
//! and the settings), group 1 per map (its pyramid, textures and surface).

use super::height_pyramid::PyramidInfo;
use crate::method::Method;
use crate::scene::View;
use crate::settings::{Lod, Settings};
use quadray_gpu::{cleared_attachment, nearest_depth};
use std::collections::HashMap;
use wgpu::util::DeviceExt;

pub(super) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
pub(super) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
pub(super) const HIT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub(super) const SEARCH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// `surface.wgsl`'s `MapParams` (group 1).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct MapParams {
    pub plane_origin: [f32; 4],
    pub plane_u: [f32; 4],
    pub plane_v: [f32; 4],
    pub pyramid: PyramidInfo,
    pub tile_world: f32,
    pub mesh_grid: u32,
    pub tiles: u32,
    pub _pad: u32,
}

/// `surface.wgsl`'s `FrameParams` (group 0).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct FrameParams {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub light: [f32; 4],
    pub depth_scale: f32,
    pub lod: i32,
    pub layers_min: f32,
    pub layers_max: f32,
    pub binary_steps: u32,
    pub shadows: u32,
    pub show_iterations: u32,
    pub _pad: u32,
}

impl FrameParams {
    /// The uniform for `s` seen from `view`, on a map whose coarsest level is `top_level`: the
    /// one place the settings reach the shader.
    pub fn new(s: &Settings, view: &View, top_level: u32) -> Self {
        let v4 = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        Self {
            view_proj: view.view_proj.to_cols_array_2d(),
            eye: v4(view.eye),
            light: v4(view.light),
            depth_scale: s.depth_scale,
            lod: match s.lod {
                Lod::Auto => -1,
                Lod::Level(l) => l.min(top_level) as i32,
            },
            layers_min: s.layers.min as f32,
            layers_max: s.layers.max as f32,
            binary_steps: s.binary_steps,
            shadows: u32::from(s.shadows),
            show_iterations: u32::from(s.show_iterations),
            _pad: 0,
        }
    }
}

/// The surface shader's whole source: the method ids, the tracing module, the cone trace, the
/// passes' code.
pub(super) fn shader_source() -> String {
    [
        Method::wgsl_constants().as_str(),
        super::TRACE_WGSL,
        include_str!("cone.wgsl"),
        include_str!("surface.wgsl"),
    ]
    .join("\n")
}

fn uniform_entry<T>(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<T>() as u64),
        },
        count: None,
    }
}

/// Where a frame is drawn: `color` Rgba8UnormSrgb and `depth` Depth32Float, of the same size.
#[derive(Clone, Copy)]
pub struct Targets<'a> {
    /// The colour attachment (Rgba8UnormSrgb).
    pub color: &'a wgpu::TextureView,
    /// The depth attachment (Depth32Float).
    pub depth: &'a wgpu::TextureView,
}

/// The per-pixel outputs beside the colour that tests and benchmarks read back: the hit
/// (Rgba32Float), the ray (Rgba32Float), and the texels read and the shadow flag (Rg32Float).
pub(super) struct DebugTargets<'a> {
    pub hits: &'a wgpu::TextureView,
    pub rays: &'a wgpu::TextureView,
    pub search: &'a wgpu::TextureView,
}

/// The textures of one map, for [`SurfacePass::map_group`].
pub(super) struct MapTextures<'a> {
    /// The pyramid the method traces (point or conservative), or the cone map.
    pub pyramid: &'a wgpu::TextureView,
    /// The map itself at mip 0 (the point pyramid).
    pub depth_map: &'a wgpu::TextureView,
    pub normal_map: &'a wgpu::TextureView,
    pub color_map: &'a wgpu::TextureView,
}

/// What a draw covers: the surface's triangles, or the mesh baseline's grid instanced over the
/// tiles listed (those in view, ascending).
pub(super) enum Geometry<'a> {
    Triangles(&'a wgpu::Buffer, u32),
    MeshGrid { grid: u32, tiles: &'a [u32] },
}

pub(super) struct SurfacePass {
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    map_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    frame_params: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    /// (method, with the hit and ray outputs) -> pipeline.
    pipelines: HashMap<(Method, bool), wgpu::RenderPipeline>,
}

impl SurfacePass {
    pub fn new(device: &wgpu::Device) -> Self {
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("displace frame"),
            entries: &[uniform_entry::<FrameParams>(0)],
        });
        let texture = |binding, filterable| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let map_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("displace map"),
            entries: &[
                uniform_entry::<MapParams>(0),
                texture(1, false),
                texture(2, false),
                texture(3, true),
                texture(4, true),
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let frame_params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("displace frame params"),
            size: std::mem::size_of::<FrameParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("displace frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_params.as_entire_binding(),
            }],
        });
        Self {
            module: device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("surface.wgsl"),
                source: wgpu::ShaderSource::Wgsl(shader_source().into()),
            }),
            pipeline_layout: device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("displace"),
                bind_group_layouts: &[Some(&frame_layout), Some(&map_layout)],
                immediate_size: 0,
            }),
            map_layout,
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("linear repeat"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::Repeat,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            frame_params,
            frame_group,
            pipelines: HashMap::new(),
        }
    }

    /// A uniform buffer holding one map's parameters.
    pub fn map_params(device: &wgpu::Device, params: &MapParams) -> wgpu::Buffer {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("displace map params"),
            contents: bytemuck::bytes_of(params),
            usage: wgpu::BufferUsages::UNIFORM,
        })
    }

    /// The per-map bind group (group 1).
    pub fn map_group(
        &self,
        device: &wgpu::Device,
        params: &wgpu::Buffer,
        textures: MapTextures,
    ) -> wgpu::BindGroup {
        let view = wgpu::BindingResource::TextureView;
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("displace map"),
            layout: &self.map_layout,
            entries: &[
                (0, params.as_entire_binding()),
                (1, view(textures.pyramid)),
                (2, view(textures.depth_map)),
                (3, view(textures.normal_map)),
                (4, view(textures.color_map)),
                (5, wgpu::BindingResource::Sampler(&self.sampler)),
            ]
            .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource }),
        })
    }

    /// Sets the per-frame parameters (group 0) for the passes recorded next.
    pub fn write_frame(&self, queue: &wgpu::Queue, params: &FrameParams) {
        queue.write_buffer(&self.frame_params, 0, bytemuck::bytes_of(params));
    }

    fn pipeline(
        &mut self,
        device: &wgpu::Device,
        method: Method,
        debug_outputs: bool,
    ) -> &wgpu::RenderPipeline {
        let (layout, module) = (&self.pipeline_layout, &self.module);
        self.pipelines
            .entry((method, debug_outputs))
            .or_insert_with(|| {
                let mesh = method == Method::Mesh;
                let debug_target = |format| {
                    debug_outputs.then_some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })
                };
                let hit_target = debug_target(HIT_FORMAT);
                let constants = [("METHOD", f64::from(method.shader_id()))];
                let options = wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                };
                let vertex_layouts = [wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<crate::scene::Vertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2],
                }];
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(method.name()),
                    layout: Some(layout),
                    vertex: wgpu::VertexState {
                        module,
                        entry_point: Some(if mesh { "vs_mesh" } else { "vs_surface" }),
                        compilation_options: options.clone(),
                        buffers: if mesh { &[] } else { &vertex_layouts },
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: if mesh {
                            wgpu::PrimitiveTopology::TriangleStrip
                        } else {
                            wgpu::PrimitiveTopology::TriangleList
                        },
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(nearest_depth(DEPTH_FORMAT)),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module,
                        entry_point: Some(if mesh { "fs_mesh" } else { "fs_surface" }),
                        compilation_options: options,
                        targets: &[
                            Some(COLOR_FORMAT.into()),
                            hit_target.clone(),
                            hit_target,
                            debug_target(SEARCH_FORMAT),
                        ],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
    }

    /// Records the pass into `targets`, and into the debug targets when given. The frame parameters must have been written for this frame.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        method: Method,
        map_group: &wgpu::BindGroup,
        geometry: Geometry,
        targets: Targets,
        debug: Option<DebugTargets>,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let Targets { color, depth } = targets;
        let sky = wgpu::Color {
            r: 0.16,
            g: 0.18,
            b: 0.22,
            a: 1.0,
        };
        let no_surface = wgpu::Color {
            r: 0.0,
            g: 0.0,
            b: -2.0,
            a: 0.0,
        };
        let debug_outputs = debug.is_some();
        let color_attachments = match debug {
            Some(d) => [
                cleared_attachment(color, sky),
                cleared_attachment(d.hits, no_surface),
                cleared_attachment(d.rays, no_surface),
                cleared_attachment(d.search, wgpu::Color::TRANSPARENT),
            ],
            None => [cleared_attachment(color, sky), None, None, None],
        };
        let pipeline = self.pipeline(device, method, debug_outputs).clone();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("displace"),
            color_attachments: &color_attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes,
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &self.frame_group, &[]);
        pass.set_bind_group(1, map_group, &[]);
        match geometry {
            Geometry::MeshGrid { grid, tiles } => {
                // one draw a run of consecutive tiles, an instance a row of quads
                for run in tiles.chunk_by(|a, b| a + 1 == *b) {
                    pass.draw(
                        0..2 * grid + 2,
                        run[0] * grid..(run[run.len() - 1] + 1) * grid,
                    );
                }
            }
            Geometry::Triangles(buffer, count) => {
                pass.set_vertex_buffer(0, buffer.slice(..));
                pass.draw(0..count, 0..1);
            }
        }
    }
}
