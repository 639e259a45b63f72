//! Scenes: a TOML file naming meshes (built-in procedural ones for now), their transforms and
//! colours, the camera and one spot light. Everything is flattened into one triangle list with a
//! per-vertex albedo, which is all the RSM and G-buffer passes need.

use glam::{Mat4, Vec3};
use quadray_core::FileError;
use quadray_core::mesh::load_model;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// One vertex as the raster passes read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub albedo: [f32; 3],
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub position: [f32; 3],
    pub target: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    /// Vertical field of view.
    pub fov_deg: f32,
}

/// A spot light: full intensity inside `cone_deg - falloff_deg` of its axis, fading smoothly to
/// zero at `cone_deg`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpotLight {
    pub position: [f32; 3],
    pub direction: [f32; 3],
    /// Half-angle of the cone; also half the field of view of the RSM.
    pub cone_deg: f32,
    #[serde(default)]
    pub falloff_deg: f32,
    /// Radiant intensity on the axis (W/sr per channel).
    pub intensity: [f32; 3],
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshEntry {
    /// A procedural mesh: `cornell` (the box with two blocks), `room` (the box alone), `blocks`
    /// (the two blocks alone) or `atrium` (a Sponza-like courtyard, about 25k triangles).
    pub builtin: Option<String>,
    /// Or a mesh file (OBJ + MTL, glTF 2.0, PLY), relative to the scene file.
    pub path: Option<PathBuf>,
    #[serde(default = "default_translate")]
    pub translate: [f32; 3],
    #[serde(default = "default_scale")]
    pub scale: f32,
    #[serde(default)]
    pub rotate_y_deg: f32,
    /// Replaces the mesh's own colours.
    pub albedo: Option<[f32; 3]>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    /// Clamp of the VPL kernel's 1/r^4 (world units); shared by every method.
    #[serde(default = "default_r_min")]
    r_min: f32,
    camera: Camera,
    light: SpotLight,
    mesh: Vec<MeshEntry>,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_translate() -> [f32; 3] {
    [0.0; 3]
}
fn default_scale() -> f32 {
    1.0
}
fn default_r_min() -> f32 {
    0.05
}

/// A loaded scene, checked and flattened.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    pub light: SpotLight,
    pub r_min: f32,
    pub triangles: Vec<[Vertex; 3]>,
}

