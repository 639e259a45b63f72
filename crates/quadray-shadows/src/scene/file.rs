//! The ray tracer's scene built from the shared scene description (`quadray_core::scene`): a
//! TOML or glTF file, or a description made in code.

use super::{Light, Material, Scene, SceneError, scene_error};
use glam::Vec3;
use quadray_core::FileError;
use quadray_core::geom::ConvexPolygon;
use quadray_core::scene::{Intensity, LUMENS_PER_WATT, SceneDescription, Shape};
use std::collections::HashMap;
use std::path::Path;

impl Scene {
    /// Reads a scene file: TOML (see `assets/scenes/shadows-demo.toml`), or glTF 2.0 for `.gltf`
    /// and `.glb`.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let description = SceneDescription::load(path).map_err(file_error)?;
        Scene::from_description(&description).map_err(|why| scene_error(path, why))
    }

    /// Parses a TOML scene; `path` names the source in errors and mesh paths start in its
    /// directory.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let description = SceneDescription::from_toml(text, path).map_err(file_error)?;
        Scene::from_description(&description).map_err(|why| scene_error(path, why))
    }

    /// The ray tracer's scene: every light becomes a point light (a spot light shines in every
    /// direction from its position, its cone left out); boxes, polygons and meshes become faces
    /// whose vertices at the same position are welded, so faces find their neighbours; a mesh
    /// without a material takes its file's base colours as matte materials. Builtin meshes are
    /// refused: this renderer's builtins are whole scenes ([`Scene::builtin`]).
    ///
    /// Light intensities in the file's own units are used as they are. This renderer's lights do
    /// not fall off with distance (a surface's radiance is intensity x albedo x cos), so a
    /// photometric intensity `I` (candela, glTF's) becomes `I / (683 pi d^2)`, with `d` the
    /// distance from the light to the centre of the scene's bounds: there, a surface facing the
    /// light shows the radiance of the inverse-square law (`albedo / pi x I / d^2`, in W/sr/m^2).
    pub fn from_description(d: &SceneDescription) -> Result<Scene, String> {
        if d.lights.is_empty() {
            return Err("no lights".into());
        }
        let mut s = Scene::new(&d.name, d.camera);
        let own: FileSettings = d.technique_settings("raytrace")?;
        for (what, colour) in [("ambient", own.ambient), ("background", own.background)] {
            if colour.is_some_and(|c| !(c.is_finite() && c.min_element() >= 0.0)) {
                return Err(format!("[raytrace] {what} must be finite and not negative"));
            }
        }
        s.ambient = own.ambient.unwrap_or(s.ambient);
        s.background = own.background.unwrap_or(s.background);
        for (_, m) in &d.materials {
            s.add_material(*m);
        }
        // Vertices at the same position are one vertex, so faces find their neighbours.
        let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
        let mut weld = |s: &mut Scene, v: Vec3| {
            let key = v.to_array().map(f32::to_bits);
            *welded.entry(key).or_insert_with(|| s.add_vertex(v))
        };
        for (o, object) in d.objects.iter().enumerate() {
            let material = object.material.map(|m| m as u32);
            let needs_material = || format!("object {o}: no material");
            match &object.shape {
                Shape::Box { min, max } => {
                    s.cuboid(*min, *max, material.ok_or_else(needs_material)?);
                }
                Shape::Polygons(polygons) => {
                    let material = material.ok_or_else(needs_material)?;
                    for (p, polygon) in polygons.iter().enumerate() {
                        check_polygon(polygon)
                            .map_err(|why| format!("object {o}, polygon {p}: {why}"))?;
                        let ids = polygon.iter().map(|&v| weld(&mut s, v)).collect();
                        s.push_face(ids, material);
                    }
                }
                Shape::Mesh { model, .. } => {
                    let to_world = object.transform.matrix();
                    let first_material = s.materials.len() as u32;
                    if material.is_none() {
                        for m in &model.materials {
                            s.add_material(Material::matte(m.base_color));
                        }
                    }
                    for m in &model.meshes {
                        let mat = material.unwrap_or(first_material + m.material as u32);
                        for tri in &m.indices {
                            let ids = tri
                                .iter()
                                .map(|&i| {
                                    weld(&mut s, to_world.transform_point3(m.positions[i as usize]))
                                })
                                .collect();
                            s.push_face(ids, mat);
                        }
                    }
                }
                Shape::Builtin(name) => {
                    return Err(format!(
                        "object {o}: builtin `{name}`: quadray raytrace has no builtin meshes \
                         (its builtins are whole scenes: --builtin NAME)"
                    ));
                }
            }
        }
        if s.faces.is_empty() {
            return Err("no polygons".into());
        }
        let (lo, hi) = s
            .vertices
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let centre = (lo + hi) * 0.5;
        // The ray tracer's lights are points: a spot shines from its apex in every direction,
        // and a directional light has no point to shadow-test against.
        s.lights = d
            .lights
            .iter()
            .filter_map(|l| {
                let Some(position) = l.position() else {
                    tracing::warn!(
                        "{}: left out (the ray tracer's lights are points)",
                        l.describe()
                    );
                    return None;
                };
                Some(Light {
                    position,
                    intensity: match l.intensity {
                        Intensity::Native(v) => v,
                        Intensity::Photometric(cd) => {
                            let d2 = position.distance_squared(centre).max(1e-12);
                            cd / (LUMENS_PER_WATT * std::f32::consts::PI * d2)
                        }
                    },
                })
            })
            .collect();
        Ok(s)
    }
}

