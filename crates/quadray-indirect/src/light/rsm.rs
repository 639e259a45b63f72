//! The RSM pass: the caller's triangles rasterised from one light view into a reflective shadow
//! map (flux, position + depth, normal, in one of the [`GBufferLayout`]s), the input of the light
//! quadtree. Also the raster helpers quadray's own G-buffer pass and the direct light's shadow
//! maps share, and the scene's base colour textures both colour passes sample
//! ([`TextureArray`]).

use crate::contract::{
    LightUniform, RasterUniform, bind_group, layout, pipeline_layout, shader_module, shader_source,
    uniform_buffer, uniform_entry, whole,
};
use crate::light::view::LightView;
use crate::method::GBufferLayout;
use crate::scene::{SceneTextures, Vertex};
use crate::settings::Settings;
use crate::wgsl;
use quadray_gpu::{GpuTimer, Limit, LimitNeed, cleared_attachment, texture_2d};

/// Format of every wide RSM and G-buffer colour target.
pub const FLOAT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// A compact target's normal: two octahedral coordinates (compact.wgsl).
const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// A compact G-buffer's albedo (a reflectance in [0, 1]): 10 bits a channel, for as many ROP
/// cycles as 8, hold a dark channel to 1% (the Cornell box's red wall's 0.05: 0.3%; 8 bits, 2%).
const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgb10a2Unorm;
/// A compact RSM's flux: high dynamic range.
const FLUX_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// A raster pass's colour target: its label and format.
pub(crate) type ColorTarget = (&'static str, wgpu::TextureFormat);

/// The G-buffer's colour targets in `layout`: position, normal and albedo, or normal and albedo.
pub(crate) fn gbuffer_targets(layout: GBufferLayout) -> &'static [ColorTarget] {
    match layout {
        GBufferLayout::Wide => &[
            ("g position", FLOAT_FORMAT),
            ("g normal", FLOAT_FORMAT),
            ("g albedo", FLOAT_FORMAT),
        ],
        GBufferLayout::Compact => &[("g normal", NORMAL_FORMAT), ("g albedo", ALBEDO_FORMAT)],
    }
}

/// An RSM's colour targets in `layout`: flux, position and normal, or flux and normal.
pub(crate) fn rsm_targets(layout: GBufferLayout) -> &'static [ColorTarget] {
    match layout {
        GBufferLayout::Wide => &[
            ("rsm flux", FLOAT_FORMAT),
            ("rsm position", FLOAT_FORMAT),
            ("rsm normal", FLOAT_FORMAT),
        ],
        GBufferLayout::Compact => &[("rsm flux", FLUX_FORMAT), ("rsm normal", NORMAL_FORMAT)],
    }
}

/// [`Vertex`]'s fields as `raster.wgsl`'s vertex stage reads them.
const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 5] = {
    use std::mem::offset_of;
    use wgpu::VertexFormat::{Float32x2, Float32x3, Uint32};
    const fn attribute(
        shader_location: u32,
        offset: usize,
        format: wgpu::VertexFormat,
    ) -> wgpu::VertexAttribute {
        wgpu::VertexAttribute {
            format,
            offset: offset as u64,
            shader_location,
        }
    }
    [
        attribute(0, offset_of!(Vertex, position), Float32x3),
        attribute(1, offset_of!(Vertex, normal), Float32x3),
        attribute(2, offset_of!(Vertex, albedo), Float32x3),
        attribute(3, offset_of!(Vertex, uv), Float32x2),
        attribute(4, offset_of!(Vertex, texture), Uint32),
    ]
};

/// The raster passes' shared modules: the vertex stage, and the compact layout's encodings.
pub(crate) const RASTER_WGSL: [&str; 2] = [include_str!("raster.wgsl"), wgsl::COMPACT];
/// The base colour textures' sampling (`surface_albedo`; group 1, a [`TextureArray`]), for the
/// passes that write the albedo.
pub(crate) const BASE_COLOUR_WGSL: &str = include_str!("base_colour.wgsl");
/// How the quadtree and the gather read an RSM texel in either layout (`load_rsm_normal`,
/// `load_rsm_position`, `load_rsm_flux`; needs [`wgsl::LIGHT`], [`wgsl::COMPACT`] and the
/// including shader's `rsm_flux`, `rsm_pos`, `rsm_normal`, `light` and `params`).
pub(crate) const RSM_READ_WGSL: &str = include_str!("rsm_read.wgsl");
/// The RSM pass's shader, in order.
pub(crate) const SOURCES: [&str; 5] = [
    wgsl::LIGHT,
    RASTER_WGSL[0],
    RASTER_WGSL[1],
    BASE_COLOUR_WGSL,
    RSM_WGSL,
];
/// The RSM's fragment stage (`rsm_wide`, `rsm_compact`).
const RSM_WGSL: &str = include_str!("rsm.wgsl");

