//! One bounce of indirect light in a Bevy app: the bundled Cornell box glTF
//! (`assets/scenes/cornell_spot.gltf`) loaded by Bevy's glTF loader, its spot light turning
//! slowly (a scene's every punctual light gives the bounce: sun, point and spot lights), Bevy's direct light and shadows as they are, and quadray's light quadtree adding the
//! bounce. G turns the bounce on and off; M cycles the method (per-tile cuts, the quadtree's one cut,
//! RSM sampling, every VPL); C shows the light quadtree's cut over the RSM in the top-left corner;
//! Space stops and restarts the light; `[` and `]` brighten and darken the picture by one EV. The
//! window's title says what is shown.
//!
//! `cargo run --release --bin quadray-bevy-gi` (`--bin`, not `-p`: Cargo then resolves features
//! as for the whole workspace, and what the test build compiled is reused).
//! `--scene PATH` shows a glTF or GLB scene of your own instead (its camera, or one that frames
//! its meshes from +z where it has none, and its punctual lights;
//! `assets/scenes/cornell_lights.gltf` has all three kinds); `--gi-lights spot,point`
//! lets only those kinds give the bounce (default: all three); `--shadows` turns on Bevy's shadow
//! maps for its lights (Bevy's glTF loader leaves them off). `--displaced` shows quadray's
//! displaced surfaces instead: a floor and a wall with `PyramidMaterial` (the tile map; Bevy's
//! parallax example's map and colours) beside a plain red wall, lit by a spot, the bounce leaving
//! from the displaced surfaces. Without a display: `... --bin quadray-bevy-gi -- --screenshot out.png [--no-gi]
//! [--cut-view] [--method quadtree|quadtree-tiles|rsm|reference]` renders off screen with the
//! light still and saves the picture. `--frames N` (with `--screenshot`) times N frames with the
//! light turning and prints their median and Bevy's render diagnostics of the bounce (GPU time of
//! the light's passes, the gather and the composite; clusters in the cut; VPL evaluations and
//! texel fetches per shaded pixel): the benchmark of the bounce's cost in a Bevy frame. `--size
//! WxH` (default 256x256) and `--rsm-size N` (default 128) size the off-screen picture and the
//! RSM. `--ev100 EV` sets the camera's exposure (Bevy's `Exposure`; default 9.7, Bevy's): about
//! 15 for a glTF lit by a physical sun, 2 for a 4-lux sun or a dim lamp. `--indirect-shadows`
//! tests each cluster's view on the scene's occupancy grid. `--rsm-source meshes` draws the
//! lights' RSMs from Bevy's meshes on the GPU instead of the scene's triangles made on the CPU.
//! At the scale of games:
//! `--large-scene SEED` makes and shows a scene of about a million triangles in hundreds of
//! meshes (`large_scene.rs`), `--move-node NAME` moves a node of the scene every frame (the
//! large scene's `mover`), `--bend-node NAME` bends a node to and fro every frame (the large
//! scene's `bend`, a joint of its skinned tube), and `--frames` then prints the medians of the plugin's CPU time in
//! each world (`quadray_gi/main_world_cpu`, `quadray_gi/render_world_cpu`) beside its GPU
//! passes'. `--turn-node NAME:DEGREES` turns a node about its own z axis once it is loaded: a
//! joint of a skinned mesh bends the mesh, and the bounce with it
//! (`--scene assets/scenes/skinned_bar.gltf --turn-node bend:-60`). `--help` lists the flags; an
//! unknown one is refused.

use bevy::camera::{Exposure, RenderTarget};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::gltf::GltfAssetLabel;
use bevy::image::ImageLoaderSettings;
use bevy::pbr::DefaultOpaqueRendererMethod;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use bevy::world_serialization::WorldAssetRoot;
use clap::Parser;
use quadray_bevy::gi::{IndirectLight, IndirectLightPlugin, IndirectLightSource, RsmSource};
use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial};
use quadray_bevy_programs::{Offscreen, add_default_plugins, repository_assets, set_title};
use quadray_indirect::{Method, Settings, Size};
use std::path::{Path, PathBuf};

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

/// The scene's camera (the glTF file's, or the displaced scene's), when it appears.
type FileCamera = (Added<Camera3d>, Without<IndirectLight>);

