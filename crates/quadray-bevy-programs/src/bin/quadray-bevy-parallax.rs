//! Bevy's own parallax-mapping example scene (a spinning cube with Bevy's maps, a point light, a
//! floor) with the pyramid as one more method: Space cycles Bevy's parallax occlusion mapping,
//! Bevy's relief mapping and quadray's pyramid tracing; 1/2 lower/raise the depth scale; a click
//! moves the camera. The window's title says which method is shown.
//!
//! `cargo run --release --bin quadray-bevy-parallax` (`--bin`, not `-p`: Cargo then resolves
//! features as for the whole workspace, and what the test build compiled is reused)
//! Without a display: `... --bin quadray-bevy-parallax -- --screenshot out.png [--method pom|relief|pyramid]`
//! renders a few frames off screen and saves the picture.

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::image::ImageLoaderSettings;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use clap::Parser;
use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial};
use quadray_bevy_programs::{Offscreen, add_default_plugins, repository_assets, set_title};

const METHODS: [&str; 3] = [
    "Bevy parallax occlusion mapping",
    "Bevy relief mapping",
    "quadray pyramid tracing",
];
const CAMERAS: [Vec3; 3] = [
    Vec3::new(1.5, 1.5, 1.5),
    Vec3::new(2.4, 0.0, 0.2),
    Vec3::new(-1.0, 0.8, -1.2),
];

#[derive(Resource)]
struct Materials {
    bevy: Handle<StandardMaterial>,
    pyramid: Handle<PyramidMaterial>,
    method: usize,
}

#[derive(Component)]
struct Cube;

/// The method shown first (`--method`).
#[derive(Resource)]
struct FirstMethod(usize);

/// The command line (`--help` lists it).
#[derive(Parser)]
#[command(
    name = "quadray-bevy-parallax",
    version,
    about = "Bevy's parallax example with Bevy's POM, Bevy's relief mapping and quadray's pyramid"
)]
struct Args {
    /// The method shown first (Space cycles them).
    #[arg(long, value_enum, default_value_t = ShownMethod::Pyramid)]
    method: ShownMethod,
    /// Render off screen, save the picture here and exit.
    #[arg(long, value_name = "PNG")]
    screenshot: Option<String>,
}

/// The methods Space cycles through, in their order.
#[derive(Clone, Copy, clap::ValueEnum)]
enum ShownMethod {
    Pom,
    Relief,
    Pyramid,
}

fn main() {
    let args = Args::parse();
    let method = args.method as usize;
    let mut app = App::new();
    let assets = repository_assets("heightmaps/bevy_parallax");
    // the picture 30 frames after Bevy's last pipeline compiled (the maps load meanwhile)
    let offscreen = args.screenshot.map(|path| Offscreen::new(path, 30, 0));
    add_default_plugins(&mut app, assets, offscreen);
    app.add_plugins(PyramidDisplacementPlugin)
        .insert_resource(FirstMethod(method))
        .add_systems(Startup, setup)
        .add_systems(
            Update,
            (
                spin.run_if(not(resource_exists::<Offscreen>)),
                switch_method,
                change_depth,
                move_camera,
                show_method,
            ),
        )
        .run();
}

