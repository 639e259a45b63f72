//! glTF 2.0 (.gltf with external or embedded buffers, .glb) through the `gltf` crate.
//!
//! Buffers and accessors are read here rather than with `gltf`'s reader, which trusts the file's
//! byte ranges and strides (and panics on some bad ones): every range is checked before use.

use super::{
    Material, MeshBuilder, MeshError, Model, TextureFilter, TextureSampler, TextureWrap, beside,
    decode_texture, finish_all, read_file, reject_utf16,
};
use base64::Engine;
use glam::{Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::path::Path;

const FORMAT: &str = "glTF";

pub(super) fn load(path: &Path) -> Result<(Model, usize), MeshError> {
    let bytes = read_file(path)?;
    reject_utf16(path, &bytes)?;
    let (document, mut blob) = parse(path, &bytes)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let buffers = document
        .buffers()
        .map(|buffer| {
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                    MeshError::parse(path, FORMAT, "buffer refers to a missing GLB BIN chunk")
                })?,
                gltf::buffer::Source::Uri(uri) => read_uri(path, dir, uri)?,
            };
            if data.len() < buffer.length() {
                return Err(MeshError::parse(
                    path,
                    FORMAT,
                    format!(
                        "buffer {} holds {} bytes, {} declared",
                        buffer.index(),
                        data.len(),
                        buffer.length()
                    ),
                ));
            }
            Ok(data)
        })
        .collect::<Result<Vec<_>, _>>()?;

    let file = File {
        path,
        dir,
        document: &document,
        buffers: &buffers,
    };
    let mut materials: Vec<Material> = document.materials().map(|m| file.material(m)).collect();
    // Primitives without a material use glTF's default material, appended after the file's own.
    let default_material = materials.len();
    materials.push(Material::default());

    let mut builders = Vec::new();
    walk_nodes(path, &document, |node, world| {
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                if let Some(mut builder) = file.primitive(&mesh, &primitive, default_material)? {
                    builder.to_world = world;
                    builders.push(builder);
                }
            }
        }
        Ok(())
    })?;
    let (meshes, dropped) = finish_all(path, builders)?;
    Ok((Model { meshes, materials }, dropped))
}

/// Reads and validates a .gltf or .glb file's JSON (the scene reader's cameras and lights).
pub(crate) fn document(path: &Path) -> Result<gltf::Document, MeshError> {
    let bytes = read_file(path)?;
    reject_utf16(path, &bytes)?;
    Ok(parse(path, &bytes)?.0)
}

/// Calls `visit` with every node of the shown scene and its node-to-world matrix, parents before
/// children, in document order. A file without a default scene shows its first one; one without
/// scenes shows nothing. A node reached twice (a cycle or a shared child) is an error.
pub(crate) fn walk_nodes(
    path: &Path,
    document: &gltf::Document,
    mut visit: impl FnMut(&gltf::Node, Mat4) -> Result<(), MeshError>,
) -> Result<(), MeshError> {
    let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return Ok(());
    };
    let mut visited = vec![false; document.nodes().len()];
    // Depth-first with an explicit stack, so a deep or cyclic graph cannot overflow the call
    // stack; pushed in reverse so nodes come out in document order.
    let mut stack: Vec<(gltf::Node, Mat4)> =
        scene.nodes().map(|node| (node, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(MeshError::NodeCycle {
                path: path.to_owned(),
                node: node.index(),
            });
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        visit(&node, world)?;
        let first_child = stack.len();
        stack.extend(node.children().map(|child| (child, world)));
        stack[first_child..].reverse();
    }
    Ok(())
}

