//! The plugin's CPU time in each world, reported to Bevy's `DiagnosticsStore` as
//! [`MAIN_WORLD_CPU`] and [`RENDER_WORLD_CPU`]: what its systems cost a frame besides the GPU's
//! passes. A system's span reads its thread's CPU clock (each system runs on one thread), so a
//! thread preempted by another program's, or by the renderer's, costs the plugin nothing: the
//! figure does not grow with the machine's load as a wall clock's would.

use ::cpu_time::ThreadTime;
use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics, RegisterDiagnostic};
use bevy::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Milliseconds a frame in the plugin's main-world systems (gathering the scene's triangles and
/// lights).
pub const MAIN_WORLD_CPU: DiagnosticPath = DiagnosticPath::const_new("quadray_gi/main_world_cpu");

/// Milliseconds a frame in the plugin's render-world systems (extracting the scene, updating
/// its vertex buffer and occupancy grid, preparing and recording the passes): the last render
/// frame finished when the main world reports (the render world runs beside the main world's
/// next frame, so a report may repeat a frame, never split one).
pub const RENDER_WORLD_CPU: DiagnosticPath =
    DiagnosticPath::const_new("quadray_gi/render_world_cpu");

/// Nanoseconds spent in the plugin's systems: the main world's since the last report, the
/// render world's this render frame, and its last finished frame's; one resource shared by both
/// worlds.
#[derive(Resource, Clone, Default)]
pub(crate) struct CpuTimes(Arc<[AtomicU64; 3]>);

/// Adds its thread's CPU time from its making to its drop to one world's total (none where the
/// thread's clock cannot be read).
pub(crate) struct Span<'a>(&'a AtomicU64, Option<ThreadTime>);

impl Span<'_> {
    fn start(total: &AtomicU64) -> Span<'_> {
        Span(total, ThreadTime::try_now().ok())
    }
}

impl Drop for Span<'_> {
    fn drop(&mut self) {
        if let Some(elapsed) = self.1.as_ref().and_then(|t| t.try_elapsed().ok()) {
            let nanos = u64::try_from(elapsed.as_nanos()).unwrap_or(u64::MAX);
            self.0.fetch_add(nanos, Ordering::Relaxed);
        }
    }
}

impl CpuTimes {
    /// Times a main-world system until the span is dropped.
    pub(crate) fn main(&self) -> Span<'_> {
        Span::start(&self.0[0])
    }

    /// Times a render-world system until the span is dropped.
    pub(crate) fn render(&self) -> Span<'_> {
        Span::start(&self.0[1])
    }
}

/// Shares the times with the render world and registers the diagnostics.
pub(super) fn build(app: &mut App) {
    let times = CpuTimes::default();
    app.insert_resource(times.clone())
        .register_diagnostic(Diagnostic::new(MAIN_WORLD_CPU).with_suffix("ms"))
        .register_diagnostic(Diagnostic::new(RENDER_WORLD_CPU).with_suffix("ms"))
        .add_systems(Last, report);
    if let Some(render_app) = app.get_sub_app_mut(bevy::render::RenderApp) {
        render_app.insert_resource(times).add_systems(
            bevy::render::Render,
            finish_render_frame.in_set(bevy::render::RenderSystems::Cleanup),
        );
    }
}

/// Ends a render frame: its time becomes the last finished frame's.
fn finish_render_frame(times: Res<CpuTimes>) {
    let nanos = times.0[1].swap(0, Ordering::Relaxed);
    times.0[2].store(nanos, Ordering::Relaxed);
}

/// Reports the main world's time since the last report and the last finished render frame's,
/// in milliseconds.
fn report(times: Res<CpuTimes>, mut diagnostics: Diagnostics) {
    let main = times.0[0].swap(0, Ordering::Relaxed);
    let render = times.0[2].load(Ordering::Relaxed);
    diagnostics.add_measurement(&MAIN_WORLD_CPU, || main as f64 * 1e-6);
    diagnostics.add_measurement(&RENDER_WORLD_CPU, || render as f64 * 1e-6);
}
