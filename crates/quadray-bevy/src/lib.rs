//! quadray's pyramid displacement mapping as a Bevy material: exact ray casting through a
//! max-height pyramid (Oh & Ki 2007) in place of `StandardMaterial`'s parallax mapping, with Bevy's
//! PBR lighting and shadows kept, self-shadowing, level-of-detail, and the traced depth written so
//! displaced surfaces intersect other geometry where they really are. Every pass Bevy draws the
//! material in traces: the forward main pass, the depth, normal and motion-vector prepasses, the
//! deferred G-buffer (with `DefaultOpaqueRendererMethod::deferred()`) and the shadow maps.
//! Self-shadowing follows Bevy's own lights: where the height field hides a light from a pixel,
//! the main pass takes that light's contribution out (see [`PyramidExtension::shadow_strength`]).
//!
//! ```no_run
//! use bevy::prelude::*;
//! use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial};
//!
//! fn main() {
//!     App::new()
//!         .add_plugins((DefaultPlugins, PyramidDisplacementPlugin))
//!         .add_systems(Startup, setup)
//!         .run();
//! }
//!
//! fn setup(
//!     mut commands: Commands,
//!     assets: Res<AssetServer>,
//!     mut meshes: ResMut<Assets<Mesh>>,
//!     mut materials: ResMut<Assets<PyramidMaterial>>,
//! ) {
//!     // the trace needs uvs and tangents
//!     let mesh = Mesh::from(Cuboid::default()).with_generated_tangents().unwrap();
//!     commands.spawn((
//!         Mesh3d(meshes.add(mesh)),
//!         MeshMaterial3d(materials.add(PyramidMaterial {
//!             // no depth_map here: the extension takes it
//!             base: StandardMaterial::from(assets.load::<Image>("cube_color.png")),
//!             // the depth map and the depth scale Bevy's parallax takes
//!             extension: PyramidExtension::new(assets.load("cube_depth.png"), 0.09),
//!         })),
//!     ));
//! }
//! ```
//!
//! The depth map is the image a Bevy user already has for `StandardMaterial::depth_map` (0 at the
//! surface, 1 deepest; any size, 8- or 16-bit, grey or colour: the first channel). Its pyramid is
//! built on the CPU by `quadray_displace` when the image loads, and the WGSL tracing module is
//! quadray_displace's own `TRACE_WGSL`, imported as `quadray::trace`.

#![warn(missing_docs)]

pub mod gi;
mod pyramid_image;

pub use pyramid_image::{PyramidImageError, depth_map, pyramid_image};

use bevy::asset::{AssetEvent, AssetId, uuid_handle};
use bevy::mesh::MeshVertexBufferLayoutRef;
use bevy::pbr::{
    ExtendedMaterial, MaterialExtension, MaterialExtensionKey, MaterialExtensionPipeline,
    MaterialPlugin, StandardMaterial,
};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::render_resource::{
    AsBindGroup, FragmentState, RenderPipelineDescriptor, ShaderType, SpecializedMeshPipelineError,
};
use bevy::render::storage::ShaderBuffer;
use bevy::shader::{Shader, ShaderDefVal, ShaderRef};
use quadray_displace::heightmap::HeightMap;
use quadray_displace::pyramid::Addressing;
use quadray_displace::{PyramidInfo, TRACE_WGSL};
use std::sync::Arc;

/// `StandardMaterial` with its parallax replaced by the pyramid trace.
pub type PyramidMaterial = ExtendedMaterial<StandardMaterial, PyramidExtension>;

const TRACE_SHADER: Handle<Shader> = uuid_handle!("5c0f3f62-8d0c-4d57-9a43-6f1f4c1f9d01");
const MATERIAL_SHADER: Handle<Shader> = uuid_handle!("5c0f3f62-8d0c-4d57-9a43-6f1f4c1f9d02");
/// The debug buffer bound when a material records no hits.
const NO_HITS: Handle<ShaderBuffer> = uuid_handle!("5c0f3f62-8d0c-4d57-9a43-6f1f4c1f9d03");

/// The most lights a pixel traces its self-shadow ray to (each ray is one more trace through the
/// pyramid): the first that light it, directional lights before the point and spot lights of the
/// pixel's cluster. Lights beyond them light the pixel as if the height field did not hide them.
pub const SELF_SHADOWED_LIGHTS: u32 = 8;

/// Registers [`PyramidMaterial`], its shaders, and the system that builds each depth map's
/// pyramid when the image loads (and again when it changes). Add it after `DefaultPlugins`.
pub struct PyramidDisplacementPlugin;

