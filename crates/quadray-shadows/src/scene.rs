//! Polygon scenes: materials, point lights, a pinhole camera, faces sharing vertices (the mesh
//! adjacency the silhouette rule needs), the paper's four scenes rebuilt procedurally with its
//! polygon and light counts (in `scene/lookalikes.rs`), and scenes read from files (TOML or glTF,
//! through `quadray_core::scene`).

mod file;
mod lookalikes;

use glam::Vec3;
use lookalikes::{desk, glasses, kaist, stars};
use quadray_core::geom::ConvexPolygon;
use std::path::Path;
use thiserror::Error;

/// A scene file that cannot be used, with the file and the reason.
#[derive(Debug, Error)]
#[error("{path}: {reason}")]
pub struct SceneError {
    /// The file.
    pub path: String,
    /// What is wrong with it.
    pub reason: String,
}

fn scene_error(path: &Path, reason: impl ToString) -> SceneError {
    SceneError {
        path: path.display().to_string(),
        reason: reason.to_string(),
    }
}

/// A point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Where the light is.
    pub position: Vec3,
    /// Its colour and strength (linear RGB).
    pub intensity: Vec3,
}

impl Light {
    /// A white point light of the given intensity.
    pub fn white(position: Vec3, intensity: f32) -> Self {
        Self {
            position,
            intensity: Vec3::splat(intensity),
        }
    }
}

pub use quadray_core::scene::{Camera, Material};

/// A convex planar face: indices into the scene's vertices (shared between faces of one mesh).
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// Indices into [`Scene::vertices`], in order around the face.
    pub vertices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

#[derive(Clone, Debug)]
/// Polygons with materials, point lights and a camera: build one with [`Scene::new`] and the `add_` methods, [`Scene::builtin`] or [`Scene::load`].
pub struct Scene {
    /// The name in reports.
    pub name: String,
    /// Vertex positions, shared by the faces of a mesh.
    pub vertices: Vec<Vec3>,
    /// Convex planar faces.
    pub faces: Vec<Face>,
    /// Materials, by the faces' indices.
    pub materials: Vec<Material>,
    /// Point lights (at most [`MAX_LIGHTS`]).
    pub lights: Vec<Light>,
    /// The camera.
    pub camera: Camera,
    /// Ambient light, times each surface's diffuse colour.
    pub ambient: Vec3,
    /// The colour of rays that hit nothing.
    pub background: Vec3,
}

/// The repository's `assets/` folder (scene files and meshes).
pub fn assets_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

/// The builtin look-alikes of the paper's scenes, with their polygon and light counts.
pub const BUILTINS: [(&str, usize, usize); 4] = [
    ("glasses", 3781, 3),
    ("desk", 523, 3),
    ("stars", 113, 5),
    ("kaist", 981, 4),
];

/// Most lights a scene may have (the tracer's per-ray shadow state is a fixed array).
pub const MAX_LIGHTS: usize = 8;

/// What is wrong with a scene built in code ([`Scene::add_face`], [`Scene::add_mesh`],
/// [`Scene::validate`]).
#[derive(Clone, Debug, Error, PartialEq)]
pub enum BuildError {
    /// A face refers to a vertex the scene does not have.
    #[error("face {face}: vertex index {index} out of range ({vertices} vertices)")]
    VertexOutOfRange {
        /// The face's index (the one it would have had).
        face: usize,
        /// The offending vertex index.
        index: u32,
        /// How many vertices the scene has.
        vertices: usize,
    },
    /// A face refers to a material the scene does not have.
    #[error("face {face}: material {material} out of range ({materials} materials)")]
    MaterialOutOfRange {
        /// The face's index.
        face: usize,
        /// The offending material index.
        material: u32,
        /// How many materials the scene has.
        materials: usize,
    },
    /// A vertex with a NaN or infinite coordinate.
    #[error("face {face}: vertex {index} is not finite ({position})")]
    NonFiniteVertex {
        /// The face's index.
        face: usize,
        /// The vertex index.
        index: u32,
        /// Where the vertex is.
        position: Vec3,
    },
    /// Fewer than three distinct vertices, or all on one line: the face has no area.
    #[error("face {face}: degenerate (no area: fewer than 3 distinct or collinear vertices)")]
    DegenerateFace {
        /// The face's index.
        face: usize,
    },
    /// A triangle list whose length is not a multiple of three.
    #[error("mesh: {0} indices is not a whole number of triangles")]
    PartialTriangle(usize),
    /// Something else about the scene: the camera, the lights, a material.
    #[error("{0}")]
    Invalid(String),
}

