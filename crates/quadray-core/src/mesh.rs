//! Triangle meshes and their materials, loaded from OBJ (+MTL), glTF 2.0 (.gltf/.glb) and PLY.
//!
//! Every loader ends in the same checks (`MeshBuilder::finish`): coordinates within
//! [`MAX_COORDINATE`] (before and after a glTF node's transform), indices in range; faces with a
//! repeated vertex or zero area are dropped (and counted in a warning); a file with no triangle
//! left is an error. Normals missing from the file are generated, area-weighted.

pub(crate) mod gltf;
mod obj;
mod ply;

use crate::image_out::Rgba8Image;
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::fmt;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use thiserror::Error;

/// The largest |coordinate| a vertex may have, in its file's units, wherever a scene places it.
///
/// Every pipeline holds positions in f32, whose spacing reaches 1 at 2^23 (8.4e6): within 1e7 a
/// coordinate is still exact to a unit, so a model in metres as wide as a country (UTM coordinates
/// included) or in millimetres as wide as a town loads. Far beyond, the ray tracer's grid, the BVH
/// and the RSM's frustum, all sized to the bounds, lose the rest of the model (one vertex at 1e38
/// left a picture of background only), and near 1e19 squared lengths and cross products overflow.
/// The bound refuses what no f32 pipeline can use; it cannot make a model of mixed scales safe (a
/// small object beside a vertex near the limit may still vanish).
pub const MAX_COORDINATE: f32 = 1e7;

/// Set by [`allow_outside_paths`]: files a scene refers to may lie anywhere.
static OUTSIDE_PATHS_ALLOWED: AtomicBool = AtomicBool::new(false);

/// Lets every later load read the files a scene or mesh file refers to wherever they lie (a
/// program's `--allow-outside-paths`). By default a glTF file's buffers and images and an OBJ
/// file's material library and textures must lie in its own folder, and a TOML scene's meshes in
/// the folder above the scene's (its folder and those beside it, as `assets/scenes` and
/// `assets/meshes`); a path that leaves it (`..`, an absolute path, a link that points out) is
/// [`MeshError::Outside`]: a scene from someone else reads only what came with it, as Bevy's
/// asset server forbids paths outside its folder.
pub fn allow_outside_paths(allow: bool) {
    OUTSIDE_PATHS_ALLOWED.store(allow, Ordering::Relaxed);
}

/// A file a scene refers to, outside the folder it may read ([`allow_outside_paths`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutsidePath {
    /// As the scene writes it.
    pub referenced: PathBuf,
    pub folder: PathBuf,
}

impl fmt::Display for OutsidePath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "`{}`, outside the folder {}: files are read only inside the scene's folder \
             (--allow-outside-paths reads it)",
            self.referenced.display(),
            self.folder.display()
        )
    }
}

/// `referenced` (as a scene writes it) in `dir`, where it is inside `folder` (`dir` or a folder
/// above it), links followed, or anywhere once [`allow_outside_paths`].
pub(crate) fn inside_folder(
    folder: &Path,
    dir: &Path,
    referenced: &Path,
) -> Result<PathBuf, OutsidePath> {
    let joined = dir.join(referenced);
    if OUTSIDE_PATHS_ALLOWED.load(Ordering::Relaxed) {
        return Ok(joined);
    }
    let inside = !referenced.has_root()
        && match (joined.canonicalize(), folder.canonicalize()) {
            (Ok(real), Ok(folder)) => real.starts_with(folder),
            // a file that is not there: its written path decides, and the read fails as missing
            _ => match (std::path::absolute(&joined), std::path::absolute(folder)) {
                (Ok(path), Ok(folder)) => lexical(&path).starts_with(lexical(&folder)),
                _ => false,
            },
        };
    if inside {
        Ok(joined)
    } else {
        Err(OutsidePath {
            referenced: referenced.to_owned(),
            folder: folder.to_owned(),
        })
    }
}

/// [`inside_folder`] for a mesh file's own references (its folder is `folder`), the error naming
/// the mesh file.
fn beside(path: &Path, folder: &Path, referenced: &Path) -> Result<PathBuf, MeshError> {
    inside_folder(folder, folder, referenced).map_err(|outside| MeshError::Outside {
        path: path.to_owned(),
        outside,
    })
}

/// `path` with `.` left out and each `..` taking away the name before it.
fn lexical(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// A point of a scene on a command line (a camera's or a light's position), `X,Y,Z` as
/// [`crate::parse_vec3`] reads it, every coordinate within [`MAX_COORDINATE`].
pub fn parse_point(s: &str) -> Result<[f32; 3], String> {
    let point = crate::parse_vec3(s)?;
    match FarCoordinate::find([Vec3::from(point)]) {
        Some((_, far)) => Err(far.to_string()),
        None => Ok(point),
    }
}

/// A vertex coordinate beyond [`MAX_COORDINATE`], or not a number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FarCoordinate {
    /// `x`, `y` or `z`.
    pub axis: char,
    pub value: f32,
}