impl Plugin for PyramidDisplacementPlugin {
    fn build(&self, app: &mut App) {
        let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
        let trace = format!("#define_import_path quadray::trace\n{TRACE_WGSL}");
        let _ = shaders.insert(
            &TRACE_SHADER,
            Shader::from_wgsl(trace, "quadray/trace.wgsl"),
        );
        let _ = shaders.insert(
            &MATERIAL_SHADER,
            Shader::from_wgsl(
                include_str!("pyramid_material.wgsl"),
                "quadray/pyramid_material.wgsl",
            ),
        );
        let no_hits = ShaderBuffer::with_size(32, default());
        let _ = app
            .world_mut()
            .resource_mut::<Assets<ShaderBuffer>>()
            .insert(&NO_HITS, no_hits);
        app.add_plugins(MaterialPlugin::<PyramidMaterial>::default())
            .init_resource::<Pyramids>()
            .add_systems(PostUpdate, build_pyramids);
    }
}

/// The pyramid tracing that replaces `StandardMaterial`'s parallax (leave the base material's
/// `depth_map` empty so Bevy's own parallax does not run as well).
#[derive(Asset, AsBindGroup, Reflect, Debug, Clone)]
#[uniform(100, PyramidUniform)]
pub struct PyramidExtension {
    /// The depth map: 0 at the polygon, 1 deepest (Bevy's `depth_map` convention); first channel.
    pub depth_map: Handle<Image>,
    /// uv units per unit of depth (Bevy's `parallax_depth_scale`).
    pub depth_scale: f32,
    /// Stop the descent at the pyramid level whose texels match the pixel's footprint
    /// (section 3.4 of the paper): cheaper far away, exact up close.
    pub lod: bool,
    /// `true`: rays that leave [0, 1)^2 miss and the pixel is discarded (a terrain patch);
    /// `false`: the map tiles.
    pub clamp_to_map: bool,
    /// Self-shadowing from the scene's lights: the share of a light's contribution (diffuse and
    /// specular, after Bevy's shadow map) a pixel loses where the height field hides that light
    /// from it; 1 is what the height field casts, 0 turns self-shadowing off and costs nothing.
    /// Each of Bevy's directional, point and spot lights that lights the pixel, up to
    /// [`SELF_SHADOWED_LIGHTS`], gets one ray through the pyramid. Ambient, environment and
    /// emissive light are untouched, and so is deferred rendering: Bevy's own lighting pass
    /// lights the G-buffer, so only the forward main pass is self-shadowed.
    pub shadow_strength: f32,
    /// The pyramid built from `depth_map` (set by [`PyramidDisplacementPlugin`]).
    #[texture(101, sample_type = "float", filterable = false)]
    pub pyramid: Option<Handle<Image>>,
    /// The depth map's width and height in texels, which `pyramid` pads to powers of two (set with
    /// it).
    pub map_size: UVec2,
    /// Debug output: per pixel the ray and the hit, for `debug_width`-wide targets.
    #[storage(102, visibility(fragment))]
    pub debug_hits: Handle<ShaderBuffer>,
    /// The render target's width when `debug_hits` records; 0 records nothing.
    pub debug_width: u32,
}

impl PyramidExtension {
    /// A tiling material over `depth_map` with Bevy's depth scale, level-of-detail on and no
    /// self-shadowing.
    pub fn new(depth_map: Handle<Image>, depth_scale: f32) -> Self {
        Self {
            depth_map,
            depth_scale,
            lod: true,
            clamp_to_map: false,
            shadow_strength: 0.0,
            pyramid: None,
            map_size: UVec2::ONE,
            debug_hits: NO_HITS,
            debug_width: 0,
        }
    }

    pub(crate) fn addressing(&self) -> Addressing {
        if self.clamp_to_map {
            Addressing::Clamp
        } else {
            Addressing::Wrap
        }
    }
}

impl MaterialExtension for PyramidExtension {
    fn fragment_shader() -> ShaderRef {
        MATERIAL_SHADER.into()
    }

    fn prepass_fragment_shader() -> ShaderRef {
        MATERIAL_SHADER.into()
    }

    fn deferred_fragment_shader() -> ShaderRef {
        MATERIAL_SHADER.into()
    }

