//! The passes, as systems of Bevy's `Core3d` schedule: the bounce added after the opaque pass, the
//! cut view drawn after tone mapping.

use super::light::LightState;
use super::meshes::{MeshDraws, record_mesh_rsm};
use super::pipelines::Pipelines;
use super::triangles::SceneWork;
use super::views::{ViewPasses, cut_view_zoom};
use crate::gi::cpu_time::CpuTimes;
use crate::gi::scene::{IndirectLight, RsmSource};
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::PipelineCache;
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::sync_world::MainEntity;
use bevy::render::view::ViewTarget;
use quadray_indirect::LightQuadtree;

/// Records, for one camera: the light's RSM, pyramid and cut when they are stale, the G-buffer
/// translation, the gather, the debug copy and the composite into the view.
pub(super) fn indirect_light_pass(
    view: ViewQuery<(
        &ViewPasses,
        &ViewTarget,
        &ViewPrepassTextures,
        &IndirectLight,
        &MainEntity,
    )>,
    mut light: ResMut<LightState>,
    (pipelines, pipeline_cache): (Res<Pipelines>, Res<PipelineCache>),
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    (mesh_draws, mut work): (Res<MeshDraws>, ResMut<SceneWork>),
    times: Res<CpuTimes>,
    mut ctx: RenderContext,
) {
    let _span = times.render();
    let (passes, target, prepass, gi, camera) = view.into_inner();
    let Some(l) = light.0.as_mut().filter(|_| gi.enabled) else {
        return;
    };
    let meshes = l.source == RsmSource::Meshes;
    let vertices = l.scene.vertices();
    if l.views.is_empty() || (vertices.is_none() && !meshes) {
        return;
    }
    let Some(translate) = pipeline_cache.get_compute_pipeline(pipelines.gbuffer) else {
        return;
    };
    let (Some(deferred), Some(depth)) = (prepass.deferred_view(), prepass.depth_view()) else {
        return;
    };
    let layout = pipeline_cache.get_bind_group_layout(&pipelines.gbuffer_layout);
    let device = ctx.render_device().wgpu_device().clone();
    let group = passes.gbuffer_group(&device, &layout, deferred, depth);
    // Bevy's diagnostics (with its RenderDiagnosticsPlugin), under the camera's own path: GPU
    // time of the light's passes, the gather and the composite, the gather's work per shaded
    // pixel; and the lights' cut's size, shared
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let encoder = ctx.command_encoder();
    let camera_path = camera_diagnostics(camera.id());
    let whole = diagnostics.time_span(encoder, camera_path.clone());
    if l.stale {
        let span = diagnostics.time_span(encoder, "light");
        for (i, view) in l.views.iter().enumerate() {
            match vertices.filter(|_| !meshes) {
                Some((vertices, vertex_count)) => {
                    view.rsm
                        .record(encoder, vertices.slice(..), vertex_count, None);
                }
                None => record_mesh_rsm(
                    encoder,
                    (&view.rsm, i),
                    &mesh_draws,
                    &pipeline_cache,
                    &mut work,
                ),
            }
            view.quadtree.record_build(encoder, None);
            view.quadtree.record_cut(encoder, None);
        }
        l.stale = false;
        span.end(encoder);
    }
    // gathered every frame: Bevy's G-buffer can change while the camera and the light stand still
    // (a mesh uploaded or a pipeline compiled frames after the scene's triangles arrived)
    let span = diagnostics.time_span(encoder, "gather");
    let size = passes.settings.size;
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("quadray gi gbuffer"),
            timestamp_writes: None,
        });
        pass.set_pipeline(translate);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(size.width.div_ceil(8), size.height.div_ceil(8), 1);
    }
    let quadtrees: Vec<&LightQuadtree> = l.views.iter().map(|v| &v.quadtree).collect();
    passes
        .gather
        .record_indirect(encoder, gi.method, &quadtrees, None);
    span.end(encoder);
    let counts = pipeline_cache.get_compute_pipeline(pipelines.counts);
    if let Some(counts) = counts.filter(|_| diagnostics.is_some()) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("quadray gi counts"),
            timestamp_writes: None,
        });
        pass.set_pipeline(counts);
        pass.set_bind_group(0, &passes.means_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    if let Some(debug) = gi.debug_indirect.as_ref().and_then(|h| buffers.get(h)) {
        let indirect = passes.gather.indirect();
        if debug.buffer.size() >= indirect.size() {
            encoder.copy_buffer_to_buffer(indirect, 0, &debug.buffer, 0, indirect.size());
        }
    }
    // (until Bevy has compiled the composite, the bounce is gathered and not added)
    if let Some(composite) = pipeline_cache.get_render_pipeline(passes.composite) {
        let span = diagnostics.time_span(encoder, "composite");
        draw_over(
            encoder,
            "quadray gi composite",
            target.main_texture_view(),
            (composite, &passes.composite_group),
            None,
        );
        span.end(encoder);
    }
    whole.end(encoder);
    if diagnostics.is_some() {
        let cut = l.views[0].quadtree.cut_count().slice(0..4);
        diagnostics.record_u32(encoder, &cut, "quadray_gi/cut_clusters");
        let evaluations = passes.means.slice(0..4);
        let path = format!("{camera_path}/vpl_evaluations_per_pixel");
        diagnostics.record_f32(encoder, &evaluations, path);
        let fetches = passes.means.slice(4..8);
        let path = format!("{camera_path}/texel_fetches_per_pixel");
        diagnostics.record_f32(encoder, &fetches, path);
    }
}

/// The diagnostics' path of `camera`'s passes and counts, below Bevy's `render/`.
pub(crate) fn camera_diagnostics(camera: Entity) -> String {
    format!("quadray_gi/camera_{camera}")
}

/// Draws the cut over the RSM into the tone-mapped picture's top-left corner, for a camera whose
/// [`IndirectLight::cut_view`] is on (and whose bounce is: the cut is built with it).
pub(super) fn cut_view_pass(
    view: ViewQuery<(&ViewPasses, &ViewTarget, &IndirectLight)>,
    light: Res<LightState>,
    pipeline_cache: Res<PipelineCache>,
    times: Res<CpuTimes>,
    mut ctx: RenderContext,
) {
    let _span = times.render();
    let (passes, target, gi) = view.into_inner();
    if !(gi.cut_view && gi.enabled) || light.0.as_ref().is_none_or(|l| l.views.is_empty()) {
        return;
    }
    let Some(cut_view) = pipeline_cache.get_render_pipeline(passes.cut_view) else {
        return;
    };
    let size = passes.settings.size;
    let side = passes.settings.rsm_size * cut_view_zoom(&passes.settings);
    draw_over(
        ctx.command_encoder(),
        "quadray gi cut view",
        target.main_texture_view(),
        (cut_view, &passes.cut_view_group),
        Some((side.min(size.width), side.min(size.height))),
    );
}

/// Draws a full-screen triangle of the composite's shader over what `view` holds, within the
/// top-left `scissor` (width, height) when one is given.
pub(super) fn draw_over(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    view: &wgpu::TextureView,
    (pipeline, group): (&wgpu::RenderPipeline, &wgpu::BindGroup),
    scissor: Option<(u32, u32)>,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    });
    if let Some((width, height)) = scissor {
        pass.set_scissor_rect(0, 0, width, height);
    }
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.draw(0..3, 0..1);
}
