//! Polygon scenes: materials, point lights, a pinhole camera, faces sharing vertices (the mesh
//! adjacency the silhouette rule needs), the paper's four scenes rebuilt procedurally with its
//! polygon and light counts, and the TOML scene file.

use crate::geom::ConvexPolygon;
use glam::{Affine3A, Vec2, Vec3};
use serde::Deserialize;
use std::collections::HashMap;
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

/// Whitted's surface: local diffuse + Blinn-Phong specular, mirror reflection and refraction.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Diffuse colour (linear RGB).
    pub diffuse: Vec3,
    #[serde(default)]
    /// Weight of the Blinn-Phong highlight.
    pub specular: f32,
    #[serde(default = "default_shininess")]
    /// Blinn-Phong exponent.
    pub shininess: f32,
    #[serde(default)]
    /// Weight of the mirror reflection.
    pub reflect: f32,
    #[serde(default)]
    /// Weight of the refracted ray (transparent when above 0).
    pub transmit: f32,
    #[serde(default = "default_ior")]
    /// Index of refraction.
    pub ior: f32,
}

fn default_shininess() -> f32 {
    32.0
}
fn default_ior() -> f32 {
    1.0
}

impl Material {
    /// A dull surface of colour `diffuse`.
    pub fn matte(diffuse: Vec3) -> Self {
        Self {
            diffuse,
            specular: 0.1,
            shininess: 16.0,
            reflect: 0.0,
            transmit: 0.0,
            ior: 1.0,
        }
    }

    /// A shiny surface that mirrors `reflect` of the light.
    pub fn glossy(diffuse: Vec3, reflect: f32) -> Self {
        Self {
            specular: 0.6,
            shininess: 64.0,
            reflect,
            ..Self::matte(diffuse)
        }
    }

    /// Clear glass (index 1.5).
    pub fn glass() -> Self {
        Self {
            diffuse: Vec3::splat(0.05),
            specular: 0.8,
            shininess: 128.0,
            reflect: 0.1,
            transmit: 0.85,
            ior: 1.5,
        }
    }
}

/// A point light.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
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

/// A pinhole camera.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Where the camera is.
    pub eye: Vec3,
    /// The point seen in the image's centre.
    pub look_at: Vec3,
    #[serde(default = "default_up")]
    /// Up in the image (need not be perpendicular to the view).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
}