impl Scene {
    pub fn load(path: &Path) -> Result<Self, FileError> {
        let text = std::fs::read_to_string(path).map_err(|e| FileError::new(path, e))?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into());
        let dir = path.parent().unwrap_or(Path::new("."));
        Self::parse_in(&text, &name, dir).map_err(|reason| FileError::new(path, reason))
    }

    /// Parses scene text without mesh files; the error says what is wrong.
    pub fn parse(text: &str, name: &str) -> Result<Self, String> {
        Self::parse_in(text, name, Path::new("."))
    }

    /// Parses scene text whose mesh paths are relative to `dir`.
    pub fn parse_in(text: &str, name: &str, dir: &Path) -> Result<Self, String> {
        let file: SceneFile = toml::from_str(text).map_err(|e| e.to_string())?;
        if file.mesh.is_empty() {
            return Err("the scene has no [[mesh]]".into());
        }
        let mut triangles = Vec::new();
        for (i, entry) in file.mesh.iter().enumerate() {
            let tris = mesh_triangles(entry, dir).map_err(|e| format!("mesh {}: {e}", i + 1))?;
            triangles.extend(tris);
        }
        let scene = Self {
            name: name.to_string(),
            camera: file.camera,
            light: file.light,
            r_min: file.r_min,
            triangles,
        };
        scene.validate()?;
        Ok(scene)
    }

    /// The bundled Cornell box with a spot light (no file needed).
    pub fn cornell() -> Self {
        Self::parse(CORNELL_TOML, "cornell").expect("the built-in Cornell scene is valid")
    }

    /// Checks the camera, the light and `r_min` (after loading, or after changing them).
    pub fn validate(&self) -> Result<(), String> {
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        let c = &self.camera;
        let l = &self.light;
        if !finite(&c.position) || !finite(&c.target) || !finite(&c.up) {
            return Err("camera has a non-finite coordinate".into());
        }
        if Vec3::from(c.position).distance(Vec3::from(c.target)) < 1e-6 {
            return Err("camera position equals its target".into());
        }
        if !(c.fov_deg > 1.0 && c.fov_deg < 179.0) {
            return Err(format!("camera fov_deg {} is outside (1, 179)", c.fov_deg));
        }
        if !finite(&l.position) || !finite(&l.direction) || !finite(&l.intensity) {
            return Err("light has a non-finite value".into());
        }
        if Vec3::from(l.direction).length() < 1e-6 {
            return Err("light direction is zero".into());
        }
        if !(l.cone_deg > 0.5 && l.cone_deg < 89.0) {
            return Err(format!(
                "light cone_deg {} is outside (0.5, 89)",
                l.cone_deg
            ));
        }
        if !(l.falloff_deg >= 0.0 && l.falloff_deg <= l.cone_deg) {
            return Err(format!(
                "light falloff_deg {} is outside [0, cone_deg]",
                l.falloff_deg
            ));
        }
        if l.intensity.iter().any(|&x| x < 0.0) {
            return Err("light intensity is negative".into());
        }
        if !(self.r_min.is_finite() && self.r_min > 0.0) {
            return Err(format!("r_min {} must be positive", self.r_min));
        }
        Ok(())
    }

    /// Axis-aligned bounds of the geometry.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        for v in self.triangles.iter().flatten() {
            lo = lo.min(v.position.into());
            hi = hi.max(v.position.into());
        }
        (lo, hi)
    }

    /// Length of the bounds' diagonal: the unit of RSM depth (validity thresholds are fractions of
    /// it) and the far plane of every projection.
    pub fn extent(&self) -> f32 {
        let (lo, hi) = self.bounds();
        (hi - lo).length().max(1e-3)
    }

    /// World -> light view.
    pub fn light_view(&self) -> Mat4 {
        let dir = Vec3::from(self.light.direction).normalize();
        let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
        glam::camera::rh::view::look_to_mat4(self.light.position.into(), dir, up)
    }

    /// World -> light clip space (the RSM and shadow map projection).
    pub fn light_view_proj(&self) -> Mat4 {
        let far = self.light_far();
        glam::camera::rh::proj::directx::perspective(
            (2.0 * self.light.cone_deg).to_radians(),
            1.0,
            far * 1e-3,
            far,
        ) * self.light_view()
    }

    /// Far plane of the light: everything in the scene is closer.
    pub fn light_far(&self) -> f32 {
        let (lo, hi) = self.bounds();
        let p = Vec3::from(self.light.position);
        let centre = (lo + hi) * 0.5;
        p.distance(centre) + self.extent()
    }

    pub fn camera_view_proj(&self, aspect: f32) -> Mat4 {
        let c = &self.camera;
        let far = Vec3::from(c.position).distance(self.bounds().0.midpoint(self.bounds().1))
            + self.extent();
        glam::camera::rh::proj::directx::perspective(
            c.fov_deg.to_radians(),
            aspect,
            far * 1e-3,
            far,
        ) * glam::camera::rh::view::look_at_mat4(c.position.into(), c.target.into(), c.up.into())
    }
}

/// The scene `quadray indirect` uses without `--scene`, also `assets/scenes/cornell.toml`.
pub const CORNELL_TOML: &str = include_str!("../../../assets/scenes/cornell.toml");

/// The bundled scene files of this technique, in `scenes_dir()`.
pub const BUNDLED_SCENES: [&str; 5] = [
    "cornell.toml",
    "cornell_obj.toml",
    "cornell_bunny.toml",
    "cornell_buddha.toml",
    "atrium.toml",
];

/// Directory of the bundled scene files.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes")
}

const WHITE: [f32; 3] = [0.73, 0.73, 0.73];
const RED: [f32; 3] = [0.63, 0.065, 0.05];
const GREEN: [f32; 3] = [0.14, 0.45, 0.091];

/// Triangles of a mesh file with per-vertex albedo: the material's base colour times its texture
/// sampled at the vertex (the RSM and G-buffer carry albedo per vertex, not per texel).
fn file_triangles(path: &Path) -> Result<Vec<[Vertex; 3]>, String> {
    let model = load_model(path).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    for mesh in &model.meshes {
        let material = model.materials.get(mesh.material);
        let base = material.map_or(Vec3::ONE, |m| m.base_color);
        let albedo = |i: usize| -> [f32; 3] {
            let texel = material
                .and_then(|m| m.base_color_texture.as_ref())
                .zip(mesh.uvs.as_ref())
                .map_or(Vec3::ONE, |(tex, uvs)| texture_at(tex, uvs[i]));
            (base * texel).clamp(Vec3::ZERO, Vec3::ONE).into()
        };
        for tri in &mesh.indices {
            out.push(tri.map(|i| {
                let i = i as usize;
                Vertex {
                    position: mesh.positions[i].into(),
                    normal: mesh.normals[i].into(),
                    albedo: albedo(i),
                }
            }));
        }
    }
    Ok(out)
}