/// What the first frame shows (`--no-gi`, `--method`, `--cut-view`), at what size (`--size`,
/// `--rsm-size`), interleaving (`--interleave`), indirect shadows (`--indirect-shadows`), the
/// RSM's source (`--rsm-source`) and exposure (`--ev100`).
#[derive(Resource, Clone, Copy)]
struct Shown {
    gi: bool,
    method: Method,
    cut_view: bool,
    turning: bool,
    size: (u32, u32),
    rsm_size: u32,
    interleave: u32,
    indirect_shadows: bool,
    rsm_source: RsmSource,
    ev100: f32,
}

/// The command line (`--help` lists it).
#[derive(Parser)]
#[command(
    name = "quadray-bevy-gi",
    version,
    about = "One bounce of indirect light from quadray's light quadtree in a Bevy app"
)]
struct Args {
    /// A glTF or GLB scene of your own: its camera (or one framing its meshes from +z), and its
    /// punctual lights (directional, point and spot) turning and giving the bounce (default: the
    /// bundled Cornell box).
    #[arg(long, value_name = "PATH.gltf")]
    scene: Option<PathBuf>,
    /// Show quadray's displaced surfaces instead of the Cornell box: a floor and a wall drawn
    /// with the pyramid material beside a plain red wall, lit by a spot; the bounce leaves from
    /// the displaced surfaces (the GI plugin's RSM holds their height fields).
    #[arg(long, conflicts_with = "scene")]
    displaced: bool,
    /// Render off screen, save the picture here and exit.
    #[arg(long, value_name = "PNG")]
    screenshot: Option<String>,
    /// With --screenshot: time this many frames with the light turning, print their median and
    /// Bevy's render diagnostics of the bounce.
    #[arg(long, requires = "screenshot", value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// The first frame's method: quadtree-tiles, quadtree, rsm or reference (M cycles them).
    #[arg(long, default_value_t = Method::DEFAULT)]
    method: Method,
    /// Start without the bounce (G turns it on).
    #[arg(long)]
    no_gi: bool,
    /// Start with the cut over the RSM in a corner (C toggles it).
    #[arg(long)]
    cut_view: bool,
    /// The off-screen picture's size, WxH.
    #[arg(long, default_value = "256x256", value_parser = Settings::parse_size)]
    size: Size,
    /// The RSM's side, a power of two.
    #[arg(long, default_value_t = 128, value_parser = Settings::parse_rsm_size)]
    rsm_size: u32,
    /// Interleaved sampling for the one cut and RSM sampling: each pixel of an NxN block sums
    /// every N^2-th cluster or sample, and a geometry-aware filter rejoins them (1: off).
    #[arg(long, default_value_t = Settings::DEFAULT.interleave,
          value_parser = Settings::INTERLEAVE.parser())]
    interleave: u32,
    /// Indirect shadows: each receiver's view of each cluster tested on the scene's occupancy
    /// grid (quadray's `--indirect-shadows`, at its default grid).
    #[arg(long)]
    indirect_shadows: bool,
    /// The camera's exposure as an EV100 (Bevy's `Exposure`; `[` and `]` step it): one less is
    /// twice as bright. About log2 of the light in lux: Bevy's default 9.7 for a room lit by lamps
    /// of a few thousand lumens or a 1,000-lux sun, 15 for a physical sun of 100,000 lux, 2 for a
    /// 4-lux sun or a dim lamp. Bevy's ambient light is scaled with it.
    #[arg(long, default_value_t = Exposure::EV100_BLENDER, value_parser = parse_ev100,
          allow_hyphen_values = true)]
    ev100: f32,
    /// The kinds of the scene's lights that give the bounce, comma-separated (the others light
    /// the scene directly only).
    #[arg(long, value_delimiter = ',', default_values = ["directional", "point", "spot"])]
    gi_lights: Vec<GiLight>,
    /// Show a large scene made from this seed instead: hundreds of meshes, about a million
    /// triangles, a few meshes shared by several nodes, most materials textured, a tube skinned
    /// to three joints (the middle one `bend`), a sun, and a node named `mover` (written as a
    /// GLB into the system's temporary folder first; the benchmark at the scale of games, with
    /// --move-node mover or --bend-node bend).
    #[arg(long, value_name = "SEED", conflicts_with_all = ["scene", "displaced"])]
    large_scene: Option<u64>,
    /// Move the scene's node of this name every frame (a circle of 2 m around where it
    /// stands), its meshes with it.
    #[arg(long, value_name = "NAME")]
    move_node: Option<String>,
    /// Bend the scene's node of this name every frame: turn it to and fro about its own z axis
    /// (up to 30 degrees either way), the meshes skinned to it with it (the large scene's `bend`,
    /// the middle joint of its skinned tube).
    #[arg(long, value_name = "NAME")]
    bend_node: Option<String>,
    /// Turn the scene's node of this name about its own z axis by this many degrees (counter-
    /// clockwise seen from its +z), once it is loaded: a joint of a skinned mesh bends the mesh
    /// (`skinned_bar.gltf`'s `bend`).
    #[arg(long, value_name = "NAME:DEGREES", value_parser = parse_turned_node)]
    turn_node: Option<TurnedNode>,
    /// Bevy's shadow maps on the scene file's lights, which Bevy's glTF loader leaves off: the
    /// direct light's shade, where the bounce is all the light there is (a sunlit scene's).
    #[arg(long, conflicts_with = "displaced")]
    shadows: bool,
    /// What the lights' RSMs are drawn from: the scene's triangles made on the CPU, or Bevy's
    /// meshes on the GPU (`IndirectLight::rsm_source`, whose documentation says what each does).
    #[arg(long, default_value_t = RsmSource::default())]
    rsm_source: RsmSource,
}

