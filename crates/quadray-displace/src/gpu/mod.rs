//! The GPU side: the pyramid builder (compute, `pyramid.wgsl`) and the renderer that runs every
//! method through one shader (`displace.wgsl`) with one shading model.

use crate::DisplaceError;
use crate::heightmap::HeightMap;
use crate::method::Method;
use crate::pyramid::Addressing;
use crate::scene::{Plane, SurfaceKind, View};
use quadray_core::image_out::Rgba8Image;
use quadray_core::stats::Summary;
use quadray_gpu::{
    Gpu, GpuError, GpuTimer, cleared_attachment, nearest_depth, read_texture_f32,
    read_texture_rgba8, texture_2d,
};
use std::collections::HashMap;
use wgpu::util::DeviceExt;

/// Finest level the traversal may reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Lod {
    /// From screen-space derivatives of the texture coordinate, as mip selection does (3.4).
    Auto,
    Level(u32),
}

/// Everything a frame depends on besides the map and the surface.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Settings {
    pub method: Method,
    pub view_angle_deg: f32,
    pub width: u32,
    pub height: u32,
    /// Texture units per unit of depth (Bevy's default 0.1).
    pub depth_scale: f32,
    /// POM / relief layer counts, from head-on (min) to grazing (max).
    pub layers: (u32, u32),
    pub binary_steps: u32,
    pub lod: Lod,
    pub shadows: bool,
    /// Camera azimuth around the surface normal (degrees), distance factor, and the light's
    /// azimuth: the benchmark keeps the defaults; the viewer moves them.
    pub azimuth_deg: f32,
    pub zoom: f32,
    pub light_azimuth_deg: f32,
    /// Colour each pixel by the iterations its search took (0..64, black to white).
    pub show_iterations: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            method: Method::Pyramid,
            view_angle_deg: 45.0,
            width: 512,
            height: 512,
            depth_scale: 0.1,
            layers: (8, 32),
            binary_steps: 5,
            lod: Lod::Level(0),
            shadows: false,
            azimuth_deg: 30.0,
            zoom: 1.0,
            light_azimuth_deg: 30.0,
            show_iterations: false,
        }
    }
}

impl Settings {
    /// Refuses parameters that would make no picture or an absurd amount of work.
    pub fn validate(&self) -> Result<(), String> {
        let s = self;
        if !(s.view_angle_deg.is_finite() && (0.0..=89.0).contains(&s.view_angle_deg)) {
            return Err(format!(
                "view angle {} is outside 0..89 degrees",
                s.view_angle_deg
            ));
        }
        if !(1..=8192).contains(&s.width) || !(1..=8192).contains(&s.height) {
            return Err(format!(
                "size {}x{} is outside 1x1..8192x8192",
                s.width, s.height
            ));
        }
        if !(s.depth_scale.is_finite() && s.depth_scale > 0.0 && s.depth_scale <= 10.0) {
            return Err(format!("depth scale {} is outside (0, 10]", s.depth_scale));
        }
        if s.layers.0 < 1 || s.layers.0 > s.layers.1 || s.layers.1 > 4096 {
            return Err(format!(
                "layers {},{} must satisfy 1 <= min <= max <= 4096",
                s.layers.0, s.layers.1
            ));
        }
        if !(s.azimuth_deg.is_finite() && s.light_azimuth_deg.is_finite()) {
            return Err("azimuths must be finite".into());
        }
        if !(s.zoom.is_finite() && (0.05..=20.0).contains(&s.zoom)) {
            return Err(format!("zoom {} is outside 0.05..20", s.zoom));
        }
        if s.binary_steps > 64 {
            return Err(format!("{} binary steps is more than 64", s.binary_steps));
        }
        Ok(())
    }
}

/// What one frame produced, read back.
pub struct Frame {
    pub color: Rgba8Image,
    /// Per pixel: hit u, hit v, hit depth (-1: left the map, -2: no surface), iterations
    /// (negative: stopped by the cap).
    pub hits: Vec<[f32; 4]>,
    /// Per pixel: the ray's p0 and e.
    pub rays: Vec<[f32; 4]>,
}

