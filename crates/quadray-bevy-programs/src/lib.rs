//! What quadray's Bevy programs share: their flags' values, a window or off-screen rendering
//! (`--screenshot PATH`: a few frames into an image, saved, then exit; `--frames N`: N frames
//! timed first, with the median of each of quadray's render diagnostics), and the window title
//! that says what is shown.

pub mod large_scene;

use bevy::app::ScheduleRunnerPlugin;
use bevy::diagnostic::DiagnosticsStore;
use bevy::prelude::*;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use bevy::render::render_resource::{PipelineCache, TextureFormat};
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy::render::{Render, RenderApp, RenderSystems};
use bevy::window::{ExitCondition, PrimaryWindow};
use bevy::winit::WinitPlugin;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Bevy's asset plugin reading the repository's `assets/<folder>`: under `BEVY_ASSET_ROOT` when
/// that is set (Bevy's own variable; for a binary copied to another machine and run outside the
/// checkout it was built in), else in the checkout it was built in.
pub fn repository_assets(folder: &str) -> AssetPlugin {
    let root = match std::env::var_os("BEVY_ASSET_ROOT") {
        // Bevy joins a relative path to BEVY_ASSET_ROOT itself
        Some(_) => std::path::PathBuf::from("assets"),
        None => std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets"),
    };
    AssetPlugin {
        file_path: root.join(folder).to_string_lossy().into_owned(),
        ..default()
    }
}

/// Off-screen rendering: where the picture goes, the image the camera renders into, and the
/// frames to wait and to time.
#[derive(Resource)]
pub struct Offscreen {
    /// The PNG to save.
    pub path: String,
    /// The camera's target (made by [`Offscreen::make_target`]).
    pub target: Handle<Image>,
    /// Frames before the picture is taken, counted from when Bevy has no pipeline left to compile
    /// and [`Self::waits_for`] have loaded (the scene loaded, the pipelines warm).
    pub warm_up: u32,
    /// Frames to time after the warm-up, before the picture (0: none).
    pub timed: usize,
    /// Assets the warm-up waits for (with their dependencies): the scene a program loads.
    pub waits_for: Vec<UntypedHandle>,
    frames: u32,
    times: Vec<f64>,
}

impl Offscreen {
    /// Saves to `path` after `warm_up` frames (and `timed` timed ones).
    pub fn new(path: String, warm_up: u32, timed: usize) -> Self {
        Self {
            path,
            target: Handle::default(),
            warm_up,
            timed,
            waits_for: Vec::new(),
            frames: 0,
            times: Vec::new(),
        }
    }

    /// Makes the `width` x `height` target the camera renders into.
    pub fn make_target(&mut self, images: &mut Assets<Image>, width: u32, height: u32) {
        self.target = images.add(Image::new_target_texture(
            width,
            height,
            TextureFormat::Rgba8UnormSrgb,
            None,
        ));
    }
}

/// Bevy's default plugins with `assets` as the asset folder: with a window, or, given
/// `offscreen`, headless (no window) saving the picture when ready; timed frames follow each
/// other at once and record Bevy's render diagnostics (GPU times where timestamps exist).
pub fn add_default_plugins(app: &mut App, assets: AssetPlugin, offscreen: Option<Offscreen>) {
    let Some(offscreen) = offscreen else {
        app.add_plugins(DefaultPlugins.set(assets));
        return;
    };
    let window = WindowPlugin {
        primary_window: None,
        exit_condition: ExitCondition::DontExit,
        ..default()
    };
    let wait = Duration::from_millis(if offscreen.timed > 0 { 0 } else { 1 });
    let timed = offscreen.timed > 0;
    app.add_plugins(
        DefaultPlugins
            .set(assets)
            .set(window)
            .disable::<WinitPlugin>(),
    )
    .add_plugins(ScheduleRunnerPlugin::run_loop(wait))
    .insert_resource(offscreen)
    .add_systems(Update, save_when_ready);
    // on a CPU rasteriser Bevy compiles its pipelines for many frames, a material's last
    let compiling = Compiling::default();
    app.insert_resource(compiling.clone());
    app.sub_app_mut(RenderApp)
        .insert_resource(compiling)
        .add_systems(Render, note_compiling.in_set(RenderSystems::Cleanup));
    // after the render app exists, which it hands its recorder to
    if timed {
        app.add_plugins(RenderDiagnosticsPlugin);
    }
}