#[allow(clippy::too_many_arguments)]
fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    mut pyramid: ResMut<Assets<PyramidMaterial>>,
    mut images: ResMut<Assets<Image>>,
    offscreen: Option<ResMut<Offscreen>>,
    first: Res<FirstMethod>,
) {
    let method = first.0;
    let linear = |s: &mut ImageLoaderSettings| s.is_srgb = false;
    let normal = assets
        .load_builder()
        .with_settings(linear)
        .load("cube_normal.png");
    let depth: Handle<Image> = assets.load("cube_depth.png");
    // Bevy's example material, parallax and all: the pyramid material is the same minus Bevy's parallax.
    let base = StandardMaterial {
        perceptual_roughness: 0.4,
        base_color_texture: Some(assets.load("cube_color.png")),
        normal_map_texture: Some(normal),
        ..default()
    };
    let bevy = standard.add(StandardMaterial {
        depth_map: Some(depth.clone()),
        parallax_depth_scale: 0.09,
        parallax_mapping_method: parallax_method(method),
        max_parallax_layer_count: 32.0,
        ..base.clone()
    });
    let mut extension = PyramidExtension::new(depth, 0.09);
    // The cube's bumps shadow each other from the scene's point light.
    extension.shadow_strength = 1.0;
    let pyramid = pyramid.add(PyramidMaterial { base, extension });

    // AgX and TonyMcMapface need the tonemapping_luts feature; ACES does not.
    let mut camera = commands.spawn((
        Camera3d::default(),
        Tonemapping::AcesFitted,
        Transform::from_translation(CAMERAS[0]).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    if let Some(mut offscreen) = offscreen {
        offscreen.make_target(&mut images, 960, 540);
        camera.insert(RenderTarget::Image(offscreen.target.clone().into()));
    }
    commands.spawn((
        PointLight {
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(2.0, 1.0, -1.1),
        children![(
            Mesh3d(meshes.add(Sphere::new(0.05).mesh().ico(3).unwrap())),
            MeshMaterial3d(standard.add(Color::WHITE))
        )],
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(10.0, 10.0))),
        MeshMaterial3d(standard.add(StandardMaterial {
            perceptual_roughness: 0.45,
            reflectance: 0.18,
            ..Color::srgb_u8(0, 80, 0).into()
        })),
        Transform::from_xyz(0.0, -1.0, 0.0),
    ));
    let cube = meshes.add(
        Mesh::from(Cuboid::default())
            .with_generated_tangents()
            .unwrap(),
    );
    // Turned so that three faces show (the off-screen pictures hold still here).
    let turned = Transform::from_rotation(Quat::from_rotation_y(-0.35));
    let mut entity = commands.spawn((Mesh3d(cube), turned, Cube));
    if method == 2 {
        entity.insert(MeshMaterial3d(pyramid.clone()));
    } else {
        entity.insert(MeshMaterial3d(bevy.clone()));
    }
    commands.insert_resource(Materials {
        bevy,
        pyramid,
        method,
    });
}

fn parallax_method(method: usize) -> ParallaxMappingMethod {
    if method == 1 {
        ParallaxMappingMethod::Relief { max_steps: 8 }
    } else {
        ParallaxMappingMethod::Occlusion
    }
}

fn spin(time: Res<Time>, mut cubes: Query<&mut Transform, With<Cube>>) {
    for mut t in &mut cubes {
        t.rotate_local_y(0.3 * time.delta_secs());
        t.rotate_local_x(0.3 * time.delta_secs());
    }
}

fn switch_method(
    keys: Res<ButtonInput<KeyCode>>,
    mut commands: Commands,
    mut materials: ResMut<Materials>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    cubes: Query<Entity, With<Cube>>,
) {
    if !keys.just_pressed(KeyCode::Space) {
        return;
    }
    materials.method = (materials.method + 1) % METHODS.len();
    if let Some(mut m) = standard.get_mut(&materials.bevy) {
        m.parallax_mapping_method = parallax_method(materials.method);
    }
    for cube in &cubes {
        let mut cube = commands.entity(cube);
        if materials.method == 2 {
            cube.remove::<MeshMaterial3d<StandardMaterial>>()
                .insert(MeshMaterial3d(materials.pyramid.clone()));
        } else {
            cube.remove::<MeshMaterial3d<PyramidMaterial>>()
                .insert(MeshMaterial3d(materials.bevy.clone()));
        }
    }
}

fn change_depth(
    keys: Res<ButtonInput<KeyCode>>,
    materials: Res<Materials>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    mut pyramid: ResMut<Assets<PyramidMaterial>>,
) {
    let step = if keys.just_pressed(KeyCode::Digit1) {
        -0.03
    } else if keys.just_pressed(KeyCode::Digit2) {
        0.03
    } else {
        return;
    };
    if let (Some(mut b), Some(mut p)) = (
        standard.get_mut(&materials.bevy),
        pyramid.get_mut(&materials.pyramid),
    ) {
        b.parallax_depth_scale = (b.parallax_depth_scale + step).clamp(0.0, 0.3);
        p.extension.depth_scale = b.parallax_depth_scale;
    }
}

fn move_camera(
    buttons: Res<ButtonInput<MouseButton>>,
    mut view: Local<usize>,
    mut camera: Single<&mut Transform, With<Camera3d>>,
) {
    if buttons.just_pressed(MouseButton::Left) {
        *view = (*view + 1) % CAMERAS.len();
        **camera = Transform::from_translation(CAMERAS[*view]).looking_at(Vec3::ZERO, Vec3::Y);
    }
}

fn show_method(
    materials: Res<Materials>,
    standard: Res<Assets<StandardMaterial>>,
    mut windows: Query<&mut Window, With<PrimaryWindow>>,
) {
    let depth = standard
        .get(&materials.bevy)
        .map_or(0.0, |m| m.parallax_depth_scale);
    let title = format!(
        "{} (Space: next method, 1/2: depth scale {depth:.2}, click: view)",
        METHODS[materials.method]
    );
    set_title(&mut windows, &title);
}
