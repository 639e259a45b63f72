//! One bounce of indirect light from Bevy's lights (`DirectionalLight`, `PointLight` and
//! `SpotLight`, each marked with [`IndirectLightSource`]) through quadray's light quadtree
//! (`quadray_indirect`): each light's reflective shadow maps (a spot's one, the sun's one
//! orthographic over the scene, a point light's six cube faces), their cluster pyramids and cuts,
//! the gather over the camera's deferred G-buffer summing them, added to the lit HDR picture
//! before tone mapping. Bevy's own direct light, shadows, cascades, materials and exposure stay as
//! they are.
//!
//! ```no_run
//! use bevy::pbr::DefaultOpaqueRendererMethod;
//! use bevy::prelude::*;
//! use quadray_bevy::gi::{IndirectLight, IndirectLightPlugin, IndirectLightSource};
//!
//! fn main() {
//!     App::new()
//!         // the gather reads the deferred G-buffer: StandardMaterials render deferred
//!         .insert_resource(DefaultOpaqueRendererMethod::deferred())
//!         .add_plugins((DefaultPlugins, IndirectLightPlugin))
//!         .add_systems(Startup, setup)
//!         .run();
//! }
//!
//! fn setup(mut commands: Commands) {
//!     // any DirectionalLight, PointLight or SpotLight marked gives the bounce
//!     let above = Transform::from_xyz(0.0, 3.0, 0.0).looking_at(Vec3::ZERO, Vec3::Z);
//!     commands.spawn((SpotLight::default(), IndirectLightSource, above));
//!     // the settings and the method; MSAA off, as deferred rendering needs
//!     commands.spawn((Camera3d::default(), Msaa::Off, IndirectLight::default()));
//! }
//! ```
//!
//! The passes are `quadray_indirect`'s own, recorded into Bevy's command encoder on Bevy's
//! device (quadray builds on the wgpu Bevy 0.19 uses); the plugin adds only the translation of
//! Bevy's packed G-buffer (`gbuffer.wgsl`, with Bevy's unpacking functions) and the additive
//! composite (`composite.wgsl`). With [`RsmSource::Meshes`] the lights' RSMs are drawn from
//! Bevy's meshes on the GPU by the plugin's mesh pipeline (`render/meshes.rs`; the variant
//! says what it draws and what not). By default the light's RSM is rasterised
//! from the scene's triangles,
//! made on the CPU per visible `Mesh3d` entity: a `StandardMaterial`'s polygons in its base
//! colour times its `base_color_texture`, sampled per texel (the distinct images, read on the
//! CPU where they keep their data, are the layers of quadray's texture array, uploaded when that
//! set changes; a mesh takes its flat base colour where its image cannot be read, with one
//! warning), a [`PyramidMaterial`](crate::PyramidMaterial)'s displaced
//! surface (its height field cut into triangles, at most [`DISPLACED_TRIANGLES_MAX`] a mesh) in
//! its base colour times its colour texture (read on the CPU where the image keeps its data; its
//! base colour alone where not); a skinned or morphed mesh posed as Bevy's vertex shader poses
//! it (its `MeshMorphWeights` applied, then linear blend skinning in world space); the same
//! triangles make the occupancy grid of indirect shadows ([`IndirectLightScene`] holds them, by
//! entity). The scene is kept up to date by what changed: an entity's triangles are made anew
//! when its transform, mesh, material or visibility changes (or the mesh, material or texture
//! asset it uses, a joint of its skin moves or its morph weights change), and only those reach
//! the render world, which writes them into the entity's range of one vertex buffer and moves
//! them in the occupancy grid (made anew only when the scene leaves the grid's bounds); a frame
//! in which nothing changed does no scene work ([`SceneWork`] counts the render world's). A
//! moving light, or a change to the scene, redraws the RSM, the pyramid and the cut; a still
//! light and a moving camera reuse them. Each camera gathers every frame: Bevy's G-buffer
//! changes without the camera moving (a mesh's pipeline compiled frames after it loaded, render
//! layers switched).
//!
//! Units: the lights' intensities are Bevy's (a point or spot light's luminous power in lumens,
//! its luminous intensity that over 4 pi, as Bevy lights it; a directional light's illuminance
//! in lux), so the indirect light is in the same units as Bevy's direct light and is scaled by the
//! camera's exposure as Bevy's is. The lights are taken in a fixed order (directional, spot, point
//! lights, each kind by entity) up to the first camera's
//! [`Settings::max_lights`](quadray_indirect::Settings::max_lights).
//!
//! With Bevy's `RenderDiagnosticsPlugin`, each camera reports to Bevy's `DiagnosticsStore` under
//! its own path, `render/quadray_gi/camera_{entity}` (its main-world entity as Bevy prints it,
//! [`camera_diagnostic_path`]): `elapsed_gpu` and `elapsed_cpu` of its passes and of their parts
//! `light` (the lights' RSMs, pyramids and cuts, in the frames that rebuild them, under the
//! camera that records them), `gather` and `composite`; `vpl_evaluations_per_pixel` and
//! `texel_fetches_per_pixel`, its gather's work per shaded pixel. The lights' cut is every
//! camera's: its size is `render/quadray_gi/cut_clusters`.
//!
//! The plugin's CPU time a frame in each world goes to Bevy's `DiagnosticsStore` as
//! [`MAIN_WORLD_CPU`] and [`RENDER_WORLD_CPU`] (milliseconds; no other plugin needed).
//!
//! A camera that loses [`IndirectLight`], or is despawned or no longer rendered, frees its passes
//! ([`ViewPasses`]); the lights' maps are freed when no rendered camera has [`IndirectLight`].