/// Nearest texel at `uv` (wrapping; (0, 0) is the top-left corner), decoded from sRGB.
fn texture_at(tex: &quadray_core::image_out::Rgba8Image, uv: glam::Vec2) -> Vec3 {
    let wrap = |t: f32, n: u32| ((t - t.floor()) * n as f32).min(n as f32 - 1.0) as u32;
    let p = tex.pixels[(wrap(uv.y, tex.height) * tex.width + wrap(uv.x, tex.width)) as usize];
    let linear = |c: u8| {
        let c = f32::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    Vec3::new(linear(p[0]), linear(p[1]), linear(p[2]))
}

fn builtin_triangles(name: &str) -> Result<Vec<[Vertex; 3]>, String> {
    Ok(match name {
        "cornell" => {
            let mut t = cornell_room();
            t.extend(cornell_blocks());
            t
        }
        "room" => cornell_room(),
        "blocks" => cornell_blocks(),
        "atrium" => atrium(),
        other => {
            return Err(format!(
                "unknown builtin `{other}` (known: cornell, room, blocks, atrium)"
            ));
        }
    })
}

fn mesh_triangles(entry: &MeshEntry, dir: &Path) -> Result<Vec<[Vertex; 3]>, String> {
    let mut tris = match (&entry.builtin, &entry.path) {
        (Some(_), Some(_)) => return Err("has both `builtin` and `path`".into()),
        (None, None) => return Err("needs `builtin` or `path`".into()),
        (None, Some(path)) => file_triangles(&dir.join(path))?,
        (Some(builtin), None) => builtin_triangles(builtin)?,
    };
    if !(entry.scale.is_finite() && entry.scale > 0.0) {
        return Err(format!("scale {} must be positive", entry.scale));
    }
    if !entry.translate.iter().all(|x| x.is_finite()) || !entry.rotate_y_deg.is_finite() {
        return Err("transform has a non-finite value".into());
    }
    if let Some(a) = entry.albedo
        && !a.iter().all(|x| (0.0..=1.0).contains(x))
    {
        return Err(format!("albedo {a:?} is outside [0, 1]"));
    }
    let rotation = Mat4::from_rotation_y(entry.rotate_y_deg.to_radians());
    let model = Mat4::from_translation(entry.translate.into())
        * rotation
        * Mat4::from_scale(Vec3::splat(entry.scale));
    for v in tris.iter_mut().flatten() {
        v.position = model.transform_point3(v.position.into()).into();
        v.normal = rotation.transform_vector3(v.normal.into()).into();
        if let Some(a) = entry.albedo {
            v.albedo = a;
        }
    }
    Ok(tris)
}

/// Two triangles of the quad a, b, c, d (counter-clockwise seen from the side `normal` faces).
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, albedo: [f32; 3]) -> [[Vertex; 3]; 2] {
    let normal = (b - a).cross(d - a).normalize();
    let v = |p: Vec3| Vertex {
        position: p.into(),
        normal: normal.into(),
        albedo,
    };
    [[v(a), v(b), v(c)], [v(a), v(c), v(d)]]
}

/// Corner `i` of the box spanned by `lo` and `hi`: bits 0, 1, 2 of `i` pick `hi` in x, y, z.
fn box_corner(lo: Vec3, hi: Vec3, i: usize) -> Vec3 {
    let pick = |bit: usize, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
    Vec3::new(
        pick(1, lo.x, hi.x),
        pick(2, lo.y, hi.y),
        pick(4, lo.z, hi.z),
    )
}

// The faces of a box seen from outside, as corners of `box_corner` in quad order.
const TOP: [usize; 4] = [6, 7, 3, 2];
const BOTTOM: [usize; 4] = [0, 1, 5, 4];
const FRONT: [usize; 4] = [4, 5, 7, 6]; // +z
const BACK: [usize; 4] = [1, 0, 2, 3]; // -z
const LEFT: [usize; 4] = [0, 4, 6, 2]; // -x
const RIGHT: [usize; 4] = [5, 1, 3, 7]; // +x

/// The two triangles of each face, the face's corners numbered as in [`box_corner`].
fn box_faces(corners: [Vec3; 8], faces: &[([usize; 4], [f32; 3])]) -> Vec<[Vertex; 3]> {
    faces
        .iter()
        .flat_map(|&([a, b, c, d], albedo)| {
            quad(corners[a], corners[b], corners[c], corners[d], albedo)
        })
        .collect()
}

