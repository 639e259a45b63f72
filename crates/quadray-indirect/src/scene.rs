//! Scenes: built from the shared scene description (`quadray_core::scene`: a TOML or glTF file)
//! with its camera, its lights (point, spot and directional) and its objects (mesh files, the builtin meshes of
//! `scene/builtin.rs`, boxes, polygons), flattened into one triangle list with a per-vertex
//! albedo and texture coordinate, and the mesh files' base colour textures as the layers of one
//! array (`scene/textures.rs`), which is all the RSM and G-buffer passes need.

mod builtin;
mod textures;

use builtin::{builtin_triangles, cuboid};
use glam::{Mat4, Vec2, Vec3};
use quadray_core::FileError;
use quadray_core::mesh::Model;
pub use quadray_core::scene::{Camera, Cone, Intensity, Light, LightKind};
use quadray_core::scene::{Object, SceneDescription, Shape};
use std::path::{Path, PathBuf};
use std::sync::Arc;
pub use textures::{MAX_TEXTURE_BYTES, MAX_TEXTURES, Relayering, SceneTextures, TextureCollector};

/// One vertex as the raster passes read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// World position.
    pub position: [f32; 3],
    /// Unit normal (the front side, which the G-buffer turns towards the viewer).
    pub normal: [f32; 3],
    /// Diffuse albedo in [0, 1] per channel, times the texture's texel at `uv` where the
    /// vertex has a texture.
    pub albedo: [f32; 3],
    /// Texture coordinate ((0, 0) the texture's top-left corner).
    pub uv: [f32; 2],
    /// The base colour texture: a layer of [`Scene::textures`] and the sampler it is read
    /// through, packed (the same on the triangle's three vertices), or [`Vertex::UNTEXTURED`].
    pub texture: u32,
}

impl Vertex {
    /// [`Vertex::texture`] of a vertex without a texture.
    pub const UNTEXTURED: u32 = u32::MAX;

    /// A vertex without a texture.
    pub fn untextured(position: [f32; 3], normal: [f32; 3], albedo: [f32; 3]) -> Self {
        Self {
            position,
            normal,
            albedo,
            uv: [0.0; 2],
            texture: Self::UNTEXTURED,
        }
    }
}

/// Axis-aligned bounds (min, max) of `points`.
pub fn bounds_of(points: impl IntoIterator<Item = Vec3>) -> (Vec3, Vec3) {
    points
        .into_iter()
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

/// Length of the diagonal of `bounds` (min, max), at least 1e-3.
pub fn extent_of((lo, hi): (Vec3, Vec3)) -> f32 {
    (hi - lo).length().max(1e-3)
}

/// A loaded scene, checked and flattened.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene's name (its file's stem), in stats and captions.
    pub name: String,
    /// The camera pictures are rendered from.
    pub camera: Camera,
    /// The lights whose RSMs make the VPLs, in the file's order (a renderer takes the first
    /// [`crate::Settings::max_lights`]). Their intensities are radiometric here: W/sr for point
    /// and spot lights, W/m^2 for directional ones ([`Intensity::Native`]).
    pub lights: Vec<Light>,
    /// Clamp of the VPL kernel's distance (world units): 1/r^4 is taken at no less than this.
    pub r_min: f32,
    /// Every object's triangles in world space.
    pub triangles: Vec<[Vertex; 3]>,
    /// The base colour textures the triangles' [`Vertex::texture`] refer to.
    pub textures: Arc<SceneTextures>,
}

impl Scene {
    /// The widest cone this renderer takes: its RSM's field of view is twice the cone.
    pub const MAX_CONE_DEG: f32 = 89.0;

    /// Reads a scene file: TOML, or glTF 2.0 for `.gltf` and `.glb`.
    pub fn load(path: &Path) -> Result<Self, FileError> {
        let description = SceneDescription::load(path)?;
        Self::from_description(&description).map_err(|reason| FileError::new(path, reason))
    }

    /// Parses scene text without mesh files; the error says what is wrong.
    pub fn parse(text: &str, name: &str) -> Result<Self, String> {
        Self::parse_in(text, name, Path::new("."))
    }

    /// Parses scene text whose mesh paths are relative to `dir`.
    pub fn parse_in(text: &str, name: &str, dir: &Path) -> Result<Self, String> {
        let description =
            SceneDescription::from_toml(text, &dir.join(name)).map_err(|e| e.reason)?;
        Ok(Self {
            name: name.to_string(),
            ..Self::from_description(&description)?
        })
    }