impl FarCoordinate {
    /// The first of `positions` with a coordinate outside the limit: its index and the coordinate.
    pub fn find(positions: impl IntoIterator<Item = Vec3>) -> Option<(usize, FarCoordinate)> {
        positions.into_iter().enumerate().find_map(|(i, p)| {
            let axis = (0..3).find(|&a| p[a].is_nan() || p[a].abs() > MAX_COORDINATE)?;
            let far = FarCoordinate {
                axis: ['x', 'y', 'z'][axis],
                value: p[axis],
            };
            Some((i, far))
        })
    }
}

impl fmt::Display for FarCoordinate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} = {:e} is outside the limit |coordinate| <= {MAX_COORDINATE:e}",
            self.axis, self.value
        )
    }
}

/// A surface description common to the three formats (Phong-style, plus emission and refraction).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear RGB diffuse albedo.
    pub base_color: Vec3,
    /// Diffuse texture as stored in the file (sRGB-encoded bytes), multiplied by `base_color`.
    pub base_color_texture: Option<Rgba8Image>,
    /// How `base_color_texture` is read between and beyond its texels.
    pub base_color_sampler: TextureSampler,
    /// Linear RGB specular reflectance.
    pub specular: Vec3,
    /// Phong exponent.
    pub shininess: f32,
    /// Linear RGB emitted radiance.
    pub emission: Vec3,
    /// 0 opaque .. 1 fully transparent.
    pub transmission: f32,
    /// Index of refraction.
    pub ior: f32,
}

impl Default for Material {
    /// White diffuse, no specular, no emission, opaque, ior 1.5.
    fn default() -> Self {
        Self {
            name: "default".to_owned(),
            base_color: Vec3::ONE,
            base_color_texture: None,
            base_color_sampler: TextureSampler::default(),
            specular: Vec3::ZERO,
            shininess: 0.0,
            emission: Vec3::ZERO,
            transmission: 0.0,
            ior: 1.5,
        }
    }
}

/// How a texture is read at a texture coordinate: glTF's sampler without mipmaps, so one filter
/// serves magnification and minification (glTF's magnification filter, or its minification
/// filter's where the file gives none). Without a sampler (and for OBJ): linear, repeating.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TextureSampler {
    pub filter: TextureFilter,
    /// Along u (glTF's s): the texture's columns.
    pub wrap_u: TextureWrap,
    /// Along v (glTF's t): the texture's rows.
    pub wrap_v: TextureWrap,
}

/// Which texels a sample reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TextureFilter {
    /// The four texels around the coordinate, weighted by distance (texel centres at
    /// half-integers).
    #[default]
    Linear,
    /// The texel the coordinate lies in.
    Nearest,
}

/// What a coordinate outside [0, 1] reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TextureWrap {
    /// The texture tiles.
    #[default]
    Repeat,
    /// The edge texels extend.
    ClampToEdge,
    /// The texture tiles, every other copy mirrored.
    MirroredRepeat,
}

/// An indexed triangle mesh with one material.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Unit normals, one per vertex (generated, area-weighted, when the file has none).
    pub normals: Vec<Vec3>,
    /// One per vertex when the file has texture coordinates; (0, 0) is the texture's top-left
    /// corner (glTF's convention; OBJ's v is flipped to match).
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Index into [`Model::materials`].
    pub material: usize,
}

/// Everything loaded from one file: meshes in world space and the materials they refer to (the
/// last material is the default given to faces without one; it may be unused).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Model {
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
}

/// Why a mesh file could not be loaded. Every message starts with the file's path.
#[derive(Debug, Error)]
pub enum MeshError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{}: unsupported mesh format (expected .obj, .gltf, .glb or .ply)",
        path.display()
    )]
    UnsupportedFormat { path: PathBuf },
    #[error(
        "{}: the file is UTF-16 encoded (or has NUL bytes); save it as UTF-8",
        path.display()
    )]
    Utf16 { path: PathBuf },
    #[error("{}: refers to {outside}", path.display())]
    Outside { path: PathBuf, outside: OutsidePath },
    #[error("{}: invalid {format} file: {reason}", path.display())]
    Parse {
        path: PathBuf,
        format: &'static str,
        reason: String,
    },
    #[error("{}: mesh `{mesh}` vertex {vertex}: {coordinate}", path.display())]
    FarVertex {
        path: PathBuf,
        mesh: String,
        vertex: usize,
        coordinate: FarCoordinate,
    },
    #[error(
        "{}: mesh `{mesh}` index {index} is out of range ({vertex_count} vertices)",
        path.display()
    )]
    IndexOutOfRange {
        path: PathBuf,
        mesh: String,
        index: i64,
        vertex_count: usize,
    },
    #[error(
        "{}: node {node} is reached twice in the scene graph (a cycle or a shared child)",
        path.display()
    )]
    NodeCycle { path: PathBuf, node: usize },
    #[error("{}: no triangles", path.display())]
    NoTriangles { path: PathBuf },
    #[error(transparent)]
    Texture(#[from] crate::image_in::ImageReadError),
}

