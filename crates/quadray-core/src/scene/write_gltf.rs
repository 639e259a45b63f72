//! The glTF writer ([`SceneDescription::to_gltf`]): one `.gltf`, its buffer a base64 `data:` URI,
//! made of `gltf::json`'s types. One file rather than a `.gltf` beside a `.bin`: a scene that
//! is copied, attached or loaded by Bevy's asset server cannot lose half of itself, and the
//! scenes it is made for (boxes and polygons) are a few kilobytes, where base64's third more
//! costs nothing worth a second file.

use super::{Camera, Intensity, LUMENS_PER_WATT, Light, LightKind, SceneDescription, Shape};
use crate::image_out::Rgba8Image;
use crate::mesh::{TextureFilter, TextureSampler, TextureWrap};
use base64::Engine;
use glam::{Mat3, Quat, Vec2, Vec3};
use gltf::json;
use gltf::json::validation::Checked::Valid;
use gltf::json::validation::USize64;
use std::collections::BTreeMap;

/// Where a primitive's material comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum MaterialSource {
    /// The scene's material of this index.
    Named(usize),
    /// Material `material` of object `object`'s mesh file.
    File { object: usize, material: usize },
    /// A shape without a material: white (glTF's own default is a metal).
    White,
}

/// One primitive: vertices in world coordinates and their triangles.
struct Part {
    material: MaterialSource,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
}

impl Part {
    fn new(material: MaterialSource) -> Self {
        Self {
            material,
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: None,
            triangles: Vec::new(),
        }
    }

    /// Adds `triangle` (indices from `first`) unless it has no area, as the reader drops it.
    fn push_triangle(&mut self, first: u32, triangle: [u32; 3]) {
        let [a, b, c] = triangle.map(|i| self.positions[(first + i) as usize]);
        if (b - a).cross(c - a) != Vec3::ZERO {
            self.triangles.push(triangle.map(|i| first + i));
        }
    }
}

/// The object's parts, the object's transform applied as every technique applies it.
fn object_parts(scene: &SceneDescription, index: usize) -> Result<Vec<Part>, String> {
    let object = &scene.objects[index];
    if let Some(m) = object.material.filter(|&m| m >= scene.materials.len()) {
        return Err(format!("object {index}: material {m} does not exist"));
    }
    let named = object.material.map(MaterialSource::Named);
    let to_world = object.transform.matrix();
    let turn = object.transform.rotation();
    let mut parts = Vec::new();
    match &object.shape {
        Shape::Builtin(name) => {
            return Err(format!(
                "object {index}: builtin `{name}` is a technique's mesh, not held by the scene: \
                 replace it by its mesh first"
            ));
        }
        Shape::Box { min, max } => {
            let mut part = Part::new(named.unwrap_or(MaterialSource::White));
            for [a, b, c, d] in Shape::box_faces(*min, *max) {
                let normal = turn.transform_vector3((b - a).cross(d - a).normalize());
                let first = part.positions.len() as u32;
                part.positions
                    .extend([a, b, c, d].map(|p| to_world.transform_point3(p)));
                part.normals.extend([normal; 4]);
                part.push_triangle(first, [0, 1, 2]);
                part.push_triangle(first, [0, 2, 3]);
            }
            parts.push(part);
        }
        Shape::Polygons(polygons) => {
            let mut part = Part::new(named.unwrap_or(MaterialSource::White));
            for polygon in polygons {
                let normal = Shape::polygon_normal(polygon);
                if normal == Vec3::ZERO {
                    continue;
                }
                let first = part.positions.len() as u32;
                let normal = turn.transform_vector3(normal);
                part.positions
                    .extend(polygon.iter().map(|&p| to_world.transform_point3(p)));
                part.normals
                    .extend(std::iter::repeat_n(normal, polygon.len()));
                for i in 1..polygon.len() as u32 - 1 {
                    part.push_triangle(first, [0, i, i + 1]);
                }
            }
            parts.push(part);
        }
        Shape::Mesh { model, path } => {
            for mesh in &model.meshes {
                let material = model.materials.get(mesh.material).ok_or_else(|| {
                    format!(
                        "object {index} ({}): mesh `{}` has no material {}",
                        path.display(),
                        mesh.name,
                        mesh.material
                    )
                })?;
                let mut part = Part::new(named.unwrap_or(MaterialSource::File {
                    object: index,
                    material: mesh.material,
                }));
                part.positions = mesh
                    .positions
                    .iter()
                    .map(|&p| to_world.transform_point3(p))
                    .collect();
                part.normals = mesh
                    .normals
                    .iter()
                    .map(|&n| turn.transform_vector3(n))
                    .collect();
                // a named material replaces the file's, its texture with it
                if named.is_none() && material.base_color_texture.is_some() {
                    part.uvs.clone_from(&mesh.uvs);
                }
                for &triangle in &mesh.indices {
                    part.push_triangle(0, triangle);
                }
                parts.push(part);
            }
        }
    }
    parts.retain(|p| !p.triangles.is_empty());
    Ok(parts)
}

