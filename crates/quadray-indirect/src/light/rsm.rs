//! The RSM pass: the caller's triangles rasterised from one light view into a reflective shadow
//! map (flux, position + depth, normal), the input of the light quadtree. Also the raster
//! helpers quadray's own G-buffer pass and the direct light's shadow maps share.

use crate::contract::{
    LightUniform, RasterUniform, bind_group, layout, pipeline_layout, shader_module,
    uniform_buffer, uniform_entry, whole,
};
use crate::light::view::LightView;
use crate::scene::Vertex;
use crate::wgsl;
use quadray_gpu::{GpuTimer, cleared_attachment, nearest_depth, texture_2d};

/// Format of every RSM and G-buffer colour target.
pub const FLOAT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];

pub(crate) const RASTER_WGSL: &str = include_str!("raster.wgsl");
/// The RSM pass's shader, in order.
pub(crate) const SOURCES: [&str; 3] = [wgsl::LIGHT, RASTER_WGSL, include_str!("rsm.wgsl")];

/// The RSM as the quadtree and the gather read it, whoever renders it: three square textures of
/// the same side (a power of two), any float format `textureLoad` reads (quadray's are
/// [`FLOAT_FORMAT`]). An empty texel has `normal.w = 0`.
#[derive(Clone, Copy)]
pub struct RsmViews<'a> {
    /// rgb: flux the texel's surface reflects (W), `I(w) * solid angle * albedo` (parallel
    /// light: `E * area * albedo`); w unused.
    pub flux: &'a wgpu::TextureView,
    /// xyz: world position; w: depth along the light's axis in units of [`LightView::extent`].
    pub position: &'a wgpu::TextureView,
    /// xyz: unit normal facing the light; w: 1 where the light sees geometry, else 0.
    pub normal: &'a wgpu::TextureView,
}

/// A render target `size` (width, height), also bound as a texture and copied from.
pub(crate) fn target(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
        | wgpu::TextureUsages::TEXTURE_BINDING
        | wgpu::TextureUsages::COPY_SRC;
    texture_2d(device, label, size, format, usage)
}

pub(crate) fn view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&Default::default())
}

/// `N` float colour targets (three for the RSM and the G-buffer, none for a shadow map) and a
/// depth buffer of one size, as the raster passes write them.
pub(crate) struct RasterTargets<const N: usize = 3> {
    pub colors: [wgpu::Texture; N],
    pub views: [wgpu::TextureView; N],
    /// Also read as a texture: a shadow map's depth.
    pub depth: wgpu::TextureView,
}

impl<const N: usize> RasterTargets<N> {
    pub fn new(device: &wgpu::Device, labels: [&str; N], size: (u32, u32)) -> Self {
        let colors = labels.map(|l| target(device, l, size, FLOAT_FORMAT));
        let depth = target(device, "depth", size, DEPTH_FORMAT);
        Self {
            views: colors.each_ref().map(view),
            colors,
            depth: view(&depth),
        }
    }
}

