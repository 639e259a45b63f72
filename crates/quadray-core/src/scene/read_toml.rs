//! The TOML reader: the canonical spelling and the older ones (see the module docs of
//! [`scene`](super)).

use super::{
    Camera, Cone, Intensity, Light, LightKind, Material, Object, SceneDescription, Shape,
    Transform, stem,
};
use crate::mesh::{FarCoordinate, inside_folder, load_model};
use glam::Vec3;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    name: Option<String>,
    indirect: Option<::toml::Table>,
    raytrace: Option<::toml::Table>,
    /// Older spellings of `[indirect] r_min` and `[raytrace] ambient`, `background`.
    r_min: Option<::toml::Value>,
    ambient: Option<::toml::Value>,
    background: Option<::toml::Value>,
    camera: CameraToml,
    /// quadray indirect's older spelling: one spot light.
    light: Option<LightToml>,
    #[serde(default)]
    lights: Vec<LightToml>,
    /// Sorted by name, so material numbers do not depend on the order of the file.
    #[serde(default)]
    materials: BTreeMap<String, Material>,
    #[serde(default, alias = "mesh")]
    objects: Vec<ObjectToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraToml {
    #[serde(alias = "eye")]
    position: Vec3,
    #[serde(alias = "look_at")]
    target: Vec3,
    #[serde(default = "up")]
    up: Vec3,
    #[serde(alias = "fov_deg")]
    fov_y_deg: f32,
}

