//! The indirect-light plugin's scene as a Bevy app changes it, headless on lavapipe: a few
//! meshes on a textured floor under a spot, a 32x32 camera with indirect shadows. A still frame
//! costs no scene work in either world; a moved mesh makes its own triangles anew, writes them
//! alone to the vertex buffer and moves them alone in the occupancy grid (the floor's texture
//! uploaded once), and the scene equals a fresh app's gather of the new places; the floor's
//! texture swapped for a flat colour drops its layer; a texture refused while the layers were full
//! is taken once one is free. The ball's texture has no CPU-side data:
//! it takes its flat colour. The app's default sampler is nearest, and the floor's texture
//! (`ImageSampler::Default`) is read through it.

use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::pbr::DefaultOpaqueRendererMethod;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::{Render, RenderApp, RenderSystems};
use quadray_bevy::gi::{
    IndirectLight, IndirectLightPlugin, IndirectLightScene, IndirectLightSource, SceneWork,
};
use quadray_indirect::Settings;
use quadray_indirect::scene::Vertex;
use std::sync::{Arc, Mutex};

/// The render world's [`SceneWork`] at the end of its last frame (the render world runs on its
/// own thread).
#[derive(Resource, Clone, Default)]
struct RenderedWork(Arc<Mutex<SceneWork>>);

fn note_work(work: Res<SceneWork>, noted: Res<RenderedWork>) {
    *noted.0.lock().unwrap() = *work;
}

/// The meshes' places: a floor, three boxes and a ball on it.
fn places() -> [Transform; 5] {
    [
        Transform::default(),
        Transform::from_xyz(-1.0, 0.25, 0.0),
        Transform::from_xyz(0.0, 0.25, -1.0),
        Transform::from_xyz(1.0, 0.25, 0.5),
        Transform::from_xyz(0.3, 0.3, 0.6),
    ]
}

/// The box that moves, among [`places`].
const MOVED: usize = 2;

/// An app with the meshes at `places` (with a camera gathering when `camera`), and the entities.
fn app(places: [Transform; 5], camera: bool) -> (App, Vec<Entity>) {
    // nearest by default: the floor's texture, whose sampler is `ImageSampler::Default`, is
    // read through it
    let mut app = crate::common::headless_app_with_images(ImagePlugin::default_nearest(), |app| {
        app.insert_resource(DefaultOpaqueRendererMethod::deferred())
            .add_plugins(IndirectLightPlugin);
        let work = RenderedWork::default();
        app.insert_resource(work.clone());
        app.sub_app_mut(RenderApp)
            .insert_resource(work)
            .add_systems(Render, note_work.in_set(RenderSystems::Cleanup));
    });
    let world = app.world_mut();
    let (floor, cube, ball) = {
        let mut meshes = world.resource_mut::<Assets<Mesh>>();
        (
            meshes.add(Plane3d::new(Vec3::Y, Vec2::splat(2.0))),
            meshes.add(Cuboid::new(0.5, 0.5, 0.5)),
            meshes.add(Sphere::new(0.3).mesh().ico(1).unwrap()),
        )
    };
    let mut images = world.resource_mut::<Assets<Image>>();
    let checker_image = images.add(checker(RenderAssetUsages::default()));
    let gpu_only = images.add(checker(RenderAssetUsages::RENDER_WORLD));
    let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
    let grey = materials.add(Color::srgb(0.7, 0.7, 0.7));
    let textured = materials.add(StandardMaterial {
        base_color_texture: Some(checker_image),
        ..default()
    });
    let unreadable = materials.add(StandardMaterial {
        base_color: Color::srgb(0.7, 0.7, 0.7),
        base_color_texture: Some(gpu_only),
        ..default()
    });
    let mesh_of = [floor, cube.clone(), cube.clone(), cube, ball];
    let entities = mesh_of
        .into_iter()
        .zip(places)
        .enumerate()
        .map(|(i, (mesh, place))| {
            let material = match i {
                0 => &textured,
                BALL => &unreadable,
                _ => &grey,
            };
            world
                .spawn((Mesh3d(mesh), MeshMaterial3d(material.clone()), place))
                .id()
        })
        .collect();
    world.spawn((
        SpotLight {
            intensity: 1.0e5,
            outer_angle: 0.8,
            ..default()
        },
        IndirectLightSource,
        Transform::from_xyz(0.0, 3.0, 0.0).looking_at(Vec3::ZERO, Vec3::Z),
    ));
    if camera {
        let target = world
            .resource_mut::<Assets<Image>>()
            .add(Image::new_target_texture(
                32,
                32,
                TextureFormat::Rgba8UnormSrgb,
                None,
            ));
        world.spawn((
            Camera3d::default(),
            Transform::from_xyz(0.0, 2.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y),
            RenderTarget::Image(target.into()),
            Tonemapping::None,
            Msaa::Off,
            IndirectLight {
                settings: Settings {
                    indirect_shadows: true,
                    shadow_grid: 16,
                    ..Settings::sized(32, 32, 32)
                },
                ..default()
            },
        ));
    }
    (app, entities)
}

