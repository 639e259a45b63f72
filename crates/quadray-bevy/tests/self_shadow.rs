//! Self-shadowing from Bevy's own lights, headless on lavapipe: a ridged height field lit by a
//! directional light from +x and a point light from -x, so that beside each ridge the height
//! field hides one light and not the other. One camera draws it four times: with ambient light
//! alone, with each light alone and with both (the lights shown and hidden in between).
//! Which pixels the height field hides a light from is the CPU ground truth's: each pixel's ray
//! (recorded by the shader) intersected exactly, then the ray from that hit towards the light,
//! with the rule of `shadow_lit` in quadray_displace's `trace.wgsl`. No shadow maps: only the
//! height field shadows.

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::render::storage::ShaderBuffer;
use glam::{DVec2, DVec3};
use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial, depth_map};
use quadray_displace::heightmap::HeightMap;
use quadray_displace::primary_rays::{MIN_COSINE, ray_slope};
use quadray_displace::pyramid::Addressing;
use quadray_displace::reference::{Hit, Ray, Surface, intersect};
use std::sync::{Arc, Mutex};

use crate::common::unit_plane;

const SIZE: u32 = 64;
const MAP: u32 = 64;
/// Ridges along v every RIDGE_PERIOD texels of u, RIDGE_WIDTH texels wide, at depth 0 over a
/// floor at depth 1.
const RIDGE_PERIOD: u32 = 32;
const RIDGE_WIDTH: u32 = 6;
const DEPTH_SCALE: f32 = 0.1;
/// Towards the directional light: from +x, 35 degrees above the plane (a shadow of 9 texels).
const SUN_ELEVATION_DEG: f32 = 35.0;
/// The point light, on the -x side.
const LAMP: Vec3 = Vec3::new(-2.0, 1.4, 0.0);
const EYE: Vec3 = Vec3::new(0.0, 1.1, 0.0);
/// Frames drawn after the lights change before the picture is read: Bevy's readback arrives a
/// frame or two late.
const SETTLE_FRAMES: usize = 10;
/// Pictures that must agree differ by at most one 8-bit sRGB step in each channel: taking a
/// hidden light's term back out of Bevy's sum is exact to f32 rounding.
const TOLERANCE: u8 = 1;
/// A light is seen to light a pixel when it adds this many 8-bit steps to the ambient light
/// (mean over the pixels compared).
const LIGHT_ADDS: f64 = 16.0;

/// What the camera sees and the shader's rays and hits, read back every frame.
#[derive(Resource)]
struct Readings {
    picture: Arc<Mutex<Option<Vec<u8>>>>,
    target: Handle<Image>,
    hits: Handle<ShaderBuffer>,
    hits_read: Arc<Mutex<Option<Vec<u8>>>>,
}

/// The directional light.
#[derive(Component)]
struct Sun;

/// The point light.
#[derive(Component)]
struct Lamp;

fn ridge_depth(x: u32) -> u8 {
    if x % RIDGE_PERIOD < RIDGE_WIDTH {
        0
    } else {
        255
    }
}

fn sun_direction() -> Vec3 {
    let (sin, cos) = SUN_ELEVATION_DEG.to_radians().sin_cos();
    Vec3::new(cos, sin, 0.0)
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PyramidMaterial>>,
    mut images: ResMut<Assets<Image>>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    let texels: Vec<u8> = (0..MAP * MAP).map(|i| ridge_depth(i % MAP)).collect();
    let map = images.add(crate::common::r8_height_map(MAP, texels));
    let hits = buffers.add(crate::common::hit_buffer(SIZE * SIZE));
    let mut extension = PyramidExtension::new(map, DEPTH_SCALE);
    extension.lod = false;
    extension.shadow_strength = 1.0;
    extension.debug_hits = hits.clone();
    extension.debug_width = SIZE;
    commands.spawn((
        Mesh3d(meshes.add(unit_plane())),
        MeshMaterial3d(materials.add(PyramidMaterial {
            base: StandardMaterial {
                perceptual_roughness: 1.0,
                ..default()
            },
            extension,
        })),
    ));
    commands.spawn((
        Sun,
        DirectionalLight {
            illuminance: 2_000.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_translation(sun_direction()).looking_at(Vec3::ZERO, Vec3::Y),
        Visibility::Hidden,
    ));
    commands.spawn((
        Lamp,
        PointLight {
            intensity: 150_000.0,
            range: 10.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_translation(LAMP),
        Visibility::Hidden,
    ));
    let mut target = Image::new_target_texture(SIZE, SIZE, TextureFormat::Rgba8UnormSrgb, None);
    target.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    let target = images.add(target);
    commands.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.clone().into()),
        Tonemapping::None,
        Msaa::Off,
        Transform::from_translation(EYE).looking_at(Vec3::ZERO, Vec3::NEG_Z),
    ));
    commands.insert_resource(Readings {
        picture: Arc::default(),
        target,
        hits,
        hits_read: Arc::default(),
    });
}