/// The unit room [0,1]^3 open towards +z: red wall at x = 0, green at x = 1.
fn cornell_room() -> Vec<[Vertex; 3]> {
    let corners = std::array::from_fn(|i| box_corner(Vec3::ZERO, Vec3::ONE, i));
    // seen from inside
    let floor = [4, 5, 1, 0];
    let ceiling = [2, 3, 7, 6];
    let back = [0, 1, 3, 2];
    let left = [4, 0, 2, 6];
    let right = [1, 5, 7, 3];
    box_faces(
        corners,
        &[
            (floor, WHITE),
            (ceiling, WHITE),
            (back, WHITE),
            (left, RED),
            (right, GREEN),
        ],
    )
}

/// The short and the tall block of the Cornell box, turned as in the original.
fn cornell_blocks() -> Vec<[Vertex; 3]> {
    let mut out = block(Vec3::new(0.66, 0.0, 0.62), 0.3, 0.3, -17.0);
    out.extend(block(Vec3::new(0.32, 0.0, 0.33), 0.3, 0.6, 17.0));
    out
}

/// An upright box of footprint `side` and `height` standing on y = 0 at `centre` (no bottom).
fn block(centre: Vec3, side: f32, height: f32, turn_deg: f32) -> Vec<[Vertex; 3]> {
    let r = Mat4::from_translation(centre) * Mat4::from_rotation_y(turn_deg.to_radians());
    let h = side * 0.5;
    let (lo, hi) = (Vec3::new(-h, 0.0, -h), Vec3::new(h, height, h));
    let corners = std::array::from_fn(|i| r.transform_point3(box_corner(lo, hi, i)));
    box_faces(
        corners,
        &[TOP, FRONT, RIGHT, BACK, LEFT].map(|f| (f, WHITE)),
    )
}

/// An axis-aligned box, faces outwards.
fn cuboid(lo: Vec3, hi: Vec3, albedo: [f32; 3]) -> Vec<[Vertex; 3]> {
    let corners = std::array::from_fn(|i| box_corner(lo, hi, i));
    box_faces(
        corners,
        &[TOP, BOTTOM, FRONT, BACK, LEFT, RIGHT].map(|f| (f, albedo)),
    )
}

/// A vertical cylinder (no caps) with smooth normals, `segments` around and `rings` high.
fn column(base: Vec3, radius: f32, height: f32, segments: u32, rings: u32) -> Vec<[Vertex; 3]> {
    let albedo = [0.75, 0.72, 0.66];
    let at = |i: u32, j: u32| {
        let a = std::f32::consts::TAU * i as f32 / segments as f32;
        let n = Vec3::new(a.cos(), 0.0, a.sin());
        Vertex {
            position: (base + n * radius + Vec3::Y * height * j as f32 / rings as f32).into(),
            normal: n.into(),
            albedo,
        }
    };
    (0..segments)
        .flat_map(|i| (0..rings).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            [[a, c, b], [a, d, c]]
        })
        .collect()
}

