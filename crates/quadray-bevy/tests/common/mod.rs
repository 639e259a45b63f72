//! A headless Bevy app for the tests: Bevy's default plugins reading the repository's assets, no
//! window, and `plugin` with the test's systems added before the renderer starts.

use bevy::app::PluginsState;
use bevy::prelude::*;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;

pub const ASSETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets");

/// The app with `add` applied (plugins, resources, systems), ready to `update`.
pub fn headless_app(add: impl FnOnce(&mut App)) -> App {
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(AssetPlugin {
                file_path: ASSETS.into(),
                ..default()
            })
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .disable::<WinitPlugin>(),
    );
    add(&mut app);
    // What App::run's runners do first: wait for the renderer, then finish the plugins.
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    app
}
