//! The material's traced hits, rendered headless by Bevy on lavapipe, against quadray's CPU ground
//! truth on the same rays: each pixel records its ray (p0, e) and its hit in a storage buffer, the
//! CPU intersects the same rays with the same height field exactly.

use bevy::camera::RenderTarget;
use bevy::camera::visibility::RenderLayers;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::TextureFormat;
use bevy::render::storage::ShaderBuffer;
use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial, depth_map};
use quadray_core::image_out::Rgba8Image;
use quadray_displace::accuracy::GroundTruth;
use quadray_displace::gpu::Frame;
use quadray_displace::heightmap::{Convention, Fit, HeightMap};
use quadray_displace::pyramid::Addressing;
use quadray_displace::reference::Surface;
use std::path::Path;
use std::sync::{Arc, Mutex};

use crate::common::{ANGLES_DEG, ASSETS, MAPS, eye, height_map, unit_plane};
const SIZE: u32 = 64;
const DEPTH_SCALE: f32 = 0.1;

/// One camera's recording: which map, which angle, and where its hits go.
struct View {
    map: usize,
    angle_deg: f32,
    hits: Handle<ShaderBuffer>,
    read: Arc<Mutex<Option<Vec<u8>>>>,
}

#[derive(Resource)]
struct Views(Vec<View>);

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PyramidMaterial>>,
    mut images: ResMut<Assets<Image>>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    let plane = meshes.add(unit_plane());
    let mut views = Vec::new();
    for (map, path) in MAPS.iter().enumerate() {
        let depth = height_map(&assets, path);
        for angle_deg in ANGLES_DEG {
            let layer = RenderLayers::layer(views.len() + 1);
            let hits = buffers.add(crate::common::hit_buffer(SIZE * SIZE));
            let mut extension = PyramidExtension::new(depth.clone(), DEPTH_SCALE);
            extension.lod = false;
            extension.debug_hits = hits.clone();
            extension.debug_width = SIZE;
            commands.spawn((
                Mesh3d(plane.clone()),
                MeshMaterial3d(materials.add(PyramidMaterial {
                    base: StandardMaterial::default(),
                    extension,
                })),
                layer.clone(),
            ));
            let target = Image::new_target_texture(SIZE, SIZE, TextureFormat::Rgba8UnormSrgb, None);
            commands.spawn((
                Camera3d::default(),
                RenderTarget::Image(images.add(target).into()),
                Tonemapping::None,
                // The plane fills the view at 0 degrees and a quarter of it at 80.
                Transform::from_translation(eye(angle_deg)).looking_at(Vec3::ZERO, Vec3::Y),
                layer,
            ));
            views.push(View {
                map,
                angle_deg,
                hits,
                read: Arc::default(),
            });
        }
    }
    commands.insert_resource(Views(views));
}

fn app() -> App {
    crate::common::headless_app(|app| {
        app.add_plugins(PyramidDisplacementPlugin)
            .add_systems(Startup, setup);
    })
}