    /// This renderer's scene: the camera, every light, and every object as triangles. A
    /// material gives an object its albedo (its diffuse colour; the other fields are the ray
    /// tracer's); without one, mesh files keep their base colours (times their textures, sampled
    /// per texel) and builtin meshes their own. A photometric intensity (glTF's) becomes a
    /// radiometric one: candela / 683 W/sr, lux / 683 W/m^2.
    pub fn from_description(d: &SceneDescription) -> Result<Self, String> {
        if d.lights.is_empty() {
            return Err(
                "no light (quadray indirect renders point, spot and directional \
                        lights: give the scene a [[lights]] entry or a glTF punctual light)"
                    .into(),
            );
        }
        let lights = d
            .lights
            .iter()
            .map(|l| Light {
                intensity: Intensity::Native(l.intensity.radiometric()),
                ..*l
            })
            .collect();
        let mut triangles = Vec::new();
        let mut textures = TextureCollector::default();
        for (i, object) in d.objects.iter().enumerate() {
            triangles.extend(
                object_triangles(object, d, &mut textures)
                    .map_err(|e| format!("object {i}: {e}"))?,
            );
        }
        let scene = Self {
            textures: Arc::new(textures.textures()),
            name: d.name.clone(),
            camera: d.camera,
            lights,
            r_min: d.technique_settings::<FileSettings>("indirect")?.r_min,
            triangles,
        };
        scene.validate()?;
        Ok(scene)
    }

    /// The bundled Cornell box with a spot light (no file needed).
    pub fn cornell() -> Self {
        Self::parse(CORNELL_TOML, "cornell").expect("the built-in Cornell scene is valid")
    }

    /// Checks the camera, the lights and `r_min` (after loading, or after changing them).
    pub fn validate(&self) -> Result<(), String> {
        self.camera.validate()?;
        if self.lights.is_empty() {
            return Err("no light".into());
        }
        for light in &self.lights {
            light.validate()?;
            // the RSM sees the whole cone: twice it must stay below a half-space
            if let LightKind::Spot { cone, .. } = light.kind
                && cone.cone_deg > Self::MAX_CONE_DEG
            {
                return Err(format!(
                    "{}: cone_deg {} is over {} (the RSM's field of view is twice the cone)",
                    light.describe(),
                    cone.cone_deg,
                    Self::MAX_CONE_DEG
                ));
            }
        }
        if !(self.r_min.is_finite() && self.r_min > 0.0) {
            return Err(format!("r_min {} must be positive", self.r_min));
        }
        Ok(())
    }

    /// The scene with every light turned `degrees` about the vertical axis through the middle of
    /// its geometry (counter-clockwise seen from above), as `--light-orbit` turns it a frame at a
    /// time: a spot and the sun turn, a point light moves round.
    pub fn light_turned(&self, degrees: f32) -> Self {
        let (lo, hi) = self.bounds();
        let mut out = self.clone();
        for light in &mut out.lights {
            *light = light.turned(degrees, lo.midpoint(hi));
        }
        out
    }

    /// The scene with its camera moved `degrees` along an orbit about the vertical axis
    /// through its target (still looking at the target).
    pub fn camera_orbited(&self, degrees: f32) -> Self {
        let turn = glam::Quat::from_rotation_y(degrees.to_radians());
        let mut out = self.clone();
        let c = &self.camera;
        out.camera.position = c.target + turn * (c.position - c.target);
        out
    }

    /// Axis-aligned bounds of the geometry.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        bounds_of(
            self.triangles
                .iter()
                .flatten()
                .map(|v| Vec3::from(v.position)),
        )
    }

    /// Length of the bounds' diagonal: the unit of RSM depth (validity thresholds are fractions of
    /// it) and the far plane of every projection.
    pub fn extent(&self) -> f32 {
        extent_of(self.bounds())
    }

    /// World -> camera clip space for a picture of this aspect ratio (width / height).
    pub fn camera_view_proj(&self, aspect: f32) -> Mat4 {
        let c = &self.camera;
        let far = c
            .position
            .distance(self.bounds().0.midpoint(self.bounds().1))
            + self.extent();
        glam::Mat4::perspective_rh(c.fov_y_deg.to_radians(), aspect, far * 1e-3, far)
            * glam::Mat4::look_at_rh(c.position, c.target, c.up)
    }
}