/// Splits a GLB into JSON and BIN chunks (a .gltf is all JSON), then parses and validates the
/// JSON, more leniently than `gltf::Gltf::from_slice` in two spec-conformant ways.
fn parse(path: &Path, bytes: &[u8]) -> Result<(gltf::Document, Option<Vec<u8>>), MeshError> {
    let error = |e: &dyn std::fmt::Display| MeshError::parse(path, FORMAT, e);
    let (json, blob) = if bytes.starts_with(b"glTF") {
        // `Glb::from_slice` subtracts the header size from the declared length unchecked.
        let declared = bytes
            .get(8..12)
            .map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]));
        if declared.is_none_or(|length| length < 12) {
            return Err(error(
                &"GLB header is truncated or declares a length under 12 bytes",
            ));
        }
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(|e| error(&e))?;
        (glb.json, glb.bin.map(|bin| bin.into_owned()))
    } else {
        (bytes.into(), None)
    };
    // glTF 2.0 makes `scene.nodes` optional, gltf-json 1.4 requires it: add empty lists where it
    // is missing. Parsing from the original bytes otherwise keeps line numbers in errors.
    let value: serde_json::Value = serde_json::from_slice(&json).map_err(|e| error(&e))?;
    let scene_without_nodes = |scene: &serde_json::Value| scene.get("nodes").is_none();
    let root: gltf::json::Root = match value.get("scenes").and_then(|s| s.as_array()) {
        Some(scenes) if scenes.iter().any(scene_without_nodes) => {
            let mut value = value;
            for scene in value["scenes"].as_array_mut().into_iter().flatten() {
                if let Some(scene) = scene.as_object_mut() {
                    scene
                        .entry("nodes")
                        .or_insert_with(|| serde_json::json!([]));
                }
            }
            serde_json::from_value(value).map_err(|e| error(&e))?
        }
        _ => serde_json::from_slice(&json).map_err(|e| error(&e))?,
    };
    // gltf-json 1.4.1 validates POSITION's min/max by indexing `accessors` with the attribute's
    // index before checking it (a panic on a bad index): check every attribute's index first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(bad) = primitive
                .attributes
                .values()
                .find(|a| a.value() >= root.accessors.len())
            {
                return Err(error(&format!(
                    "meshes[{m}].primitives[{p}].attributes: accessor {} out of range ({} \
                     accessors)",
                    bad.value(),
                    root.accessors.len()
                )));
            }
        }
    }
    // POSITION's min/max are required by the spec but unused here (bounds are computed from the
    // data), and many exporters leave them out: their absence is not an error.
    let mut problems = Vec::new();
    gltf::json::validation::Validate::validate(
        &root,
        &root,
        gltf::json::Path::new,
        &mut |where_, problem| {
            let where_ = where_().to_string();
            let optional_bound =
                where_.ends_with("[\"POSITION\"].min") || where_.ends_with("[\"POSITION\"].max");
            if !(optional_bound && matches!(problem, gltf::json::validation::Error::Missing)) {
                problems.push(format!("{where_}: {problem}"));
            }
        },
    );
    if !problems.is_empty() {
        return Err(error(&problems.join("; ")));
    }
    Ok((gltf::Document::from_json_without_validation(root), blob))
}

/// Reads a `data:` URI or a file relative to the glTF file.
fn read_uri(path: &Path, dir: &Path, uri: &str) -> Result<Vec<u8>, MeshError> {
    if let Some(data) = uri.strip_prefix("data:") {
        let (_, encoded) = data
            .split_once(";base64,")
            .ok_or_else(|| MeshError::parse(path, FORMAT, "data URI without ;base64, payload"))?;
        return base64::engine::general_purpose::STANDARD
            .decode(encoded)
            .map_err(|e| MeshError::parse(path, FORMAT, format!("data URI: {e}")));
    }
    if uri.contains(':') {
        return Err(MeshError::parse(
            path,
            FORMAT,
            format!("unsupported URI scheme in `{uri}`"),
        ));
    }
    let relative = percent_encoding::percent_decode_str(uri)
        .decode_utf8()
        .map_err(|e| MeshError::parse(path, FORMAT, format!("URI `{uri}`: {e}")))?;
    let referenced = beside(path, dir, Path::new(&*relative))?;
    // Named in the error as "<gltf file>: cannot read: <referenced file>: <reason>".
    read_file(&referenced).map_err(|e| match e {
        MeshError::Io {
            path: referenced,
            source,
        } => MeshError::Io {
            path: path.to_owned(),
            source: std::io::Error::new(
                source.kind(),
                format!("referenced file {}: {source}", referenced.display()),
            ),
        },
        other => other,
    })
}

/// A parsed glTF file with its buffers loaded.
struct File<'a> {
    path: &'a Path,
    dir: &'a Path,
    document: &'a gltf::Document,
    buffers: &'a [Vec<u8>],
}

/// glTF's sampler as quadray reads it (no mipmaps: one filter, [`TextureSampler`]).
fn sampler(s: &gltf::texture::Sampler) -> TextureSampler {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let nearest = match (s.mag_filter(), s.min_filter()) {
        (Some(mag), _) => mag == MagFilter::Nearest,
        (None, Some(min)) => matches!(
            min,
            MinFilter::Nearest | MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear
        ),
        (None, None) => false,
    };
    let wrap = |mode| match mode {
        WrappingMode::Repeat => TextureWrap::Repeat,
        WrappingMode::ClampToEdge => TextureWrap::ClampToEdge,
        WrappingMode::MirroredRepeat => TextureWrap::MirroredRepeat,
    };
    TextureSampler {
        filter: if nearest {
            TextureFilter::Nearest
        } else {
            TextureFilter::Linear
        },
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
    }
}