fn default_up() -> Vec3 {
    Vec3::Y
}

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

    /// Checks what the tracer relies on: a finite camera looking somewhere with a field of view
    /// in (0, 180) degrees, 1 to [`MAX_LIGHTS`] finite lights, finite materials with an index
    /// of refraction above 0, at least one face.
    pub fn validate(&self) -> Result<(), BuildError> {
        let bad = |why: String| Err(BuildError::Invalid(why));
        let c = &self.camera;
        if !(c.eye.is_finite() && c.look_at.is_finite() && c.up.is_finite())
            || c.look_at == c.eye
            || c.up.cross(c.look_at - c.eye) == Vec3::ZERO
        {
            return bad("camera: eye, look_at and up must be finite, eye and look_at distinct, up not along the view".into());
        }
        if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
            return bad(format!(
                "camera: fov_y_deg {} is not in (0, 180)",
                c.fov_y_deg
            ));
        }
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

    /// A surface of revolution about the local y axis: `profile` is (radius, height), a zero
    /// radius is a single vertex on the axis (its faces become triangles).
    fn lathe(&mut self, profile: &[(f32, f32)], slices: u32, place: Affine3A, material: u32) {
        let rings: Vec<Vec<u32>> = profile
            .iter()
            .map(|&(r, y)| {
                if r == 0.0 {
                    vec![
                        self.add_vertex(place.transform_point3(Vec3::new(0.0, y, 0.0)));
                        slices as usize
                    ]
                } else {
                    (0..slices)
                        .map(|j| {
                            let a = j as f32 / slices as f32 * std::f32::consts::TAU;
                            self.add_vertex(place.transform_point3(Vec3::new(
                                r * a.cos(),
                                y,
                                -r * a.sin(),
                            )))
                        })
                        .collect()
                }
            })
            .collect();
        for w in rings.windows(2) {
            for j in 0..slices as usize {
                let k = (j + 1) % slices as usize;
                self.push_face(vec![w[0][j], w[0][k], w[1][k], w[1][j]], material);
            }
        }
    }

    /// A prism: 2-D `points` in the local xy plane extruded along z by `depth`. `pieces` are convex
    /// (counter-clockwise) index lists covering the outline, `outline` its boundary loop.
    fn extrude(
        &mut self,
        points: &[Vec2],
        pieces: &[Vec<u32>],
        outline: &[u32],
        depth: f32,
        place: Affine3A,
        material: u32,
    ) {
        let base = self.vertices.len() as u32;
        for z in [0.0, depth] {
            for p in points {
                self.add_vertex(place.transform_point3(p.extend(z)));
            }
        }
        let back = |i: u32| base + points.len() as u32 + i;
        for piece in pieces {
            self.push_face(piece.iter().rev().map(|&i| base + i).collect(), material);
            self.push_face(piece.iter().map(|&i| back(i)).collect(), material);
        }
        for (e, &i) in outline.iter().enumerate() {
            let j = outline[(e + 1) % outline.len()];
            self.push_face(vec![base + i, base + j, back(j), back(i)], material);
        }
    }

    /// A straight bar from `a` to `b` of the given width, extruded (6 faces).
    fn bar(&mut self, a: Vec2, b: Vec2, width: f32, depth: f32, place: Affine3A, material: u32) {
        let n = (b - a).perp().normalize() * (width * 0.5);
        let pts = [a - n, b - n, b + n, a + n];
        self.extrude(
            &pts,
            &[vec![0, 1, 2, 3]],
            &[0, 1, 2, 3],
            depth,
            place,
            material,
        );
    }

    fn cuboid(&mut self, min: Vec3, max: Vec3, material: u32) {
        let e = max - min;
        let pts = [
            Vec2::ZERO,
            Vec2::new(e.x, 0.0),
            Vec2::new(e.x, e.y),
            Vec2::new(0.0, e.y),
        ];
        self.extrude(
            &pts,
            &[vec![0, 1, 2, 3]],
            &[0, 1, 2, 3],
            e.z,
            Affine3A::from_translation(min),
            material,
        );
    }

    /// `count` polygons of floor at height `y` over `[x0, x1] x [z0, z1]`: a checkerboard grid of
    /// tiles sharing vertices, and the few left over as strips of a back wall at `z0`.
    #[allow(clippy::too_many_arguments)]
    fn floor(
        &mut self,
        count: usize,
        x0: f32,
        x1: f32,
        z0: f32,
        z1: f32,
        y: f32,
        wall_height: f32,
        tiles: [u32; 2],
    ) {
        let cols = (count as f32).sqrt().floor().max(1.0) as usize;
        let rows = count / cols;
        let rest = count - rows * cols;
        let lerp = |a: f32, b: f32, t: usize, n: usize| a + (b - a) * t as f32 / n as f32;
        let base = self.vertices.len() as u32;
        for r in 0..=rows {
            for c in 0..=cols {
                self.add_vertex(Vec3::new(lerp(x0, x1, c, cols), y, lerp(z0, z1, r, rows)));
            }
        }
        let at = |r: usize, c: usize| base + (r * (cols + 1) + c) as u32;
        for r in 0..rows {
            for c in 0..cols {
                self.push_face(
                    vec![at(r, c), at(r + 1, c), at(r + 1, c + 1), at(r, c + 1)],
                    tiles[(r + c) % 2],
                );
            }
        }
        if rest > 0 {
            let wall: Vec<(u32, u32)> = (0..=rest)
                .map(|c| {
                    let x = lerp(x0, x1, c, rest);
                    (
                        self.add_vertex(Vec3::new(x, y, z0)),
                        self.add_vertex(Vec3::new(x, y + wall_height, z0)),
                    )
                })
                .collect();
            for c in 0..rest {
                self.push_face(
                    vec![wall[c].0, wall[c + 1].0, wall[c + 1].1, wall[c].1],
                    tiles[c % 2],
                );
            }
        }
    }
}

fn camera(eye: Vec3, look_at: Vec3, fov_y_deg: f32) -> Camera {
    Camera {
        eye,
        look_at,
        up: Vec3::Y,
        fov_y_deg,
    }
}

fn at(x: f32, y: f32, z: f32) -> Affine3A {
    Affine3A::from_translation(Vec3::new(x, y, z))
}