/// The scene `quadray indirect` uses without `--scene`, in the crate (so that it packages) and
/// linked as `assets/scenes/cornell.toml`.
pub const CORNELL_TOML: &str = include_str!("../scenes/cornell.toml");

/// The bundled scene files of this technique, in `scenes_dir()`.
pub const BUNDLED_SCENES: [&str; 11] = [
    "cornell.toml",
    "cornell_obj.toml",
    "cornell_bunny.toml",
    "cornell_buddha.toml",
    "atrium.toml",
    "cornell_spot.gltf",
    "leak.toml",
    "courtyard.toml",
    "lamplit_room.toml",
    "cornell_lights.gltf",
    "textured_floor.gltf",
];

/// Directory of the bundled scene files.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes")
}

/// Clamp of the VPL kernel's 1/r^4 (world units) of a scene that does not set `r_min`.
pub const DEFAULT_R_MIN: f32 = 0.05;

/// A scene file's `[indirect]` table.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
struct FileSettings {
    /// [`Scene::r_min`].
    r_min: f32,
}

impl Default for FileSettings {
    fn default() -> Self {
        Self {
            r_min: DEFAULT_R_MIN,
        }
    }
}

/// Triangles of mesh file `path` with its materials' base colours per vertex and their textures
/// (where the mesh has texture coordinates) as layers of `textures`, which the raster passes
/// sample per texel.
fn model_triangles(
    model: &Model,
    path: &Path,
    textures: &mut TextureCollector,
) -> Result<Vec<[Vertex; 3]>, String> {
    let mut out = Vec::new();
    for mesh in &model.meshes {
        let material = model.materials.get(mesh.material);
        let albedo = material
            .map_or(Vec3::ONE, |m| m.base_color)
            .clamp(Vec3::ZERO, Vec3::ONE)
            .into();
        let texture = match (material, &mesh.uvs) {
            (Some(m), Some(_)) => match &m.base_color_texture {
                Some(image) => textures.index(
                    image,
                    m.base_color_sampler,
                    &format!("{} (material `{}`)", path.display(), m.name),
                )?,
                None => Vertex::UNTEXTURED,
            },
            _ => Vertex::UNTEXTURED,
        };
        let uv = |i: usize| mesh.uvs.as_ref().map_or(Vec2::ZERO, |uvs| uvs[i]).into();
        for tri in &mesh.indices {
            out.push(tri.map(|i| {
                let i = i as usize;
                Vertex {
                    position: mesh.positions[i].into(),
                    normal: mesh.normals[i].into(),
                    albedo,
                    uv: uv(i),
                    texture,
                }
            }));
        }
    }
    Ok(out)
}

/// Convex polygons as triangle fans, each with its plane's normal (Newell's, so the winding
/// decides the side); zero-area polygons are left out.
fn polygon_triangles(polygons: &[Vec<Vec3>]) -> Vec<[Vertex; 3]> {
    let mut out = Vec::new();
    for polygon in polygons {
        let n = polygon.len();
        let normal = Shape::polygon_normal(polygon);
        if normal == Vec3::ZERO {
            continue;
        }
        let v = |p: Vec3| Vertex::untextured(p.into(), normal.into(), [1.0; 3]);
        for i in 1..n.saturating_sub(1) {
            out.push([v(polygon[0]), v(polygon[i]), v(polygon[i + 1])]);
        }
    }
    out
}

/// Builtin mesh `name` as a mesh file's model: its triangles, one mesh for each run of triangles
/// of one albedo (in their order), a material for each albedo (named `NAME N`, white's the
/// default last).
pub fn builtin_model(name: &str) -> Result<Model, String> {
    let mut model = Model::default();
    for triangle in builtin_triangles(name)? {
        let albedo = Vec3::from(triangle[0].albedo);
        let material = match model.materials.iter().position(|m| m.base_color == albedo) {
            Some(m) => m,
            None => {
                model.materials.push(quadray_core::mesh::Material {
                    name: format!("{name} {}", model.materials.len()),
                    base_color: albedo,
                    ..Default::default()
                });
                model.materials.len() - 1
            }
        };
        if model.meshes.last().is_none_or(|m| m.material != material) {
            model.meshes.push(quadray_core::mesh::Mesh {
                name: format!("{name}/{}", model.meshes.len()),
                positions: Vec::new(),
                normals: Vec::new(),
                uvs: None,
                indices: Vec::new(),
                material,
            });
        }
        let mesh = model.meshes.last_mut().expect("pushed above");
        let first = mesh.positions.len() as u32;
        mesh.positions
            .extend(triangle.map(|v| Vec3::from(v.position)));
        mesh.normals.extend(triangle.map(|v| Vec3::from(v.normal)));
        mesh.indices.push([first, first + 1, first + 2]);
    }
    model.materials.push(Default::default());
    Ok(model)
}

