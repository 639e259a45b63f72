//! The pyramid build pass (`pyramid_build.wgsl`): level 0 padded to powers of two (the map, or
//! the conservative level 0 for the bilinear surface), then one compute dispatch per level.

use super::height_pyramid::{HeightPyramid, PyramidKind};
use crate::heightmap::HeightMap;
use crate::pyramid::{Addressing, level_size};

impl HeightPyramid {
    /// Builds the pyramid with compute passes (bit-identical to [`HeightPyramid::build_cpu`]);
    /// keep a [`PyramidBuilder`] instead to build many.
    pub fn build_gpu(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        map: &HeightMap,
        kind: PyramidKind,
    ) -> Self {
        PyramidBuilder::new(device).build(device, queue, map, kind)
    }
}

/// Builds min-depth pyramids on the GPU; keeps its pipelines for any number of maps.
pub struct PyramidBuilder {
    reduce: wgpu::ComputePipeline,
    pad: wgpu::ComputePipeline,
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
        let pipeline = |entry: &str, wrap: f64, radius: f64| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[("WRAP", wrap), ("RADIUS", radius)],
                    ..Default::default()
                },
                cache: None,
            })
        };
        Self {
            reduce: pipeline("reduce", 1.0, 0.0),
            pad: pipeline("level0", 1.0, 0.0),
            dilate_wrap: pipeline("level0", 1.0, 1.0),
            dilate_clamp: pipeline("level0", 0.0, 1.0),
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
        let padded = map.padded_size();
        let texture = HeightPyramid::create_texture(device, padded);
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
        let source = quadray_gpu::texture_2d_with_data(
            device,
            queue,
            "depth map",
            (map.width, map.height),
            HeightPyramid::FORMAT,
            bytemuck::cast_slice(&map.depth),
        );
        let level0 = match kind {
            PyramidKind::Point => &self.pad,
            PyramidKind::Conservative(Addressing::Wrap) => &self.dilate_wrap,
            PyramidKind::Conservative(Addressing::Clamp) => &self.dilate_clamp,
        };
        let level0_group = bind(&level_view(&source, 0), &level_view(&texture, 0));
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(level0);
        pass.set_bind_group(0, &level0_group, &[]);
        pass.dispatch_workgroups(padded.0.div_ceil(8), padded.1.div_ceil(8), 1);
        drop(pass);
        let levels = map.levels();
        let groups: Vec<_> = (1..=levels)
            .map(|k| bind(&level_view(&texture, k - 1), &level_view(&texture, k)))
            .collect();
        // One compute pass per level: with every level's dispatch in one pass, wgpu (29) leaves
        // the levels that a dispatch reads and the next writes in the layout of the read, and the
        // next submission expects another (the validation layer's InvalidImageLayout); a real GPU
        // may then read garbage. The timestamps bracket the first and the last pass.
        let (first, last) = (1, levels);
        for (k, group) in (1..=levels).zip(&groups) {
            let (width, height) = level_size(map.width, map.height, k);
            let timestamp_writes = timestamp_writes
                .as_ref()
                .filter(|_| k == first || k == last)
                .map(|t| wgpu::ComputePassTimestampWrites {
                    query_set: t.query_set,
                    beginning_of_pass_write_index: t
                        .beginning_of_pass_write_index
                        .filter(|_| k == first),
                    end_of_pass_write_index: t.end_of_pass_write_index.filter(|_| k == last),
                });
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pyramid reduce"),
                timestamp_writes,
            });
            pass.set_pipeline(&self.reduce);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
        }
        if levels == 0 {
            // a 1x1 map has no level to reduce; its timestamps are written all the same (an
            // unwritten query may never resolve)
            encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pyramid reduce"),
                timestamp_writes,
            });
        }
        HeightPyramid::from_texture(texture, kind, (map.width, map.height))
    }
}