/// Sets the primary window's title (when it changed).
pub fn set_title(windows: &mut Query<&mut Window, With<PrimaryWindow>>, title: &str) {
    // The title, not text in the picture: Bevy's UI and text stack would be most of the build.
    for mut window in windows {
        if window.title != title {
            window.title = title.to_owned();
        }
    }
}

/// Whether Bevy's render world had a pipeline left to compile at the end of its last frame;
/// shared by both worlds.
#[derive(Resource, Clone, Default)]
struct Compiling(Arc<AtomicBool>);

fn note_compiling(pipelines: Res<PipelineCache>, compiling: Res<Compiling>) {
    let waiting = pipelines.waiting_pipelines().next().is_some();
    compiling.0.store(waiting, Ordering::Relaxed);
}

/// Off screen: after the warm-up, times the frames asked for (printing their median and the
/// medians of quadray's render diagnostics over their last frames), then saves the target and
/// quits.
fn save_when_ready(
    mut commands: Commands,
    mut offscreen: ResMut<Offscreen>,
    mut exit: MessageWriter<AppExit>,
    time: Res<Time<Real>>,
    mut diagnostics: ResMut<DiagnosticsStore>,
    (compiling, assets): (Res<Compiling>, Res<AssetServer>),
) {
    // (a large scene may take longer to load than the warm-up's frames)
    let loading = offscreen.waits_for.iter().any(|h| {
        use bevy::asset::RecursiveDependencyLoadState::{Loading, NotLoaded};
        matches!(
            assets.recursive_dependency_load_state(h.id()),
            Loading | NotLoaded
        )
    });
    if offscreen.frames <= offscreen.warm_up && (compiling.0.load(Ordering::Relaxed) || loading) {
        offscreen.frames = 0;
    }
    offscreen.frames += 1;
    let warm_up = offscreen.warm_up;
    if offscreen.frames == warm_up + 1 {
        // the medians are over the timed frames only
        for d in diagnostics.iter_mut() {
            d.clear_history();
        }
    }
    if offscreen.frames > warm_up && offscreen.times.len() < offscreen.timed {
        offscreen.times.push(time.delta_secs_f64() * 1e3);
        if offscreen.times.len() == offscreen.timed {
            let mut times = offscreen.times.clone();
            times.sort_by(f64::total_cmp);
            println!(
                "median frame {:.1} ms over {} frames",
                times[times.len() / 2],
                times.len()
            );
            print_quadray_diagnostics(&diagnostics);
        }
        return;
    }
    if offscreen.frames == warm_up + 1 + offscreen.timed as u32 {
        let path = offscreen.path.clone();
        commands
            .spawn(Screenshot::image(offscreen.target.clone()))
            .observe(save_to_disk(path))
            .observe(
                |_: On<ScreenshotCaptured>, mut offscreen: ResMut<Offscreen>| {
                    offscreen.frames = u32::MAX / 2
                },
            );
    } else if offscreen.frames > u32::MAX / 2 {
        exit.write(AppExit::Success);
    }
}

/// Each of quadray's diagnostics (`render/quadray*`, and the plugins' CPU times
/// `quadray*`): the median of its kept history.
fn print_quadray_diagnostics(diagnostics: &DiagnosticsStore) {
    let mut found: Vec<_> = diagnostics
        .iter()
        .filter(|d| {
            let path = d.path().as_str();
            path.starts_with("render/quadray") || path.starts_with("quadray")
        })
        .collect();
    found.sort_by_key(|d| d.path().as_str());
    for d in found {
        let mut values: Vec<f64> = d.values().copied().collect();
        if values.is_empty() {
            continue;
        }
        values.sort_by(f64::total_cmp);
        println!(
            "{}: median {:.4}{} over {} frames",
            d.path(),
            values[values.len() / 2],
            d.suffix,
            values.len()
        );
    }
}