fn up() -> Vec3 {
    Vec3::Y
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightToml {
    position: Option<Vec3>,
    intensity: Option<Vec3>,
    candela: Option<Vec3>,
    lux: Option<Vec3>,
    direction: Option<Vec3>,
    cone_deg: Option<f32>,
    falloff_deg: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectToml {
    #[serde(alias = "path")]
    mesh: Option<PathBuf>,
    builtin: Option<String>,
    #[serde(rename = "box")]
    cuboid: Option<BoxToml>,
    polygons: Option<Vec<Vec<Vec3>>>,
    material: Option<String>,
    albedo: Option<Vec3>,
    scale: Option<f32>,
    rotate_y_deg: Option<f32>,
    translate: Option<Vec3>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxToml {
    min: Vec3,
    max: Vec3,
}

pub(super) fn parse(text: &str, path: &Path) -> Result<SceneDescription, String> {
    let file: SceneToml = ::toml::from_str(text).map_err(|e| e.to_string())?;
    let c = file.camera;
    let camera = Camera {
        position: c.position,
        target: c.target,
        up: c.up,
        fov_y_deg: c.fov_y_deg,
    };
    camera.validate()?;
    let lights = file
        .light
        .into_iter()
        .chain(file.lights)
        .map(light)
        .collect::<Result<Vec<_>, _>>()?;
    let mut techniques = BTreeMap::new();
    let older = [
        ("indirect", file.indirect, vec![("r_min", file.r_min)]),
        (
            "raytrace",
            file.raytrace,
            vec![("ambient", file.ambient), ("background", file.background)],
        ),
    ];
    for (technique, table, top_level) in older {
        let mut table = table.unwrap_or_default();
        for (key, value) in top_level.into_iter().filter_map(|(k, v)| Some((k, v?))) {
            if table.insert(key.to_string(), value).is_some() {
                return Err(format!("{key} is set both at the top and in [{technique}]"));
            }
        }
        if !table.is_empty() {
            techniques.insert(technique.to_string(), table);
        }
    }
    for (name, m) in &file.materials {
        let values = [m.specular, m.shininess, m.reflect, m.transmit, m.ior];
        if !(values.iter().all(|x| x.is_finite()) && m.diffuse.is_finite() && m.ior > 0.0) {
            return Err(format!(
                "material {name}: values must be finite and ior > 0"
            ));
        }
    }
    let mut materials: Vec<(String, Material)> = file.materials.into_iter().collect();
    let named = materials.len();
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut objects = Vec::new();
    for (o, entry) in file.objects.into_iter().enumerate() {
        let object = object(entry, dir, &mut materials, named, o)
            .map_err(|why| format!("object {o}: {why}"))?;
        objects.push(object);
    }
    if objects.is_empty() {
        return Err("no [[objects]] (or [[mesh]])".into());
    }
    Ok(SceneDescription {
        name: file.name.unwrap_or_else(|| stem(path)),
        camera,
        lights,
        materials,
        objects,
        techniques,
    })
}

/// A point light (a position), a spot (a position, `direction` and `cone_deg`) or a directional
/// light (a `direction` alone).
fn light(l: LightToml) -> Result<Light, String> {
    let name = match l.position {
        Some(p) => format!("light at {p}"),
        None => "light without a position".to_string(),
    };
    let kind = match (l.position, l.direction, l.cone_deg) {
        (Some(position), None, None) if l.falloff_deg.is_none() => LightKind::Point { position },
        (Some(position), Some(direction), Some(cone_deg)) => LightKind::Spot {
            position,
            cone: Cone {
                direction,
                cone_deg,
                falloff_deg: l.falloff_deg.unwrap_or(0.0),
            },
        },
        (None, Some(direction), None) if l.falloff_deg.is_none() => {
            LightKind::Directional { direction }
        }
        (Some(_), ..) => {
            return Err(format!(
                "{name}: a spot light needs `direction` and `cone_deg`"
            ));
        }
        (None, ..) => {
            return Err(format!(
                "{name}: give a `position` (a point or spot light) or a `direction` alone (a \
                 directional light)"
            ));
        }
    };
    let photometric_key = match kind {
        LightKind::Directional { .. } => "lux",
        _ => "candela",
    };
    let intensity = match (l.intensity, l.candela, l.lux) {
        (Some(v), None, None) => Intensity::Native(v),
        (None, Some(v), None) if photometric_key == "candela" => Intensity::Photometric(v),
        (None, None, Some(v)) if photometric_key == "lux" => Intensity::Photometric(v),
        _ => {
            return Err(format!(
                "{name}: give one of `intensity` and `{photometric_key}`"
            ));
        }
    };
    let light = Light { kind, intensity };
    light.validate()?;
    Ok(light)
}

/// One `[[objects]]` entry; `albedo` adds a material after the `named` ones.
fn object(
    entry: ObjectToml,
    dir: &Path,
    materials: &mut Vec<(String, Material)>,
    named: usize,
    index: usize,
) -> Result<Object, String> {
    let transform = Transform {
        scale: entry.scale.unwrap_or(1.0),
        rotate_y_deg: entry.rotate_y_deg.unwrap_or(0.0),
        translate: entry.translate.unwrap_or(Vec3::ZERO),
    };
    if !(transform.scale.is_finite() && transform.scale > 0.0) {
        return Err(format!("scale {} must be finite and > 0", transform.scale));
    }
    if !(transform.translate.is_finite() && transform.rotate_y_deg.is_finite()) {
        return Err("translate and rotate_y_deg must be finite".into());
    }
    let material = match (entry.material, entry.albedo) {
        (Some(_), Some(_)) => return Err("has both `material` and `albedo`".into()),
        (Some(name), None) => Some(
            materials[..named]
                .iter()
                .position(|(n, _)| *n == name)
                .ok_or_else(|| format!("unknown material {name:?}"))?,
        ),
        (None, Some(albedo)) => {
            if !albedo.cmpge(Vec3::ZERO).all() || !albedo.cmple(Vec3::ONE).all() {
                return Err(format!("albedo {albedo} is outside [0, 1]"));
            }
            materials.push((format!("object {index} albedo"), Material::diffuse(albedo)));
            Some(materials.len() - 1)
        }
        (None, None) => None,
    };
    let shape = match (entry.mesh, entry.builtin, entry.cuboid, entry.polygons) {
        (Some(mesh), None, None, None) => {
            // the scene's folder and those beside it: `scenes/` and `meshes/`
            let path = inside_folder(&dir.join(".."), dir, &mesh)
                .map_err(|outside| format!("mesh {outside}"))?;
            let model = load_model(&path).map_err(|e| e.to_string())?;
            model
                .check_placed(&path, transform.matrix())
                .map_err(|e| format!("{e}, once the object's transform places it"))?;
            Shape::Mesh {
                path,
                model: Box::new(model),
            }
        }
        (None, Some(name), None, None) => Shape::Builtin(name),
        (None, None, Some(b), None) => {
            if let Some((corner, c)) = FarCoordinate::find([b.min, b.max]) {
                return Err(format!("box {}: {c}", ["min", "max"][corner]));
            }
            if b.min.cmpge(b.max).any() {
                return Err("box min must be below max".into());
            }
            Shape::Box {
                min: b.min,
                max: b.max,
            }
        }
        (None, None, None, Some(polygons)) => {
            for (p, polygon) in polygons.iter().enumerate() {
                if polygon.len() < 3 {
                    return Err(format!(
                        "polygon {p}: {} vertices, need at least 3",
                        polygon.len()
                    ));
                }
                if let Some((v, c)) = FarCoordinate::find(polygon.iter().copied()) {
                    return Err(format!("polygon {p}: vertex {v}: {c}"));
                }
            }
            Shape::Polygons(polygons)
        }
        (None, None, None, None) => {
            return Err("needs one of `mesh`, `builtin`, `box`, `polygons`".into());
        }
        _ => return Err("has more than one of `mesh`, `builtin`, `box`, `polygons`".into()),
    };
    if matches!(shape, Shape::Box { .. } | Shape::Polygons(_)) {
        if transform != Transform::IDENTITY {
            return Err(
                "a box or polygons are written in world coordinates: no scale, \
                 rotate_y_deg or translate"
                    .into(),
            );
        }
        if material.is_none() {
            return Err("a box or polygons need a `material` (or `albedo`)".into());
        }
    }
    Ok(Object {
        shape,
        transform,
        material,
    })
}
