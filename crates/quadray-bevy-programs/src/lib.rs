//! What quadray's Bevy programs share: their flags' values, a window or off-screen rendering
//! (`--screenshot PATH`: a few frames into an image, saved, then exit; `--frames N`: N frames
//! timed first), and the window title that says what is shown.

use bevy::app::ScheduleRunnerPlugin;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy::window::{ExitCondition, PrimaryWindow};
use bevy::winit::WinitPlugin;
use std::time::Duration;

/// The value after `flag` on the command line, if any.
pub fn flag_value(args: &[String], flag: &str) -> Option<String> {
    args.iter()
        .position(|a| a == flag)
        .and_then(|i| args.get(i + 1))
        .cloned()
}

/// Off-screen rendering: where the picture goes, the image the camera renders into, and the
/// frames to wait and to time.
#[derive(Resource)]
pub struct Offscreen {
    /// The PNG to save.
    pub path: String,
    /// The camera's target (made by [`Offscreen::make_target`]).
    pub target: Handle<Image>,
    /// Frames before the picture is taken (the scene loaded, the pipelines warm).
    pub warm_up: u32,
    /// Frames to time after the warm-up, before the picture (0: none).
    pub timed: usize,
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
/// `offscreen`, headless (no window, a loop of 1 ms) saving the picture when ready.
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
    app.add_plugins(
        DefaultPlugins
            .set(assets)
            .set(window)
            .disable::<WinitPlugin>(),
    )
    .add_plugins(ScheduleRunnerPlugin::run_loop(Duration::from_millis(1)))
    .insert_resource(offscreen)
    .add_systems(Update, save_when_ready);
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

/// Off screen: after the warm-up, times the frames asked for (printing their median), then saves
/// the target and quits.
fn save_when_ready(
    mut commands: Commands,
    mut offscreen: ResMut<Offscreen>,
    mut exit: MessageWriter<AppExit>,
    time: Res<Time<Real>>,
) {
    offscreen.frames += 1;
    let warm_up = offscreen.warm_up;
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
