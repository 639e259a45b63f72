//! The direct light's shadow maps: the caller's triangles rasterised from each light view
//! ([`crate::LightView`]; the sun's fitted to the camera) into depth only, with the RSM pass's
//! raster helpers and vertex stage.

use crate::contract::{
    RasterUniform, bind_group, layout, shader_module, uniform_buffer, uniform_entry, whole,
};
use crate::light::rsm::{RASTER_WGSL, RasterTargets, raster_pipeline, record_raster};
use crate::light::view::LightView;
use quadray_gpu::GpuTimer;

/// One light view's map: its projection and its depth.
struct ShadowMap {
    raster: wgpu::Buffer,
    group: wgpu::BindGroup,
    targets: RasterTargets,
}

/// A depth-only shadow map of `size`^2 texels for each of a gather's light views.
pub(crate) struct ShadowMaps {
    size: u32,
    pipeline: wgpu::RenderPipeline,
    maps: Vec<ShadowMap>,
}

impl ShadowMaps {
    pub fn new(device: &wgpu::Device, size: u32, views: usize) -> Self {
        let group_layout = layout(
            device,
            "shadow map",
            &[uniform_entry::<RasterUniform>(
                0,
                wgpu::ShaderStages::VERTEX_FRAGMENT,
                false,
            )],
        );
        let module = shader_module(device, "shadow map", &RASTER_WGSL);
        let maps = (0..views)
            .map(|_| {
                let raster = uniform_buffer::<RasterUniform>(device, "shadow map projection");
                ShadowMap {
                    group: bind_group(device, "shadow map", &group_layout, vec![whole(&raster)]),
                    raster,
                    targets: RasterTargets::new(device, &[], (size, size)),
                }
            })
            .collect();
        Self {
            size,
            pipeline: raster_pipeline(device, &[&group_layout], &module, "shadow map", None, &[]),
            maps,
        }
    }

    /// The maps' side in texels.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// Sets map `index`'s view (its [`LightView::shadow_view`]).
    pub fn set_view(&self, queue: &wgpu::Queue, index: usize, view: &LightView) {
        let uniform = view.raster_uniform();
        queue.write_buffer(&self.maps[index].raster, 0, bytemuck::bytes_of(&uniform));
    }

    /// Records every map of `vertex_count` vertices of `vertices`, timed together into `timer`'s
    /// `slot`.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        vertices: wgpu::BufferSlice,
        vertex_count: u32,
        timer: Option<(&GpuTimer, u32)>,
    ) {
        let last = self.maps.len().saturating_sub(1);
        for (i, map) in self.maps.iter().enumerate() {
            let mut record = || {
                record_raster(
                    encoder,
                    "shadow map",
                    &map.targets,
                    &self.pipeline,
                    &[&map.group],
                    vertices,
                    vertex_count,
                    timer.and_then(|(t, slot)| t.render_pass(slot)),
                )
            };
            match timer {
                Some((t, _)) => t.span(i == 0, i == last, record),
                None => record(),
            }
        }
    }

    /// Map `index`'s depth, for the direct pass.
    pub fn depth(&self, index: usize) -> &wgpu::TextureView {
        &self.maps[index].targets.depth
    }
}