/// Hard cap on any one trace; the per-ray bound in the shader is far lower.
pub const ITERATION_CAP: u32 = 1 << 20;
const BILINEAR_ROUNDS: u32 = 1 << 16;
const HIT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    plane_origin: [f32; 4],
    plane_u: [f32; 4],
    plane_v: [f32; 4],
    tile_world: f32,
    depth_scale: f32,
    levels: i32,
    lod: i32,
    layers_min: f32,
    layers_max: f32,
    binary_steps: u32,
    iteration_cap: u32,
    clamp_to_map: u32,
    shadows: u32,
    mesh_grid: u32,
    tiles: u32,
    bilinear_cap: u32,
    show_iterations: u32,
    _pad: [u32; 2],
}

/// Builds min-depth pyramids on the GPU (one compute dispatch per level).
pub struct PyramidBuilder {
    reduce: wgpu::ComputePipeline,
    dilate_wrap: wgpu::ComputePipeline,
    dilate_clamp: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl PyramidBuilder {
    pub fn new(gpu: &Gpu) -> Self {
        let module = gpu
            .device
            .create_shader_module(wgpu::include_wgsl!("pyramid.wgsl"));
        let layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("pyramid level pair"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 1,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::StorageTexture {
                            access: wgpu::StorageTextureAccess::WriteOnly,
                            format: wgpu::TextureFormat::R32Float,
                            view_dimension: wgpu::TextureViewDimension::D2,
                        },
                        count: None,
                    },
                ],
            });
        let pipeline_layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("pyramid"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
        let pipeline = |entry: &str, wrap: f64| {
            gpu.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &[("WRAP", wrap)],
                        ..Default::default()
                    },
                    cache: None,
                })
        };
        Self {
            reduce: pipeline("reduce", 1.0),
            dilate_wrap: pipeline("dilate", 1.0),
            dilate_clamp: pipeline("dilate", 0.0),
            layout,
        }
    }

    /// Uploads `map` and builds its pyramid: the paper's, or with `conservative` the bound for the
    /// bilinear surface under that addressing. Returns (map texture, pyramid texture).
    pub fn build(
        &self,
        gpu: &Gpu,
        map: &HeightMap,
        conservative: Option<Addressing>,
        timer: Option<&GpuTimer>,
    ) -> (wgpu::Texture, wgpu::Texture) {
        let size = map.size();
        let extent = wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: 1,
        };
        let usage = wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC;
        let depth = gpu.device.create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some("depth map"),
                size: extent,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R32Float,
                usage,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&map.depth),
        );
        let pyramid = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("min-depth pyramid"),
            size: extent,
            mip_level_count: map.levels + 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage,
            view_formats: &[],
        });
        let level_view = |t: &wgpu::Texture, level: u32| {
            t.create_view(&wgpu::TextureViewDescriptor {
                base_mip_level: level,
                mip_level_count: Some(1),
                ..Default::default()
            })
        };
        let bind = |src: &wgpu::TextureView, dst: &wgpu::TextureView| {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pyramid level pair"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(src),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(dst),
                    },
                ],
            })
        };
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        match conservative {
            None => encoder.copy_texture_to_texture(
                depth.as_image_copy(),
                pyramid.as_image_copy(),
                extent,
            ),
            Some(addressing) => {
                let pipeline = match addressing {
                    Addressing::Wrap => &self.dilate_wrap,
                    Addressing::Clamp => &self.dilate_clamp,
                };
                let group = bind(&level_view(&depth, 0), &level_view(&pyramid, 0));
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(size.div_ceil(8), size.div_ceil(8), 1);
            }
        }
        {
            let groups: Vec<_> = (1..=map.levels)
                .map(|k| bind(&level_view(&pyramid, k - 1), &level_view(&pyramid, k)))
                .collect();
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pyramid reduce"),
                timestamp_writes: timer.and_then(|t| t.compute_pass(0)),
            });
            pass.set_pipeline(&self.reduce);
            for (k, group) in (1..=map.levels).zip(&groups) {
                let side = size >> k;
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(side.div_ceil(8), side.div_ceil(8), 1);
            }
        }
        if let Some(t) = timer {
            t.resolve(&mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);
        (depth, pyramid)
    }
}

/// Reads every level of a pyramid texture back, finest first.
pub fn read_pyramid(gpu: &Gpu, pyramid: &wgpu::Texture) -> Result<Vec<Vec<f32>>, GpuError> {
    (0..pyramid.mip_level_count())
        .map(|level| read_texture_f32(gpu, pyramid, level, 1))
        .collect()
}