/// The ball, among [`places`].
const BALL: usize = 4;

/// A 2x2 sRGB texture, red and green above, green and red below, kept in the worlds `usage` says.
fn checker(usage: RenderAssetUsages) -> Image {
    use bevy::render::render_resource::{Extent3d, TextureDimension};
    let (red, green) = ([200, 30, 30, 255], [30, 200, 30, 255]);
    Image::new(
        Extent3d {
            width: 2,
            height: 2,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        [red, green, green, red].concat(),
        TextureFormat::Rgba8UnormSrgb,
        usage,
    )
}

fn work(app: &App) -> SceneWork {
    *app.world().resource::<RenderedWork>().0.lock().unwrap()
}

fn scene(app: &App) -> &IndirectLightScene {
    app.world().resource::<IndirectLightScene>()
}

/// The scene's triangles, sorted (two apps' entities need not be the same).
fn sorted_triangles(app: &App) -> Vec<Vec<u32>> {
    let mut t: Vec<Vec<u32>> = scene(app)
        .triangles()
        .map(|t| bytemuck::cast_slice::<Vertex, u32>(t).to_vec())
        .collect();
    t.sort_unstable();
    t
}

/// Updates `app` until its scene has not changed for three frames (and the render world has
/// seen the last change).
fn settle(app: &mut App) {
    let mut still = 0;
    for _ in 0..50 {
        let generation = scene(app).generation();
        app.update();
        still = if scene(app).generation() == generation && generation > 0 {
            still + 1
        } else {
            0
        };
        if still == 3 {
            return;
        }
    }
    panic!("the scene still changed after 50 frames");
}

/// Updates `app` a few frames: the render world's last one is done.
fn frames(app: &mut App, n: u32) {
    for _ in 0..n {
        app.update();
    }
}

#[test]
fn a_moved_mesh_alone_is_made_anew_and_the_scene_equals_a_fresh_gather() {
    let (mut app, entities) = app(places(), true);
    // until the assets' first events have been read (an entity's triangles may be made again
    // then) and the render world has taken the scene
    settle(&mut app);
    let first = work(&app);
    assert_eq!(
        (first.buffers_made, first.grids_made),
        (1, 1),
        "the render world took the scene: {first:?}"
    );
    let total = scene(&app).triangle_count() as u64;
    assert!(first.triangles_written >= total, "{first:?}");
    // the floor samples its texture, the one layer, uploaded
    let first_vertex = |app: &App, entity: Entity| {
        let (_, o) = scene(app).objects().find(|(e, _)| *e == entity).unwrap();
        o.triangles()[0][0]
    };
    let floor = entities[0];
    let floor_texture = |app: &App| first_vertex(app, floor).texture;
    assert_ne!(floor_texture(&app), Vertex::UNTEXTURED);
    assert_eq!(scene(&app).textures().layers.len(), 1);
    // through the app's default sampler, nearest: a tenth of a texel from the top-left texel's
    // edge is that texel alone (linear would take a tenth of its green neighbour)
    let red = Vec3::new(200.0, 30.0, 30.0).map(|c| Color::srgb_u8(c as u8, 0, 0).to_linear().red);
    let sampled = scene(&app)
        .textures()
        .sample(floor_texture(&app), Vec2::new(0.3, 0.3));
    assert!(
        (sampled - red).abs().max_element() < 1e-6,
        "the floor's texture read through {sampled}, not the app's nearest default ({red})"
    );
    // the ball's texture, on the GPU alone, is left out: its flat colour
    let ball = first_vertex(&app, entities[BALL]);
    assert_eq!(ball.texture, Vertex::UNTEXTURED);
    let grey = LinearRgba::from(Color::srgb(0.7, 0.7, 0.7));
    assert_eq!(ball.albedo, [grey.red, grey.green, grey.blue]);
    assert!(first.textures_uploaded >= 1, "{first:?}");
    let (generation, made) = (scene(&app).generation(), scene(&app).triangles_made());

    // still: no scene work in either world
    frames(&mut app, 3);
    assert_eq!(scene(&app).generation(), generation, "still");
    assert_eq!(scene(&app).triangles_made(), made, "still");
    assert_eq!(work(&app), first, "still");

    // one box moves within the scene's bounds
    let moved = entities[MOVED];
    let box_triangles = scene(&app)
        .objects()
        .find(|(e, _)| *e == moved)
        .map(|(_, o)| o.triangles().len() as u64)
        .unwrap();
    assert!(box_triangles * 4 < total, "a small part of the scene");
    let mut place = places();
    place[MOVED].translation = Vec3::new(-0.4, 0.25, 1.2);
    *app.world_mut().get_mut::<Transform>(moved).unwrap() = place[MOVED];
    frames(&mut app, 3);
    assert_eq!(scene(&app).generation(), generation + 1);
    assert_eq!(scene(&app).triangles_made(), made + box_triangles);
    let after = work(&app);
    assert_eq!(
        after,
        SceneWork {
            triangles_written: first.triangles_written + box_triangles,
            grid_triangles: first.grid_triangles + 2 * box_triangles,
            ..first
        },
        "its triangles written, out of the grid and in again"
    );
    let (fresh, _) = app_fresh(place);
    assert_eq!(sorted_triangles(&app), sorted_triangles(&fresh));

    // out of the grid's bounds: the grid is made anew; despawned: its range is freed
    *app.world_mut().get_mut::<Transform>(moved).unwrap() = Transform::from_xyz(0.0, 3.5, 0.0);
    frames(&mut app, 3);
    assert_eq!(work(&app).grids_made, 2, "{:?}", work(&app));
    app.world_mut().despawn(moved);
    frames(&mut app, 3);
    assert_eq!(
        scene(&app).triangle_count() as u64,
        total - box_triangles,
        "despawned"
    );
    let gone = work(&app);
    assert_eq!(
        gone.triangles_written,
        after.triangles_written + box_triangles
    );
    assert_eq!(gone.buffers_made, 1);

    // the floor's texture swapped for a flat colour: its layer dropped, the array uploaded anew
    let grey = app
        .world()
        .get::<MeshMaterial3d<StandardMaterial>>(entities[1])
        .unwrap()
        .clone();
    app.world_mut().entity_mut(floor).insert(grey);
    frames(&mut app, 3);
    assert_eq!(floor_texture(&app), Vertex::UNTEXTURED);
    assert!(scene(&app).textures().layers.is_empty());
    assert_eq!(work(&app).textures_uploaded, gone.textures_uploaded + 1);
}

/// A fresh app with the meshes at `places` from the start, gathered (the main world alone).
fn app_fresh(places: [Transform; 5]) -> (App, Vec<Entity>) {
    let (mut app, entities) = app(places, false);
    settle(&mut app);
    (app, entities)
}

/// Quads with as many distinct 1x1 textures as the layers hold, beside the floor's: the last
/// made is refused (its triangles untextured); once a textured quad is despawned, its layer
/// dropped, the refused texture is read again and its quad's triangles sample it.
#[test]
fn a_texture_refused_while_the_layers_are_full_is_taken_once_one_is_free() {
    use bevy::render::render_resource::{Extent3d, TextureDimension};
    use quadray_indirect::scene::MAX_TEXTURES;
    let (mut app, _) = app_fresh(places());
    let textured = |app: &App| {
        scene(app)
            .triangles()
            .filter(|t| t[0].texture != Vertex::UNTEXTURED)
            .count()
    };
    let floor = textured(&app);
    // the quads one a metre apart, below the floor: which is untextured
    let refused = |app: &App| {
        let mut quads = scene(app)
            .triangles()
            .filter(|t| t[0].position[1] == -1.0 && t[0].texture == Vertex::UNTEXTURED);
        quads.next().map(|t| t[0].position[0].round() as usize)
    };
    let world = app.world_mut();
    let quad = world
        .resource_mut::<Assets<Mesh>>()
        .add(Plane3d::new(Vec3::Y, Vec2::splat(0.1)));
    let quads: Vec<Entity> = (0..MAX_TEXTURES)
        .map(|i| {
            let colour = [(i % 256) as u8, (i / 256) as u8, 9, 255];
            let image = world.resource_mut::<Assets<Image>>().add(Image::new(
                Extent3d {
                    width: 1,
                    height: 1,
                    depth_or_array_layers: 1,
                },
                TextureDimension::D2,
                colour.to_vec(),
                TextureFormat::Rgba8UnormSrgb,
                RenderAssetUsages::default(),
            ));
            let material = world
                .resource_mut::<Assets<StandardMaterial>>()
                .add(StandardMaterial {
                    base_color_texture: Some(image),
                    ..default()
                });
            let place = Transform::from_xyz(i as f32, -1.0, 0.0);
            world
                .spawn((Mesh3d(quad.clone()), MeshMaterial3d(material), place))
                .id()
        })
        .collect();
    settle(&mut app);
    let layers = scene(&app).textures().layers.len();
    assert_eq!(layers, MAX_TEXTURES, "the layers full");
    let full = textured(&app);
    assert_eq!(full, floor + 2 * (MAX_TEXTURES - 1), "one quad refused");
    let refused_quad = refused(&app).expect("a quad refused");
    app.world_mut()
        .despawn(quads[(refused_quad + 1) % MAX_TEXTURES]);
    settle(&mut app);
    assert_eq!(
        (refused(&app), textured(&app)),
        (None, full),
        "quad {refused_quad}'s texture not taken once a layer was free"
    );
    assert_eq!(scene(&app).textures().layers.len(), MAX_TEXTURES);
}