/// Four lathed wine glasses (closed, thick, transparent) on a checkered floor: 3,781 polygons,
/// 3 lights.
fn glasses() -> Scene {
    let mut s = Scene::new(
        "glasses",
        camera(Vec3::new(0.0, 3.0, 6.5), Vec3::new(0.0, 1.0, 0.0), 45.0),
    );
    let glass = s.add_material(Material::glass());
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.8, 0.75, 0.6))),
        s.add_material(Material::glossy(Vec3::new(0.25, 0.2, 0.3), 0.2)),
    ];
    // A closed profile from the foot's centre, out and up the outside, over the rim and down the
    // inside of the bowl back to the axis: 21 points, 20 segments.
    let profile = [
        (0.0, 0.0),
        (0.9, 0.0),
        (0.9, 0.06),
        (0.3, 0.1),
        (0.1, 0.2),
        (0.07, 0.5),
        (0.07, 0.9),
        (0.12, 1.1),
        (0.35, 1.22),
        (0.55, 1.4),
        (0.66, 1.7),
        (0.66, 2.0),
        (0.6, 2.3),
        (0.56, 2.3),
        (0.62, 2.0),
        (0.62, 1.7),
        (0.52, 1.43),
        (0.33, 1.27),
        (0.15, 1.18),
        (0.05, 1.15),
        (0.0, 1.14),
    ];
    // A hair above the floor: a refracted ray must meet every surface it passes through, which
    // a face lying on another (coplanar, touching) would hide.
    for (x, z) in [(-1.6, 0.3), (0.0, -0.6), (1.5, 0.5), (0.3, 1.6)] {
        s.lathe(&profile, 36, at(x, 0.002, z), glass);
    }
    s.floor(901, -4.0, 4.0, -4.0, 4.0, 0.0, 2.0, tiles);
    s.add_light(Light::white(Vec3::new(-3.0, 6.0, 3.0), 0.6));
    s.add_light(Light::white(Vec3::new(4.0, 5.0, 2.0), 0.5));
    s.add_light(Light::white(Vec3::new(0.5, 7.0, -3.0), 0.4));
    s
}

/// A desk with books, a lamp (with a light under its shade, inside the grid), a glass vase and a mirror
/// ball: 523 polygons, 3 lights.
fn desk() -> Scene {
    let mut s = Scene::new(
        "desk",
        camera(Vec3::new(0.5, 3.2, 5.0), Vec3::new(0.0, 1.4, 0.0), 45.0),
    );
    let wood = s.add_material(Material::glossy(Vec3::new(0.55, 0.35, 0.2), 0.1));
    let books = [
        s.add_material(Material::matte(Vec3::new(0.7, 0.15, 0.1))),
        s.add_material(Material::matte(Vec3::new(0.1, 0.3, 0.6))),
        s.add_material(Material::matte(Vec3::new(0.2, 0.5, 0.2))),
    ];
    let metal = s.add_material(Material::glossy(Vec3::new(0.6, 0.6, 0.55), 0.3));
    let mirror = s.add_material(Material::glossy(Vec3::splat(0.2), 0.7));
    let glass = s.add_material(Material::glass());
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.6, 0.6, 0.6))),
        s.add_material(Material::matte(Vec3::new(0.35, 0.35, 0.4))),
    ];
    s.cuboid(Vec3::new(-2.0, 1.5, -1.0), Vec3::new(2.0, 1.6, 1.0), wood);
    for (x, z) in [(-1.9, -0.9), (1.8, -0.9), (-1.9, 0.8), (1.8, 0.8)] {
        s.cuboid(Vec3::new(x, 0.0, z), Vec3::new(x + 0.1, 1.5, z + 0.1), wood);
    }
    for (i, &m) in books.iter().enumerate() {
        let x = 0.6 + i as f32 * 0.25;
        s.cuboid(
            Vec3::new(x, 1.6, -0.6),
            Vec3::new(x + 0.2, 2.2 - 0.1 * i as f32, 0.1),
            m,
        );
    }
    // Lamp: base, arm and an open shade around the bulb (9 segments x 16 slices).
    let lamp = [
        (0.0, 0.0),
        (0.3, 0.0),
        (0.3, 0.05),
        (0.05, 0.1),
        (0.05, 0.7),
        (0.08, 0.75),
        (0.12, 0.8),
        (0.35, 0.75),
        (0.45, 0.55),
        (0.42, 0.55),
    ];
    s.lathe(&lamp, 16, at(-1.5, 1.6, -0.3), metal);
    // Vase (10 segments x 16 slices), closed and transparent.
    let vase = [
        (0.0, 0.0),
        (0.25, 0.0),
        (0.3, 0.2),
        (0.22, 0.5),
        (0.12, 0.65),
        (0.15, 0.8),
        (0.12, 0.8),
        (0.09, 0.65),
        (0.18, 0.5),
        (0.24, 0.2),
        (0.0, 0.04),
    ];
    s.lathe(&vase, 16, at(-0.5, 1.602, 0.4), glass); // a hair above the desk, as the glasses
    // Mirror ball (8 segments x 16 slices).
    let ball: Vec<(f32, f32)> = (0..=8)
        .map(|i| {
            let a = i as f32 / 8.0 * std::f32::consts::PI;
            (
                if i == 0 || i == 8 { 0.0 } else { 0.3 * a.sin() },
                0.3 - 0.3 * a.cos(),
            )
        })
        .collect();
    s.lathe(&ball, 16, at(0.2, 1.6, 0.3), mirror);
    s.floor(523 - s.faces.len(), -4.0, 4.0, -3.0, 3.0, 0.0, 3.0, tiles);
    s.add_light(Light::white(Vec3::new(-1.28, 2.2, -0.3), 0.5));
    s.add_light(Light::white(Vec3::new(3.0, 5.0, 2.5), 0.5));
    s.add_light(Light::white(Vec3::new(-3.0, 4.5, 2.0), 0.4));
    s
}