impl MeshError {
    fn parse(path: &Path, format: &'static str, reason: impl ToString) -> Self {
        Self::Parse {
            path: path.to_owned(),
            format,
            reason: reason.to_string(),
        }
    }
}

impl Model {
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }

    /// Axis-aligned bounds (min, max) of all vertices; (+inf, -inf) for an empty model.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.meshes
            .iter()
            .flat_map(|m| &m.positions)
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            })
    }

    /// Checks that `m` (a scene's placement of the model) keeps every vertex within
    /// [`MAX_COORDINATE`]; `path` is the model's file, for the error.
    pub fn check_placed(&self, path: &Path, m: Mat4) -> Result<(), MeshError> {
        self.meshes.iter().try_for_each(|mesh| {
            let placed = mesh.positions.iter().map(|&p| m.transform_point3(p));
            check_coordinates(path, &mesh.name, placed)
        })
    }

    /// The model with `m` applied to positions and normals (winding kept front-facing when `m`
    /// mirrors).
    pub fn transformed(mut self, m: Mat4) -> Model {
        for mesh in &mut self.meshes {
            transform_vertices(&mut mesh.positions, &mut mesh.normals, &mut mesh.indices, m);
        }
        self
    }
}

/// Applies `m` to positions and (through its inverse transpose) normals; swaps the winding when
/// `m` mirrors so front faces stay front faces.
fn transform_vertices(
    positions: &mut [Vec3],
    normals: &mut [Vec3],
    triangles: &mut [[u32; 3]],
    m: Mat4,
) {
    let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
    for p in positions {
        *p = m.transform_point3(*p);
    }
    for n in normals {
        *n = (normal_matrix * *n).normalize_or_zero();
    }
    if m.determinant() < 0.0 {
        for tri in triangles {
            tri.swap(1, 2);
        }
    }
}

/// Decodes a PNG or JPEG texture (within [`crate::image_in::MAX_SIDE`]).
fn decode_texture(path: &Path, bytes: &[u8]) -> Result<Rgba8Image, MeshError> {
    let image = crate::image_in::from_memory(path, bytes)?.into_rgba8();
    let (width, height) = image.dimensions();
    Ok(Rgba8Image::from_bytes(width, height, image.as_raw()))
}

/// Loads an OBJ (with its MTL), glTF 2.0 (.gltf or .glb) or PLY file, chosen by extension.
pub fn load_model(path: &Path) -> Result<Model, MeshError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let load = match extension.as_deref() {
        Some("obj") => obj::load,
        Some("gltf" | "glb") => gltf::load,
        Some("ply") => ply::load,
        _ => {
            return Err(MeshError::UnsupportedFormat {
                path: path.to_owned(),
            });
        }
    };
    // A safety net under the third-party parsers, which can still panic on hostile input (e.g.
    // tobj 4.0.5 overflows `vt * 2 + 1` in debug builds on a far negative texcoord index).
    let (model, dropped) = std::panic::catch_unwind(|| load(path)).map_err(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        MeshError::parse(path, "mesh", format!("the parser panicked: {message}"))
    })??;
    if dropped > 0 {
        tracing::warn!(
            "{}: dropped {dropped} degenerate faces (repeated vertex or zero area)",
            path.display()
        );
    }
    if model.triangle_count() == 0 {
        return Err(MeshError::NoTriangles {
            path: path.to_owned(),
        });
    }
    Ok(model)
}

/// Reads a whole regular file (not a device or pipe, which could be endless).
fn read_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    let io_error = |source| MeshError::Io {
        path: path.to_owned(),
        source,
    };
    if !std::fs::metadata(path).map_err(io_error)?.is_file() {
        return Err(io_error(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        )));
    }
    std::fs::read(path).map_err(io_error)
}

/// No mesh format starts with a UTF-16 byte-order mark, so one means a UTF-16 text file.
fn reject_utf16(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
    if bytes.starts_with(&[0xFE, 0xFF]) || bytes.starts_with(&[0xFF, 0xFE]) {
        return Err(MeshError::Utf16 {
            path: path.to_owned(),
        });
    }
    Ok(())
}