/// Where a frame is drawn: `color` Rgba8UnormSrgb and `depth` Depth32Float, of the same size.
#[derive(Clone, Copy)]
pub struct Targets<'a> {
    pub color: &'a wgpu::TextureView,
    pub depth: &'a wgpu::TextureView,
}

/// One map on one surface, ready to render with any method.
pub struct Renderer {
    map_levels: u32,
    map_size: u32,
    surface: SurfaceKind,
    bind_group_point: wgpu::BindGroup,
    bind_group_conservative: wgpu::BindGroup,
    layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    params: wgpu::Buffer,
    quad: wgpu::Buffer,
    vertex_count: u32,
    /// (method, with debug outputs) -> pipeline.
    pipelines: HashMap<(Method, bool), wgpu::RenderPipeline>,
}

impl Renderer {
    /// `color`: the albedo texture; `None` tints by depth.
    pub fn new(
        gpu: &Gpu,
        map: &HeightMap,
        color: Option<&Rgba8Image>,
        surface: SurfaceKind,
    ) -> Self {
        let addressing = if surface.wraps() {
            Addressing::Wrap
        } else {
            Addressing::Clamp
        };
        let builder = PyramidBuilder::new(gpu);
        let (depth, point_pyramid) = builder.build(gpu, map, None, None);
        let (_, conservative_pyramid) = builder.build(gpu, map, Some(addressing), None);
        let tinted;
        let color = match color {
            Some(c) => c,
            None => {
                tinted = tint_by_depth(map);
                &tinted
            }
        };
        let color_texture = gpu.device.create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some("albedo"),
                size: wgpu::Extent3d {
                    width: color.width,
                    height: color.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8UnormSrgb,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            color.pixels.as_flattened(),
        );
        let normal_map = upload_gradients(gpu, map);
        let layout_entries: Vec<_> = (0..6)
            .map(|binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: match binding {
                    0 => wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    5 => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    _ => wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float {
                            filterable: binding >= 3,
                        },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                },
                count: None,
            })
            .collect();
        let bind_layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("displace"),
                entries: &layout_entries,
            });
        let params = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("displace params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear repeat"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let views = [
            &point_pyramid,
            &conservative_pyramid,
            &depth,
            &color_texture,
        ]
        .map(|t| t.create_view(&Default::default()));
        let normal_view = normal_map.create_view(&Default::default());
        let group = |pyramid: &wgpu::TextureView| {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("displace"),
                layout: &bind_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(pyramid),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&views[2]),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(&normal_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::TextureView(&views[3]),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::Sampler(&sampler),
                    },
                ],
            })
        };
        let layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("displace"),
                bind_group_layouts: &[Some(&bind_layout)],
                immediate_size: 0,
            });
        let vertices = surface.vertices();
        let quad = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("surface triangles"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX,
            });
        Self {
            map_levels: map.levels,
            map_size: map.size(),
            surface,
            bind_group_point: group(&views[0]),
            bind_group_conservative: group(&views[1]),
            layout,
            module: gpu
                .device
                .create_shader_module(wgpu::include_wgsl!("displace.wgsl")),
            params,
            quad,
            vertex_count: vertices.len() as u32,
            pipelines: HashMap::new(),
        }
    }

    pub fn surface(&self) -> SurfaceKind {
        self.surface
    }

    /// Memory the method needs beyond the albedo: (bytes, what).
    pub fn memory_bytes(&self, method: Method) -> u64 {
        let texels = u64::from(self.map_size).pow(2);
        match method {
            // Pyramid levels above 0 add a third; normal map RGBA16F.
            Method::Pyramid | Method::PyramidAscend | Method::PyramidBilinear => {
                texels * 4 * 4 / 3 + texels * 8
            }
            Method::Mesh => {
                // The paper's figure 20 counts a vertex buffer (position + normal) per grid point.
                let vertices = (u64::from(self.map_size) + 1).pow(2);
                vertices * 24 + texels * 4 + texels * 8
            }
            _ => texels * 4 + texels * 8,
        }
    }

    fn pipeline(
        &mut self,
        gpu: &Gpu,
        method: Method,
        debug_outputs: bool,
    ) -> &wgpu::RenderPipeline {
        let (layout, module) = (&self.layout, &self.module);
        self.pipelines
            .entry((method, debug_outputs))
            .or_insert_with(|| {
                let mesh = method == Method::Mesh;
                let hit_target = debug_outputs.then_some(wgpu::ColorTargetState {
                    format: HIT_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                });
                let constants = [("METHOD", method.shader_id())];
                let options = wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                };
                let vertex_layouts = [Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<crate::scene::Vertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2],
                })];
                gpu.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some(method.name()),
                        layout: Some(layout),
                        vertex: wgpu::VertexState {
                            module,
                            entry_point: Some(if mesh { "vs_mesh" } else { "vs_surface" }),
                            compilation_options: options.clone(),
                            buffers: if mesh { &[] } else { &vertex_layouts },
                        },
                        primitive: wgpu::PrimitiveState {
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
                            ],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
            })
    }

    fn write_params(&mut self, gpu: &Gpu, s: &Settings, view: &View) {
        let plane = Plane::of(self.surface);
        let v4 = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        let params = Params {
            view_proj: view.view_proj.to_cols_array_2d(),
            eye: v4(view.eye),
            light: v4(view.light),
            plane_origin: v4(plane.origin),
            plane_u: v4(plane.u),
            plane_v: v4(plane.v),
            tile_world: self.surface.tile_world(),
            depth_scale: s.depth_scale,
            levels: self.map_levels as i32,
            lod: match s.lod {
                Lod::Auto => -1,
                Lod::Level(l) => l.min(self.map_levels) as i32,
            },
            layers_min: s.layers.0 as f32,
            layers_max: s.layers.1 as f32,
            binary_steps: s.binary_steps,
            iteration_cap: ITERATION_CAP,
            clamp_to_map: u32::from(!self.surface.wraps()),
            shadows: u32::from(s.shadows),
            mesh_grid: self.map_size,
            tiles: self.surface.tiles(),
            bilinear_cap: BILINEAR_ROUNDS,
            show_iterations: u32::from(s.show_iterations),
            _pad: [0; 2],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
    }

    fn targets(gpu: &Gpu, s: &Settings, debug_outputs: bool) -> Vec<wgpu::Texture> {
        let make = |format, label| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
            texture_2d(gpu, label, (s.width, s.height), format, usage)
        };
        let mut t = vec![make(COLOR_FORMAT, "color"), make(DEPTH_FORMAT, "depth")];
        if debug_outputs {
            t.push(make(HIT_FORMAT, "hits"));
            t.push(make(HIT_FORMAT, "rays"));
        }
        t
    }

    /// Records the shading pass into `color` (Rgba8UnormSrgb) and `depth` (Depth32Float), and
    /// into the hit and ray targets (Rgba32Float) when given. The parameters must have been
    /// written for this frame.
    fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        method: Method,
        targets: Targets,
        debug: Option<(&wgpu::TextureView, &wgpu::TextureView)>,
        timer: Option<&GpuTimer>,
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
        let color_attachments = match debug {
            Some((hits, rays)) => [
                cleared_attachment(color, sky),
                cleared_attachment(hits, no_surface),
                cleared_attachment(rays, no_surface),
            ],
            None => [cleared_attachment(color, sky), None, None],
        };
        let bind_group = if method.uses_conservative_pyramid() {
            self.bind_group_conservative.clone()
        } else {
            self.bind_group_point.clone()
        };
        let tiles = self.surface.tiles();
        let grid = self.map_size;
        let vertex_count = self.vertex_count;
        let quad = self.quad.clone();
        let pipeline = self.pipeline(gpu, method, debug.is_some()).clone();
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
            timestamp_writes: timer.and_then(|t| t.render_pass(0)),
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        if method == Method::Mesh {
            pass.draw(0..6 * grid * grid, 0..tiles * tiles);
        } else {
            pass.set_vertex_buffer(0, quad.slice(..));
            pass.draw(0..vertex_count, 0..1);
        }
    }

    /// Draws one frame into an application's own targets, seen from `view`. `timer`, when given,
    /// times the pass as its query 0.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        s: &Settings,
        view: &View,
        targets: Targets,
        timer: Option<&GpuTimer>,
    ) -> Result<(), DisplaceError> {
        self.check(s)?;
        self.write_params(gpu, s, view);
        self.encode(gpu, encoder, s.method, targets, None, timer);
        Ok(())
    }

    fn check(&self, s: &Settings) -> Result<(), DisplaceError> {
        s.validate().map_err(DisplaceError::Settings)?;
        if s.method == Method::Mesh && !self.surface.is_planar() {
            return Err(DisplaceError::Settings(format!(
                "the mesh baseline displaces a flat grid; the {:?} surface is curved",
                self.surface
            )));
        }
        Ok(())
    }

    /// Renders one frame with the hit and ray outputs and reads everything back.
    pub fn render(&mut self, gpu: &Gpu, s: &Settings) -> Result<Frame, DisplaceError> {
        self.check(s)?;
        self.write_params(gpu, s, &View::of(self.surface, s));
        let targets = Self::targets(gpu, s, true);
        let views: Vec<_> = targets
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        gpu.checked(|| {
            self.encode(
                gpu,
                &mut encoder,
                s.method,
                Targets {
                    color: &views[0],
                    depth: &views[1],
                },
                Some((&views[2], &views[3])),
                None,
            )
        })?;
        gpu.queue.submit([encoder.finish()]);
        let pixels = |v: Vec<f32>| -> Vec<[f32; 4]> {
            v.chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect()
        };
        Ok(Frame {
            color: Rgba8Image::from_bytes(
                s.width,
                s.height,
                &read_texture_rgba8(gpu, &targets[0])?,
            ),
            hits: pixels(read_texture_f32(gpu, &targets[2], 0, 4)?),
            rays: pixels(read_texture_f32(gpu, &targets[3], 0, 4)?),
        })
    }

    /// GPU time of the shading pass alone (colour target only, as an application would draw),
    /// median of `frames` frames after two warm-up frames. `None` without timestamp queries.
    pub fn time(
        &mut self,
        gpu: &Gpu,
        s: &Settings,
        frames: usize,
    ) -> Result<Option<Summary>, DisplaceError> {
        self.check(s)?;
        let view = View::of(self.surface, s);
        let targets = Self::targets(gpu, s, false);
        let views: Vec<_> = targets
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let mut timer = GpuTimer::new(gpu, 1);
        for frame in 0..frames + 2 {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            gpu.checked(|| {
                self.draw(
                    gpu,
                    &mut encoder,
                    s,
                    &view,
                    Targets {
                        color: &views[0],
                        depth: &views[1],
                    },
                    Some(&timer),
                )
            })??;
            timer.resolve(&mut encoder);
            gpu.queue.submit([encoder.finish()]);
            timer.collect(gpu)?;
            if frame == 1 {
                timer.clear();
            }
        }
        Ok(timer.summaries()[0])
    }
}

