//! The plugin's own pipelines, made at startup: the G-buffer translation (Bevy's cache), the
//! additive composite and the cut view (one a target format) and the work counts' means.

use bevy::asset::uuid_handle;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::render_resource::binding_types::{
    texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer_sized,
};
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, CachedComputePipelineId,
    ComputePipelineDescriptor, PipelineCache, ShaderStages, StorageTextureAccess, TextureFormat,
    TextureSampleType,
};
use bevy::render::renderer::RenderDevice;
use bevy::shader::Shader;
use quadray_indirect::FLOAT_FORMAT;
use std::num::NonZero;

/// Bevy's packed G-buffer translated into quadray's (`gbuffer.wgsl`).
pub(super) const GBUFFER_SHADER: Handle<Shader> =
    uuid_handle!("5c0f3f62-8d0c-4d57-9a43-6f1f4c1f9d11");
pub(super) const COUNTS_WGSL: &str = include_str!("counts.wgsl");
/// The G-buffer translation's uniform: world_from_clip, the eye (xyz), the size (two u32).
pub(super) const VIEW_UNIFORM_BYTES: u64 = 64 + 16 + 16;

/// The composite's and the cut view's shader: quadray's engine-neutral modules, then this
/// plugin's bindings and entry points.
pub(super) fn composite_source() -> String {
    use quadray_indirect::wgsl;
    [
        wgsl::prelude().as_str(),
        wgsl::NODE,
        wgsl::KERNEL,
        wgsl::CUT_RULE,
        wgsl::CUT_VIEW,
        include_str!("composite.wgsl"),
    ]
    .concat()
}

#[derive(Resource)]
pub(super) struct Pipelines {
    pub(super) gbuffer_layout: BindGroupLayoutDescriptor,
    pub(super) gbuffer: CachedComputePipelineId,
    pub(super) composite_layout: wgpu::BindGroupLayout,
    pub(super) cut_view_layout: wgpu::BindGroupLayout,
    pub(super) composite_module: wgpu::ShaderModule,
    /// By the view target's format.
    pub(super) composite: HashMap<TextureFormat, wgpu::RenderPipeline>,
    pub(super) cut_view: HashMap<TextureFormat, wgpu::RenderPipeline>,
    /// The work counts' means, for Bevy's diagnostics.
    pub(super) counts: wgpu::ComputePipeline,
}

pub(super) fn init_pipelines(
    mut commands: Commands,
    device: Res<RenderDevice>,
    pipeline_cache: Res<PipelineCache>,
) {
    let gbuffer_layout = BindGroupLayoutDescriptor::new(
        "quadray gi gbuffer",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                texture_2d(TextureSampleType::Uint),
                texture_depth_2d(),
                uniform_buffer_sized(false, NonZero::new(VIEW_UNIFORM_BYTES)),
                texture_storage_2d(FLOAT_FORMAT, StorageTextureAccess::WriteOnly),
                texture_storage_2d(FLOAT_FORMAT, StorageTextureAccess::WriteOnly),
                texture_storage_2d(FLOAT_FORMAT, StorageTextureAccess::WriteOnly),
            ),
        ),
    );
    let gbuffer = pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("quadray gi gbuffer".into()),
        layout: vec![gbuffer_layout.clone()],
        shader: GBUFFER_SHADER,
        entry_point: Some("translate".into()),
        ..default()
    });
    let device = device.wgpu_device();
    let fragment_buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let storage = wgpu::BufferBindingType::Storage { read_only: true };
    let uniform = wgpu::BufferBindingType::Uniform;
    let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("quadray gi composite"),
        entries: &[fragment_buffer(0, storage), fragment_buffer(1, uniform)],
    });
    let cut_view_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("quadray gi cut view"),
        entries: &[
            fragment_buffer(2, uniform),
            fragment_buffer(3, storage),
            fragment_buffer(4, uniform),
        ],
    });
    let composite_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("quadray gi composite"),
        source: wgpu::ShaderSource::Wgsl(composite_source().into()),
    });
    let counts_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("quadray gi counts"),
        source: wgpu::ShaderSource::Wgsl(COUNTS_WGSL.into()),
    });
    let counts = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("quadray gi counts"),
        layout: None,
        module: &counts_module,
        entry_point: Some("mean_counts"),
        compilation_options: Default::default(),
        cache: None,
    });
    commands.insert_resource(Pipelines {
        gbuffer_layout,
        gbuffer,
        composite_layout,
        cut_view_layout,
        composite_module,
        composite: HashMap::default(),
        cut_view: HashMap::default(),
        counts,
    });
}

/// What a pipeline of the composite's shader draws.
#[derive(Clone, Copy)]
pub(super) enum Draw {
    /// The indirect light, added.
    Composite,
    /// The cut view, over what is there.
    CutView,
}

/// The composite's shader's pipeline for `draw` into a target of `format` (made once a format).
pub(super) fn composite_pipeline(
    device: &wgpu::Device,
    pipelines: &mut Pipelines,
    draw: Draw,
    format: TextureFormat,
) -> wgpu::RenderPipeline {
    let Pipelines {
        composite,
        cut_view,
        composite_layout,
        cut_view_layout,
        composite_module: module,
        ..
    } = pipelines;
    let (cache, layout, entry_point, blend) = match draw {
        Draw::Composite => {
            let add = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let keep = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let blend = wgpu::BlendState {
                color: add,
                alpha: keep,
            };
            (composite, &*composite_layout, "add_indirect", Some(blend))
        }
        Draw::CutView => (cut_view, &*cut_view_layout, "draw_cut_view", None),
    };
    if let Some(pipeline) = cache.get(&format) {
        return pipeline.clone();
    }
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry_point),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entry_point),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry_point),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
    cache.insert(format, pipeline.clone());
    pipeline
}
