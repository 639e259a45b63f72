//! One bounce of indirect light in a Bevy app: the bundled Cornell box glTF
//! (`assets/scenes/cornell_spot.gltf`) loaded by Bevy's glTF loader, its spot light turning
//! slowly, Bevy's direct light and shadows as they are, and quadray's light quadtree adding the
//! bounce. G turns the bounce on and off; M cycles the method (per-tile cuts, the quadtree's one cut,
//! RSM sampling, every VPL); C shows the light quadtree's cut over the RSM in the top-left corner;
//! Space stops and restarts the light. The window's title says what is shown.
//!
//! `cargo run --release --bin quadray-bevy-gi` (`--bin`, not `-p`: Cargo then resolves features
//! as for the whole workspace, and what the test build compiled is reused).
//! Without a display: `... --bin quadray-bevy-gi -- --screenshot out.png [--no-gi] [--cut-view]
//! [--method quadtree|quadtree-tiles|rsm|reference]` renders off screen with the light still and
//! saves the picture. `--frames N` (with `--screenshot`) times N frames with the light turning
//! and prints their median and Bevy's render diagnostics of the bounce (GPU time of the light's
//! passes, the gather and the composite; clusters in the cut; VPL evaluations and texel fetches
//! per shaded pixel): the benchmark of the bounce's cost in a Bevy frame. `--size WxH` (default
//! 256x256) and `--rsm-size N` (default 128) size the off-screen picture and the RSM.

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::gltf::GltfAssetLabel;
use bevy::pbr::DefaultOpaqueRendererMethod;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use bevy::world_serialization::WorldAssetRoot;
use quadray_bevy::gi::{IndirectLight, IndirectLightPlugin, IndirectLightSource};
use quadray_bevy_programs::{
    Offscreen, add_default_plugins, flag_value, repository_assets, set_title,
};
use quadray_indirect::{Method, Settings};

const SCENE: &str = "scenes/cornell_spot.gltf";
/// The methods M cycles through.
const METHODS: [Method; 4] = [
    Method::QuadtreeTiles,
    Method::Quadtree,
    Method::Rsm,
    Method::Reference,
];
/// The light's turn about the vertical (radians a second).
const TURN: f32 = 0.25;

/// The glTF file's camera, when it appears.
type FileCamera = (Added<Camera3d>, Without<IndirectLight>);

/// What the first frame shows (`--no-gi`, `--method`, `--cut-view`) and at what size (`--size`,
/// `--rsm-size`).
#[derive(Resource, Clone, Copy)]
struct Shown {
    gi: bool,
    method: Method,
    cut_view: bool,
    turning: bool,
    size: (u32, u32),
    rsm_size: u32,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| flag_value(&args, flag);
    let method = match value("--method").map(|m| m.parse::<Method>()) {
        None => Method::DEFAULT,
        Some(Ok(m)) => m,
        Some(Err(e)) => {
            eprintln!("--method: {e}");
            std::process::exit(2);
        }
    };
    let offscreen = value("--screenshot");
    let timed = match value("--frames").map(|n| n.parse::<usize>()) {
        None => 0,
        Some(Ok(n)) if n > 0 && offscreen.is_some() => n,
        _ => {
            eprintln!("--frames: expected a positive count, with --screenshot");
            std::process::exit(2);
        }
    };
    let size = match value("--size").map(|s| parse_size(&s)) {
        None => (256, 256),
        Some(Some(size)) => size,
        Some(None) => {
            eprintln!("--size: expected WIDTHxHEIGHT, each 1..=8192");
            std::process::exit(2);
        }
    };
    let rsm_size = match value("--rsm-size").map(|n| n.parse::<u32>()) {
        None => 128,
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            eprintln!("--rsm-size: {e}");
            std::process::exit(2);
        }
    };
    let shown = Shown {
        gi: !args.iter().any(|a| a == "--no-gi"),
        method,
        cut_view: args.iter().any(|a| a == "--cut-view"),
        turning: offscreen.is_none() || timed > 0,
        size,
        rsm_size,
    };
    let mut app = App::new();
    let assets = repository_assets("");
    // the scene loads in a few frames; each frame gathers anew while the light turns (on the
    // CPU rasteriser about a second a frame at this size)
    let offscreen = offscreen.map(|path| Offscreen::new(path, 60, timed));
    add_default_plugins(&mut app, assets, offscreen);
    app.insert_resource(DefaultOpaqueRendererMethod::deferred())
        .add_plugins(IndirectLightPlugin)
        .insert_resource(shown)
        .add_systems(Startup, setup)
        .add_systems(Update, (configure, keys, turn_light, show_title).chain())
        .run();
}