/// The scene's base colour textures on the GPU ([`SceneTextures`]): one `Rgba8UnormSrgb` 2D
/// array, whose texels the RSM and G-buffer passes read per fragment (the format decodes sRGB)
/// and filter as each triangle's sampler says.
pub struct TextureArray {
    /// Group 1 of the passes that sample it.
    group: wgpu::BindGroup,
}

impl TextureArray {
    /// `textures` uploaded (a scene without textures binds one texel that no vertex reads).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, textures: &SceneTextures) -> Self {
        if textures.layers.is_empty() {
            return Self::empty(device);
        }
        let texture = Self::texture(
            device,
            textures.width,
            textures.height,
            textures.layers.len() as u32,
        );
        let texels: Vec<[u8; 4]> = textures.layers.concat();
        queue.write_texture(
            texture.as_image_copy(),
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * textures.width),
                rows_per_image: Some(textures.height),
            },
            texture.size(),
        );
        Self::of(device, &texture)
    }

    /// What the array of `textures` needs of the device: its layers' sides.
    pub fn limit_needs(textures: &SceneTextures) -> Vec<LimitNeed> {
        let side = textures.width.max(textures.height);
        vec![LimitNeed {
            limit: Limit::TextureDimension2d,
            needed: side.into(),
            needed_by: format!(
                "the scene's base colour texture array ({}x{})",
                textures.width, textures.height
            ),
        }]
    }

    /// No texture: for triangles that all have [`Vertex::UNTEXTURED`].
    pub fn empty(device: &wgpu::Device) -> Self {
        Self::of(device, &Self::texture(device, 1, 1, 1))
    }

    fn texture(device: &wgpu::Device, width: u32, height: u32, layers: u32) -> wgpu::Texture {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some("base colours"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    }

    fn of(device: &wgpu::Device, texture: &wgpu::Texture) -> Self {
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        Self {
            group: bind_group(
                device,
                "base colours",
                &Self::layout(device),
                vec![wgpu::BindingResource::TextureView(&view)],
            ),
        }
    }

    /// The group layout of the passes that sample it: the array, read by the fragment stage
    /// with `textureLoad`.
    pub(crate) fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        layout(
            device,
            "base colours",
            &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                count: None,
            }],
        )
    }

    /// The group the passes bind.
    pub(crate) fn group(&self) -> &wgpu::BindGroup {
        &self.group
    }
}

/// The RSM as the quadtree and the gather read it, whoever renders it: square textures of the
/// same side (a power of two), any float formats `textureLoad` reads (quadray's
/// [`RsmPass`] writes the layout [`Settings::gbuffer_layout`] names).
#[derive(Clone, Copy)]
pub enum RsmViews<'a> {
    /// Each quantity whole. An empty texel has `normal.w = 0`.
    Wide {
        /// rgb: flux the texel's surface reflects (W), `I(w) * solid angle * albedo` (parallel
        /// light: `E * area * albedo`); w unused.
        flux: &'a wgpu::TextureView,
        /// xyz: world position; w: depth along the light's axis in units of
        /// [`LightView::extent`].
        position: &'a wgpu::TextureView,
        /// xyz: unit normal facing the light; w: 1 where the light sees geometry, else 0.
        normal: &'a wgpu::TextureView,
    },
    /// The position rebuilt from the light view's depth.
    Compact {
        /// rgb: the texel's flux over the view's intensity times its texel measure on the axis
        /// (the light's uniform holds both): the spot's falloff times cos^3 off the axis times
        /// the albedo, in [0, 1], where a float keeps its precision however small the texel.
        flux: &'a wgpu::TextureView,
        /// x: the depth the light view's projection gave the texel's surface, reversed: clip
        /// (w - z) / w, 1 at the near plane, 0 at the far plane and where the light sees
        /// nothing (a depth buffer cleared to 0).
        depth: &'a wgpu::TextureView,
        /// xy: the unit normal facing the light in octahedral coordinates.
        normal: &'a wgpu::TextureView,
        /// The light view the RSM was rendered from, as [`RsmPass::set_light`] writes it: the
        /// quadtree rebuilds positions and depths with it.
        light: &'a wgpu::Buffer,
    },
}

impl<'a> RsmViews<'a> {
    /// The layout the views are in.
    pub fn layout(&self) -> GBufferLayout {
        match self {
            RsmViews::Wide { .. } => GBufferLayout::Wide,
            RsmViews::Compact { .. } => GBufferLayout::Compact,
        }
    }