impl File<'_> {
    fn error(&self, reason: impl ToString) -> MeshError {
        MeshError::parse(self.path, FORMAT, reason)
    }

    /// Maps metallic-roughness onto the Phong-style [`Material`]: specular reflectance is the
    /// Fresnel F0 (0.04 for dielectrics, the base colour for metals) and the exponent is the
    /// Blinn-Phong equivalent of the GGX roughness, 2/alpha^2 - 2 with alpha = roughness^2.
    fn material(&self, m: gltf::Material) -> Material {
        let pbr = m.pbr_metallic_roughness();
        let base_color = Vec3::from_slice(&pbr.base_color_factor()[..3]);
        let alpha = pbr.roughness_factor().clamp(0.01, 1.0).powi(2);
        let emission = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
        let name = m
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("material{}", m.index().unwrap_or_default()));
        let base_color_texture = pbr.base_color_texture().and_then(|info| {
            let image = info.texture().source().index();
            self.image(image)
                .inspect_err(|e| tracing::warn!("{e}; material `{name}` left untextured"))
                .ok()
        });
        let base_color_sampler = pbr
            .base_color_texture()
            .map_or_else(TextureSampler::default, |info| {
                sampler(&info.texture().sampler())
            });
        Material {
            base_color_texture,
            base_color_sampler,
            base_color,
            specular: Vec3::splat(0.04).lerp(base_color, pbr.metallic_factor()),
            shininess: 2.0 / (alpha * alpha) - 2.0,
            emission,
            transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
            ior: m.ior().unwrap_or(1.5),
            name,
        }
    }

    /// Decodes image `index` (read from the JSON: `gltf::Image::source` panics on some invalid
    /// combinations of fields).
    fn image(&self, index: usize) -> Result<crate::image_out::Rgba8Image, MeshError> {
        let json = self
            .document
            .as_json()
            .images
            .get(index)
            .ok_or_else(|| self.error(format!("image {index} does not exist")))?;
        let bytes = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                let view = self
                    .document
                    .views()
                    .nth(view.value())
                    .ok_or_else(|| self.error(format!("image {index}: no such buffer view")))?;
                self.view_bytes(&view)?.to_vec()
            }
            (None, Some(uri)) => read_uri(self.path, self.dir, uri)?,
            (None, None) => return Err(self.error(format!("image {index} has no data"))),
        };
        decode_texture(self.path, &bytes)
    }

    fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&[u8], MeshError> {
        let buffer = self
            .buffers
            .get(view.buffer().index())
            .ok_or_else(|| self.error(format!("buffer view {}: no buffer", view.index())))?;
        view.offset()
            .checked_add(view.length())
            .and_then(|end| buffer.get(view.offset()..end))
            .ok_or_else(|| {
                self.error(format!(
                    "buffer view {} runs past the end of its buffer",
                    view.index()
                ))
            })
    }

    /// The bytes of each element of `accessor`, after checking every range.
    fn elements(
        &self,
        accessor: &gltf::Accessor,
    ) -> Result<impl Iterator<Item = &[u8]>, MeshError> {
        let which = format!("accessor {}", accessor.index());
        if accessor.sparse().is_some() {
            return Err(self.error(format!("{which}: sparse accessors are not supported")));
        }
        let view = accessor
            .view()
            .ok_or_else(|| self.error(format!("{which} has no buffer view")))?;
        let bytes = self.view_bytes(&view)?;
        let size = accessor.size();
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(self.error(format!("{which}: stride {stride} < element size {size}")));
        }
        let count = accessor.count();
        let end = match count.checked_sub(1) {
            None => accessor.offset(),
            Some(last) => last
                .checked_mul(stride)
                .and_then(|o| o.checked_add(accessor.offset()))
                .and_then(|o| o.checked_add(size))
                .ok_or_else(|| self.error(format!("{which}: size overflows")))?,
        };
        if end > bytes.len() {
            return Err(self.error(format!(
                "{which}: {count} elements need {end} bytes, its buffer view has {}",
                bytes.len()
            )));
        }
        let start = accessor.offset();
        Ok((0..count).map(move |i| &bytes[start + i * stride..][..size]))
    }

    /// The elements of `accessor`, each decoded from its bytes and the accessor's component type,
    /// after checking that they are `dimensions` of one of `data_types`.
    fn read<T>(
        &self,
        accessor: &gltf::Accessor,
        what: &str,
        dimensions: Dimensions,
        data_types: &[DataType],
        decode: impl Fn(DataType, &[u8]) -> T,
    ) -> Result<Vec<T>, MeshError> {
        let data_type = accessor.data_type();
        if accessor.dimensions() != dimensions || !data_types.contains(&data_type) {
            return Err(self.error(format!(
                "{what} accessor {} is {:?} {data_type:?}, expected {dimensions:?} of {data_types:?}",
                accessor.index(),
                accessor.dimensions(),
            )));
        }
        Ok(self
            .elements(accessor)?
            .map(|e| decode(data_type, e))
            .collect())
    }

    fn read_vec3(&self, accessor: &gltf::Accessor, what: &str) -> Result<Vec<Vec3>, MeshError> {
        self.read(
            accessor,
            what,
            Dimensions::Vec3,
            &[DataType::F32],
            |_, e| Vec3::new(f32_at(e, 0), f32_at(e, 4), f32_at(e, 8)),
        )
    }

    /// Texture coordinates: floats, or normalized unsigned bytes or shorts.
    fn read_uvs(&self, accessor: &gltf::Accessor) -> Result<Vec<Vec2>, MeshError> {
        use DataType::{F32, U8, U16};
        let types = [F32, U8, U16];
        self.read(accessor, "TEXCOORD_0", Dimensions::Vec2, &types, |t, e| {
            if t == F32 {
                return Vec2::new(f32_at(e, 0), f32_at(e, 4));
            }
            let max = if t == U8 { 255.0 } else { 65535.0 };
            Vec2::new(uint_at(t, e, 0) as f32, uint_at(t, e, 1) as f32) / max
        })
    }

    fn read_indices(&self, accessor: &gltf::Accessor) -> Result<Vec<u32>, MeshError> {
        use DataType::{U8, U16, U32};
        let types = [U8, U16, U32];
        self.read(accessor, "index", Dimensions::Scalar, &types, |t, e| {
            uint_at(t, e, 0)
        })
    }

    /// The primitive's vertices in its mesh's space, or `None` for points and lines.
    fn primitive(
        &self,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        default_material: usize,
    ) -> Result<Option<MeshBuilder>, MeshError> {
        let mode = primitive.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            tracing::warn!(
                "{}: mesh {} skips a {mode:?} primitive",
                self.path.display(),
                mesh.index()
            );
            return Ok(None);
        }
        let position_accessor = primitive
            .get(&gltf::Semantic::Positions)
            .ok_or_else(|| self.error(format!("mesh {} has no POSITION", mesh.index())))?;
        let positions = self.read_vec3(&position_accessor, "POSITION")?;
        let normals = match primitive.get(&gltf::Semantic::Normals) {
            Some(accessor) => self.read_vec3(&accessor, "NORMAL")?,
            None => Vec::new(),
        };
        let uvs = match primitive.get(&gltf::Semantic::TexCoords(0)) {
            Some(accessor) => self.read_uvs(&accessor)?,
            None => Vec::new(),
        };
        let indices = match primitive.indices() {
            Some(accessor) => self.read_indices(&accessor)?,
            None => (0..positions.len() as u32).collect(),
        };
        let triangles = match mode {
            Mode::TriangleStrip => indices
                .windows(3)
                .enumerate()
                .map(|(i, w)| {
                    if i % 2 == 0 {
                        [w[0], w[1], w[2]]
                    } else {
                        [w[1], w[0], w[2]]
                    }
                })
                .collect(),
            Mode::TriangleFan => indices
                .windows(2)
                .skip(1)
                .map(|w| [indices[0], w[0], w[1]])
                .collect(),
            _ if indices.len() % 3 != 0 => {
                return Err(self.error(format!(
                    "mesh {} has {} triangle-list indices, not a multiple of 3",
                    mesh.index(),
                    indices.len()
                )));
            }
            _ => indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        };
        let name = match mesh.name() {
            Some(name) => format!("{name}/{}", primitive.index()),
            None => format!("mesh{}/{}", mesh.index(), primitive.index()),
        };
        Ok(Some(MeshBuilder {
            name,
            positions,
            normals,
            uvs,
            triangles,
            material: primitive.material().index().unwrap_or(default_material),
            to_world: Mat4::IDENTITY,
        }))
    }
}

fn f32_at(bytes: &[u8], offset: usize) -> f32 {
    f32::from_le_bytes([
        bytes[offset],
        bytes[offset + 1],
        bytes[offset + 2],
        bytes[offset + 3],
    ])
}

/// Component `i` of an element of unsigned bytes, shorts or ints (`data_type`).
fn uint_at(data_type: DataType, bytes: &[u8], i: usize) -> u32 {
    match data_type {
        DataType::U8 => u32::from(bytes[i]),
        DataType::U16 => u32::from(u16::from_le_bytes([bytes[2 * i], bytes[2 * i + 1]])),
        _ => u32::from_le_bytes([
            bytes[4 * i],
            bytes[4 * i + 1],
            bytes[4 * i + 2],
            bytes[4 * i + 3],
        ]),
    }
}