    // The main pass's light loop is bounded by SELF_SHADOWED_LIGHTS. Bevy draws depth-only
    // prepasses and shadow maps without a fragment stage and without the tangent frame: the
    // polygon's depth. The trace needs both, in every prepass.
    fn specialize(
        _pipeline: &MaterialExtensionPipeline,
        descriptor: &mut RenderPipelineDescriptor,
        layout: &MeshVertexBufferLayoutRef,
        _key: MaterialExtensionKey<Self>,
    ) -> Result<(), SpecializedMeshPipelineError> {
        let defs = &mut descriptor.vertex.shader_defs;
        if !defs.contains(&"PREPASS_PIPELINE".into()) {
            if let Some(fragment) = &mut descriptor.fragment {
                fragment.shader_defs.push(ShaderDefVal::UInt(
                    "SELF_SHADOWED_LIGHTS".into(),
                    SELF_SHADOWED_LIGHTS,
                ));
            }
            return Ok(());
        }
        let frame = "NORMAL_PREPASS_OR_DEFERRED_PREPASS".into();
        if !defs.contains(&frame) {
            defs.push(frame);
            // Bevy's prepass locations for the normal and the tangent (prepass_io.wgsl).
            for (attribute, location, def) in [
                (Mesh::ATTRIBUTE_NORMAL, 3, "VERTEX_NORMALS"),
                (Mesh::ATTRIBUTE_TANGENT, 4, "VERTEX_TANGENTS"),
            ] {
                if layout.0.contains(attribute.id) {
                    let extra = layout
                        .0
                        .get_layout(&[attribute.at_shader_location(location)])?;
                    descriptor.vertex.buffers[0]
                        .attributes
                        .extend(extra.attributes);
                    defs.push(def.into());
                }
            }
        }
        let defs = defs.clone();
        let fragment = descriptor.fragment.get_or_insert_with(|| FragmentState {
            shader: MATERIAL_SHADER,
            ..default()
        });
        for def in defs {
            if !fragment.shader_defs.contains(&def) {
                fragment.shader_defs.push(def);
            }
        }
        Ok(())
    }
}

/// The uniform the shader reads (`PyramidParams` in pyramid_material.wgsl).
#[derive(ShaderType, Clone, Copy, Debug)]
pub struct PyramidUniform {
    levels: i32,
    clamp_to_map: u32,
    iteration_cap: u32,
    refine_cap: u32,
    map_size: UVec2,
    depth_scale: f32,
    flags: u32,
    debug_width: u32,
    shadow_strength: f32,
}

impl From<&PyramidExtension> for PyramidUniform {
    fn from(m: &PyramidExtension) -> Self {
        let info = PyramidInfo::new(m.map_size.x, m.map_size.y, m.addressing());
        Self {
            levels: info.levels,
            clamp_to_map: info.clamp_to_map,
            iteration_cap: info.iteration_cap,
            refine_cap: info.refine_cap,
            map_size: UVec2::from(info.size),
            // Until the pyramid is built the shader traces the fallback image: flat.
            depth_scale: if m.pyramid.is_some() {
                m.depth_scale
            } else {
                0.0
            },
            flags: u32::from(m.lod),
            debug_width: m.debug_width,
            shadow_strength: m.shadow_strength,
        }
    }
}

/// Each depth map's pyramid image, size and height field, or `None` once the map proved
/// unusable (the GI plugin tessellates the height field for its RSM).
#[derive(Resource, Default)]
pub(crate) struct Pyramids(pub(crate) HashMap<AssetId<Image>, Option<BuiltPyramid>>);

/// The pyramid image, the depth map's width and height in texels and its height field.
pub(crate) type BuiltPyramid = (Handle<Image>, UVec2, Arc<HeightMap>);

/// Builds the pyramid of every depth map a material uses once the image is loaded (and again when
/// it changes), and points the materials at it. An unusable map is logged once, naming the asset.
pub(crate) fn build_pyramids(
    mut image_events: MessageReader<AssetEvent<Image>>,
    mut pyramids: ResMut<Pyramids>,
    mut images: ResMut<Assets<Image>>,
    mut materials: ResMut<Assets<PyramidMaterial>>,
    assets: Res<AssetServer>,
) {
    for event in image_events.read() {
        if let AssetEvent::Modified { id } | AssetEvent::Removed { id } = event {
            pyramids.0.remove(id);
        }
    }
    let stale: Vec<_> = materials
        .iter()
        .filter(|(_, m)| {
            let wanted = pyramids.0.get(&m.extension.depth_map.id());
            let current = m
                .extension
                .pyramid
                .as_ref()
                .map(|p| (p.id(), m.extension.map_size));
            match wanted {
                Some(Some((handle, size, _))) => current != Some((handle.id(), *size)),
                Some(None) => false,
                None => images.contains(&m.extension.depth_map),
            }
        })
        .map(|(id, _)| id)
        .collect();
    for id in stale {
        let Some(mut material) = materials.get_mut(id) else {
            continue;
        };
        let source = material.extension.depth_map.id();
        let built = pyramids.0.entry(source).or_insert_with(|| {
            let name = assets
                .get_path(source)
                .map_or_else(|| format!("{source:?}"), |p| p.to_string());
            let map = images.get(source).map(|image| depth_map(&name, image));
            match map {
                Some(Ok(map)) => Some((
                    images.add(pyramid_image(&map)),
                    UVec2::new(map.width, map.height),
                    Arc::new(map),
                )),
                Some(Err(e)) => {
                    error!("quadray-bevy: {e}");
                    None
                }
                None => None,
            }
        });
        if let Some((handle, size, _)) = built {
            material.extension.pyramid = Some(handle.clone());
            material.extension.map_size = *size;
        }
    }
}