/// Depth gradients per unit of uv at texel centres (central differences), filtered by the sampler
/// and turned into normals in the shader with the frame's depth scale: n ~ (grad * s, 1).
fn upload_gradients(gpu: &Gpu, map: &HeightMap) -> wgpu::Texture {
    let n = map.size() as i64;
    let d = |i: i64, j: i64| map.at(i.rem_euclid(n) as u32, j.rem_euclid(n) as u32);
    let mut texels: Vec<half::f16> = Vec::with_capacity((n * n * 4) as usize);
    for j in 0..n {
        for i in 0..n {
            let du = (d(i + 1, j) - d(i - 1, j)) * 0.5 * n as f32;
            let dv = (d(i, j + 1) - d(i, j - 1)) * 0.5 * n as f32;
            texels.extend([du, dv, 0.0, 0.0].map(half::f16::from_f32));
        }
    }
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("depth gradients"),
            size: wgpu::Extent3d {
                width: n as u32,
                height: n as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&texels),
    )
}

/// An albedo for maps without a colour image: warm stone, darker with depth.
fn tint_by_depth(map: &HeightMap) -> Rgba8Image {
    let mut img = Rgba8Image::new(map.size(), map.size(), [0, 0, 0, 255]);
    for (px, d) in img.pixels.iter_mut().zip(&map.depth) {
        let k = 1.0 - 0.55 * d;
        *px = [(220.0 * k) as u8, (190.0 * k) as u8, (150.0 * k) as u8, 255];
    }
    img
}
