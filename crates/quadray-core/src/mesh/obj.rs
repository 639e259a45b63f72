//! Wavefront OBJ + MTL through `tobj`.

use super::{
    Material, MeshBuilder, MeshError, Model, beside, decode_texture, finish_all, read_file,
    read_text_file,
};
use glam::{Mat4, Vec2, Vec3};
use std::cell::RefCell;
use std::path::Path;

pub(super) fn load(path: &Path) -> Result<(Model, usize), MeshError> {
    let text = read_text_file(path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mtl_problems = RefCell::new(Vec::new());
    let (objects, materials) = tobj::load_obj_buf(&mut text.as_slice(), &options, |mtl_path| {
        beside(path, dir, mtl_path)
            .map_err(|e| e.to_string())
            .and_then(|mtl_path| read_mtl(&mtl_path).map(|mtl| (mtl, mtl_path)))
            .and_then(|(mtl, mtl_path)| {
                tobj::load_mtl_buf(&mut mtl.as_bytes())
                    .map_err(|e| format!("{}: {e}", mtl_path.display()))
            })
            .map_err(|problem| {
                mtl_problems.borrow_mut().push(problem);
                tobj::LoadError::GenericFailure
            })
    })
    .map_err(|e| MeshError::parse(path, "OBJ", e))?;
    for problem in mtl_problems.into_inner() {
        tracing::warn!(
            "{}: material library unusable ({problem}); using default materials",
            path.display()
        );
    }
    // tobj yields the materials it could load, or an error only when none loaded (warned above).
    let mut materials: Vec<Material> = materials
        .unwrap_or_default()
        .iter()
        .map(|m| convert_material(m, path, dir))
        .collect();
    // Objects without a (known) material use a default appended after the file's own.
    let default_material = materials.len();
    materials.push(Material::default());

    let builders = objects.into_iter().map(|object| {
        let mesh = object.mesh;
        MeshBuilder {
            name: object.name,
            positions: mesh
                .positions
                .chunks_exact(3)
                .map(Vec3::from_slice)
                .collect(),
            normals: mesh.normals.chunks_exact(3).map(Vec3::from_slice).collect(),
            // OBJ puts v = 0 at the bottom of the image; Mesh uses glTF's top-left origin.
            uvs: mesh
                .texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                .collect(),
            triangles: mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            material: mesh.material_id.unwrap_or(default_material),
            to_world: Mat4::IDENTITY,
        }
    });
    let (meshes, dropped) = finish_all(path, builders)?;
    Ok((Model { meshes, materials }, dropped))
}

/// Reads an MTL file for tobj; the error says why it cannot be used. Colours with one value are
/// expanded to grey as the MTL spec says (tobj would panic on them); other short colours are an
/// error.
fn read_mtl(path: &Path) -> Result<String, String> {
    let text = read_text_file(path).map_err(|e| e.to_string())?;
    let text = String::from_utf8(text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut normalised = String::with_capacity(text.len());
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match (words.next(), words.clone().count()) {
            (Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")), 1) => {
                let value = words.next().unwrap_or_default();
                normalised.push_str(&format!("{key} {value} {value} {value}"));
            }
            (Some("Ka" | "Kd" | "Ks" | "Ke"), 0 | 2) => {
                return Err(format!(
                    "{} line {}: a colour needs 1 or 3 values: `{line}`",
                    path.display(),
                    number + 1
                ));
            }
            _ => normalised.push_str(line),
        }
        normalised.push('\n');
    }
    Ok(normalised)
}

fn convert_material(m: &tobj::Material, path: &Path, dir: &Path) -> Material {
    let defaults = Material::default();
    let transmission = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => 1.0 - d,
        (None, Some(tr)) => tr.trim().parse().unwrap_or(0.0),
        (None, None) => 0.0,
    };
    Material {
        name: m.name.clone(),
        base_color: m.diffuse.map_or(defaults.base_color, Vec3::from),
        base_color_texture: m.diffuse_texture.as_ref().and_then(|file| {
            beside(path, dir, Path::new(file))
                .and_then(|texture_path| {
                    read_file(&texture_path).and_then(|bytes| decode_texture(&texture_path, &bytes))
                })
                .inspect_err(|e| tracing::warn!("{e}; material `{}` left untextured", m.name))
                .ok()
        }),
        base_color_sampler: defaults.base_color_sampler,
        specular: m.specular.map_or(defaults.specular, Vec3::from),
        shininess: m.shininess.unwrap_or(defaults.shininess),
        // Embree's convention (used by the bundled Cornell box): Ka is the emission when there
        // is no Ke.
        emission: m
            .emissive
            .or(m.ambient)
            .map_or(defaults.emission, Vec3::from),
        transmission: transmission.clamp(0.0, 1.0),
        ior: m.optical_density.unwrap_or(defaults.ior),
    }
}
