//! The cost of the pyramid material in Bevy's prepass and shadow pass over the flat polygon's, in
//! one run with paired rounds (a benchmark, not part of the normal test run):
//!
//! ```sh
//! cargo test --release -p quadray-bevy --test suite -- pass_cost:: --ignored --nocapture
//! ```
//!
//! A 1x1 plane with the tile map (depth scale 0.1, level-of-detail on, as a user gets it) fills
//! most of a 256x256 depth + normal prepass seen at 60 degrees, and most of a spot light's 256^2
//! shadow map. The plane's material is, in turn: `StandardMaterial` (what Bevy draws for the flat
//! polygon: a depth-only shadow pass without a fragment stage), the pyramid material with depth
//! scale 0 (the same shader and pipeline tracing a flat surface) and with depth scale 0.1.
//! - Prepass: Bevy's render diagnostics' GPU time of the early prepass (the plane and nothing
//!   else in it), median per round.
//! - Shadow pass: Bevy 0.19 times no shadow pass, so this test puts a GPU time span of Bevy's
//!   render diagnostics around the spot light's (early) shadow pass; the plane is hidden from the
//!   camera, seen by the light only.

use bevy::camera::RenderTarget;
use bevy::camera::visibility::RenderLayers;
use bevy::core_pipeline::prepass::{DepthPrepass, NormalPrepass};
use bevy::core_pipeline::schedule::Core3d;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::diagnostic::DiagnosticsStore;
use bevy::ecs::system::NonSendMarker;
use bevy::light::DirectionalLightShadowMap;
use bevy::pbr::{EARLY_SHADOW_PASS, ShadowView, shared_shadow_pass};
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy::render::diagnostic::{RecordDiagnostics, RenderDiagnosticsPlugin};
use bevy::render::render_resource::TextureFormat;
use bevy::render::renderer::RenderAdapterInfo;
use bevy::render::renderer::{RenderContext, ViewQuery};
use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial};

const SIZE: u32 = 256;
const MAP: &str = "heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png";
const DEPTH_SCALE: f32 = 0.1;
const WARM_UP: usize = 15;
const TIMED: usize = 41;
const ROUNDS: usize = 2;
/// The prepass's GPU time in Bevy's render diagnostics.
const PREPASS: &str = "render/early prepass/elapsed_gpu";
/// The shadow pass's, with the span below.
const SHADOW: &str = "render/shadow pass/elapsed_gpu";

/// Opens the span around each shadow view's early shadow pass (the late one draws nothing
/// without occlusion culling). Bevy's spans are per thread: both ends run on the schedule's own
/// thread.
fn begin_shadow_span(_view: ViewQuery<&ShadowView>, mut ctx: RenderContext, _: NonSendMarker) {
    if let Some(recorder) = ctx.diagnostic_recorder() {
        recorder.begin_time_span(ctx.command_encoder(), "shadow pass".into());
    }
}

fn end_shadow_span(_view: ViewQuery<&ShadowView>, mut ctx: RenderContext, _: NonSendMarker) {
    if let Some(recorder) = ctx.diagnostic_recorder() {
        recorder.end_time_span(ctx.command_encoder());
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Shown {
    Standard,
    PyramidFlat,
    Pyramid,
}

#[derive(Resource)]
struct Scene {
    plane: Entity,
    standard: Handle<StandardMaterial>,
    flat: Handle<PyramidMaterial>,
    pyramid: Handle<PyramidMaterial>,
}

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PyramidMaterial>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
) {
    let depth = crate::common::height_map(&assets, MAP);
    let plane = crate::common::unit_plane();
    let material = |scale| PyramidMaterial {
        base: StandardMaterial::default(),
        extension: PyramidExtension::new(depth.clone(), scale),
    };
    let flat = materials.add(material(0.0));
    let pyramid = materials.add(material(DEPTH_SCALE));
    let plane = commands.spawn(Mesh3d(meshes.add(plane))).id();
    commands.spawn((
        SpotLight {
            shadow_maps_enabled: true,
            outer_angle: 0.6,
            inner_angle: 0.5,
            range: 10.0,
            ..default()
        },
        Transform::from_xyz(0.0, 0.7, -1.2).looking_at(Vec3::ZERO, Vec3::Y),
        RenderLayers::from_layers(&[0, 1]),
    ));
    let target = images.add(Image::new_target_texture(
        SIZE,
        SIZE,
        TextureFormat::Rgba8UnormSrgb,
        None,
    ));
    commands.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.into()),
        Tonemapping::None,
        Msaa::Off,
        Transform::from_xyz(0.0, 0.55, 0.95).looking_at(Vec3::ZERO, Vec3::Y),
        DepthPrepass,
        NormalPrepass,
    ));
    commands.insert_resource(Scene {
        plane,
        standard: standard.add(StandardMaterial::default()),
        flat,
        pyramid,
    });
}

