//! The glTF reader: the meshes through [`load_model`], the first camera and the punctual lights
//! from the node tree (read from the validated JSON, so no accessor of the `gltf` crate can
//! panic on a file that mixes up its fields).

use super::{
    Camera, Cone, Intensity, Light, LightKind, Object, SceneDescription, Shape, Transform, stem,
};
use crate::FileError;
use crate::mesh::gltf::{document, walk_nodes};
use crate::mesh::{MeshError, load_model};
use glam::{Mat4, Vec3};
use gltf::json::extensions::scene::khr_lights_punctual::Type;
use gltf::json::validation::Checked;
use std::path::Path;

/// The scene, and whether its camera was made by [`Camera::framing`] (with `frame`, where the
/// file has none; without, that is an error).
pub(super) fn load(path: &Path, frame: bool) -> Result<(SceneDescription, bool), FileError> {
    let model = load_model(path).map_err(|e| mesh_error(path, e))?;
    let document = document(path).map_err(|e| mesh_error(path, e))?;
    let json = document.as_json();
    let mut camera = None;
    let mut lights = Vec::new();
    let invalid = |reason: String| MeshError::Parse {
        path: path.to_owned(),
        format: "glTF",
        reason,
    };
    walk_nodes(path, &document, |node, world| {
        let index = node.index();
        let node_json = &json.nodes[index];
        let light_index = node_json
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map(|l| l.light.value());
        let wanted_camera = node_json.camera.filter(|_| camera.is_none());
        if (wanted_camera.is_some() || light_index.is_some()) && !world.is_finite() {
            return Err(invalid(format!(
                "node {index}: its transform is not finite"
            )));
        }
        if let Some(c) = wanted_camera {
            let c = c.value();
            camera = Some(
                node_camera(json, c, world)
                    .map_err(|why| invalid(format!("node {index}: camera {c}: {why}")))?,
            );
        }
        if let Some(l) = light_index {
            let light = node_light(json, l, world)
                .map_err(|why| invalid(format!("node {index}: light {l}: {why}")))?;
            lights.push(light);
        }
        Ok(())
    })
    .map_err(|e| mesh_error(path, e))?;
    let framed = camera.is_none() && frame;
    let camera = match camera {
        Some(camera) => camera,
        None if frame => Camera::framing(model.bounds()),
        None => {
            return Err(FileError::new(
                path,
                "no camera: the scene needs a node with a perspective camera",
            ));
        }
    };
    let scene = SceneDescription {
        name: stem(path),
        camera,
        lights,
        materials: Vec::new(),
        objects: vec![Object {
            shape: Shape::Mesh {
                path: path.to_owned(),
                model: Box::new(model),
            },
            transform: Transform::IDENTITY,
            material: None,
        }],
        techniques: scene_extras(json).map_err(|why| FileError::new(path, why))?,
    };
    Ok((scene, framed))
}

/// Each technique's own settings from the default scene's `extras` (`{"indirect": {"r_min":
/// 0.05}, "raytrace": {...}}`, as the TOML tables; Blender writes a scene's custom properties
/// there). Other extras are left alone.
fn scene_extras(
    json: &gltf::json::Root,
) -> Result<std::collections::BTreeMap<String, toml::Table>, String> {
    let scene = json.scene.map_or(0, |s| s.value());
    let Some(raw) = json.scenes.get(scene).and_then(|s| s.extras.as_ref()) else {
        return Ok(Default::default());
    };
    let extras: serde_json::Value =
        serde_json::from_str(raw.get()).map_err(|e| format!("scene {scene}: extras: {e}"))?;
    let mut techniques = std::collections::BTreeMap::new();
    for technique in ["indirect", "raytrace"] {
        if let Some(settings) = extras.get(technique) {
            let table = toml::Table::try_from(settings).map_err(|e| {
                format!("scene {scene}: extras: {technique}: not a table of settings ({e})")
            })?;
            techniques.insert(technique.to_string(), table);
        }
    }
    Ok(techniques)
}

/// A glTF camera looks down its node's -z with +y up.
fn node_camera(json: &gltf::json::Root, index: usize, world: Mat4) -> Result<Camera, String> {
    let perspective = json.cameras[index]
        .perspective
        .as_ref()
        .ok_or("only perspective cameras are supported")?;
    let position = world.transform_point3(Vec3::ZERO);
    let camera = Camera {
        position,
        target: position + world.transform_vector3(Vec3::NEG_Z).normalize_or_zero(),
        up: world.transform_vector3(Vec3::Y).normalize_or_zero(),
        fov_y_deg: perspective.yfov.to_degrees(),
    };
    camera.validate()?;
    Ok(camera)
}

/// A point, spot or directional light (spot and directional lights shine down their node's -z).
fn node_light(json: &gltf::json::Root, index: usize, world: Mat4) -> Result<Light, String> {
    let light = json
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .and_then(|l| l.lights.get(index))
        .ok_or("does not exist")?;
    let position = world.transform_point3(Vec3::ZERO);
    let down_z = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let kind = match (&light.type_, &light.spot) {
        (Checked::Valid(Type::Point), _) => LightKind::Point { position },
        (Checked::Valid(Type::Spot), Some(s)) => {
            let (inner, outer) = (s.inner_cone_angle, s.outer_cone_angle);
            if !(0.0 <= inner && inner < outer && outer <= std::f32::consts::FRAC_PI_2) {
                return Err(format!(
                    "cone angles {inner}, {outer} are not 0 <= inner < outer <= pi/2"
                ));
            }
            LightKind::Spot {
                position,
                cone: Cone {
                    direction: down_z,
                    cone_deg: outer.to_degrees(),
                    falloff_deg: (outer - inner).to_degrees(),
                },
            }
        }
        (Checked::Valid(Type::Directional), _) => LightKind::Directional { direction: down_z },
        _ => return Err("has no valid type".into()),
    };
    let light = Light {
        kind,
        intensity: Intensity::Photometric(Vec3::from(light.color) * light.intensity),
    };
    light.validate()?;
    Ok(light)
}

/// A mesh error as the scene's error (its message already starts with the file).
fn mesh_error(path: &Path, e: MeshError) -> FileError {
    let message = e.to_string();
    let prefix = format!("{}: ", path.display());
    FileError::new(path, message.strip_prefix(&prefix).unwrap_or(&message))
}