/// A kind of light `--gi-lights` names.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum GiLight {
    Directional,
    Point,
    Spot,
}

/// The kinds of light marked as the bounce's sources, and whether the file's lights cast
/// Bevy's shadows (`--shadows`).
#[derive(Resource)]
struct GiLights {
    kinds: Vec<GiLight>,
    shadows: bool,
}

/// What is shown: a scene file under the asset root (with the camera that frames it when it has
/// none), or the displaced surfaces built here.
#[derive(Resource, Clone)]
enum Shows {
    File(String, Option<quadray_core::scene::Camera>),
    Displaced,
}

/// The node `--move-node` names.
#[derive(Resource)]
struct MovedNode(String);

/// The node `--bend-node` names.
#[derive(Resource)]
struct BentNode(String);

/// The node `--turn-node` names and its turn.
#[derive(Resource, Clone)]
struct TurnedNode {
    name: String,
    degrees: f32,
}

fn parse_turned_node(text: &str) -> Result<TurnedNode, String> {
    let (name, degrees) = text
        .rsplit_once(':')
        .filter(|(name, _)| !name.is_empty())
        .ok_or_else(|| format!("{text:?} is not NAME:DEGREES"))?;
    let degrees: f32 = degrees
        .parse()
        .ok()
        .filter(|d: &f32| d.is_finite())
        .ok_or_else(|| format!("{degrees:?} in {text:?} is not a finite number of degrees"))?;
    Ok(TurnedNode {
        name: name.to_string(),
        degrees,
    })
}

fn main() {
    let mut args = Args::parse();
    if let Some(seed) = args.large_scene {
        args.scene = Some(large_scene(seed).unwrap_or_else(|e| {
            eprintln!("error: --large-scene {seed}: {e}");
            std::process::exit(2);
        }));
    }
    let (assets, scene) = match &args.scene {
        None if args.displaced => (repository_assets(""), Shows::Displaced),
        None => (repository_assets(""), Shows::File(SCENE.to_string(), None)),
        Some(path) => scene_assets(path)
            .map(|(assets, file, framing)| (assets, Shows::File(file, framing)))
            .unwrap_or_else(|e| {
                eprintln!("error: --scene {}: {e}", path.display());
                std::process::exit(2);
            }),
    };
    let timed = args.frames.unwrap_or(0) as usize;
    let shown = Shown {
        gi: !args.no_gi,
        method: args.method,
        cut_view: args.cut_view,
        turning: args.screenshot.is_none() || timed > 0,
        size: (args.size.width, args.size.height),
        rsm_size: args.rsm_size,
        interleave: args.interleave,
        indirect_shadows: args.indirect_shadows,
        rsm_source: args.rsm_source,
        ev100: args.ev100,
    };
    let mut app = App::new();
    // the picture 10 frames after Bevy's last pipeline compiled (the scene loads meanwhile);
    // each frame gathers anew while the light turns (on the CPU rasteriser about a second a
    // frame at this size)
    let offscreen = args.screenshot.map(|path| Offscreen::new(path, 10, timed));
    add_default_plugins(&mut app, assets, offscreen);
    app.insert_resource(DefaultOpaqueRendererMethod::deferred())
        .add_plugins((IndirectLightPlugin, PyramidDisplacementPlugin))
        .insert_resource(shown)
        .insert_resource(GiLights {
            kinds: args.gi_lights.clone(),
            shadows: args.shadows,
        })
        .insert_resource(scene)
        .add_systems(Startup, setup)
        .add_systems(Update, (configure, keys, turn_light, show_title).chain());
    if let Some(name) = args.move_node {
        app.insert_resource(MovedNode(name))
            .add_systems(Update, move_node);
    }
    if let Some(name) = args.bend_node {
        app.insert_resource(BentNode(name))
            .add_systems(Update, bend_node);
    }
    if let Some(turned) = args.turn_node {
        app.insert_resource(turned).add_systems(Update, turn_node);
    }
    app.run();
}

