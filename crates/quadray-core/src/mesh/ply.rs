//! Stanford PLY (ascii and binary) through `ply-rs-bw`.

use super::{Material, MeshBuilder, MeshError, Model, finish_all, read_file, reject_utf16};
use glam::{Mat4, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};
use std::path::Path;

const FORMAT: &str = "PLY";

#[derive(Default)]
struct PlyVertex {
    position: Vec3,
    normal: Vec3,
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.position.x,
            "y" => &mut self.position.y,
            "z" => &mut self.position.z,
            "nx" => &mut self.normal.x,
            "ny" => &mut self.normal.y,
            "nz" => &mut self.normal.z,
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = match property {
            Property::Float(v) => v,
            Property::Double(v) => v as f32,
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

#[derive(Default)]
struct PlyFace {
    /// Widened so that negative and too-large indices reach the range check intact.
    vertices: Vec<i64>,
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        self.vertices = match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

/// Elements other than vertex and face (edges, materials, ...) are read past and dropped.
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Skipped
    }
}

pub(super) fn load(path: &Path) -> Result<(Model, usize), MeshError> {
    let bytes = read_file(path)?;
    reject_utf16(path, &bytes)?;
    let parse_error = |e: ply_rs_bw::parser::ParseError| MeshError::parse(path, FORMAT, e);
    let mut reader = Reader::new(bytes.as_slice());
    let header = Parser::<Skipped>::new()
        .read_header(&mut reader)
        .map_err(parse_error)?;
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    let mut has_normals = false;
    // Payload elements come in header order, so each is read (or skipped) in turn.
    for element in header.elements.values() {
        match element.name.as_str() {
            "vertex" => {
                has_normals = element.properties.contains_key("nx");
                vertices = Parser::<PlyVertex>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(parse_error)?;
            }
            "face" => {
                faces = Parser::<PlyFace>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(parse_error)?;
            }
            _ => {
                Parser::<Skipped>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(parse_error)?;
            }
        }
    }

    let mesh_name = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let mut triangles = Vec::with_capacity(faces.len());
    let mut short_faces = 0;
    for face in &faces {
        let index = |i: i64| {
            u32::try_from(i).map_err(|_| MeshError::IndexOutOfRange {
                path: path.to_owned(),
                mesh: mesh_name.clone(),
                index: i,
                vertex_count: vertices.len(),
            })
        };
        match face.vertices.as_slice() {
            [first, rest @ ..] if rest.len() >= 2 => {
                let first = index(*first)?;
                for pair in rest.windows(2) {
                    triangles.push([first, index(pair[0])?, index(pair[1])?]);
                }
            }
            _ => short_faces += 1,
        }
    }
    let builder = MeshBuilder {
        name: mesh_name,
        positions: vertices.iter().map(|v| v.position).collect(),
        normals: if has_normals {
            vertices.iter().map(|v| v.normal).collect()
        } else {
            Vec::new()
        },
        uvs: Vec::new(),
        triangles,
        material: 0,
        to_world: Mat4::IDENTITY,
    };
    let (meshes, dropped) = finish_all(path, [builder])?;
    let materials = vec![Material::default()];
    Ok((Model { meshes, materials }, dropped + short_faces))
}