impl Scene {
    /// An empty scene seen through `camera`, with the default ambient light and background. Add
    /// materials, lights, vertices and faces with the `add_` methods.
    pub fn new(name: &str, camera: Camera) -> Self {
        Self {
            name: name.into(),
            vertices: Vec::new(),
            faces: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            camera,
            ambient: Vec3::splat(0.08),
            background: Vec3::new(0.05, 0.06, 0.09),
        }
    }

    /// The faces as polygons ready for ray tests, in face order.
    pub fn polygons(&self) -> Vec<ConvexPolygon> {
        self.faces
            .iter()
            .map(|f| {
                ConvexPolygon::new(
                    f.vertices
                        .iter()
                        .map(|&i| self.vertices[i as usize])
                        .collect(),
                )
            })
            .collect()
    }

    /// A look-alike of one of the paper's scenes ([`BUILTINS`]), None for another name.
    pub fn builtin(name: &str) -> Option<Scene> {
        match name {
            "glasses" => Some(glasses()),
            "desk" => Some(desk()),
            "stars" => Some(stars()),
            "kaist" => Some(kaist()),
            _ => None,
        }
    }

    /// Adds a material; faces refer to it by the index returned.
    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        self.materials.len() as u32 - 1
    }

    /// Adds a point light (at most [`MAX_LIGHTS`]; [`Self::validate`] checks).
    pub fn add_light(&mut self, light: Light) {
        self.lights.push(light);
    }

    /// Adds a vertex; faces refer to it by the index returned. Faces of one closed mesh must
    /// share their vertices: the shadow volumes find silhouette edges through shared indices.
    pub fn add_vertex(&mut self, p: Vec3) -> u32 {
        self.vertices.push(p);
        self.vertices.len() as u32 - 1
    }

    /// Adds a convex planar face through `vertices` (indices of [`Self::add_vertex`]), counter-
    /// clockwise seen from its front, and returns its index. An index or material out of range,
    /// a vertex that is not finite and a face without area are errors, and nothing is added.
    pub fn add_face(&mut self, vertices: Vec<u32>, material: u32) -> Result<u32, BuildError> {
        let face = self.faces.len();
        if material as usize >= self.materials.len() {
            return Err(BuildError::MaterialOutOfRange {
                face,
                material,
                materials: self.materials.len(),
            });
        }
        for &index in &vertices {
            let Some(&position) = self.vertices.get(index as usize) else {
                return Err(BuildError::VertexOutOfRange {
                    face,
                    index,
                    vertices: self.vertices.len(),
                });
            };
            if !position.is_finite() {
                return Err(BuildError::NonFiniteVertex {
                    face,
                    index,
                    position,
                });
            }
        }
        let corners = vertices
            .iter()
            .map(|&i| self.vertices[i as usize])
            .collect();
        if ConvexPolygon::new(corners).is_degenerate() {
            return Err(BuildError::DegenerateFace { face });
        }
        self.push_face(vertices, material);
        Ok(face as u32)
    }

    /// Adds an indexed triangle mesh: `positions` become vertices shared by its triangles
    /// (`indices`, three per triangle, counter-clockwise from the front, into `positions`).
    /// Checked as [`Self::add_face`]; on an error nothing is added.
    pub fn add_mesh(
        &mut self,
        positions: &[Vec3],
        indices: &[u32],
        material: u32,
    ) -> Result<(), BuildError> {
        if !indices.len().is_multiple_of(3) {
            return Err(BuildError::PartialTriangle(indices.len()));
        }
        let (vertices, faces) = (self.vertices.len(), self.faces.len());
        let base = vertices as u32;
        self.vertices.extend_from_slice(positions);
        let added = indices.chunks_exact(3).try_for_each(|tri| {
            let ids = tri
                .iter()
                .map(|&i| {
                    if (i as usize) < positions.len() {
                        Ok(base + i)
                    } else {
                        Err(BuildError::VertexOutOfRange {
                            face: self.faces.len(),
                            index: i,
                            vertices: positions.len(),
                        })
                    }
                })
                .collect::<Result<Vec<u32>, _>>()?;
            self.add_face(ids, material).map(|_| ())
        });
        if added.is_err() {
            self.vertices.truncate(vertices);
            self.faces.truncate(faces);
        }
        added
    }

    /// Adds a closed axis-aligned box from `min` to `max` (8 shared vertices, 6 faces), as a
    /// scene file's `box` object. `min` must lie below `max` on every axis.
    pub fn add_box(&mut self, min: Vec3, max: Vec3, material: u32) -> Result<(), BuildError> {
        if !(min.is_finite() && max.is_finite()) || min.cmpge(max).any() {
            return Err(BuildError::Invalid(format!(
                "box from {min} to {max}: min must be finite and below max"
            )));
        }
        if material as usize >= self.materials.len() {
            return Err(BuildError::MaterialOutOfRange {
                face: self.faces.len(),
                material,
                materials: self.materials.len(),
            });
        }
        self.cuboid(min, max, material);
        Ok(())
    }

    /// Says so where every light delivers less than half the ambient light at the scene's centre
    /// (a light's intensity is what it delivers there): the picture then shows mostly the
    /// ambient term, flat, whatever the exposure. A glTF light's intensity is in candela, so a desk
    /// lamp's few candela in a room-sized scene comes out so.
    pub fn lighting_advice(&self) -> Option<String> {
        let luminance = |c: Vec3| quadray_core::image_out::luminance(c.to_array());
        let ambient = luminance(self.ambient);
        let strongest = self
            .lights
            .iter()
            .map(|l| luminance(l.intensity))
            .fold(0.0, f32::max);
        (ambient > 0.0 && strongest < 0.5 * ambient).then(|| {
            format!(
                "the lights are weak against the ambient light ({strongest:.2e} at the scene's \
                 centre against {ambient:.2e}): the picture shows mostly the flat ambient term; \
                 brighten the lights (glTF intensities are candela) or lower `ambient`"
            )
        })
    }

    /// Checks what the tracer relies on: a valid camera ([`Camera::validate`], the one check both
    /// techniques use), 1 to [`MAX_LIGHTS`] finite lights, finite materials with an index
    /// of refraction above 0, at least one face.
    pub fn validate(&self) -> Result<(), BuildError> {
        let bad = |why: String| Err(BuildError::Invalid(why));
        self.camera.validate().map_err(BuildError::Invalid)?;
        if self.lights.is_empty() || self.lights.len() > MAX_LIGHTS {
            return bad(format!("{} lights; 1 to {MAX_LIGHTS}", self.lights.len()));
        }
        if let Some(l) = self
            .lights
            .iter()
            .find(|l| !(l.position.is_finite() && l.intensity.is_finite()))
        {
            return bad(format!("light at {} is not finite", l.position));
        }
        for (i, m) in self.materials.iter().enumerate() {
            let finite = [m.specular, m.shininess, m.reflect, m.transmit, m.ior]
                .iter()
                .all(|x| x.is_finite());
            if !finite || !m.diffuse.is_finite() || m.ior <= 0.0 {
                return bad(format!("material {i}: values must be finite and ior > 0"));
            }
        }
        if self.faces.is_empty() {
            return bad("no faces".into());
        }
        Ok(())
    }

    /// Adds a face unchecked: the builtin scenes and mesh files may hold faces without area
    /// (welded mesh triangles), which are never hit and cast no shadow. Repeated corners (a
    /// lathe's apex) are dropped.
    fn push_face(&mut self, mut vertices: Vec<u32>, material: u32) {
        vertices.dedup();
        if vertices.len() > 1 && vertices.first() == vertices.last() {
            vertices.pop();
        }
        self.faces.push(Face { vertices, material });
    }
}