/// Writes the large scene of `seed` into the temporary folder and says what it holds.
fn large_scene(seed: u64) -> std::io::Result<PathBuf> {
    let folder = std::env::temp_dir().join(format!("quadray-large-scene-{seed}"));
    std::fs::create_dir_all(&folder)?;
    let path = folder.join("scene.glb");
    let made = quadray_bevy_programs::large_scene::write_large_scene(&path, seed)?;
    println!(
        "large scene {seed}: {} triangles, {} meshes, {} nodes with a mesh, {} triangles in \
         `{}`, {} skinned to `{}`, {} of {} materials textured ({} textures) ({})",
        made.triangles,
        made.meshes,
        made.nodes,
        made.mover_triangles,
        quadray_bevy_programs::large_scene::MOVER,
        made.skinned_triangles,
        quadray_bevy_programs::large_scene::BENDER,
        made.textured_materials,
        made.materials,
        made.images,
        path.display()
    );
    Ok(path)
}

/// The node named `name` and `keep` of its transform as loaded: looked for until it is there
/// (the scene loads over several frames), then kept in `found`.
fn find_node<T: Copy>(
    found: &mut Option<(Entity, T)>,
    nodes: &Query<(Entity, &Name, &mut Transform)>,
    name: &str,
    keep: impl Fn(&Transform) -> T,
) -> Option<(Entity, T)> {
    if found.is_none() {
        *found = nodes
            .iter()
            .find(|(_, node, _)| node.as_str() == name)
            .map(|(entity, _, t)| (entity, keep(t)));
    }
    *found
}

/// Moves the node `--move-node` names a step along its circle each frame, once it is loaded.
fn move_node(
    moved: Res<MovedNode>,
    mut nodes: Query<(Entity, &Name, &mut Transform)>,
    mut found: Local<Option<(Entity, Vec3)>>,
    mut frame: Local<u32>,
) {
    let Some((entity, start)) = find_node(&mut found, &nodes, &moved.0, |t| t.translation) else {
        return;
    };
    let Ok((_, _, mut transform)) = nodes.get_mut(entity) else {
        return;
    };
    *frame += 1;
    let turn = *frame as f32 * 0.1;
    transform.translation = start + 2.0 * Vec3::new(turn.cos() - 1.0, 0.0, turn.sin());
}

/// Turns the node `--bend-node` names to and fro about its z axis each frame, once it is
/// loaded.
fn bend_node(
    bent: Res<BentNode>,
    mut nodes: Query<(Entity, &Name, &mut Transform)>,
    mut found: Local<Option<(Entity, Quat)>>,
    mut frame: Local<u32>,
) {
    let Some((entity, start)) = find_node(&mut found, &nodes, &bent.0, |t| t.rotation) else {
        return;
    };
    let Ok((_, _, mut transform)) = nodes.get_mut(entity) else {
        return;
    };
    *frame += 1;
    let angle = 30f32.to_radians() * (*frame as f32 * 0.3).sin();
    transform.rotation = start * Quat::from_rotation_z(angle);
}

/// Turns the nodes `--turn-node` names about their z axis, in the first frame they are there.
fn turn_node(
    turned: Res<TurnedNode>,
    mut nodes: Query<(&Name, &mut Transform)>,
    mut done: Local<bool>,
) {
    if *done {
        return;
    }
    for (name, mut transform) in &mut nodes {
        if name.as_str() == turned.name {
            transform.rotate_local_z(turned.degrees.to_radians());
            *done = true;
        }
    }
}

/// The EV100s `--ev100` takes: from a starlit night to well beyond a sunlit snowfield.
const EV100_RANGE: std::ops::RangeInclusive<f32> = -10.0..=25.0;