fn file_error(e: FileError) -> SceneError {
    SceneError {
        path: e.path.display().to_string(),
        reason: e.reason,
    }
}

/// A file polygon must be finite, planar and convex (a zero-area polygon is allowed; it is never hit).
fn check_polygon(poly: &[Vec3]) -> Result<(), String> {
    // The scene reader checks these too; a description made in code may not have been read.
    if poly.len() < 3 || poly.iter().any(|v| !v.is_finite()) {
        return Err("needs at least 3 finite vertices".into());
    }
    let p = ConvexPolygon::new(poly.to_vec());
    if p.is_degenerate() {
        return Ok(());
    }
    let size = p.bounds().extent().max_element();
    if poly
        .iter()
        .any(|v| (p.normal.dot(*v) - p.offset).abs() > 1e-4 * size)
    {
        return Err("not planar".into());
    }
    let n = poly.len();
    let convex = (0..n).all(|i| {
        let (a, b, c) = (poly[i], poly[(i + 1) % n], poly[(i + 2) % n]);
        (b - a).cross(c - b).dot(p.normal) >= -1e-6 * size * size
    });
    if !convex {
        return Err("not convex".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenes() -> std::path::PathBuf {
        super::super::assets_dir().join("scenes")
    }

    /// The spot light becomes a point light whose candela are turned into this renderer's units
    /// at the scene's centre; the camera and the faces come from the glTF file.
    #[test]
    fn the_gltf_scene_loads_with_its_spot_as_a_point_light() {
        let s = Scene::load(&scenes().join("cornell_spot.gltf")).unwrap();
        assert_eq!(s.faces.len(), 30);
        assert_eq!(s.lights.len(), 1);
        let light = s.lights[0];
        assert!(light.position.abs_diff_eq(Vec3::new(0.5, 0.97, 0.85), 1e-6));
        let d2 = light.position.distance_squared(Vec3::splat(0.5));
        let expected = 1366.0 / (683.0 * std::f32::consts::PI * d2);
        assert!(
            light.intensity.abs_diff_eq(Vec3::splat(expected), 1e-4),
            "{light:?}"
        );
        assert!(
            s.camera
                .position
                .abs_diff_eq(Vec3::new(0.5, 0.5, 2.4), 1e-6)
        );
        let red = s
            .materials
            .iter()
            .any(|m| m.diffuse.x > 0.5 && m.diffuse.y < 0.1);
        assert!(red, "the red wall's base colour");
    }

    #[test]
    fn builtin_meshes_are_refused_with_the_object_named() {
        let e = Scene::load(&scenes().join("cornell.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cornell.toml: object 0: builtin `cornell`"),
            "{e}"
        );
    }
}

/// A scene file's `[raytrace]` table (unset: [`Scene::new`]'s ambient light and background).
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct FileSettings {
    ambient: Option<Vec3>,
    background: Option<Vec3>,
}
