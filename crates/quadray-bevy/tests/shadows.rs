//! The material in Bevy's shadow maps, headless on lavapipe: a displaced cone on a patch (a
//! clamped map) floats over a flat floor that cuts through the patch's depth, so only the cone's
//! tip stands above the floor; a spot light, a directional light (its cascade) or a point light
//! (its cube map) casts its shadow through Bevy's own shadow map and filtering. The floor's
//! shadowed pixels against the CPU ground truth: each floor point's ray to the light traced
//! through the height field, shadowed where it meets the surface above the floor. A shadow pass
//! that wrote the polygon's depth would shadow the whole patch's outline.

use bevy::camera::RenderTarget;
use bevy::camera::visibility::RenderLayers;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::light::{CascadeShadowConfigBuilder, DirectionalLightShadowMap};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use glam::{DVec2, DVec3};
use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial, depth_map};
use quadray_displace::heightmap::HeightMap;
use quadray_displace::pyramid::Addressing;
use quadray_displace::reference::{Ray, Surface, intersect};
use std::sync::{Arc, Mutex};

const SIZE: u32 = 64;
const MAP: u32 = 64;
/// The patch is 1 x 1 at this height over the floor, its depth scale (uv units per unit of
/// depth) puts its deepest point below the floor: only depths under HEIGHT / DEPTH_SCALE = 0.75
/// stand above it.
const HEIGHT: f32 = 0.3;
const DEPTH_SCALE: f32 = 0.4;
/// The cone's radius in uv: depth r / RADIUS inside, 1 outside.
const RADIUS: f32 = 0.45;
/// The spot and the point light stand here; the directional light shines from this direction.
const LIGHT: Vec3 = Vec3::new(1.0, 1.6, 0.2);
const EYE: Vec3 = Vec3::new(0.0, 2.5, 0.0);
/// The second scene, the same floor, camera and light without the patch: the lit floor each
/// pixel's shadow is measured against.
const BESIDE: Vec3 = Vec3::new(20.0, 0.0, 0.0);
/// Pixels whose shadow differs from the truth's, as a share of the pixels the truth shadows:
/// Bevy's shadow map (512 texels over the spot's cone or the directional light's cascade, 1024
/// over a face of the point light's cube), its depth bias and filtering blur the outline by a
/// pixel or so.
const MISMATCH_TOLERANCE: f64 = 0.1;

/// The light that casts the shadow.
#[derive(Resource, Clone, Copy, Debug)]
enum Caster {
    Spot,
    Directional,
    Point,
}

impl Caster {
    /// The unit direction from a floor point towards the light.
    fn towards(self, floor: DVec3) -> DVec3 {
        match self {
            Caster::Directional => LIGHT.as_dvec3().normalize(),
            Caster::Spot | Caster::Point => (LIGHT.as_dvec3() - floor).normalize(),
        }
    }
}

/// What each scene's camera sees, read back every frame.
#[derive(Resource)]
struct Pictures {
    with_patch: Handle<Image>,
    without: Handle<Image>,
    read: [Arc<Mutex<Option<Vec<u8>>>>; 2],
    camera: Entity,
}

fn cone_depth(x: u32, y: u32) -> f32 {
    let uv = (Vec2::new(x as f32, y as f32) + 0.5) / MAP as f32;
    let r = (uv - 0.5).length();
    (r / RADIUS).min(1.0)
}