/// Five extruded five-pointed stars, tilted and floating over a floor: 113 polygons, 5 lights.
fn stars() -> Scene {
    let mut s = Scene::new(
        "stars",
        camera(Vec3::new(0.0, 2.5, 7.0), Vec3::new(0.0, 1.5, 0.0), 50.0),
    );
    let colours = [
        Vec3::new(0.9, 0.7, 0.1),
        Vec3::new(0.8, 0.2, 0.2),
        Vec3::new(0.2, 0.6, 0.9),
        Vec3::new(0.3, 0.8, 0.3),
        Vec3::new(0.8, 0.4, 0.8),
    ];
    let mats: Vec<u32> = colours
        .iter()
        .map(|&c| s.add_material(Material::glossy(c, 0.3)))
        .collect();
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.7, 0.7, 0.7))),
        s.add_material(Material::matte(Vec3::new(0.4, 0.4, 0.45))),
    ];
    // Outline alternates outer points and inner corners; a pentagon and five triangles cover it.
    let points: Vec<Vec2> = (0..10)
        .map(|i| {
            let a = std::f32::consts::FRAC_PI_2 + i as f32 * std::f32::consts::PI / 5.0;
            Vec2::from_angle(a) * if i % 2 == 0 { 1.0 } else { 0.4 }
        })
        .collect();
    let mut pieces: Vec<Vec<u32>> = (0..5)
        .map(|i| vec![(2 * i + 9) % 10, 2 * i, 2 * i + 1])
        .collect();
    pieces.push(vec![1, 3, 5, 7, 9]);
    let outline: Vec<u32> = (0..10).collect();
    let places = [
        (Vec3::new(-2.6, 1.4, 0.0), 0.3),
        (Vec3::new(-0.9, 2.6, -1.0), -0.2),
        (Vec3::new(0.8, 1.3, 0.6), 0.6),
        (Vec3::new(2.5, 2.2, -0.5), -0.5),
        (Vec3::new(0.2, 3.6, -2.0), 0.1),
    ];
    for (&(pos, yaw), &m) in places.iter().zip(&mats) {
        let place = Affine3A::from_translation(pos)
            * Affine3A::from_rotation_y(yaw)
            * Affine3A::from_rotation_z(yaw * 0.7);
        s.extrude(&points, &pieces, &outline, 0.3, place, m);
    }
    s.floor(3, -5.0, 5.0, -4.0, 4.0, 0.0, 4.0, tiles);
    s.add_light(Light::white(Vec3::new(-4.0, 6.0, 4.0), 0.3));
    s.add_light(Light::white(Vec3::new(4.0, 6.0, 4.0), 0.3));
    s.add_light(Light::white(Vec3::new(0.0, 3.0, 2.0), 0.25));
    s.add_light(Light::white(Vec3::new(-3.0, 5.0, -3.0), 0.25));
    s.add_light(Light::white(Vec3::new(3.5, 2.0, -2.0), 0.25));
    s
}