/// A Sponza-like courtyard, 30 x 15 x 13 m, open to the sky: stone floor, two storeys of
/// galleries on columns along both long sides, coloured banners hanging between the columns.
fn atrium() -> Vec<[Vertex; 3]> {
    const STONE: [f32; 3] = [0.62, 0.57, 0.48];
    const PLASTER: [f32; 3] = [0.74, 0.68, 0.58];
    const BANNERS: [[f32; 3]; 3] = [[0.7, 0.08, 0.06], [0.08, 0.15, 0.6], [0.1, 0.5, 0.12]];
    let (length, width, height) = (30.0, 13.0, 15.0);
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let mut out: Vec<[Vertex; 3]> = Vec::new();
    out.extend(quad(
        p(0., 0., width),
        p(length, 0., width),
        p(length, 0., 0.),
        p(0., 0., 0.),
        STONE,
    ));
    out.extend(quad(
        p(0., 0., 0.),
        p(length, 0., 0.),
        p(length, height, 0.),
        p(0., height, 0.),
        PLASTER,
    ));
    out.extend(quad(
        p(length, 0., width),
        p(0., 0., width),
        p(0., height, width),
        p(length, height, width),
        PLASTER,
    ));
    out.extend(quad(
        p(0., 0., width),
        p(0., 0., 0.),
        p(0., height, 0.),
        p(0., height, width),
        PLASTER,
    ));
    out.extend(quad(
        p(length, 0., 0.),
        p(length, 0., width),
        p(length, height, width),
        p(length, height, 0.),
        PLASTER,
    ));
    for (side, z) in [(0.0f32, 3.0f32), (1.0, width - 3.0)] {
        let (z0, z1) = if side == 0.0 { (0.0, z) } else { (z, width) };
        for storey in 0..2 {
            let floor = 5.0 * (storey as f32 + 1.0);
            out.extend(cuboid(p(0.0, floor - 0.4, z0), p(length, floor, z1), STONE));
            for i in 0..12 {
                let x = 1.5 + 2.45 * i as f32;
                out.extend(column(p(x, floor - 5.0, z), 0.35, 4.6, 32, 8));
                if storey == 1 && i < 11 {
                    let banner = BANNERS[i % 3];
                    let (bz, x0, x1) =
                        (z + if side == 0.0 { 0.2 } else { -0.2 }, x + 0.5, x + 1.95);
                    out.extend(quad(
                        p(x0, 5.0, bz),
                        p(x1, 5.0, bz),
                        p(x1, 9.0, bz),
                        p(x0, 9.0, bz),
                        banner,
                    ));
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_room_normals_face_inwards_and_blocks_outwards() {
        let scene = Scene::cornell();
        let centre = Vec3::new(0.5, 0.5, 0.5);
        for t in cornell_room() {
            let n = Vec3::from(t[0].normal);
            assert!(n.dot(centre - Vec3::from(t[0].position)) > 0.0);
        }
        let centre = Vec3::new(0.4, 0.0, 0.3);
        for t in block(centre, 0.3, 0.6, 17.0) {
            let mid =
                (Vec3::from(t[0].position) + Vec3::from(t[1].position) + Vec3::from(t[2].position))
                    / 3.0;
            let inside = centre + Vec3::new(0.0, 0.3, 0.0);
            assert!(Vec3::from(t[0].normal).dot(mid - inside) > 0.0);
        }
        assert_eq!(scene.triangles.len(), 10 + 20);
        assert!((scene.extent() - 3f32.sqrt()).abs() < 1e-4);
    }

    #[test]
    fn the_atrium_is_large_and_its_scene_file_loads() {
        let scene = Scene::load(&scenes_dir().join("atrium.toml")).unwrap();
        assert!(scene.triangles.len() > 20_000, "{}", scene.triangles.len());
        let (lo, hi) = scene.bounds();
        assert!(lo.min_element() >= 0.0 && hi.x <= 30.0 && hi.y <= 15.0);
        for t in &scene.triangles {
            let [a, b, c] = t.map(|v| Vec3::from(v.position));
            assert!(
                (b - a).cross(c - a).length() > 1e-6,
                "no degenerate triangles"
            );
        }
    }

    #[test]
    fn scenes_with_mesh_files_load_in_the_unit_room() {
        for (file, min_triangles) in [
            ("cornell_obj.toml", 30),
            ("cornell_bunny.toml", 60_000),
            ("cornell_buddha.toml", 90_000),
        ] {
            let scene = Scene::load(&scenes_dir().join(file)).unwrap();
            assert!(scene.triangles.len() >= min_triangles, "{file}");
            let (lo, hi) = scene.bounds();
            assert!(
                lo.min_element() > -0.01 && hi.max_element() < 1.01,
                "{file}: {lo} {hi}"
            );
        }
    }

    #[test]
    fn a_malformed_mesh_file_is_named_in_the_error() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/malformed/obj");
        let text = CORNELL_TOML.replace("builtin = \"cornell\"", "path = \"empty.obj\"");
        let err = Scene::parse_in(&text, "bad", &dir).unwrap_err();
        assert!(err.contains("empty.obj"), "{err}");
        let both = CORNELL_TOML.replace(
            "builtin = \"cornell\"",
            "builtin = \"room\"\npath = \"x.obj\"",
        );
        assert!(Scene::parse(&both, "bad").unwrap_err().contains("both"));
    }

    #[test]
    fn bad_scenes_are_refused_with_the_reason() {
        let good = CORNELL_TOML;
        let cases = [
            (
                good.replace("cone_deg = 55.0", "cone_deg = 95.0"),
                "cone_deg",
            ),
            (
                good.replace("builtin = \"cornell\"", "builtin = \"sponza\""),
                "unknown builtin",
            ),
            (good.replace("fov_deg = 39.0", "fov_deg = nan"), "fov_deg"),
            (good.replace("[light]", "[lamp]"), "light"),
            ("r_min = 0.1".to_string(), "camera"),
        ];
        for (text, needle) in cases {
            let err = Scene::parse(&text, "bad").unwrap_err();
            assert!(err.contains(needle), "{err} should mention {needle}");
        }
    }
}