fn setup(
    caster: Res<Caster>,
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PyramidMaterial>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
) {
    let texels: Vec<u8> = (0..MAP * MAP)
        .map(|i| (cone_depth(i % MAP, i / MAP) * 255.0).round() as u8)
        .collect();
    let map = images.add(crate::common::r8_height_map(MAP, texels));
    let patch = crate::common::unit_plane();
    let mut extension = PyramidExtension::new(map, DEPTH_SCALE);
    extension.lod = false;
    extension.clamp_to_map = true;
    // The patch casts shadows but no camera sees it: the light sees layer 1, the cameras do not.
    commands.spawn((
        Mesh3d(meshes.add(patch)),
        MeshMaterial3d(materials.add(PyramidMaterial {
            base: StandardMaterial::default(),
            extension,
        })),
        Transform::from_xyz(0.0, HEIGHT, 0.0),
        RenderLayers::layer(1),
    ));
    let floor = meshes.add(Plane3d::new(Vec3::Y, Vec2::splat(2.0)));
    let white = standard.add(StandardMaterial {
        perceptual_roughness: 1.0,
        ..default()
    });
    // The light sees layer 1 too, where the patch is.
    let light_layers = RenderLayers::from_layers(&[0, 1]);
    if let Caster::Directional = *caster {
        // One cascade over what the cameras see (the floor, 2.5 in front of them).
        let cascades = CascadeShadowConfigBuilder {
            num_cascades: 1,
            maximum_distance: 4.0,
            ..default()
        };
        commands.spawn((
            DirectionalLight {
                illuminance: 5_000.0,
                shadow_maps_enabled: true,
                // As the spot's below: Bevy's (0.02, 1.8) shrink a shadow cast this close, and
                // with the cascade's coarser texels the spot's normal bias still does.
                shadow_depth_bias: 0.005,
                shadow_normal_bias: 0.2,
                ..default()
            },
            cascades.build(),
            Transform::from_translation(LIGHT).looking_at(Vec3::ZERO, Vec3::Y),
            light_layers.clone(),
        ));
    }
    let mut pictures = Vec::new();
    for origin in [Vec3::ZERO, BESIDE] {
        commands.spawn((
            Mesh3d(floor.clone()),
            MeshMaterial3d(white.clone()),
            Transform::from_translation(origin),
        ));
        let at_light = Transform::from_translation(origin + LIGHT)
            .looking_at(origin + Vec3::new(0.0, HEIGHT, 0.0), Vec3::Y);
        match *caster {
            Caster::Spot => {
                commands.spawn((
                    SpotLight {
                        intensity: 20_000.0,
                        range: 6.0,
                        shadow_maps_enabled: true,
                        // Bevy's biases (0.02, 1.8) would shrink the shadow of a caster this
                        // close to the floor by about a pixel all round.
                        shadow_depth_bias: 0.005,
                        shadow_normal_bias: 0.5,
                        outer_angle: 0.8,
                        inner_angle: 0.7,
                        ..default()
                    },
                    at_light,
                    light_layers.clone(),
                ));
            }
            Caster::Point => {
                commands.spawn((
                    PointLight {
                        intensity: 20_000.0,
                        range: 6.0,
                        shadow_maps_enabled: true,
                        // Bevy's (0.08, 0.6), like the spot's, shrink a shadow cast this close.
                        shadow_depth_bias: 0.005,
                        shadow_normal_bias: 0.5,
                        ..default()
                    },
                    at_light,
                    light_layers.clone(),
                ));
            }
            Caster::Directional => {}
        }
        let mut target = Image::new_target_texture(SIZE, SIZE, TextureFormat::Rgba8UnormSrgb, None);
        target.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        let target = images.add(target);
        let camera = commands
            .spawn((
                Camera3d::default(),
                RenderTarget::Image(target.clone().into()),
                Tonemapping::None,
                Msaa::Off,
                Transform::from_translation(origin + EYE).looking_at(origin, Vec3::NEG_Z),
            ))
            .id();
        pictures.push((target, camera));
    }
    commands.insert_resource(Pictures {
        with_patch: pictures[0].0.clone(),
        without: pictures[1].0.clone(),
        read: Default::default(),
        camera: pictures[0].1,
    });
}

fn app(caster: Caster) -> App {
    crate::common::headless_app(|app| {
        app.insert_resource(caster)
            .insert_resource(DirectionalLightShadowMap { size: 512 })
            .insert_resource(GlobalAmbientLight::NONE)
            .add_plugins(PyramidDisplacementPlugin)
            .add_systems(Startup, setup);
    })
}

/// Linear luminance-ish of an sRGB pixel (its green: the floor is white).
fn linear(srgb: u8) -> f64 {
    (f64::from(srgb) / 255.0).powf(2.2)
}

/// Per pixel: whether the floor is in the patch's shadow, on the CPU (None: off the floor).
fn truth(map: &HeightMap, caster: Caster, world_from_clip: Mat4, x: u32, y: u32) -> Option<bool> {
    let world_from_clip = world_from_clip.as_dmat4();
    let ndc = DVec2::new(
        (f64::from(x) + 0.5) / f64::from(SIZE) * 2.0 - 1.0,
        1.0 - (f64::from(y) + 0.5) / f64::from(SIZE) * 2.0,
    );
    let eye = EYE.as_dvec3();
    let dir = (world_from_clip.project_point3(ndc.extend(0.5)) - eye).normalize();
    let floor = eye + dir * (-eye.y / dir.y);
    if floor.x.abs() > 2.0 || floor.z.abs() > 2.0 {
        return None;
    }
    // Towards the light, through the patch's plane.
    let towards = caster.towards(floor);
    let (height, s) = (f64::from(HEIGHT), f64::from(DEPTH_SCALE));
    let on_patch = floor + towards * (height / towards.y);
    let p0 = DVec2::new(on_patch.x + 0.5, on_patch.z + 0.5);
    if p0.min_element() < 0.0 || p0.max_element() >= 1.0 {
        return Some(false);
    }
    let ray = Ray {
        p0,
        e: -DVec2::new(towards.x, towards.z) / towards.y * s,
    };
    // The light's ray meets the surface above the floor (the patch is 1 x 1: uv units are world
    // units), or leaves the clamped map through its side, or meets it below the floor.
    Some(
        intersect(map, Addressing::Clamp, Surface::Point, ray)
            .is_some_and(|hit| hit.z * s < height),
    )
}