fn parse_ev100(text: &str) -> Result<f32, String> {
    let ev100: f32 = text.parse().map_err(|e| format!("{e}"))?;
    if EV100_RANGE.contains(&ev100) {
        Ok(ev100)
    } else {
        Err(format!(
            "EV100 {text} is outside {}..{}",
            EV100_RANGE.start(),
            EV100_RANGE.end()
        ))
    }
}

/// Bevy's ambient light at its default exposure (80 cd/m^2 at EV100 9.7), scaled with the
/// exposure: the same faint fill on screen at every light level, where Bevy's fixed 80 would
/// wash out a scene lit by a 4-lux sun and exposed for it.
fn ambient(ev100: f32) -> AmbientLight {
    let at_default = AmbientLight::default();
    AmbientLight {
        brightness: at_default.brightness * (ev100 - Exposure::EV100_BLENDER).exp2(),
        ..at_default
    }
}

/// Bevy's asset plugin reading the folder of a scene file of the user's, the file's name under
/// it, and a camera framing its meshes where it has none: a glTF or GLB file that exists and
/// that quadray's reader reads (so that a bad file is an error here, not a black picture).
fn scene_assets(
    path: &Path,
) -> Result<(AssetPlugin, String, Option<quadray_core::scene::Camera>), String> {
    let gltf = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
    if !gltf {
        return Err("not a glTF scene (.gltf or .glb)".into());
    }
    let path = std::fs::canonicalize(path).map_err(|e| format!("cannot read it: {e}"))?;
    let (scene, framed) =
        quadray_core::scene::SceneDescription::load_framing(&path).map_err(|e| e.reason)?;
    let framing = framed.then_some(scene.camera);
    let (Some(folder), Some(name)) = (path.parent(), path.file_name()) else {
        return Err("not a file".into());
    };
    let assets = AssetPlugin {
        file_path: folder.to_string_lossy().into_owned(),
        ..default()
    };
    Ok((assets, name.to_string_lossy().into_owned(), framing))
}

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut images: ResMut<Assets<Image>>,
    mut offscreen: Option<ResMut<Offscreen>>,
    shown: Res<Shown>,
    scene: Res<Shows>,
) {
    match &*scene {
        Shows::File(file, framing) => {
            let world = assets.load(GltfAssetLabel::Scene(0).from_asset(file.clone()));
            if let Some(offscreen) = offscreen.as_deref_mut() {
                offscreen.waits_for.push(world.clone().untyped());
            }
            commands.spawn(WorldAssetRoot(world));
            // where the file's camera would be (`configure` gives it the bounce)
            if let Some(c) = framing {
                commands.spawn((
                    Camera3d::default(),
                    Transform::from_translation(c.position).looking_at(c.target, c.up),
                    Projection::Perspective(PerspectiveProjection {
                        fov: c.fov_y_deg.to_radians(),
                        ..default()
                    }),
                ));
            }
        }
        Shows::Displaced => commands.run_system_cached(displaced_scene),
    }
    if let Some(mut offscreen) = offscreen {
        let (width, height) = shown.size;
        offscreen.make_target(&mut images, width, height);
    }
}