/// Reads a text format as UTF-8 (dropping a UTF-8 byte-order mark). UTF-16 is refused up front,
/// with or without a byte-order mark: its NUL bytes are valid UTF-8, so a line parser would
/// silently misread the file as empty.
fn read_text_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    let mut bytes = read_file(path)?;
    reject_utf16(path, &bytes)?;
    if bytes.contains(&0) {
        return Err(MeshError::Utf16 {
            path: path.to_owned(),
        });
    }
    if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        bytes.drain(..3);
    }
    Ok(bytes)
}

/// The per-vertex data of one mesh as read from a file, before validation.
struct MeshBuilder {
    name: String,
    positions: Vec<Vec3>,
    /// Empty when the file has none.
    normals: Vec<Vec3>,
    /// Empty when the file has none.
    uvs: Vec<Vec2>,
    /// Raw indices, unchecked.
    triangles: Vec<[u32; 3]>,
    material: usize,
    /// Placement in the model (glTF node transforms), applied after the file's values are checked.
    to_world: Mat4,
}

impl MeshBuilder {
    /// Checks the data and makes the mesh; also returns how many degenerate faces were dropped.
    fn finish(mut self, path: &Path) -> Result<(Mesh, usize), MeshError> {
        let check = |b: &Self| check_coordinates(path, &b.name, b.positions.iter().copied());
        check(&self)?;
        if self.to_world != Mat4::IDENTITY {
            transform_vertices(
                &mut self.positions,
                &mut self.normals,
                &mut self.triangles,
                self.to_world,
            );
            // A vertex in range can leave it under a huge scale.
            check(&self)?;
        }
        let vertex_count = self.positions.len();
        if let Some(&index) = self
            .triangles
            .iter()
            .flatten()
            .find(|&&i| i as usize >= vertex_count)
        {
            return Err(MeshError::IndexOutOfRange {
                path: path.to_owned(),
                mesh: self.name,
                index: index.into(),
                vertex_count,
            });
        }
        let positions = self.positions;
        let face_count = self.triangles.len();
        let indices: Vec<[u32; 3]> = self
            .triangles
            .into_iter()
            .filter(|&[a, b, c]| {
                let [pa, pb, pc] = [a, b, c].map(|i| positions[i as usize]);
                a != b && b != c && a != c && (pb - pa).cross(pc - pa) != Vec3::ZERO
            })
            .collect();
        let dropped = face_count - indices.len();
        let normals = vertex_normals(&positions, &indices, self.normals);
        let uvs = (self.uvs.len() == vertex_count && !self.uvs.is_empty()).then_some(self.uvs);
        let mesh = Mesh {
            name: self.name,
            positions,
            normals,
            uvs,
            indices,
            material: self.material,
        };
        Ok((mesh, dropped))
    }
}

/// Every coordinate of `positions` within [`MAX_COORDINATE`], or the first vertex beyond.
fn check_coordinates(
    path: &Path,
    mesh: &str,
    positions: impl IntoIterator<Item = Vec3>,
) -> Result<(), MeshError> {
    match FarCoordinate::find(positions) {
        None => Ok(()),
        Some((vertex, coordinate)) => Err(MeshError::FarVertex {
            path: path.to_owned(),
            mesh: mesh.to_owned(),
            vertex,
            coordinate,
        }),
    }
}

/// The file's normals, normalised; generated area-weighted normals where the file has none or a
/// vertex's normal is zero or not finite.
fn vertex_normals(positions: &[Vec3], indices: &[[u32; 3]], from_file: Vec<Vec3>) -> Vec<Vec3> {
    let mut normals: Vec<Vec3> = if from_file.len() == positions.len() {
        from_file.into_iter().map(Vec3::normalize_or_zero).collect()
    } else {
        vec![Vec3::ZERO; positions.len()]
    };
    if normals.iter().all(|n| *n != Vec3::ZERO) {
        return normals;
    }
    let mut generated = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in indices {
        let [pa, pb, pc] = [a, b, c].map(|i| positions[i as usize]);
        // The cross product's length is twice the triangle's area: the weighting we want.
        let face_normal = (pb - pa).cross(pc - pa);
        for i in [a, b, c] {
            generated[i as usize] += face_normal;
        }
    }
    for (n, g) in normals.iter_mut().zip(generated) {
        if *n == Vec3::ZERO {
            *n = g.normalize_or_zero();
        }
    }
    normals
}

/// Sums the dropped-face counts while collecting finished meshes.
fn finish_all(
    path: &Path,
    builders: impl IntoIterator<Item = MeshBuilder>,
) -> Result<(Vec<Mesh>, usize), MeshError> {
    let mut meshes = Vec::new();
    let mut dropped = 0;
    for builder in builders {
        let (mesh, n) = builder.finish(path)?;
        dropped += n;
        if !mesh.indices.is_empty() {
            meshes.push(mesh);
        }
    }
    Ok((meshes, dropped))
}