    /// The textures in the order the readers bind them: flux, position (or depth), normal.
    pub(crate) fn textures(&self) -> [&'a wgpu::TextureView; 3] {
        match *self {
            RsmViews::Wide {
                flux,
                position,
                normal,
            } => [flux, position, normal],
            RsmViews::Compact {
                flux,
                depth,
                normal,
                ..
            } => [flux, depth, normal],
        }
    }
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

/// The colour targets of one layout (none for a shadow map) and a depth buffer of one size, as
/// the raster passes write them.
pub(crate) struct RasterTargets {
    pub colors: Vec<wgpu::Texture>,
    pub views: Vec<wgpu::TextureView>,
    /// Also read as a texture: a shadow map's depth.
    pub depth: wgpu::TextureView,
}

impl RasterTargets {
    /// The colour `targets` and a depth buffer.
    pub fn new(device: &wgpu::Device, targets: &[ColorTarget], size: (u32, u32)) -> Self {
        let colors: Vec<wgpu::Texture> = targets
            .iter()
            .map(|&(label, format)| target(device, label, size, format))
            .collect();
        Self {
            views: colors.iter().map(view).collect(),
            colors,
            depth: view(&target(device, "depth", size, DEPTH_FORMAT)),
        }
    }
}

/// A raster pipeline over [`Vertex`] triangles into the colour `targets` (written by the entry
/// point `fragment`; none: depth only) with a depth test, binding `groups`.
pub(crate) fn raster_pipeline(
    device: &wgpu::Device,
    groups: &[&wgpu::BindGroupLayout],
    module: &wgpu::ShaderModule,
    label: &str,
    fragment: Option<&str>,
    targets: &[ColorTarget],
) -> wgpu::RenderPipeline {
    let targets: Vec<Option<wgpu::ColorTargetState>> =
        targets.iter().map(|&(_, f)| Some(f.into())).collect();
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout(device, groups)),
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
        // reversed depth (`reversed_depth`): the nearest surface has the greatest
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: Default::default(),
            bias: Default::default(),
        }),
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

/// The fragment entry point of a raster pass `name` in `layout` (`rsm_wide`, `gbuffer_compact`).
pub(crate) fn fragment_entry(name: &str, layout: GBufferLayout) -> String {
    format!("{name}_{}", layout.name())
}

/// A render pass over `targets`, cleared (the depth to 0: depths are reversed).
fn begin_cleared<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    targets: &RasterTargets,
    timestamps: Option<wgpu::RenderPassTimestampWrites>,
) -> wgpu::RenderPass<'e> {
    let attachments: Vec<_> = targets
        .views
        .iter()
        .map(|v| cleared_attachment(v, wgpu::Color::TRANSPARENT))
        .collect();
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &attachments,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(0.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: timestamps,
        ..Default::default()
    })
}

/// Clears `targets` and draws `vertex_count` vertices of `vertices` into them, binding `groups`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn record_raster(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    targets: &RasterTargets,
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
    vertices: wgpu::BufferSlice,
    vertex_count: u32,
    timestamps: Option<wgpu::RenderPassTimestampWrites>,
) {
    let mut pass = begin_cleared(encoder, label, targets, timestamps);
    pass.set_pipeline(pipeline);
    for (index, group) in groups.iter().enumerate() {
        pass.set_bind_group(index as u32, *group, &[]);
    }
    pass.set_vertex_buffer(0, vertices);
    pass.draw(0..vertex_count, 0..1);
}

/// Renders the RSM of one light view into textures it owns ([`RsmPass::views`]), in the layout
/// [`Settings::gbuffer_layout`] names. The wide layout's three Rgba32Float targets take 48 bytes
/// a sample: open the device with the adapter's limits (`max_color_attachment_bytes_per_sample`
/// is 32 by default).
pub struct RsmPass {
    rsm_size: u32,
    layout: GBufferLayout,
    pipeline: wgpu::RenderPipeline,
    light: wgpu::Buffer,
    raster: wgpu::Buffer,
    /// Per light update: the light and its projection.
    group: wgpu::BindGroup,
    /// The base colour textures.
    textures: wgpu::BindGroup,
    targets: RasterTargets,
}

impl RsmPass {
    /// An RSM of [`Settings::rsm_size`]^2 texels in [`Settings::gbuffer_layout`], of triangles
    /// without textures until [`RsmPass::set_textures`].
    pub fn new(device: &wgpu::Device, settings: &Settings) -> Self {
        let (rsm_size, layout) = (settings.rsm_size, settings.gbuffer_layout);
        let group_layout = layout_of(device);
        let module = shader_module(device, "rsm", &SOURCES);
        let light = uniform_buffer::<LightUniform>(device, "rsm light");
        let raster = uniform_buffer::<RasterUniform>(device, "rsm projection");
        let targets = rsm_targets(layout);
        Self {
            rsm_size,
            layout,
            pipeline: raster_pipeline(
                device,
                &[&group_layout, &TextureArray::layout(device)],
                &module,
                "rsm",
                Some(&fragment_entry("rsm", layout)),
                targets,
            ),
            group: bind_group(
                device,
                "rsm",
                &group_layout,
                vec![whole(&raster), whole(&light)],
            ),
            textures: TextureArray::empty(device).group().clone(),
            light,
            raster,
            targets: RasterTargets::new(device, targets, (rsm_size, rsm_size)),
        }
    }

