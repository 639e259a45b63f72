//! The plugin's own pipelines, through Bevy's pipeline cache: the G-buffer translation and the
//! work counts' means (made at startup), the additive composite and the cut view (specialised
//! by the view target's format).

use bevy::asset::uuid_handle;
use bevy::prelude::*;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, texture_2d, texture_depth_2d,
    texture_storage_2d, uniform_buffer_sized,
};
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, BlendComponent, BlendFactor, BlendOperation,
    BlendState, CachedComputePipelineId, ColorTargetState, ColorWrites, ComputePipelineDescriptor,
    FragmentState, PipelineCache, RenderPipelineDescriptor, ShaderStages,
    SpecializedRenderPipeline, StorageTextureAccess, TextureFormat, TextureSampleType, VertexState,
};
use bevy::shader::Shader;
use quadray_indirect::FLOAT_FORMAT;
use std::num::NonZero;

/// Bevy's packed G-buffer translated into quadray's (`gbuffer.wgsl`).
pub(super) const GBUFFER_SHADER: Handle<Shader> =
    uuid_handle!("5c0f3f62-8d0c-4d57-9a43-6f1f4c1f9d11");
/// The composite's and the cut view's shader ([`composite_source`]).
pub(super) const COMPOSITE_SHADER: Handle<Shader> =
    uuid_handle!("0b8e5d8e-3f7a-4a57-b1f0-2c6d3e9a7c41");
/// The work counts' means (`counts.wgsl`).
pub(super) const COUNTS_SHADER: Handle<Shader> =
    uuid_handle!("9d2f6c1a-57e4-4b0e-8a35-4f1c7b2e6d90");
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
    pub(super) composite_layout: BindGroupLayoutDescriptor,
    pub(super) cut_view_layout: BindGroupLayoutDescriptor,
    /// The work counts' means, for Bevy's diagnostics.
    pub(super) counts_layout: BindGroupLayoutDescriptor,
    pub(super) counts: CachedComputePipelineId,
}

pub(super) fn init_pipelines(mut commands: Commands, pipeline_cache: Res<PipelineCache>) {
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
    // the composite's shader declares both draws' bindings, each layout those its draw reads
    let composite_layout = BindGroupLayoutDescriptor::new(
        "quadray gi composite",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::FRAGMENT,
            (
                storage_buffer_read_only_sized(false, None),
                uniform_buffer_sized(false, None),
            ),
        ),
    );
    let cut_view_layout = BindGroupLayoutDescriptor::new(
        "quadray gi cut view",
        &BindGroupLayoutEntries::with_indices(
            ShaderStages::FRAGMENT,
            (
                (2, uniform_buffer_sized(false, None)),
                (3, storage_buffer_read_only_sized(false, None)),
                (4, uniform_buffer_sized(false, None)),
            ),
        ),
    );
    let counts_layout = BindGroupLayoutDescriptor::new(
        "quadray gi counts",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                storage_buffer_read_only_sized(false, None),
                texture_2d(TextureSampleType::Float { filterable: false }),
                storage_buffer_sized(false, None),
            ),
        ),
    );
    let counts = pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("quadray gi counts".into()),
        layout: vec![counts_layout.clone()],
        shader: COUNTS_SHADER,
        entry_point: Some("mean_counts".into()),
        ..default()
    });
    commands.insert_resource(Pipelines {
        gbuffer_layout,
        gbuffer,
        composite_layout,
        cut_view_layout,
        counts_layout,
        counts,
    });
}

/// What a pipeline of the composite's shader draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Draw {
    /// The indirect light, added.
    Composite,
    /// The cut view, over what is there.
    CutView,
}

/// The composite's shader's pipelines, by what they draw and the view target's format
/// (Bevy's `SpecializedRenderPipelines<Pipelines>` keeps one a key).
impl SpecializedRenderPipeline for Pipelines {
    type Key = (Draw, TextureFormat);

    fn specialize(&self, (draw, format): Self::Key) -> RenderPipelineDescriptor {
        let (layout, entry_point, blend) = match draw {
            Draw::Composite => {
                let add = BlendComponent {
                    src_factor: BlendFactor::One,
                    dst_factor: BlendFactor::One,
                    operation: BlendOperation::Add,
                };
                let keep = BlendComponent {
                    src_factor: BlendFactor::Zero,
                    dst_factor: BlendFactor::One,
                    operation: BlendOperation::Add,
                };
                let blend = BlendState {
                    color: add,
                    alpha: keep,
                };
                (&self.composite_layout, "add_indirect", Some(blend))
            }
            Draw::CutView => (&self.cut_view_layout, "draw_cut_view", None),
        };
        RenderPipelineDescriptor {
            label: Some(entry_point.into()),
            layout: vec![layout.clone()],
            vertex: VertexState {
                shader: COMPOSITE_SHADER,
                entry_point: Some("fullscreen".into()),
                ..default()
            },
            fragment: Some(FragmentState {
                shader: COMPOSITE_SHADER,
                entry_point: Some(entry_point.into()),
                targets: vec![Some(ColorTargetState {
                    format,
                    blend,
                    write_mask: ColorWrites::ALL,
                })],
                ..default()
            }),
            ..default()
        }
    }
}