/// Puts `shown` on the plane; `in_view`: the camera sees it, else only the light does.
fn show(app: &mut App, shown: Shown, in_view: bool) {
    let world = app.world_mut();
    let scene = world.resource::<Scene>();
    let (plane, standard, flat, pyramid) = (
        scene.plane,
        scene.standard.clone(),
        scene.flat.clone(),
        scene.pyramid.clone(),
    );
    let mut entity = world.entity_mut(plane);
    entity
        .remove::<MeshMaterial3d<StandardMaterial>>()
        .remove::<MeshMaterial3d<PyramidMaterial>>()
        .insert(RenderLayers::layer(if in_view { 0 } else { 1 }));
    match shown {
        Shown::Standard => entity.insert(MeshMaterial3d(standard)),
        Shown::PyramidFlat => entity.insert(MeshMaterial3d(flat)),
        Shown::Pyramid => entity.insert(MeshMaterial3d(pyramid)),
    };
}

/// Median and interquartile range.
fn median(mut values: Vec<f64>) -> (f64, f64, f64) {
    values.sort_by(f64::total_cmp);
    let at = |q: f64| values[((values.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.25), at(0.75))
}

/// `frames` timed updates of `shown`: the GPU times of the diagnostic `path` (ms).
fn measure(app: &mut App, shown: Shown, in_view: bool, frames: usize, path: &str) -> Vec<f64> {
    show(app, shown, in_view);
    for _ in 0..WARM_UP {
        app.update();
    }
    for d in app
        .world_mut()
        .resource_mut::<DiagnosticsStore>()
        .iter_mut()
    {
        d.clear_history();
    }
    for _ in 0..frames {
        app.update();
    }
    app.world()
        .resource::<DiagnosticsStore>()
        .iter()
        .find(|d| d.path().as_str() == path)
        .map(|d| d.values().copied().collect())
        .unwrap_or_default()
}

#[test]
#[ignore = "a benchmark: about two minutes on lavapipe"]
fn prepass_and_shadow_cost_over_the_flat_polygon() {
    let mut app = crate::common::headless_app(|app| {
        app.insert_resource(DirectionalLightShadowMap {
            size: SIZE as usize,
        })
        .insert_resource(GlobalAmbientLight::NONE)
        .add_plugins((PyramidDisplacementPlugin, RenderDiagnosticsPlugin))
        .add_systems(Startup, setup);
        app.sub_app_mut(RenderApp).add_systems(
            Core3d,
            (
                begin_shadow_span.before(shared_shadow_pass::<EARLY_SHADOW_PASS>),
                end_shadow_span.after(shared_shadow_pass::<EARLY_SHADOW_PASS>),
            ),
        );
    });
    app.update();
    let adapter = app.world().resource::<RenderAdapterInfo>();
    println!("adapter: {} ({})", adapter.name, adapter.driver_info);
    // The map loads, its pyramid is built, every pipeline compiles: a round not counted.
    let configs = [Shown::Standard, Shown::PyramidFlat, Shown::Pyramid];
    for in_view in [true, false] {
        for shown in configs {
            measure(&mut app, shown, in_view, 60, PREPASS);
        }
    }
    let mut medians = [[[0.0; 3]; 2]; ROUNDS];
    for (round, figures) in medians.iter_mut().enumerate() {
        for (pass, (name, path)) in [("prepass", PREPASS), ("shadow pass", SHADOW)]
            .into_iter()
            .enumerate()
        {
            for (i, &shown) in configs.iter().enumerate() {
                let times = measure(&mut app, shown, pass == 0, TIMED, path);
                assert!(!times.is_empty(), "no GPU time for the {name}");
                let (m, lo, hi) = median(times);
                println!(
                    "round {} {name} {shown:?}: median {m:.3} ms (IQR {lo:.3}-{hi:.3})",
                    round + 1
                );
                figures[pass][i] = m;
            }
        }
    }
    for (round, [p, s]) in medians.iter().enumerate() {
        println!(
            "round {}: pyramid / standard: prepass {:.1}, shadow pass {:.1}; pyramid / pyramid \
             at depth 0: prepass {:.2}, shadow pass {:.2}",
            round + 1,
            p[2] / p[0],
            s[2] / s[0],
            p[2] / p[1],
            s[2] / s[1],
        );
    }
    // Dropping the app after the span systems ran never returns (its render thread is not
    // joined); the figures are printed, the process ends with the test.
    std::mem::forget(app);
}