    /// Sets the base colour textures the triangles' [`Vertex::texture`] refer to.
    pub fn set_textures(&mut self, textures: &TextureArray) {
        self.textures = textures.group().clone();
    }

    /// Sets the light view the next recordings render from (per light update).
    pub fn set_light(&self, queue: &wgpu::Queue, view: &LightView) {
        let uniform = view.uniform(self.rsm_size);
        queue.write_buffer(&self.light, 0, bytemuck::bytes_of(&uniform));
        queue.write_buffer(&self.raster, 0, bytemuck::bytes_of(&view.raster_uniform()));
    }

    /// Records the RSM of `vertex_count` vertices of `vertices`: triangle lists of [`Vertex`]
    /// (world position, normal, albedo, texture coordinate, packed texture), timed into
    /// `timer`'s `slot`.
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
            &[&self.group, &self.textures],
            vertices,
            vertex_count,
            timer.and_then(|(t, slot)| t.render_pass(slot)),
        );
    }

    /// For a renderer that draws the light view's geometry itself (an engine's own meshes) into
    /// this RSM: a render pass over its targets, cleared, in which to draw with a pipeline whose
    /// fragment stage is [`RsmPass::fragment_source`]'s entry [`RsmPass::fragment_entry`] into
    /// [`RsmPass::target_formats`] and a depth test as this pass's own (`depth32float`, the
    /// `Greater` compare: the raster uniform's projection reverses depth), binding
    /// [`RsmPass::uniforms`] as its group 0. The quadtree then builds from it as from
    /// [`RsmPass::record`].
    pub fn begin<'e>(&self, encoder: &'e mut wgpu::CommandEncoder) -> wgpu::RenderPass<'e> {
        begin_cleared(encoder, "rsm", &self.targets, None)
    }

    /// The uniforms [`RsmPass::set_light`] writes, as the RSM's shaders bind them (group 0):
    /// the raster uniform (binding 0: the light view's projection, depth reversed, and its eye)
    /// and the light (binding 1).
    pub fn uniforms(&self) -> [&wgpu::Buffer; 2] {
        [&self.raster, &self.light]
    }

    /// The colour targets' formats in `layout`, in the order of the fragment stage's outputs.
    pub fn target_formats(layout: GBufferLayout) -> Vec<wgpu::TextureFormat> {
        rsm_targets(layout).iter().map(|&(_, f)| f).collect()
    }

    /// The depth buffer's format.
    pub const DEPTH_FORMAT: wgpu::TextureFormat = DEPTH_FORMAT;

    /// The RSM's fragment stage as WGSL, the prelude first, for a renderer with its own vertex
    /// stage ([`RsmPass::begin`]): the entry points `rsm_wide` and `rsm_compact` take
    /// `raster.wgsl`'s `VertexOut` (clip position, world position, normal, albedo, uv, a flat
    /// `texture` word); the including shader adds its vertex stage and
    /// `fn surface_albedo(v: VertexOut) -> vec3<f32>`, the texel's albedo.
    pub fn fragment_source() -> String {
        shader_source(&[wgsl::LIGHT, RASTER_WGSL[0], RASTER_WGSL[1], RSM_WGSL])
    }

    /// The fragment entry point of [`RsmPass::fragment_source`] that writes `layout`.
    pub fn fragment_entry(layout: GBufferLayout) -> String {
        fragment_entry("rsm", layout)
    }

    /// The RSM's textures, for the quadtree and the gather.
    pub fn views(&self) -> RsmViews<'_> {
        let v = &self.targets.views;
        match self.layout {
            GBufferLayout::Wide => RsmViews::Wide {
                flux: &v[0],
                position: &v[1],
                normal: &v[2],
            },
            GBufferLayout::Compact => RsmViews::Compact {
                flux: &v[0],
                depth: &self.targets.depth,
                normal: &v[1],
                light: &self.light,
            },
        }
    }

    /// The RSM's colour targets, for reading back: flux, position and normal (wide), or flux and
    /// normal (compact, whose positions lie in the depth of [`RsmViews::Compact`]).
    pub fn textures(&self) -> &[wgpu::Texture] {
        &self.targets.colors
    }
}

/// The RSM pass's group layout: its projection and its light.
fn layout_of(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let vertex_fragment = wgpu::ShaderStages::VERTEX_FRAGMENT;
    layout(
        device,
        "rsm",
        &[
            uniform_entry::<RasterUniform>(0, vertex_fragment, false),
            uniform_entry::<LightUniform>(1, vertex_fragment, false),
        ],
    )
}
