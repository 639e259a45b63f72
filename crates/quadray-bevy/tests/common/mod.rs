//! A headless Bevy app for the tests: Bevy's default plugins reading the repository's assets, no
//! window, and `plugin` with the test's systems added before the renderer starts; and what the
//! material's tests share: the height maps and angles they trace, the unit plane they displace.

use bevy::app::PluginsState;
use bevy::prelude::*;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;

pub const ASSETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets");

/// The material tests' view angles off the plane's normal (degrees).
pub const ANGLES_DEG: [f32; 3] = [0.0, 60.0, 80.0];
/// The material tests' height maps: a tile map and Bevy's own parallax example's.
pub const MAPS: [&str; 2] = [
    "heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png",
    "heightmaps/bevy_parallax/cube_depth.png",
];

/// The camera of a view `angle_deg` off the unit plane's normal, 1.1 from its centre.
pub fn eye(angle_deg: f32) -> Vec3 {
    let (sin, cos) = angle_deg.to_radians().sin_cos();
    Vec3::new(0.0, 1.1 * cos, 1.1 * sin)
}

/// The unit plane facing +y with the tangents the material's trace needs.
pub fn unit_plane() -> Mesh {
    Mesh::from(Plane3d::new(Vec3::Y, Vec2::splat(0.5)))
        .with_generated_tangents()
        .expect("the plane has normals and uvs")
}

/// A height map loaded as linear data (not sRGB).
pub fn height_map(assets: &AssetServer, path: &'static str) -> Handle<Image> {
    assets
        .load_builder()
        .with_settings(|s: &mut bevy::image::ImageLoaderSettings| s.is_srgb = false)
        .load(path)
}

/// The material's debug buffer for `pixels` pixels: two entries a pixel (ray, hit); hit depth -2
/// marks a pixel no fragment wrote.
pub fn hit_buffer(pixels: u32) -> bevy::render::storage::ShaderBuffer {
    let blank: Vec<f32> = (0..pixels)
        .flat_map(|_| [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -2.0, 0.0])
        .collect();
    let mut buffer =
        bevy::render::storage::ShaderBuffer::new(bytemuck::cast_slice(&blank), default());
    buffer.buffer_description.usage |= bevy::render::render_resource::BufferUsages::COPY_SRC;
    buffer
}

/// A `side` x `side` height map of one byte a texel (0: the top), row-major.
pub fn r8_height_map(side: u32, texels: Vec<u8>) -> Image {
    use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
    Image::new(
        Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        texels,
        TextureFormat::R8Unorm,
        bevy::asset::RenderAssetUsages::all(),
    )
}

/// The log (stdout and stderr) of the ignored `tests` of this binary run again in a child process,
/// which must pass.
pub fn child_log(tests: &[&str]) -> String {
    let output = std::process::Command::new(std::env::current_exe().unwrap())
        .arg("--exact")
        .args(tests)
        .args(["--ignored", "--nocapture"])
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&output.stdout).into_owned()
        + &String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "the child {}: {log}",
        output.status
    );
    log
}

/// The app with `add` applied (plugins, resources, systems), ready to `update`.
pub fn headless_app(add: impl FnOnce(&mut App)) -> App {
    headless_app_with_images(ImagePlugin::default(), add)
}

/// [`headless_app`] with `images` as its `ImagePlugin` (its default sampler, say).
pub fn headless_app_with_images(images: ImagePlugin, add: impl FnOnce(&mut App)) -> App {
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(images)
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
