//! The pyramid build pass (`pyramid_build.wgsl`): one compute dispatch per level, and the
//! conservative level 0 for the bilinear surface.

use super::height_pyramid::{HeightPyramid, PyramidKind};
use crate::heightmap::HeightMap;
use crate::pyramid::Addressing;
use wgpu::util::DeviceExt;

/// Builds min-depth pyramids on the GPU; keeps its pipelines for any number of maps.
pub struct PyramidBuilder {
    reduce: wgpu::ComputePipeline,
    dilate_wrap: wgpu::ComputePipeline,
    dilate_clamp: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl PyramidBuilder {
    /// Compiles the build pipelines on `device`.
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::include_wgsl!("pyramid_build.wgsl"));
        let texture_entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("pyramid level pair"),
            entries: &[
                texture_entry(
                    0,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
                texture_entry(
                    1,
                    wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: HeightPyramid::FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                ),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("pyramid"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str, wrap: f64| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
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

    /// Uploads `map`, builds its pyramid and submits the work.
    pub fn build(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        map: &HeightMap,
        kind: PyramidKind,
    ) -> HeightPyramid {
        let mut encoder = device.create_command_encoder(&Default::default());
        let pyramid = self.record(device, queue, &mut encoder, map, kind, None);
        queue.submit([encoder.finish()]);
        pyramid
    }

    /// Uploads `map` (through `queue`) and records its pyramid's build into `encoder`; the
    /// pyramid is ready once the encoder's work is submitted. `timestamp_writes` time the pass
    /// that reduces the levels.
    pub fn record(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        map: &HeightMap,
        kind: PyramidKind,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> HeightPyramid {
        let size = map.size();
        let texture = HeightPyramid::create_texture(device, size);
        let level_view = |t: &wgpu::Texture, level: u32| {
            t.create_view(&wgpu::TextureViewDescriptor {
                base_mip_level: level,
                mip_level_count: Some(1),
                ..Default::default()
            })
        };
        let bind = |src: &wgpu::TextureView, dst: &wgpu::TextureView| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
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
        let extent = wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: 1,
        };
        let depths = bytemuck::cast_slice(&map.depth);
        match kind {
            PyramidKind::Point => queue.write_texture(
                texture.as_image_copy(),
                depths,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(size * 4),
                    rows_per_image: Some(size),
                },
                extent,
            ),
            PyramidKind::Conservative(addressing) => {
                let source = device.create_texture_with_data(
                    queue,
                    &wgpu::TextureDescriptor {
                        label: Some("depth map"),
                        size: extent,
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: HeightPyramid::FORMAT,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    },
                    wgpu::util::TextureDataOrder::LayerMajor,
                    depths,
                );
                let pipeline = match addressing {
                    Addressing::Wrap => &self.dilate_wrap,
                    Addressing::Clamp => &self.dilate_clamp,
                };
                let group = bind(&level_view(&source, 0), &level_view(&texture, 0));
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(size.div_ceil(8), size.div_ceil(8), 1);
            }
        }
        let groups: Vec<_> = (1..=map.levels)
            .map(|k| bind(&level_view(&texture, k - 1), &level_view(&texture, k)))
            .collect();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("pyramid reduce"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.reduce);
        for (k, group) in (1..=map.levels).zip(&groups) {
            let side = size >> k;
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(side.div_ceil(8), side.div_ceil(8), 1);
        }
        drop(pass);
        HeightPyramid::from_texture(texture, kind)
    }
}