fn app() -> App {
    crate::common::headless_app(|app| {
        app.insert_resource(GlobalAmbientLight {
            brightness: 200.0,
            ..default()
        })
        .add_plugins(PyramidDisplacementPlugin)
        .add_systems(Startup, setup);
    })
}

/// Whether the light reaches the exact `hit` along the tangent-space direction `l`, by the rule
/// of `shadow_lit` in `trace.wgsl`: the light's ray from above first meets the surface within 1.5
/// texels along it, or within 0.002 in depth, of the hit.
fn reaches(map: &HeightMap, hit: Hit, l: DVec3) -> bool {
    if l.z <= MIN_COSINE {
        return false;
    }
    let el = ray_slope(l, f64::from(DEPTH_SCALE));
    let from_light = Ray {
        p0: hit.uv - el * hit.z,
        e: el,
    };
    let Some(first) = intersect(map, Addressing::Wrap, Surface::Point, from_light) else {
        return true;
    };
    let short_by = hit.z - first.z;
    short_by * (el * map.texels_per_uv()).length() <= 1.5 || short_by <= 2.0e-3
}

/// Per pixel, by the CPU ground truth: (the sun is hidden, the lamp is hidden), or None where no
/// fragment was drawn or the shader's hit is more than half a texel from the truth's.
fn hidden_lights(map: &HeightMap, hits: &[f32]) -> Vec<Option<(bool, bool)>> {
    hits.chunks_exact(8)
        .map(|p| {
            if p[6] < 0.0 {
                return None;
            }
            let ray = Ray {
                p0: DVec2::new(p[0].into(), p[1].into()),
                e: DVec2::new(p[2].into(), p[3].into()),
            };
            let hit = intersect(map, Addressing::Wrap, Surface::Point, ray)?;
            let gpu = DVec2::new(p[4].into(), p[5].into());
            if ((gpu - hit.uv) * map.texels_per_uv()).length() > 0.5 {
                return None;
            }
            // The unit plane: uv (u, v) is world (u - 0.5, 0, v - 0.5), depth goes down -y, and
            // tangent space is (x, z, y).
            let world = DVec3::new(
                hit.uv.x - 0.5,
                -hit.z * f64::from(DEPTH_SCALE),
                hit.uv.y - 0.5,
            );
            let tangent = |w: DVec3| DVec3::new(w.x, w.z, w.y);
            let sun = tangent(sun_direction().as_dvec3());
            let lamp = tangent((LAMP.as_dvec3() - world).normalize());
            Some((!reaches(map, hit, sun), !reaches(map, hit, lamp)))
        })
        .collect()
}

/// The pixels whose own classification and their eight neighbours' are `wanted`: a pixel whose
/// hit is a fraction of a pixel off still has the same lights hidden.
fn pixels_where(hidden: &[Option<(bool, bool)>], wanted: (bool, bool)) -> Vec<usize> {
    let size = SIZE as i64;
    (0..hidden.len())
        .filter(|&i| {
            let (x, y) = (i as i64 % size, i as i64 / size);
            (-1..=1).all(|dy| {
                (-1..=1).all(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    (0..size).contains(&nx)
                        && (0..size).contains(&ny)
                        && hidden[(ny * size + nx) as usize] == Some(wanted)
                })
            })
        })
        .collect()
}

/// The largest channel difference between two pictures at `pixels`.
fn largest_difference(a: &[u8], b: &[u8], pixels: &[usize]) -> u8 {
    pixels
        .iter()
        .flat_map(|&i| (0..3).map(move |c| a[4 * i + c].abs_diff(b[4 * i + c])))
        .max()
        .unwrap_or(0)
}

/// The mean green of `picture` at `pixels` (8-bit steps).
fn mean_green(picture: &[u8], pixels: &[usize]) -> f64 {
    pixels
        .iter()
        .map(|&i| f64::from(picture[4 * i + 1]))
        .sum::<f64>()
        / pixels.len().max(1) as f64
}

/// The picture with the sun and the lamp shown or not.
fn picture_lit_by(app: &mut App, sun: bool, lamp: bool) -> Vec<u8> {
    let world = app.world_mut();
    let shown = |on: bool| {
        if on {
            Visibility::Visible
        } else {
            Visibility::Hidden
        }
    };
    for mut visibility in world
        .query_filtered::<&mut Visibility, With<Sun>>()
        .iter_mut(world)
    {
        *visibility = shown(sun);
    }
    for mut visibility in world
        .query_filtered::<&mut Visibility, With<Lamp>>()
        .iter_mut(world)
    {
        *visibility = shown(lamp);
    }
    for _ in 0..SETTLE_FRAMES {
        app.update();
    }
    let readings = app.world().resource::<Readings>();
    readings.picture.lock().unwrap().clone().unwrap()
}