/// Bevy's picture of the floor with the shadow `caster` casts against the truth: at most
/// MISMATCH_TOLERANCE of the pixels the truth shadows differ.
fn shadow_mismatch(caster: Caster) {
    let mut app = app(caster);
    app.update(); // Startup: the scene and its views.
    let pictures = app.world().resource::<Pictures>();
    for (image, read) in [
        (pictures.with_patch.clone(), pictures.read[0].clone()),
        (pictures.without.clone(), pictures.read[1].clone()),
    ] {
        app.world_mut()
            .spawn(Readback::texture(image))
            .observe(move |e: On<ReadbackComplete>| *read.lock().unwrap() = Some(e.data.clone()));
    }
    // The scene's pipelines compile, the map's pyramid is built: wait for a shadow on the lit
    // floor, then a few frames more.
    let lit_mask = |app: &App| {
        let read = &app.world().resource::<Pictures>().read;
        let (Some(a), Some(b)) = (
            read[0].lock().unwrap().clone(),
            read[1].lock().unwrap().clone(),
        ) else {
            return None;
        };
        // Pixels the light reaches on the floor without the patch: lit where it reaches them
        // with the patch too.
        let lit_share = |x: usize| linear(a[4 * x + 1]) / linear(b[4 * x + 1]).max(1e-6);
        let reached = (0..(SIZE * SIZE) as usize).map(|x| b[4 * x + 1] > 16);
        Some(
            reached
                .enumerate()
                .map(|(x, r)| r.then(|| lit_share(x) > 0.5))
                .collect::<Vec<_>>(),
        )
    };
    // Both floors drawn and lit, and a shadow on the patch's.
    let shadow = |app: &App| lit_mask(app).filter(|lit| lit.contains(&Some(false)));
    let mut frames = 0;
    while shadow(&app).is_none() {
        assert!(frames < 1000, "no shadow after {frames} frames");
        app.update();
        frames += 1;
    }
    for _ in 0..5 {
        app.update();
    }
    let lit = lit_mask(&app).unwrap();
    let world = app.world();
    let pictures = world.resource::<Pictures>();
    let entity = world.entity(pictures.camera);
    let camera = entity.get::<Camera>().unwrap();
    let transform = entity.get::<GlobalTransform>().unwrap();
    let world_from_clip = (camera.clip_from_view() * transform.to_matrix().inverse()).inverse();
    let images = world.resource::<Assets<Image>>();
    let (_, image) = images
        .iter()
        .find(|(_, i)| i.texture_descriptor.format == TextureFormat::R8Unorm)
        .expect("the cone's map");
    let map = depth_map("cone", image).unwrap();
    let (mut shadowed, mut mismatched) = (0, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(truth) = truth(&map, caster, world_from_clip, x, y) else {
                continue;
            };
            shadowed += usize::from(truth);
            mismatched += usize::from(Some(truth) == lit[(y * SIZE + x) as usize]);
        }
    }
    let fraction = mismatched as f64 / shadowed.max(1) as f64;
    println!(
        "{caster:?}: {shadowed} pixels in the traced shadow, {mismatched} differ ({fraction:.4})"
    );
    assert!(shadowed > 100, "only {shadowed} pixels in shadow");
    assert!(
        fraction <= MISMATCH_TOLERANCE,
        "{mismatched} pixels differ from the traced shadow's {shadowed}"
    );
}

#[test]
#[ignore = "run under the validation layer by validation::every_pass_passes_the_layer, in a child process"]
fn the_displaced_surface_casts_its_traced_shadow() {
    shadow_mismatch(Caster::Spot);
}

#[test]
fn the_directional_light_s_cascade_holds_the_traced_shadow() {
    shadow_mismatch(Caster::Directional);
}

#[test]
fn the_point_light_s_cube_map_holds_the_traced_shadow() {
    shadow_mismatch(Caster::Point);
}