#[test]
#[ignore = "run under the validation layer by validation::every_pass_passes_the_layer, in a child process"]
fn bevy_hits_agree_with_the_cpu_ground_truth() {
    let mut app = app();
    app.update(); // Startup: the scene and its views.
    let views: Vec<_> = app
        .world()
        .resource::<Views>()
        .0
        .iter()
        .map(|v| (v.hits.clone(), v.read.clone()))
        .collect();
    // Every frame reads each view's hits back; keep the latest.
    for (hits, read) in views {
        app.world_mut().spawn(Readback::buffer(hits)).observe(
            move |event: On<ReadbackComplete>| {
                *read.lock().unwrap() = Some(event.data.clone());
            },
        );
    }
    // The maps load, their pyramids are built, the pipelines compile (asynchronously), and then
    // every view's fragments write their hits: wait for that, then render a few frames more.
    let traced = |app: &App| {
        app.world().resource::<Views>().0.iter().all(|v| {
            v.read.lock().unwrap().as_ref().is_some_and(|bytes| {
                let values: Vec<f32> = bytemuck::pod_collect_to_vec(bytes);
                values.chunks_exact(8).any(|p| p[6] != -2.0)
            })
        })
    };
    let mut frames = 0;
    while !traced(&app) {
        assert!(frames < 3000, "no hits after {frames} frames");
        app.update();
        frames += 1;
    }
    for _ in 0..5 {
        app.update();
    }

    let world = app.world();
    let images = world.resource::<Assets<Image>>();
    let assets = world.resource::<AssetServer>();
    let mut maps = Vec::new();
    for path in MAPS {
        let handle: Handle<Image> = assets.get_handle(path).expect("the map was loaded");
        let image = images.get(&handle).expect("the map's CPU data is kept");
        let map = depth_map(path, image).unwrap();
        // The material traces exactly what quadray's own loader reads from the file, at the
        // file's own size (Bevy's map is 348x348: no resampling).
        let file = HeightMap::load(&Path::new(ASSETS).join(path), Convention::Depth, Fit::Exact);
        assert_eq!(
            Some(&map),
            file.as_ref().ok(),
            "{path}: Bevy's image and quadray's load differ"
        );
        maps.push(map);
    }
    for view in &world.resource::<Views>().0 {
        let bytes = view.read.lock().unwrap().clone().expect("read back");
        let values: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        let (rays, hits): (Vec<[f32; 4]>, Vec<[f32; 4]>) = values
            .chunks_exact(8)
            .map(|p| ([p[0], p[1], p[2], p[3]], [p[4], p[5], p[6], p[7]]))
            .unzip();
        // The rays are the view's: from the surface point towards the camera, in the plane's uv
        // space (u along +x, v along +z), e = -V.uv / V.n * depth scale.
        let eye = eye(view.angle_deg);
        for ray in rays
            .iter()
            .zip(&hits)
            .filter(|(_, h)| h[2] != -2.0)
            .map(|(r, _)| r)
        {
            let e = Vec2::new(ray[2], ray[3]);
            let expected = |uv: Vec2| {
                let towards = (eye - Vec3::new(uv.x - 0.5, 0.0, uv.y - 0.5)).normalize();
                -Vec2::new(towards.x, towards.z) / towards.y * DEPTH_SCALE
            };
            // p0 is wrapped into [0, 1), and a pixel the plane's edge only partly covers (MSAA)
            // shades at its centre, off the plane: its uv may be a whole tile off.
            let p0 = Vec2::new(ray[0], ray[1]);
            let tiles = [-1.0, 0.0, 1.0].map(|du| [-1.0, 0.0, 1.0].map(|dv| Vec2::new(du, dv)));
            assert!(
                tiles.as_flattened().iter().any(|&t| {
                    let expected = expected(p0 + t);
                    (e - expected).length() <= 1e-3 * expected.length() + 1e-5
                }),
                "{} at {} degrees: ray at {p0} has e {e}, expected {}",
                MAPS[view.map],
                view.angle_deg,
                expected(p0)
            );
        }
        let frame = Frame {
            color: Rgba8Image::new(SIZE, SIZE, [0; 4]),
            hits,
            rays,
            // Only the accuracy is measured here, not the cost or the shadows.
            fetches: Vec::new(),
            in_shadow: Vec::new(),
        };
        let accuracy = GroundTruth::of_rays(
            &maps[view.map],
            Addressing::Wrap,
            Surface::Point,
            frame.traced_rays(),
        )
        .measure(&frame);
        let what = format!("{} at {} degrees", MAPS[view.map], view.angle_deg);
        println!(
            "{what}: {} covered, wrong-hit fraction {:.5}, mean error {:.4} texels",
            accuracy.covered, accuracy.wrong_hit_fraction, accuracy.mean_error_texels
        );
        assert!(
            accuracy.covered > (SIZE * SIZE / 8) as usize,
            "{what}: only {} pixels traced",
            accuracy.covered
        );
        assert!(
            accuracy.wrong_hit_fraction <= 0.001,
            "{what}: wrong-hit fraction {}",
            accuracy.wrong_hit_fraction
        );
        // A trace that stopped at the polygon would agree only where the map is at depth 0.
        let mean_depth = frame
            .hits
            .iter()
            .filter(|h| h[2] >= 0.0)
            .map(|h| h[2])
            .sum::<f32>()
            / accuracy.covered as f32;
        assert!(mean_depth > 0.01, "{what}: mean hit depth {mean_depth}");
    }
}