#[test]
#[ignore = "run under the validation layer by validation::every_pass_passes_the_layer, in a child process"]
fn each_light_is_hidden_by_the_height_field_on_its_own() {
    let mut app = app();
    app.update(); // Startup: the scene and its view.
    let readings = app.world().resource::<Readings>();
    let (target, read) = (readings.target.clone(), readings.picture.clone());
    let (hits, hits_read) = (readings.hits.clone(), readings.hits_read.clone());
    app.world_mut()
        .spawn(Readback::texture(target))
        .observe(move |e: On<ReadbackComplete>| *read.lock().unwrap() = Some(e.data.clone()));
    app.world_mut()
        .spawn(Readback::buffer(hits))
        .observe(move |e: On<ReadbackComplete>| *hits_read.lock().unwrap() = Some(e.data.clone()));
    // The pipelines compile and the map's pyramid is built: wait for traced hits below the
    // polygon and a picture.
    let ready = |app: &App| {
        let readings = app.world().resource::<Readings>();
        let traced = readings
            .hits_read
            .lock()
            .unwrap()
            .as_ref()
            .is_some_and(|b| {
                let values: Vec<f32> = bytemuck::pod_collect_to_vec(b);
                values.chunks_exact(8).any(|p| p[6] > 0.5)
            });
        traced && readings.picture.lock().unwrap().is_some()
    };
    let mut frames = 0;
    while !ready(&app) {
        assert!(frames < 1000, "nothing traced after {frames} frames");
        app.update();
        frames += 1;
    }
    let ambient = picture_lit_by(&mut app, false, false);
    let sun = picture_lit_by(&mut app, true, false);
    let lamp = picture_lit_by(&mut app, false, true);
    let both = picture_lit_by(&mut app, true, true);

    let world = app.world();
    let readings = world.resource::<Readings>();
    let hits: Vec<f32> =
        bytemuck::pod_collect_to_vec(readings.hits_read.lock().unwrap().as_ref().unwrap());
    let images = world.resource::<Assets<Image>>();
    let (_, image) = images
        .iter()
        .find(|(_, i)| i.texture_descriptor.format == TextureFormat::R8Unorm)
        .expect("the ridges' map");
    let map = depth_map("ridges", image).unwrap();
    let hidden = hidden_lights(&map, &hits);
    let sun_hidden = pixels_where(&hidden, (true, false));
    let lamp_hidden = pixels_where(&hidden, (false, true));
    let compared = hidden.iter().flatten().count();
    println!(
        "{compared} pixels compared; the sun alone hidden at {}, the lamp alone at {}",
        sun_hidden.len(),
        lamp_hidden.len()
    );
    assert!(
        sun_hidden.len() >= 100 && lamp_hidden.len() >= 100,
        "too few pixels with one light hidden: {} and {}",
        sun_hidden.len(),
        lamp_hidden.len()
    );
    let [ambient, sun, lamp, both] = [&ambient, &sun, &lamp, &both].map(|p| &p[..]);
    // The test means something: there is ambient light, and each light adds to it where it is
    // not hidden.
    let ambient_level = mean_green(ambient, &sun_hidden);
    let lamp_adds = mean_green(lamp, &sun_hidden) - ambient_level;
    let sun_adds = mean_green(sun, &lamp_hidden) - mean_green(ambient, &lamp_hidden);
    println!(
        "ambient {ambient_level:.1} steps; the lamp adds {lamp_adds:.1} where the sun is hidden, \
         the sun {sun_adds:.1} where the lamp is"
    );
    assert!(ambient_level >= LIGHT_ADDS, "ambient {ambient_level}");
    assert!(lamp_adds >= LIGHT_ADDS, "the lamp adds {lamp_adds}");
    assert!(sun_adds >= LIGHT_ADDS, "the sun adds {sun_adds}");
    for (what, pixels, hidden_alone, unhidden_alone) in [
        ("the sun hidden", &sun_hidden, sun, lamp),
        ("the lamp hidden", &lamp_hidden, lamp, sun),
    ] {
        let both_to_unhidden = largest_difference(both, unhidden_alone, pixels);
        let hidden_to_ambient = largest_difference(hidden_alone, ambient, pixels);
        println!(
            "{what}: both lights against the other alone {both_to_unhidden} steps, \
             the hidden light alone against ambient light {hidden_to_ambient}"
        );
        assert!(
            both_to_unhidden <= TOLERANCE,
            "{what}: both lights differ from the other light alone by {both_to_unhidden} steps"
        );
        assert!(
            hidden_to_ambient <= TOLERANCE,
            "{what}: the hidden light alone differs from ambient light by {hidden_to_ambient} steps"
        );
    }
}