/// A raster pipeline over [`Vertex`] triangles into `N` float targets (written by the entry
/// point `fragment`; none: depth only) with a depth test.
pub(crate) fn raster_pipeline<const N: usize>(
    device: &wgpu::Device,
    group: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
    label: &str,
    fragment: Option<&str>,
) -> wgpu::RenderPipeline {
    let targets: [Option<wgpu::ColorTargetState>; N] =
        std::array::from_fn(|_| Some(FLOAT_FORMAT.into()));
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout(device, &[group])),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vertex"),
            compilation_options: Default::default(),
            buffers: &[wgpu::VertexBufferLayout {
                array_stride: size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &VERTEX_ATTRIBUTES,
            }],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(nearest_depth(DEPTH_FORMAT)),
        multisample: Default::default(),
        fragment: fragment.map(|entry| wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Clears `targets` and draws `vertex_count` vertices of `vertices` into them.
#[allow(clippy::too_many_arguments)]
pub(crate) fn record_raster<const N: usize>(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    targets: &RasterTargets<N>,
    pipeline: &wgpu::RenderPipeline,
    group: &wgpu::BindGroup,
    vertices: wgpu::BufferSlice,
    vertex_count: u32,
    timestamps: Option<wgpu::RenderPassTimestampWrites>,
) {
    let attachments = targets
        .views
        .each_ref()
        .map(|v| cleared_attachment(v, wgpu::Color::TRANSPARENT));
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &attachments,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: timestamps,
        ..Default::default()
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.set_vertex_buffer(0, vertices);
    pass.draw(0..vertex_count, 0..1);
}

/// Renders the RSM of one light view into textures it owns ([`RsmPass::views`]). Its three
/// Rgba32Float targets take 48 bytes a sample: open the device with the adapter's limits
/// (`max_color_attachment_bytes_per_sample` is 32 by default).
pub struct RsmPass {
    rsm_size: u32,
    pipeline: wgpu::RenderPipeline,
    light: wgpu::Buffer,
    raster: wgpu::Buffer,
    /// Per light update: the light and its projection.
    group: wgpu::BindGroup,
    targets: RasterTargets,
}

impl RsmPass {
    /// An RSM of `rsm_size`^2 texels (the size [`crate::Settings::rsm_size`] names).
    pub fn new(device: &wgpu::Device, rsm_size: u32) -> Self {
        let vertex_fragment = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let group_layout = layout(
            device,
            "rsm",
            &[
                uniform_entry::<RasterUniform>(0, vertex_fragment, false),
                uniform_entry::<LightUniform>(1, vertex_fragment, false),
            ],
        );
        let module = shader_module(device, "rsm", &SOURCES);
        let light = uniform_buffer::<LightUniform>(device, "rsm light");
        let raster = uniform_buffer::<RasterUniform>(device, "rsm projection");
        Self {
            rsm_size,
            pipeline: raster_pipeline::<3>(device, &group_layout, &module, "rsm", Some("rsm")),
            group: bind_group(
                device,
                "rsm",
                &group_layout,
                vec![whole(&raster), whole(&light)],
            ),
            light,
            raster,
            targets: RasterTargets::new(
                device,
                ["rsm flux", "rsm position", "rsm normal"],
                (rsm_size, rsm_size),
            ),
        }
    }

    /// Sets the light view the next recordings render from (per light update).
    pub fn set_light(&self, queue: &wgpu::Queue, view: &LightView) {
        queue.write_buffer(&self.light, 0, bytemuck::bytes_of(&view.uniform()));
        let p = view.position;
        queue.write_buffer(
            &self.raster,
            0,
            bytemuck::bytes_of(&RasterUniform {
                view_proj: view.view_proj.to_cols_array_2d(),
                eye: [p.x, p.y, p.z, 1.0],
                texel: [view.texel_measure(self.rsm_size), 0.0, 0.0, 0.0],
            }),
        );
    }

    /// Records the RSM of `vertex_count` vertices of `vertices`: triangle lists of [`Vertex`]
    /// (world position, normal, albedo; three `Float32x3`), timed into `timer`'s `slot`.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        vertices: wgpu::BufferSlice,
        vertex_count: u32,
        timer: Option<(&GpuTimer, u32)>,
    ) {
        record_raster(
            encoder,
            "rsm",
            &self.targets,
            &self.pipeline,
            &self.group,
            vertices,
            vertex_count,
            timer.and_then(|(t, slot)| t.render_pass(slot)),
        );
    }

    /// The RSM's textures, for the quadtree and the gather.
    pub fn views(&self) -> RsmViews<'_> {
        let [flux, position, normal] = &self.targets.views;
        RsmViews {
            flux,
            position,
            normal,
        }
    }

    /// The RSM's textures (flux, position, normal), for reading back.
    pub fn textures(&self) -> &[wgpu::Texture; 3] {
        &self.targets.colors
    }
}