mod cpu_time;
mod displaced;
mod lights;
mod posed;
mod render;
mod scene;
mod textures;

pub use cpu_time::{MAIN_WORLD_CPU, RENDER_WORLD_CPU};
pub use displaced::DISPLACED_TRIANGLES_MAX;
pub use lights::{quadray_directional, quadray_point, quadray_spot};
pub use render::{SceneWork, ViewPasses};
pub use scene::{
    IndirectLight, IndirectLightScene, IndirectLightSource, ObjectTriangles, RsmSource,
};

use bevy::diagnostic::DiagnosticPath;
use bevy::prelude::*;
use bevy::render::extract_component::ExtractComponentPlugin;
use lights::collect_lights;
use scene::{collect_meshes, collect_triangles};

/// Adds [`IndirectLight`] to the cameras that carry it, from the lights marked
/// [`IndirectLightSource`]. Add it after `DefaultPlugins`; the cameras need deferred rendering
/// (`DefaultOpaqueRendererMethod::deferred()` or deferred materials) and `Msaa::Off`.
pub struct IndirectLightPlugin;

impl Plugin for IndirectLightPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins(ExtractComponentPlugin::<IndirectLight>::default())
            .init_resource::<IndirectLightScene>()
            .add_systems(
                PostUpdate,
                (collect_triangles, collect_lights)
                    .after(bevy::transform::TransformSystems::Propagate)
                    .after(crate::build_pyramids)
                    .after(bevy::camera::visibility::VisibilitySystems::VisibilityPropagate)
                    // this frame's asset events read this frame: an entity's triangles made once
                    .after(bevy::asset::AssetEventSystems),
            );
        app.add_systems(
            PostUpdate,
            collect_meshes.in_set(bevy::camera::visibility::VisibilitySystems::CheckVisibility),
        );
        render::build(app);
        cpu_time::build(app);
    }

    fn finish(&self, app: &mut App) {
        // what a texture with `ImageSampler::Default` is read through (`ImagePlugin` is added
        // by then, with `DefaultPlugins`)
        if let Some(image_plugin) = app.get_added_plugins::<bevy::image::ImagePlugin>().first() {
            let default_sampler = image_plugin.default_sampler.clone();
            app.world_mut()
                .resource_mut::<IndirectLightScene>()
                .base_colours
                .default_sampler = default_sampler;
        }
    }
}

/// The path in Bevy's `DiagnosticsStore` of `camera`'s diagnostic `name`: `elapsed_gpu`,
/// `gather/elapsed_gpu`, `vpl_evaluations_per_pixel`, ... (the module's documentation lists
/// them), reported with Bevy's `RenderDiagnosticsPlugin`.
pub fn camera_diagnostic_path(camera: Entity, name: &str) -> DiagnosticPath {
    DiagnosticPath::new(format!(
        "render/{}/{name}",
        render::camera_diagnostics(camera)
    ))
}