/// The letters K, A, I, S, T extruded (the S swept along two arcs): 981 polygons, 4 lights.
fn kaist() -> Scene {
    let mut s = Scene::new(
        "kaist",
        camera(Vec3::new(4.0, 3.0, 7.5), Vec3::new(4.0, 1.0, 0.0), 50.0),
    );
    let colours = [
        Vec3::new(0.15, 0.3, 0.8),
        Vec3::new(0.8, 0.3, 0.15),
        Vec3::new(0.2, 0.7, 0.3),
        Vec3::new(0.8, 0.75, 0.2),
        Vec3::new(0.6, 0.2, 0.7),
    ];
    let m: Vec<u32> = colours
        .iter()
        .map(|&c| s.add_material(Material::glossy(c, 0.25)))
        .collect();
    let tiles = [
        s.add_material(Material::matte(Vec3::new(0.75, 0.75, 0.7))),
        s.add_material(Material::glossy(Vec3::new(0.3, 0.3, 0.35), 0.3)),
    ];
    let v = Vec2::new;
    let (w, depth) = (0.35, 0.5);
    let place = |x: f32| Affine3A::from_translation(Vec3::new(x, 0.0, 0.0));
    // K
    s.bar(v(0.17, 0.0), v(0.17, 2.0), w, depth, place(0.0), m[0]);
    s.bar(v(0.3, 1.0), v(1.4, 2.0), w, depth, place(0.0), m[0]);
    s.bar(v(0.55, 1.2), v(1.45, 0.0), w, depth, place(0.0), m[0]);
    // A
    s.bar(v(0.15, 0.0), v(0.75, 2.0), w, depth, place(1.9), m[1]);
    s.bar(v(1.35, 0.0), v(0.75, 2.0), w, depth, place(1.9), m[1]);
    s.bar(v(0.4, 0.7), v(1.1, 0.7), 0.25, depth, place(1.9), m[1]);
    // I
    s.bar(v(0.17, 0.0), v(0.17, 2.0), w, depth, place(3.7), m[2]);
    // S: a strip swept along two arcs, 120 segments (4 * 120 + 2 faces).
    let segments = 120;
    let centre_line = |t: f32| -> (Vec2, Vec2) {
        // Upper arc counter-clockwise from 20 to 270 degrees, then the lower arc clockwise.
        if t < 0.5 {
            let a = (20.0 + 500.0 * t).to_radians();
            (
                v(0.5, 1.5) + Vec2::from_angle(a) * 0.5,
                v(-a.sin(), a.cos()),
            )
        } else {
            let a = (90.0 - 500.0 * (t - 0.5)).to_radians();
            (
                v(0.5, 0.5) + Vec2::from_angle(a) * 0.5,
                v(a.sin(), -a.cos()),
            )
        }
    };
    let mut points = Vec::new();
    for i in 0..=segments {
        let (c, tangent) = centre_line(i as f32 / segments as f32);
        points.push(c + tangent.perp() * 0.15);
    }
    for i in (0..=segments).rev() {
        let (c, tangent) = centre_line(i as f32 / segments as f32);
        points.push(c - tangent.perp() * 0.15);
    }
    let n = points.len() as u32;
    let pieces: Vec<Vec<u32>> = (0..segments as u32)
        .map(|i| vec![i, n - 1 - i, n - 2 - i, i + 1])
        .collect();
    let outline: Vec<u32> = (0..n).collect();
    s.extrude(
        &points,
        &pieces,
        &outline,
        depth,
        Affine3A::from_translation(Vec3::new(4.6, 0.15, 0.0)),
        m[3],
    );
    // T
    s.bar(v(0.7, 0.0), v(0.7, 1.85), w, depth, place(6.1), m[4]);
    s.bar(v(0.0, 1.85), v(1.4, 1.85), 0.3, depth, place(6.1), m[4]);
    s.floor(981 - s.faces.len(), -2.0, 10.0, -3.0, 4.0, 0.0, 3.0, tiles);
    s.add_light(Light::white(Vec3::new(-1.0, 5.0, 4.0), 0.35));
    s.add_light(Light::white(Vec3::new(8.0, 5.0, 4.0), 0.35));
    s.add_light(Light::white(Vec3::new(4.0, 2.6, 3.0), 0.3));
    s.add_light(Light::white(Vec3::new(4.0, 6.0, -2.5), 0.3));
    s
}