/// `WIDTHxHEIGHT`, each side 1..=8192.
fn parse_size(text: &str) -> Option<(u32, u32)> {
    let (w, h) = text.split_once('x')?;
    let side = |s: &str| s.parse::<u32>().ok().filter(|n| (1..=8192).contains(n));
    Some((side(w)?, side(h)?))
}

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    offscreen: Option<ResMut<Offscreen>>,
    shown: Res<Shown>,
) {
    commands.spawn(WorldAssetRoot(
        assets.load(GltfAssetLabel::Scene(0).from_asset(SCENE)),
    ));
    if let Some(mut offscreen) = offscreen {
        let (width, height) = shown.size;
        offscreen.make_target(&mut images, width, height);
    }
}

/// A camera where the file's is (that one turned off) gets the bounce (deferred, no MSAA, by
/// default a 128^2 RSM: interactive on a CPU rasteriser too); the file's spot is marked as its
/// source. A refused RSM size is Bevy's log's warning, as for any app.
fn configure(
    mut commands: Commands,
    cameras: Query<(Entity, &Transform, &Projection), FileCamera>,
    lights: Query<Entity, (Added<SpotLight>, Without<IndirectLightSource>)>,
    offscreen: Option<Res<Offscreen>>,
    shown: Res<Shown>,
) {
    for light in &lights {
        commands.entity(light).insert(IndirectLightSource);
    }
    for (file_camera, transform, projection) in &cameras {
        commands.entity(file_camera).insert(Camera {
            is_active: false,
            ..default()
        });
        let mut camera = commands.spawn((
            Camera3d::default(),
            *transform,
            projection.clone(),
            Msaa::Off,
            Tonemapping::AcesFitted,
            IndirectLight {
                settings: Settings {
                    rsm_size: shown.rsm_size,
                    ..Settings::DEFAULT
                },
                method: shown.method,
                enabled: shown.gi,
                cut_view: shown.cut_view,
                ..default()
            },
        ));
        if let Some(offscreen) = &offscreen {
            camera.insert(RenderTarget::Image(offscreen.target.clone().into()));
        }
    }
}

fn keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut shown: ResMut<Shown>,
    mut cameras: Query<&mut IndirectLight>,
) {
    if keys.just_pressed(KeyCode::KeyG) {
        shown.gi = !shown.gi;
    }
    if keys.just_pressed(KeyCode::KeyM) {
        let next = METHODS
            .iter()
            .position(|&m| m == shown.method)
            .map_or(0, |i| i + 1);
        shown.method = METHODS[next % METHODS.len()];
    }
    if keys.just_pressed(KeyCode::KeyC) {
        shown.cut_view = !shown.cut_view;
    }
    if keys.just_pressed(KeyCode::Space) {
        shown.turning = !shown.turning;
    }
    for mut gi in &mut cameras {
        if gi.enabled != shown.gi || gi.method != shown.method || gi.cut_view != shown.cut_view {
            gi.enabled = shown.gi;
            gi.method = shown.method;
            gi.cut_view = shown.cut_view;
        }
    }
}

fn turn_light(
    time: Res<Time>,
    shown: Res<Shown>,
    mut lights: Query<&mut Transform, With<IndirectLightSource>>,
) {
    if shown.turning {
        for mut t in &mut lights {
            t.rotate_y(TURN * time.delta_secs());
        }
    }
}

fn show_title(shown: Res<Shown>, mut windows: Query<&mut Window, With<PrimaryWindow>>) {
    let title = format!(
        "quadray indirect light: {} ({}) - G: bounce on/off, M: method, C: cut over the RSM, \
         Space: light {}",
        if shown.gi { "on" } else { "off" },
        shown.method.name(),
        if shown.turning { "turning" } else { "still" },
    );
    set_title(&mut windows, &title);
}