/// glTF's document being written and its buffer's contents.
struct Writer<'a> {
    scene: &'a SceneDescription,
    root: json::Root,
    /// Positions, normals and texture coordinates (buffer view 0).
    vertices: Vec<u8>,
    /// Triangle indices (buffer view 1).
    indices: Vec<u8>,
    /// Each texture as PNG (buffer views 2, 3, ...).
    images: Vec<Vec<u8>>,
    materials: BTreeMap<MaterialSource, json::Index<json::Material>>,
}

const VERTEX_VIEW: u32 = 0;
const INDEX_VIEW: u32 = 1;

pub(super) fn write(scene: &SceneDescription) -> Result<String, String> {
    let mut w = Writer {
        scene,
        root: json::Root::default(),
        vertices: Vec::new(),
        indices: Vec::new(),
        images: Vec::new(),
        materials: BTreeMap::new(),
    };
    w.root.asset.generator = Some(format!(
        "quadray {} (quadray scene export)",
        env!("CARGO_PKG_VERSION")
    ));
    let mut nodes = Vec::new();
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for index in 0..scene.objects.len() {
        let parts = object_parts(scene, index)?;
        if parts.is_empty() {
            continue;
        }
        for p in parts.iter().flat_map(|p| &p.positions) {
            (lo, hi) = (lo.min(*p), hi.max(*p));
        }
        let mut primitives = Vec::new();
        for part in &parts {
            primitives.push(w.primitive(part)?);
        }
        let name = match &scene.objects[index].shape {
            Shape::Mesh { path, .. } => path
                .file_stem()
                .map_or_else(|| format!("object {index}"), |s| s.to_string_lossy().into()),
            Shape::Box { .. } => format!("box {index}"),
            _ => format!("polygons {index}"),
        };
        let mesh = w.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(name.clone()),
            primitives,
            weights: None,
        });
        nodes.push(w.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(name),
            ..Default::default()
        }));
    }
    if w.indices.is_empty() {
        return Err("no triangles to write (glTF scenes are read as one mesh)".into());
    }
    nodes.push(w.camera(&scene.camera, (hi - lo).length().max(1e-3))?);
    for (i, light) in scene.lights.iter().enumerate() {
        nodes.push(w.light(i, light)?);
    }
    let extras = if scene.techniques.is_empty() {
        None
    } else {
        Some(serde_json::value::to_raw_value(&scene.techniques).map_err(|e| e.to_string())?)
    };
    let shown = w.root.push(json::Scene {
        extensions: None,
        extras,
        name: Some(scene.name.clone()),
        nodes,
    });
    w.root.scene = Some(shown);
    w.finish_buffer();
    let mut text = serde_json::to_string_pretty(&w.root).map_err(|e| e.to_string())?;
    text.push('\n');
    Ok(text)
}

