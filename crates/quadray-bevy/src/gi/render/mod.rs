//! The render world's side: per light view, quadray's RSM and light quadtree; per camera, the
//! G-buffer translated from Bevy's, quadray's gather, the additive composite into the view and,
//! on request, the cut over the RSM drawn into the tone-mapped picture.
//!
//! By render phase, as Bevy's own features: `pipelines.rs` (Bevy's pipeline cache), `triangles.rs`
//! (extract and prepare: the scene's triangles as the main world's updates change them, their
//! vertex buffer and occupancy grid), `light.rs` and `views.rs` (prepare: the lights' maps,
//! each camera's passes) and `passes.rs` (the `Core3d` systems that record them).

mod light;
mod meshes;
mod passes;
mod pipelines;
mod triangles;
pub(super) mod views;

use light::{LightState, prepare_light};
use meshes::{
    MeshDraws, RSM_MESH_SHADER, RsmMaterials, RsmMeshPipeline, extract_materials,
    init_rsm_mesh_pipeline, prepare_mesh_rsm, rsm_mesh_source,
};
pub(super) use passes::camera_diagnostics;
use passes::{cut_view_pass, indirect_light_pass};
use pipelines::{
    COMPOSITE_SHADER, COUNTS_SHADER, GBUFFER_SHADER, Pipelines, composite_source, init_pipelines,
};
pub use triangles::SceneWork;
use triangles::{SceneMirror, extract_scene};
pub use views::ViewPasses;
use views::{drop_unused_views, prepare_views};

use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::core_pipeline::tonemapping::tonemapping;
use bevy::pbr::MeshPipelineSystems;
use bevy::prelude::*;
use bevy::render::render_resource::{SpecializedMeshPipelines, SpecializedRenderPipelines};
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;

pub(super) fn build(app: &mut App) {
    let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
    let _ = shaders.insert(
        &GBUFFER_SHADER,
        Shader::from_wgsl(include_str!("gbuffer.wgsl"), "quadray/gi_gbuffer.wgsl"),
    );
    let _ = shaders.insert(
        &COMPOSITE_SHADER,
        Shader::from_wgsl(composite_source(), "quadray/gi_composite.wgsl"),
    );
    let _ = shaders.insert(
        &COUNTS_SHADER,
        Shader::from_wgsl(include_str!("counts.wgsl"), "quadray/gi_counts.wgsl"),
    );
    let _ = shaders.insert(
        &RSM_MESH_SHADER,
        Shader::from_wgsl(rsm_mesh_source(), "quadray/gi_rsm_meshes.wgsl"),
    );
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .init_resource::<LightState>()
        .init_resource::<SceneMirror>()
        .init_resource::<SceneWork>()
        .init_resource::<SpecializedRenderPipelines<Pipelines>>()
        .init_resource::<RsmMaterials>()
        .init_resource::<MeshDraws>()
        .init_resource::<SpecializedMeshPipelines<RsmMeshPipeline>>()
        .add_systems(
            RenderStartup,
            (
                init_pipelines,
                init_rsm_mesh_pipeline.after(MeshPipelineSystems),
            ),
        )
        .add_systems(ExtractSchedule, (extract_scene, extract_materials))
        .add_systems(
            Render,
            (
                drop_unused_views,
                prepare_light,
                prepare_mesh_rsm,
                prepare_views,
            )
                .chain()
                .in_set(RenderSystems::PrepareBindGroups),
        )
        .add_systems(
            Core3d,
            (
                indirect_light_pass
                    .after(main_opaque_pass_3d)
                    .before(main_transparent_pass_3d)
                    .in_set(Core3dSystems::MainPass),
                cut_view_pass
                    .after(tonemapping)
                    .in_set(Core3dSystems::PostProcess),
            ),
        );
}