// ---------------------------------------------------------------------------------------------
// TOML scene file

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    ambient: Option<Vec3>,
    background: Option<Vec3>,
    camera: Camera,
    lights: Vec<Light>,
    #[serde(default)]
    materials: HashMap<String, Material>,
    objects: Vec<ObjectFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectFile {
    /// One of `materials`; a mesh without it takes its file's materials (diffuse colours).
    material: Option<String>,
    #[serde(default)]
    polygons: Vec<Vec<Vec3>>,
    #[serde(rename = "box")]
    cuboid: Option<BoxFile>,
    /// A mesh file (OBJ, PLY, glTF) relative to the scene file, placed by `scale` then
    /// `translate`.
    mesh: Option<String>,
    scale: Option<f32>,
    translate: Option<Vec3>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxFile {
    min: Vec3,
    max: Vec3,
}

impl Scene {
    /// Reads a TOML scene file (see `assets/scenes/shadows-demo.toml` for the format).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| scene_error(path, e))?;
        Scene::parse(&text, path)
    }

    /// Parses a TOML scene; `path` only names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| scene_error(path, e))?;
        let bad = |what: String| Err(scene_error(path, what));
        let finite = |v: Vec3| v.is_finite();
        let c = file.camera;
        if !(finite(c.eye) && finite(c.look_at) && finite(c.up))
            || (c.look_at - c.eye).length() == 0.0
        {
            return bad("camera: eye and look_at must be finite and distinct".into());
        }
        if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
            return bad(format!(
                "camera: fov_y_deg {} is not in (0, 180)",
                c.fov_y_deg
            ));
        }
        if file.lights.is_empty() {
            return bad("no lights".into());
        }
        if let Some(l) = file
            .lights
            .iter()
            .find(|l| !finite(l.position) || !finite(l.intensity))
        {
            return bad(format!("light at {} is not finite", l.position));
        }
        let mut s = Scene::new(file.name.as_deref().unwrap_or("scene"), c);
        s.lights = file.lights;
        s.ambient = file.ambient.unwrap_or(s.ambient);
        s.background = file.background.unwrap_or(s.background);
        let mut names: Vec<&String> = file.materials.keys().collect();
        names.sort();
        for n in &names {
            let m = file.materials[*n];
            let ok = [m.specular, m.shininess, m.reflect, m.transmit, m.ior]
                .iter()
                .all(|x| x.is_finite());
            if !ok || !finite(m.diffuse) || m.ior <= 0.0 {
                return bad(format!("material {n}: values must be finite and ior > 0"));
            }
            s.add_material(m);
        }
        // Vertices at the same position are one vertex, so faces find their neighbours.
        let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
        let mut weld = |s: &mut Scene, v: Vec3| {
            let key = v.to_array().map(f32::to_bits);
            *welded.entry(key).or_insert_with(|| s.add_vertex(v))
        };
        for (o, obj) in file.objects.iter().enumerate() {
            let material = match &obj.material {
                Some(name) => match names.iter().position(|n| *n == name) {
                    Some(m) => Some(m as u32),
                    None => return bad(format!("object {o}: unknown material {name:?}")),
                },
                None if obj.mesh.is_some() => None,
                None => return bad(format!("object {o}: no material")),
            };
            if let Some(b) = &obj.cuboid {
                if !(finite(b.min) && finite(b.max)) || b.min.cmpge(b.max).any() {
                    return bad(format!("object {o}: box min must be below max"));
                }
                s.cuboid(b.min, b.max, material.expect("checked above"));
            }
            for (p, poly) in obj.polygons.iter().enumerate() {
                if let Err(why) = check_polygon(poly) {
                    return bad(format!("object {o}, polygon {p}: {why}"));
                }
                let ids = poly.iter().map(|&v| weld(&mut s, v)).collect();
                s.push_face(ids, material.expect("checked above"));
            }
            if let Some(mesh) = &obj.mesh {
                let scale = obj.scale.unwrap_or(1.0);
                let translate = obj.translate.unwrap_or(Vec3::ZERO);
                if !(scale.is_finite() && scale > 0.0 && finite(translate)) {
                    return bad(format!(
                        "object {o}: scale must be finite and > 0, translate finite"
                    ));
                }
                let file_path = path.parent().unwrap_or(Path::new("")).join(mesh);
                let model = quadray_core::mesh::load_model(&file_path)
                    .map_err(|e| scene_error(path, format!("object {o}: {e}")))?;
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
                            .map(|&i| weld(&mut s, m.positions[i as usize] * scale + translate))
                            .collect();
                        s.push_face(ids, mat);
                    }
                }
            }
        }
        if s.faces.is_empty() {
            return bad("no polygons".into());
        }
        Ok(s)
    }
}

/// A file polygon must be finite, planar and convex (a zero-area polygon is allowed; it is never hit).
fn check_polygon(poly: &[Vec3]) -> Result<(), String> {
    if poly.len() < 3 {
        return Err(format!("{} vertices, need at least 3", poly.len()));
    }
    if poly.iter().any(|v| !v.is_finite()) {
        return Err("a vertex is not finite".into());
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