impl Writer<'_> {
    /// An accessor over `bytes` appended to the vertex data (floats) or the indices.
    fn accessor(
        &mut self,
        view: u32,
        bytes: &[u8],
        count: usize,
        component: json::accessor::ComponentType,
        type_: json::accessor::Type,
        bounds: Option<(Vec3, Vec3)>,
    ) -> json::Index<json::Accessor> {
        let data = if view == VERTEX_VIEW {
            &mut self.vertices
        } else {
            &mut self.indices
        };
        let offset = data.len();
        data.extend_from_slice(bytes);
        // every accessor starts on 4 bytes, whatever its component
        data.resize(data.len().next_multiple_of(4), 0);
        let value = |v: Vec3| serde_json::json!(v.to_array());
        self.root.push(json::Accessor {
            buffer_view: Some(json::Index::new(view)),
            byte_offset: Some(USize64::from(offset)),
            count: USize64::from(count),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(type_),
            min: bounds.map(|(lo, _)| value(lo)),
            max: bounds.map(|(_, hi)| value(hi)),
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn primitive(&mut self, part: &Part) -> Result<json::mesh::Primitive, String> {
        use json::accessor::{ComponentType, Type};
        let floats = |v: &mut dyn Iterator<Item = f32>| -> Vec<u8> {
            v.flat_map(f32::to_le_bytes).collect()
        };
        let bounds = part
            .positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let count = part.positions.len();
        let positions = floats(&mut part.positions.iter().flat_map(|p| p.to_array()));
        let normals = floats(&mut part.normals.iter().flat_map(|n| n.to_array()));
        let mut attributes = BTreeMap::new();
        let position = self.accessor(
            VERTEX_VIEW,
            &positions,
            count,
            ComponentType::F32,
            Type::Vec3,
            Some(bounds),
        );
        attributes.insert(Valid(json::mesh::Semantic::Positions), position);
        let normal = self.accessor(
            VERTEX_VIEW,
            &normals,
            count,
            ComponentType::F32,
            Type::Vec3,
            None,
        );
        attributes.insert(Valid(json::mesh::Semantic::Normals), normal);
        if let Some(uvs) = &part.uvs {
            let uvs = floats(&mut uvs.iter().flat_map(|t| t.to_array()));
            let uv = self.accessor(
                VERTEX_VIEW,
                &uvs,
                count,
                ComponentType::F32,
                Type::Vec2,
                None,
            );
            attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), uv);
        }
        // 16-bit indices where they reach (65535 itself is the primitive restart value)
        let flat = part.triangles.iter().flatten();
        let (bytes, component): (Vec<u8>, _) = if count < usize::from(u16::MAX) {
            let bytes = flat.flat_map(|&i| (i as u16).to_le_bytes()).collect();
            (bytes, ComponentType::U16)
        } else {
            (
                flat.flat_map(|&i| i.to_le_bytes()).collect(),
                ComponentType::U32,
            )
        };
        let count = part.triangles.len() * 3;
        let indices = self.accessor(INDEX_VIEW, &bytes, count, component, Type::Scalar, None);
        Ok(json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: Some(self.material(part.material)?),
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        })
    }

    /// The glTF material of `source`, made the first time it is asked for.
    fn material(&mut self, source: MaterialSource) -> Result<json::Index<json::Material>, String> {
        if let Some(&index) = self.materials.get(&source) {
            return Ok(index);
        }
        let (name, base, emission, texture) = match source {
            MaterialSource::Named(m) => {
                let (name, material) = &self.scene.materials[m];
                (name.clone(), material.diffuse, Vec3::ZERO, None)
            }
            MaterialSource::White => ("white".to_string(), Vec3::ONE, Vec3::ZERO, None),
            MaterialSource::File { object, material } => {
                let Shape::Mesh { model, .. } = &self.scene.objects[object].shape else {
                    unreachable!("file materials come from mesh objects");
                };
                let m = &model.materials[material];
                let texture = match &m.base_color_texture {
                    Some(image) => Some(self.texture(image, m.base_color_sampler, &m.name)?),
                    None => None,
                };
                (m.name.clone(), m.base_color, m.emission, texture)
            }
        };
        let base = base.clamp(Vec3::ZERO, Vec3::ONE);
        // a factor within [0, 1] and, above 1, the strength it is multiplied by
        let brightest = emission.max_element();
        let mut extensions = None;
        let emissive = if brightest > 1.0 {
            extensions = Some(json::extensions::material::Material {
                emissive_strength: Some(json::extensions::material::EmissiveStrength {
                    emissive_strength: json::extensions::material::EmissiveStrengthFactor(
                        brightest,
                    ),
                }),
                ..Default::default()
            });
            self.uses("KHR_materials_emissive_strength");
            emission / brightest
        } else {
            emission.max(Vec3::ZERO)
        };
        let index = self.root.push(json::Material {
            name: Some(name),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(base.extend(1.0).into()),
                base_color_texture: texture.map(|index| json::texture::Info {
                    index,
                    tex_coord: 0,
                    extensions: None,
                    extras: None,
                }),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(1.0),
                ..Default::default()
            },
            emissive_factor: json::material::EmissiveFactor(emissive.into()),
            extensions,
            ..Default::default()
        });
        self.materials.insert(source, index);
        Ok(index)
    }

    /// A texture of `image` (sRGB bytes, as read), stored as PNG in the buffer, read through
    /// `sampler` (a sampler written only where it is not glTF's default).
    fn texture(
        &mut self,
        image: &Rgba8Image,
        sampler: TextureSampler,
        material: &str,
    ) -> Result<json::Index<json::Texture>, String> {
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut png),
            image.pixels.as_flattened(),
            image.width,
            image.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| format!("material `{material}`: its texture: {e}"))?;
        let view = INDEX_VIEW + 1 + self.images.len() as u32;
        self.images.push(png);
        let source = self.root.push(json::Image {
            buffer_view: Some(json::Index::new(view)),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(material.to_string()),
            uri: None,
            extensions: None,
            extras: None,
        });
        let sampler = (sampler != TextureSampler::default()).then(|| {
            use json::texture::{MagFilter, MinFilter, WrappingMode};
            let (mag, min) = match sampler.filter {
                TextureFilter::Linear => (MagFilter::Linear, MinFilter::Linear),
                TextureFilter::Nearest => (MagFilter::Nearest, MinFilter::Nearest),
            };
            let wrap = |w| {
                Valid(match w {
                    TextureWrap::Repeat => WrappingMode::Repeat,
                    TextureWrap::ClampToEdge => WrappingMode::ClampToEdge,
                    TextureWrap::MirroredRepeat => WrappingMode::MirroredRepeat,
                })
            };
            self.root.push(json::texture::Sampler {
                mag_filter: Some(Valid(mag)),
                min_filter: Some(Valid(min)),
                wrap_s: wrap(sampler.wrap_u),
                wrap_t: wrap(sampler.wrap_v),
                name: None,
                extensions: None,
                extras: None,
            })
        });
        Ok(self.root.push(json::Texture {
            name: None,
            sampler,
            source,
            extensions: None,
            extras: None,
        }))
    }

    /// The camera's node: at its position, looking down its -z at the target, its +y up (made
    /// square to the view).
    fn camera(&mut self, camera: &Camera, extent: f32) -> Result<json::Index<json::Node>, String> {
        camera.validate()?;
        let forward = (camera.target - camera.position).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        let rotation = Quat::from_mat3(&Mat3::from_cols(right, up, -forward)).normalize();
        let index = self.root.push(json::Camera {
            name: Some("camera".into()),
            orthographic: None,
            perspective: Some(json::camera::Perspective {
                // none: the picture's own, as the reader takes it
                aspect_ratio: None,
                yfov: camera.fov_y_deg.to_radians(),
                zfar: None,
                // as near as quadray's own cameras see
                znear: extent * 1e-3,
                extensions: None,
                extras: None,
            }),
            type_: Valid(json::camera::Type::Perspective),
            extensions: None,
            extras: None,
        });
        Ok(self.root.push(json::Node {
            camera: Some(index),
            name: Some("camera".into()),
            rotation: Some(json::scene::UnitQuaternion(rotation.to_array())),
            translation: Some(camera.position.to_array()),
            ..Default::default()
        }))
    }

    /// Light `i`'s node and its `KHR_lights_punctual` light.
    fn light(&mut self, i: usize, light: &Light) -> Result<json::Index<json::Node>, String> {
        use json::extensions::scene::khr_lights_punctual as punctual;
        light.validate().map_err(|e| format!("light {i}: {e}"))?;
        // photometric, as the reader reads it back
        let photometric = match light.intensity {
            Intensity::Native(radiometric) => radiometric * LUMENS_PER_WATT,
            Intensity::Photometric(v) => v,
        };
        let brightest = photometric.max_element();
        let (color, intensity) = if brightest > 0.0 {
            (photometric / brightest, brightest)
        } else {
            (Vec3::ONE, 0.0)
        };
        // spots and the sun shine down their node's -z
        let aim = |d: Vec3| Quat::from_rotation_arc(Vec3::NEG_Z, d.normalize()).normalize();
        let (type_, spot, position, rotation) = match light.kind {
            LightKind::Point { position } => (punctual::Type::Point, None, Some(position), None),
            LightKind::Spot { position, cone } => {
                let outer = cone.cone_deg.to_radians().min(std::f32::consts::FRAC_PI_2);
                let inner = (cone.cone_deg - cone.falloff_deg).to_radians().max(0.0);
                // glTF wants inner < outer; a sharp edge is one float step wide
                let inner = if inner < outer {
                    inner
                } else {
                    f32::from_bits(outer.to_bits() - 1)
                };
                let spot = punctual::Spot {
                    inner_cone_angle: inner,
                    outer_cone_angle: outer,
                };
                let turn = aim(cone.direction);
                (punctual::Type::Spot, Some(spot), Some(position), Some(turn))
            }
            LightKind::Directional { direction } => (
                punctual::Type::Directional,
                None,
                None,
                Some(aim(direction)),
            ),
        };
        let name = format!("{} light {i}", light.kind_name());
        let index = self.root.push(punctual::Light {
            color: color.into(),
            extensions: None,
            extras: None,
            intensity,
            name: Some(name.clone()),
            range: None,
            spot,
            type_: Valid(type_),
        });
        self.uses("KHR_lights_punctual");
        Ok(self.root.push(json::Node {
            extensions: Some(json::extensions::scene::Node {
                khr_lights_punctual: Some(punctual::KhrLightsPunctual { light: index }),
                ..Default::default()
            }),
            name: Some(name),
            rotation: rotation.map(|q| json::scene::UnitQuaternion(q.to_array())),
            translation: position.map(|p| p.to_array()),
            ..Default::default()
        }))
    }

    fn uses(&mut self, extension: &str) {
        if !self.root.extensions_used.iter().any(|e| e == extension) {
            self.root.extensions_used.push(extension.to_string());
        }
    }

    /// The buffer: the vertex data, the indices, then each image, each 4-byte aligned, as one
    /// `data:` URI, and a view of each.
    fn finish_buffer(&mut self) {
        let mut bytes = Vec::new();
        let buffer = json::Index::new(0);
        let views = [
            (
                std::mem::take(&mut self.vertices),
                Some(json::buffer::Target::ArrayBuffer),
            ),
            (
                std::mem::take(&mut self.indices),
                Some(json::buffer::Target::ElementArrayBuffer),
            ),
        ]
        .into_iter()
        .chain(
            std::mem::take(&mut self.images)
                .into_iter()
                .map(|png| (png, None)),
        );
        for (data, target) in views {
            let offset = bytes.len();
            bytes.extend_from_slice(&data);
            bytes.resize(bytes.len().next_multiple_of(4), 0);
            self.root.push(json::buffer::View {
                buffer,
                byte_length: USize64::from(data.len()),
                byte_offset: Some(USize64::from(offset)),
                byte_stride: None,
                name: None,
                target: target.map(Valid),
                extensions: None,
                extras: None,
            });
        }
        let encoded = base64::engine::general_purpose::STANDARD.encode(&bytes);
        self.root.push(json::Buffer {
            byte_length: USize64::from(bytes.len()),
            name: None,
            uri: Some(format!("data:application/octet-stream;base64,{encoded}")),
            extensions: None,
            extras: None,
        });
    }
}
