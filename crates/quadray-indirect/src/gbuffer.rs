//! The camera's side: the G-buffer the gather reads ([`GBufferViews`], the caller's or quadray's),
//! and quadray's own G-buffer pass (a renderer embedding the gather brings its own): the scene's
//! triangles from the camera into position, normal and albedo targets.

use crate::contract::{
    CameraUniform, RasterUniform, bind_group, layout, shader_module, uniform_buffer, uniform_entry,
    whole,
};
use crate::light::rsm::{RASTER_WGSL, RasterTargets, raster_pipeline, record_raster};
use glam::{Mat4, Vec3};

/// The caller's G-buffer: three textures of the output's size, any float format `textureLoad`
/// reads (quadray's are [`crate::FLOAT_FORMAT`]).
#[derive(Clone, Copy)]
pub struct GBufferViews<'a> {
    /// xyz: world position; w: 1 where geometry is seen, 0 elsewhere (no light there).
    pub position: &'a wgpu::TextureView,
    /// xyz: unit normal, turned towards the viewer.
    pub normal: &'a wgpu::TextureView,
    /// rgb: diffuse albedo.
    pub albedo: &'a wgpu::TextureView,
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
        eye: eye.extend(1.0).to_array(),
        width,
        height,
        _pad: [0; 2],
    }
}

/// The G-buffer pass's shader, in order.
pub(crate) const SOURCES: [&str; 2] = [RASTER_WGSL, include_str!("gbuffer.wgsl")];

pub(crate) struct GBufferPass {
    pipeline: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    /// Per frame: the camera.
    group: wgpu::BindGroup,
    pub targets: RasterTargets,
}

impl GBufferPass {
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let group_layout = layout(
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
        Self {
            pipeline: raster_pipeline::<3>(
                device,
                &group_layout,
                &module,
                "gbuffer",
                Some("gbuffer"),
            ),
            group: bind_group(device, "gbuffer", &group_layout, vec![whole(&camera)]),
            camera,
            targets: RasterTargets::new(device, ["g position", "g normal", "g albedo"], size),
        }
    }

    pub fn set_camera(&self, queue: &wgpu::Queue, view_proj: Mat4, eye: Vec3) {
        queue.write_buffer(
            &self.camera,
            0,
            bytemuck::bytes_of(&RasterUniform {
                view_proj: view_proj.to_cols_array_2d(),
                eye: [eye.x, eye.y, eye.z, 1.0],
                texel: [0.0; 4],
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
            &self.group,
            vertices,
            vertex_count,
            timestamps,
        );
    }

    pub fn views(&self) -> GBufferViews<'_> {
        let [position, normal, albedo] = &self.targets.views;
        GBufferViews {
            position,
            normal,
            albedo,
        }
    }
}