/// `scene` with every builtin mesh replaced by its [`builtin_model`], placed and coloured as
/// before: a scene that holds all of its geometry, as writing it to glTF needs.
pub fn builtins_as_meshes(scene: &SceneDescription) -> Result<SceneDescription, String> {
    let mut scene = scene.clone();
    for (i, object) in scene.objects.iter_mut().enumerate() {
        if let Shape::Builtin(name) = &object.shape {
            let model = builtin_model(name).map_err(|e| format!("object {i}: {e}"))?;
            object.shape = Shape::Mesh {
                path: PathBuf::from(name),
                model: Box::new(model),
            };
        }
    }
    Ok(scene)
}

/// One object's triangles in world space, with its material's albedo (and no texture) when it
/// has one.
fn object_triangles(
    object: &Object,
    d: &SceneDescription,
    textures: &mut TextureCollector,
) -> Result<Vec<[Vertex; 3]>, String> {
    let mut tris = match &object.shape {
        Shape::Builtin(name) => builtin_triangles(name)?,
        Shape::Mesh { model, path } => model_triangles(model, path, textures)?,
        Shape::Box { min, max } => cuboid(*min, *max, [1.0; 3]),
        Shape::Polygons(polygons) => polygon_triangles(polygons),
    };
    let albedo = match object.material {
        Some(m) => {
            let (name, material) = d
                .materials
                .get(m)
                .ok_or_else(|| format!("material {m} does not exist"))?;
            let albedo = material.diffuse;
            if !(albedo.cmpge(Vec3::ZERO).all() && albedo.cmple(Vec3::ONE).all()) {
                return Err(format!(
                    "material {name}: diffuse {albedo} is outside [0, 1] (an albedo here)"
                ));
            }
            Some(albedo.to_array())
        }
        None => None,
    };
    let model = object.transform.matrix();
    let rotation = object.transform.rotation();
    for v in tris.iter_mut().flatten() {
        v.position = model.transform_point3(v.position.into()).into();
        v.normal = rotation.transform_vector3(v.normal.into()).into();
        if let Some(a) = albedo {
            v.albedo = a;
            v.texture = Vertex::UNTEXTURED;
        }
    }
    Ok(tris)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cornell_scene_is_the_room_and_its_blocks() {
        let scene = Scene::cornell();
        assert_eq!(scene.triangles.len(), 10 + 20);
        assert!((scene.extent() - 3f32.sqrt()).abs() < 1e-4);
    }

    /// The first light's cone, for scenes lit by a spot.
    fn cone(scene: &Scene) -> Cone {
        match scene.lights[0].kind {
            LightKind::Spot { cone, .. } => cone,
            _ => panic!("{}: not a spot", scene.lights[0].describe()),
        }
    }

    #[test]
    fn the_light_turns_about_the_vertical_axis() {
        let scene = Scene::cornell();
        let d = cone(&scene).direction;
        let t = cone(&scene.light_turned(90.0)).direction;
        assert!((t.y - d.y).abs() < 1e-6, "{d} -> {t}");
        assert!(
            (t.x - d.z).abs() < 1e-5 && (t.z + d.x).abs() < 1e-5,
            "{d} -> {t}"
        );
    }

    #[test]
    fn every_bundled_scene_loads() {
        for file in BUNDLED_SCENES {
            let scene = Scene::load(&scenes_dir().join(file)).unwrap();
            assert!(
                !scene.lights.is_empty() && !scene.triangles.is_empty(),
                "{file}"
            );
        }
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
        let err = Scene::parse(&both, "bad").unwrap_err();
        assert!(err.contains("more than one"), "{err}");
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
            (good.replace("fov_deg = 39.0", "fov_deg = nan"), "fov_y_deg"),
            (good.replace("[light]", "[lamp]"), "light"),
            ("r_min = 0.1".to_string(), "camera"),
        ];
        for (text, needle) in cases {
            let err = Scene::parse(&text, "bad").unwrap_err();
            assert!(err.contains(needle), "{err} should mention {needle}");
        }
    }

    #[test]
    fn the_gltf_scene_matches_the_cornell_scene() {
        let gltf = Scene::load(&scenes_dir().join("cornell_spot.gltf")).unwrap();
        let toml = Scene::cornell();
        assert_eq!(gltf.triangles.len(), toml.triangles.len());
        let close = |a: [f32; 3], b: [f32; 3], tolerance: f32| {
            Vec3::from(a).abs_diff_eq(Vec3::from(b), tolerance)
        };
        assert!(gltf.camera.position.abs_diff_eq(toml.camera.position, 1e-6));
        assert!((gltf.camera.fov_y_deg - toml.camera.fov_y_deg).abs() < 1e-4);
        let (g, t) = (cone(&gltf), cone(&toml));
        assert!(g.direction.abs_diff_eq(t.direction.normalize(), 1e-5));
        assert_eq!(gltf.lights[0].intensity, toml.lights[0].intensity);
        assert!((g.cone_deg - t.cone_deg).abs() < 1e-4);
        assert!((g.falloff_deg - t.falloff_deg).abs() < 1e-4);
        assert_eq!(gltf.r_min, toml.r_min);
        let (lo, hi) = gltf.bounds();
        assert!(close(lo.to_array(), [0.0; 3], 1e-6) && close(hi.to_array(), [1.0; 3], 1e-6));
        // The same albedos on the same area.
        let albedo_area = |s: &Scene| -> Vec3 {
            s.triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|v| Vec3::from(v.position));
                    Vec3::from(t[0].albedo) * (b - a).cross(c - a).length() * 0.5
                })
                .sum()
        };
        assert!(albedo_area(&gltf).abs_diff_eq(albedo_area(&toml), 1e-4));
    }

    #[test]
    fn every_light_is_kept_in_order_and_a_scene_without_one_is_refused() {
        let three = CORNELL_TOML.replace(
            "[[mesh]]",
            "[[lights]]\nposition = [0.5, 0.5, 0.5]\ncandela = [683, 683, 683]\n\
             [[lights]]\ndirection = [0.2, -1, 0.1]\nlux = [1366, 0, 0]\n[[mesh]]",
        );
        let scene = Scene::parse(&three, "three").unwrap();
        let kinds: Vec<_> = scene.lights.iter().map(Light::kind_name).collect();
        assert_eq!(kinds, ["spot", "point", "directional"]);
        // photometric intensities become radiometric ones
        let radiometric: Vec<_> = scene.lights.iter().map(|l| l.intensity).collect();
        assert_eq!(
            radiometric,
            [
                Intensity::Native(Vec3::splat(2.0)),
                Intensity::Native(Vec3::ONE),
                Intensity::Native(Vec3::new(2.0, 0.0, 0.0))
            ]
        );
        let dark = format!(
            "{}\n[[mesh]]",
            CORNELL_TOML.split("[light]").next().unwrap()
        );
        let err = Scene::parse(
            &dark.replace("[[mesh]]", "[[mesh]]\nbuiltin = \"room\""),
            "dark",
        )
        .unwrap_err();
        assert!(err.contains("no light"), "{err}");
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes");
        let missing = Scene::load(&dir.join("no-such-scene.toml")).unwrap_err();
        assert!(
            missing.to_string().contains("no-such-scene.toml"),
            "{missing}"
        );
    }

    /// The ray tracer's shapes: a box and polygons (with their materials' diffuse colours).
    #[test]
    fn boxes_and_polygons_become_triangles_along_their_winding() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes");
        let demo = std::fs::read_to_string(dir.join("shadows-demo.toml")).unwrap();
        let with_spot = demo.replacen(
            "intensity = [0.7, 0.7, 0.7]",
            "intensity = [0.7, 0.7, 0.7]\ndirection = [-1.5, -3.5, -1.0]\ncone_deg = 40",
            1,
        );
        let scene = Scene::parse_in(&with_spot, "demo", &dir).unwrap();
        // Two boxes (12 triangles each), a tetrahedron (4) and two floor quads (2 each).
        assert_eq!(scene.triangles.len(), 2 * 12 + 4 + 2 * 2);
        for t in &scene.triangles {
            let [a, b, c] = t.map(|v| Vec3::from(v.position));
            let geometric = (b - a).cross(c - a).normalize();
            assert!(geometric.dot(Vec3::from(t[0].normal)) > 0.999, "{t:?}");
        }
        let red = [0.7, 0.15, 0.1];
        assert_eq!(
            scene
                .triangles
                .iter()
                .filter(|t| t[0].albedo == red)
                .count(),
            12 + 4
        );
    }
}
