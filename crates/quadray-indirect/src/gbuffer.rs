//! The camera's side: the G-buffer the gather reads ([`GBufferViews`], the caller's or quadray's),
//! and quadray's own G-buffer pass (a renderer embedding the gather brings its own): the scene's
//! triangles from the camera into the targets of one [`GBufferLayout`].

use crate::contract::{
    CameraUniform, RasterUniform, bind_group, layout, shader_module, uniform_buffer, uniform_entry,
    whole,
};
use crate::light::rsm::{
    BASE_COLOUR_WGSL, RASTER_WGSL, RasterTargets, TextureArray, fragment_entry, gbuffer_targets,
    raster_pipeline, record_raster,
};
use crate::light::view::{relative_inverse, reversed_depth};
use crate::method::GBufferLayout;
use glam::{Mat4, Vec3};

/// The caller's G-buffer: textures of the output's size, any float formats `textureLoad` reads,
/// in one of the [`GBufferLayout`]s (quadray's own pass writes the one
/// [`crate::Settings::gbuffer_layout`] names).
#[derive(Clone, Copy)]
pub enum GBufferViews<'a> {
    /// Each quantity whole (quadray's are [`crate::FLOAT_FORMAT`]).
    Wide {
        /// xyz: world position; w: 1 where geometry is seen, 0 elsewhere (no light there).
        position: &'a wgpu::TextureView,
        /// xyz: unit normal, turned towards the viewer.
        normal: &'a wgpu::TextureView,
        /// rgb: diffuse albedo.
        albedo: &'a wgpu::TextureView,
    },
    /// The position rebuilt from the depth through the camera that
    /// [`crate::Gather::set_camera`] gives (which it then needs).
    Compact {
        /// x: the depth the camera's `view_proj` gave the pixel's surface, reversed: clip
        /// (w - z) / w, 1 at the near plane, 0 at the far plane and where geometry is not seen
        /// (a depth buffer cleared to 0, as Bevy's).
        depth: &'a wgpu::TextureView,
        /// xy: the unit normal turned towards the viewer, in octahedral coordinates
        /// (`octahedral_encode` of the `COMPACT` WGSL module, [`crate::wgsl::COMPACT`]).
        normal: &'a wgpu::TextureView,
        /// rgb: diffuse albedo.
        albedo: &'a wgpu::TextureView,
    },
}

impl<'a> GBufferViews<'a> {
    /// The layout the views are in.
    pub fn layout(&self) -> GBufferLayout {
        match self {
            GBufferViews::Wide { .. } => GBufferLayout::Wide,
            GBufferViews::Compact { .. } => GBufferLayout::Compact,
        }
    }

    /// The textures in the order the gather binds them: position (or depth), normal, albedo.
    pub(crate) fn textures(&self) -> [&'a wgpu::TextureView; 3] {
        match *self {
            GBufferViews::Wide {
                position,
                normal,
                albedo,
            } => [position, normal, albedo],
            GBufferViews::Compact {
                depth,
                normal,
                albedo,
            } => [depth, normal, albedo],
        }
    }
}

/// The gather's per-camera uniform: the camera a `width` x `height` G-buffer was rendered from
/// (`view_proj`: world -> clip, `eye`: its position).
pub(crate) fn camera_uniform(
    view_proj: Mat4,
    eye: Vec3,
    (width, height): (u32, u32),
) -> CameraUniform {
    CameraUniform {
        view_proj: view_proj.to_cols_array_2d(),
        inv_view_proj: relative_inverse(view_proj, eye).to_cols_array_2d(),
        eye: eye.extend(1.0).to_array(),
        width,
        height,
        _pad: [0; 2],
    }
}

/// The G-buffer pass's shader, in order.
pub(crate) const SOURCES: [&str; 4] = [
    RASTER_WGSL[0],
    RASTER_WGSL[1],
    BASE_COLOUR_WGSL,
    include_str!("gbuffer.wgsl"),
];

pub(crate) struct GBufferPass {
    layout: GBufferLayout,
    pipeline: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    /// Per frame: the camera.
    group: wgpu::BindGroup,
    /// The scene's base colour textures.
    textures: wgpu::BindGroup,
    targets: RasterTargets,
}

impl GBufferPass {
    /// The G-buffer of triangles whose [`crate::scene::Vertex::texture`] refer to `textures`.
    pub fn new(
        device: &wgpu::Device,
        size: (u32, u32),
        layout: GBufferLayout,
        textures: &TextureArray,
    ) -> Self {
        let group_layout = self::layout(
            device,
            "gbuffer",
            &[uniform_entry::<RasterUniform>(
                0,
                wgpu::ShaderStages::VERTEX_FRAGMENT,
                false,
            )],
        );
        let module = shader_module(device, "gbuffer", &SOURCES);
        let camera = uniform_buffer::<RasterUniform>(device, "camera");
        let targets = gbuffer_targets(layout);
        let entry = fragment_entry("gbuffer", layout);
        Self {
            layout,
            pipeline: raster_pipeline(
                device,
                &[&group_layout, &TextureArray::layout(device)],
                &module,
                "gbuffer",
                Some(&entry),
                targets,
            ),
            group: bind_group(device, "gbuffer", &group_layout, vec![whole(&camera)]),
            textures: textures.group().clone(),
            camera,
            targets: RasterTargets::new(device, targets, size),
        }
    }

    pub fn set_camera(&self, queue: &wgpu::Queue, view_proj: Mat4, eye: Vec3) {
        queue.write_buffer(
            &self.camera,
            0,
            bytemuck::bytes_of(&RasterUniform {
                view_proj: reversed_depth(view_proj).to_cols_array_2d(),
                eye: [eye.x, eye.y, eye.z, 1.0],
            }),
        );
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        vertices: wgpu::BufferSlice,
        vertex_count: u32,
        timestamps: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        record_raster(
            encoder,
            "gbuffer",
            &self.targets,
            &self.pipeline,
            &[&self.group, &self.textures],
            vertices,
            vertex_count,
            timestamps,
        );
    }

    pub fn views(&self) -> GBufferViews<'_> {
        let v = &self.targets.views;
        match self.layout {
            GBufferLayout::Wide => GBufferViews::Wide {
                position: &v[0],
                normal: &v[1],
                albedo: &v[2],
            },
            GBufferLayout::Compact => GBufferViews::Compact {
                depth: &self.targets.depth,
                normal: &v[0],
                albedo: &v[1],
            },
        }
    }
}