/// The displaced surfaces: a 4 x 4 floor with the tile map and a 4 x 4 wall with Bevy's parallax
/// example's maps (`PyramidMaterial`, self-shadowed), a plain red wall on the left, a spot
/// light, and a camera where a glTF file's would be (`configure` gives it the bounce).
fn displaced_scene(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    mut pyramid: ResMut<Assets<PyramidMaterial>>,
) {
    let linear = |s: &mut ImageLoaderSettings| s.is_srgb = false;
    let mut square = |normal: Vec3| {
        let plane = Plane3d::new(normal, Vec2::splat(2.0)).mesh().build();
        meshes.add(
            plane
                .with_generated_tangents()
                .expect("a plane has normals and uvs"),
        )
    };
    let (floor, wall, side) = (square(Vec3::Y), square(Vec3::Z), square(Vec3::X));
    let mut displaced = |base: StandardMaterial, map: &str, depth_scale: f32| {
        let map = assets
            .load_builder()
            .with_settings(linear)
            .load(map.to_owned());
        let mut extension = PyramidExtension::new(map, depth_scale);
        extension.shadow_strength = 1.0;
        pyramid.add(PyramidMaterial { base, extension })
    };
    let tiles = displaced(
        StandardMaterial {
            base_color: Color::srgb(0.85, 0.8, 0.7),
            perceptual_roughness: 0.8,
            ..default()
        },
        "heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png",
        0.015,
    );
    let stones = displaced(
        StandardMaterial {
            base_color_texture: Some(assets.load("heightmaps/bevy_parallax/cube_color.png")),
            perceptual_roughness: 0.7,
            ..default()
        },
        "heightmaps/bevy_parallax/cube_depth.png",
        0.03,
    );
    commands.spawn((Mesh3d(floor), MeshMaterial3d(tiles), Transform::default()));
    commands.spawn((
        Mesh3d(wall),
        MeshMaterial3d(stones),
        Transform::from_xyz(0.0, 2.0, -2.0),
    ));
    commands.spawn((
        Mesh3d(side),
        MeshMaterial3d(standard.add(Color::srgb(0.8, 0.1, 0.08))),
        Transform::from_xyz(-2.0, 2.0, 0.0),
    ));
    commands.spawn((
        SpotLight {
            intensity: 2.0e6,
            outer_angle: 0.7,
            inner_angle: 0.5,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(1.2, 3.4, 1.6).looking_at(Vec3::new(-0.6, 0.0, -1.0), Vec3::Y),
    ));
    commands.spawn((
        Camera3d::default(),
        Transform::from_xyz(1.2, 1.9, 4.6).looking_at(Vec3::new(-0.2, 1.0, -0.8), Vec3::Y),
        Projection::default(),
    ));
}

/// A light of the three kinds glTF files hold: one of the three is there.
type FileLight = (
    Entity,
    Option<&'static mut DirectionalLight>,
    Option<&'static mut PointLight>,
    Option<&'static mut SpotLight>,
);

/// A light of the three kinds glTF files hold, just loaded.
type NewLight = (
    Or<(Added<SpotLight>, Added<PointLight>, Added<DirectionalLight>)>,
    Without<IndirectLightSource>,
);

/// A camera where the file's is (that one turned off) gets the bounce (deferred, no MSAA, by
/// default a 128^2 RSM: interactive on a CPU rasteriser too); the file's lights of the kinds
/// `--gi-lights` names are marked as its sources, and with `--shadows` every light casts
/// Bevy's shadows. A refused RSM size is Bevy's log's warning, as for any app.
fn configure(
    mut commands: Commands,
    cameras: Query<(Entity, &Transform, &Projection), FileCamera>,
    mut lights: Query<FileLight, NewLight>,
    gi_lights: Res<GiLights>,
    offscreen: Option<Res<Offscreen>>,
    shown: Res<Shown>,
) {
    for (light, directional, point, spot) in &mut lights {
        let kind = match (&directional, &point) {
            (Some(_), _) => GiLight::Directional,
            (_, Some(_)) => GiLight::Point,
            _ => GiLight::Spot,
        };
        if gi_lights.kinds.contains(&kind) {
            commands.entity(light).insert(IndirectLightSource);
        }
        if gi_lights.shadows {
            if let Some(mut l) = directional {
                l.shadow_maps_enabled = true;
            }
            if let Some(mut l) = point {
                l.shadow_maps_enabled = true;
            }
            if let Some(mut l) = spot {
                l.shadow_maps_enabled = true;
            }
        }
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
            Exposure { ev100: shown.ev100 },
            ambient(shown.ev100),
            IndirectLight {
                settings: Settings {
                    rsm_size: shown.rsm_size,
                    interleave: shown.interleave,
                    indirect_shadows: shown.indirect_shadows,
                    ..Settings::DEFAULT
                },
                method: shown.method,
                enabled: shown.gi,
                cut_view: shown.cut_view,
                rsm_source: shown.rsm_source,
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
    mut cameras: Query<(&mut IndirectLight, &mut Exposure, &mut AmbientLight)>,
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
    for (key, step) in [(KeyCode::BracketLeft, -1.0), (KeyCode::BracketRight, 1.0)] {
        if keys.just_pressed(key) {
            shown.ev100 = (shown.ev100 + step).clamp(*EV100_RANGE.start(), *EV100_RANGE.end());
        }
    }
    for (mut gi, mut exposure, mut ambient_light) in &mut cameras {
        if exposure.ev100 != shown.ev100 {
            exposure.ev100 = shown.ev100;
            *ambient_light = ambient(shown.ev100);
        }
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
        "quadray indirect light: {} ({}), EV100 {} - G: bounce on/off, M: method, C: cut over \
         the RSM, Space: light {}, [ ]: exposure",
        if shown.gi { "on" } else { "off" },
        shown.method.name(),
        shown.ev100,
        if shown.turning { "turning" } else { "still" },
    );
    set_title(&mut windows, &title);
}
