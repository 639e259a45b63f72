//! Polygon scenes: materials, point lights, a pinhole camera, faces sharing vertices (the mesh
//! adjacency the silhouette rule needs), the paper's four scenes rebuilt procedurally with its
//! polygon and light counts (in `scene/lookalikes.rs`), and scenes read from files (TOML or glTF,
//! through `quadray_core::scene`).

mod file;
mod lookalikes;

use crate::geom::ConvexPolygon;
use glam::Vec3;
use lookalikes::{desk, glasses, kaist, stars};
use std::path::Path;
use thiserror::Error;

/// A scene file that cannot be used, with the file and the reason.
#[derive(Debug, Error)]
#[error("{path}: {reason}")]
pub struct SceneError {
    pub path: String,
    pub reason: String,
}

fn scene_error(path: &Path, reason: impl ToString) -> SceneError {
    SceneError {
        path: path.display().to_string(),
        reason: reason.to_string(),
    }
}

/// Whitted's surface: local diffuse + Blinn-Phong specular, mirror reflection and refraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub diffuse: Vec3,
    pub specular: f32,
    pub shininess: f32,
    pub reflect: f32,
    pub transmit: f32,
    pub ior: f32,
}

impl Material {
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

    pub fn glossy(diffuse: Vec3, reflect: f32) -> Self {
        Self {
            specular: 0.6,
            shininess: 64.0,
            reflect,
            ..Self::matte(diffuse)
        }
    }

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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub position: Vec3,
    pub intensity: Vec3,
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    pub fov_y_deg: f32,
}

/// A convex planar face: indices into the scene's vertices (shared between faces of one mesh).
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    pub vertices: Vec<u32>,
    pub material: u32,
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub vertices: Vec<Vec3>,
    pub faces: Vec<Face>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub ambient: Vec3,
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

impl Scene {
    fn empty(name: &str, camera: Camera) -> Self {
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

    pub fn builtin(name: &str) -> Option<Scene> {
        match name {
            "glasses" => Some(glasses()),
            "desk" => Some(desk()),
            "stars" => Some(stars()),
            "kaist" => Some(kaist()),
            _ => None,
        }
    }

    fn material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        self.materials.len() as u32 - 1
    }

    fn light(&mut self, position: Vec3, intensity: f32) {
        self.lights.push(Light {
            position,
            intensity: Vec3::splat(intensity),
        });
    }

    fn vertex(&mut self, p: Vec3) -> u32 {
        self.vertices.push(p);
        self.vertices.len() as u32 - 1
    }

    fn face(&mut self, mut vertices: Vec<u32>, material: u32) {
        vertices.dedup();
        if vertices.len() > 1 && vertices.first() == vertices.last() {
            vertices.pop();
        }
        self.faces.push(Face { vertices, material });
    }
}
