//! One scene description for every technique: a camera, point, spot and directional lights, named materials
//! and objects (mesh files, a technique's builtin meshes, boxes, polygons) with their transforms,
//! plus the few per-scene settings. Read from TOML ([`SceneDescription::from_toml`]) or glTF 2.0
//! ([`SceneDescription::load`] on a `.gltf` or `.glb`); each technique builds its own runtime scene
//! from it.
//!
//! # TOML
//!
//! The canonical spelling for new files (`assets/scenes/shadows-demo.toml` is a full example):
//!
//! ```toml
//! name = "demo"                  # default: the file's stem
//!
//! [indirect]                     # quadray indirect's own settings
//! r_min = 0.05                   # clamp of the VPL kernel (default 0.05)
//!
//! [raytrace]                     # quadray raytrace's own settings
//! ambient = [0.08, 0.08, 0.08]   # ambient light (default 0.08)
//! background = [0.0, 0.0, 0.0]   # colour of rays that leave (default dark blue)
//!
//! [camera]
//! position = [0.5, 0.5, 2.4]
//! target = [0.5, 0.5, 0.0]
//! up = [0.0, 1.0, 0.0]           # default +y
//! fov_y_deg = 39.0               # vertical field of view
//!
//! [[lights]]                     # a point light; any number
//! position = [0.5, 0.97, 0.85]
//! intensity = [2.0, 2.0, 2.0]    # in the renderer's own units, or `candela = [...]` (as glTF)
//! direction = [-0.25, -1.0, -0.55]  # these three make it a spot light:
//! cone_deg = 55.0                #   half-angle where the light ends
//! falloff_deg = 15.0             #   width of the smooth edge inside the cone (default 0)
//!
//! [[lights]]                     # a direction without a position: a directional light (the sun)
//! direction = [-0.3, -1.0, -0.2] # where its light travels
//! intensity = [3.0, 3.0, 3.0]    # irradiance on a surface facing it, or `lux = [...]`
//!
//! [materials.porcelain]          # Whitted surfaces, referred to by name
//! diffuse = [0.8, 0.75, 0.65]
//! specular = 0.5                 # default 0; shininess 32, reflect 0, transmit 0, ior 1
//!
//! [[objects]]                    # one shape each: mesh, builtin, box or polygons
//! mesh = "../meshes/stanford_bunny/stanford-bunny.obj"  # OBJ, glTF or PLY, relative to the file
//! material = "porcelain"         # or `albedo = [r, g, b]`; none keeps the mesh's own colours
//! scale = 2.5                    # uniform; then rotate_y_deg, then translate
//! rotate_y_deg = 0.0
//! translate = [0.54, -0.08, 0.5]
//!
//! [[objects]]
//! builtin = "room"               # a technique's procedural mesh (quadray indirect: cornell,
//!                                # room, blocks, atrium)
//! [[objects]]
//! box = { min = [0, 0, 0], max = [1, 1, 1] }  # world coordinates, no transform
//! material = "porcelain"
//! [[objects]]
//! polygons = [[[0, 0, 0], [1, 0, 0], [1, 1, 0]]]  # convex, planar, world coordinates
//! material = "porcelain"
//! ```
//!
//! The older spellings stay accepted, so every bundled file loads unchanged: `eye`, `look_at`,
//! `fov_deg` in `[camera]`; a single `[light]` table (listed before `[[lights]]`); `[[mesh]]` for
//! `[[objects]]` and `path` for `mesh`.
//!
//! # glTF
//!
//! A `.gltf` or `.glb` scene gives one object (every mesh of the shown scene, placed by its node
//! transforms, with its materials' base colours), the first perspective camera met in the node
//! tree (required, but [`SceneDescription::load_framing`] makes one that frames the meshes; its
//! aspect ratio is ignored, the image size decides), and every
//! `KHR_lights_punctual` light: point, spot and directional (`range` is ignored). Their
//! intensities are [`Intensity::Photometric`]: colour times intensity.
//!
//! [`SceneDescription::to_gltf`] writes a scene as one `.gltf` that this reader reads back as the
//! same scene: every object's triangles in world coordinates with matte materials, the camera,
//! and every light as a `KHR_lights_punctual` light (see its docs for what changes form).

mod read_gltf;
mod read_toml;
mod write_gltf;

use crate::FileError;
use crate::mesh::Model;
use glam::{Mat4, Vec3};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A scene as read from a file, before a technique builds its own geometry from it.
#[derive(Clone, Debug)]
pub struct SceneDescription {
    /// The file's `name`, else its stem.
    pub name: String,
    /// The view.
    pub camera: Camera,
    /// Point, spot and directional lights in file order.
    pub lights: Vec<Light>,
    /// Named materials, sorted by name, then the anonymous ones of `albedo = [...]`; objects
    /// refer to them by index.
    pub materials: Vec<(String, Material)>,
    /// Everything that is drawn.
    pub objects: Vec<Object>,
    /// Each technique's own scene settings, by the technique's name: the file's table of that
    /// name (`[indirect]`, `[raytrace]`), for the technique to read with
    /// [`SceneDescription::technique_settings`]; in glTF, the default scene's `extras` of that
    /// name.
    pub techniques: BTreeMap<String, toml::Table>,
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Where the eye is.
    pub position: Vec3,
    /// A point the camera looks at.
    pub target: Vec3,
    /// Up on the screen (need not be at right angles to the view direction).
    pub up: Vec3,
    /// Vertical field of view, in (0, 180).
    pub fov_y_deg: f32,
}

/// A light: where it shines from (a point, a spot's apex, or a direction for the sun) and how
/// strongly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Its kind, with where it is.
    pub kind: LightKind,
    /// Per RGB channel: intensity for point and spot lights (on the axis for a spot), irradiance
    /// on a surface facing a directional light.
    pub intensity: Intensity,
}

/// The three punctual lights of glTF's `KHR_lights_punctual`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Shines equally in all directions from `position`.
    Point {
        /// Where the light is.
        position: Vec3,
    },
    /// Shines from `position` within a cone.
    Spot {
        /// The apex of the cone.
        position: Vec3,
        /// The cone.
        cone: Cone,
    },
    /// Parallel light from infinitely far away (the sun).
    Directional {
        /// Where the light travels (not necessarily unit length).
        direction: Vec3,
    },
}

/// The cone of a spot light: full intensity inside `cone_deg - falloff_deg` of its axis, fading
/// smoothly to zero at `cone_deg`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Direction of the axis (not necessarily unit length).
    pub direction: Vec3,
    /// Half-angle of the cone, in (0, 90].
    pub cone_deg: f32,
    /// In [0, cone_deg].
    pub falloff_deg: f32,
}

/// A light's strength per RGB channel: intensity (point and spot lights; for a spot, on its axis)
/// or irradiance (directional lights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Intensity {
    /// As a TOML file's `intensity` gives it: in the units of the renderer it is written for.
    Native(Vec3),
    /// Photometric, as glTF's `KHR_lights_punctual` gives it (or a TOML file's `candela` or
    /// `lux`): candela for point and spot lights, lux for directional ones; each renderer
    /// documents how it converts them to its own units.
    Photometric(Vec3),
}

/// Luminous efficacy of 555 nm light (lm/W): the factor between candela and W/sr.
pub const LUMENS_PER_WATT: f32 = 683.0;

impl Intensity {
    /// Radiometric values (W/sr per channel for point and spot lights, W/m^2 for directional
    /// ones): native values as given, photometric ones divided by [`LUMENS_PER_WATT`].
    pub fn radiometric(self) -> Vec3 {
        match self {
            Intensity::Native(v) => v,
            Intensity::Photometric(v) => v / LUMENS_PER_WATT,
        }
    }
}

/// Whitted's surface: local diffuse + Blinn-Phong specular, mirror reflection and refraction.
/// A renderer without some of these (quadray indirect: diffuse only) ignores them.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Linear RGB albedo.
    pub diffuse: Vec3,
    /// Blinn-Phong specular weight (default 0).
    #[serde(default)]
    pub specular: f32,
    /// Blinn-Phong exponent (default 32).
    #[serde(default = "default_shininess")]
    pub shininess: f32,
    /// Weight of the mirror reflection (default 0).
    #[serde(default)]
    pub reflect: f32,
    /// Weight of the refracted ray (default 0).
    #[serde(default)]
    pub transmit: f32,
    /// Index of refraction (default 1).
    #[serde(default = "default_ior")]
    pub ior: f32,
}

fn default_shininess() -> f32 {
    32.0
}
fn default_ior() -> f32 {
    1.0
}

impl Material {
    /// A dull surface of colour `diffuse` with a faint highlight (the ray tracer's builtin
    /// scenes' walls and tables).
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

    /// A plain diffuse surface (what `albedo = [...]` means).
    pub fn diffuse(diffuse: Vec3) -> Self {
        Self {
            diffuse,
            specular: 0.0,
            shininess: default_shininess(),
            reflect: 0.0,
            transmit: 0.0,
            ior: default_ior(),
        }
    }
}

/// One shape placed in the scene.
#[derive(Clone, Debug)]
pub struct Object {
    /// What it is made of.
    pub shape: Shape,
    /// Identity for boxes and polygons (written in world coordinates).
    pub transform: Transform,
    /// Index into [`SceneDescription::materials`]; `None` keeps the shape's own colours.
    pub material: Option<usize>,
}

/// What an object is made of.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A technique's procedural mesh, by name; the technique says which names it knows.
    Builtin(String),
    /// A mesh file, loaded (glTF node transforms already applied).
    Mesh {
        /// The file, as the scene names it (joined to the scene's directory).
        path: PathBuf,
        /// Its meshes and materials.
        model: Box<Model>,
    },
    /// An axis-aligned box, closed.
    Box {
        /// The lowest corner.
        min: Vec3,
        /// The highest corner.
        max: Vec3,
    },
    /// Convex planar polygons, vertices in order.
    Polygons(Vec<Vec<Vec3>>),
}

impl Shape {
    /// The faces of a box seen from outside, each four corners (numbered as in
    /// [`Shape::box_corner`]) counter-clockwise: top (+y), bottom, front (+z), back, left (-x),
    /// right. The one cut of a box into faces, so that a box written to glTF is the box a
    /// technique builds.
    pub const BOX_FACES: [[usize; 4]; 6] = [
        [6, 7, 3, 2],
        [0, 1, 5, 4],
        [4, 5, 7, 6],
        [1, 0, 2, 3],
        [0, 4, 6, 2],
        [5, 1, 3, 7],
    ];

    /// Corner `i` of the box from `min` to `max`: bits 0, 1, 2 of `i` pick `max` in x, y, z.
    pub fn box_corner(min: Vec3, max: Vec3, i: usize) -> Vec3 {
        let picks = glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0);
        Vec3::select(picks, max, min)
    }

    /// The corners of [`Shape::BOX_FACES`] of the box from `min` to `max`.
    pub fn box_faces(min: Vec3, max: Vec3) -> [[Vec3; 4]; 6] {
        Self::BOX_FACES.map(|face| face.map(|i| Self::box_corner(min, max, i)))
    }

    /// The unit normal of a planar polygon (Newell's, so the winding decides the side: vertices
    /// counter-clockwise seen from where it points); zero for a polygon of no area.
    pub fn polygon_normal(polygon: &[Vec3]) -> Vec3 {
        let n = polygon.len();
        (0..n)
            .map(|i| polygon[i].cross(polygon[(i + 1) % n]))
            .sum::<Vec3>()
            .normalize_or_zero()
    }
}

/// Uniform scale, then a turn about +y, then a translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Uniform scale, > 0.
    pub scale: f32,
    /// Turn about +y, counter-clockwise seen from above.
    pub rotate_y_deg: f32,
    /// Offset.
    pub translate: Vec3,
}

impl Transform {
    /// Leaves everything where it is.
    pub const IDENTITY: Transform = Transform {
        scale: 1.0,
        rotate_y_deg: 0.0,
        translate: Vec3::ZERO,
    };

    /// Object -> world for points.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_translation(self.translate)
            * self.rotation()
            * Mat4::from_scale(Vec3::splat(self.scale))
    }

    /// Object -> world for normals (the scale is uniform, so the turn alone).
    pub fn rotation(&self) -> Mat4 {
        Mat4::from_rotation_y(self.rotate_y_deg.to_radians())
    }
}

impl SceneDescription {
    /// Reads a scene file: glTF 2.0 for `.gltf` and `.glb`, TOML otherwise. Errors name the file.
    pub fn load(path: &Path) -> Result<Self, FileError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("gltf" | "glb") => return read_gltf::load(path, false).map(|(scene, _)| scene),
            Some("obj" | "ply") => {
                return Err(FileError::new(
                    path,
                    "a mesh file, not a scene: give a scene that places it with a camera and a \
                     light (TOML: [camera], [[lights]] and [[objects]] mesh = \"FILE\", see \
                     docs/scenes.md), or a glTF file with a camera and a light",
                ));
            }
            _ => {}
        }
        let text = std::fs::read_to_string(path).map_err(|e| FileError::new(path, e))?;
        Self::from_toml(&text, path)
    }

    /// As [`SceneDescription::load`], but a glTF scene without a camera is given
    /// [`Camera::framing`] its meshes instead of being refused; `true` with a camera so made.
    /// (For a viewer of any glTF file; a renderer's scene names its view.)
    pub fn load_framing(path: &Path) -> Result<(Self, bool), FileError> {
        let gltf = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
        if gltf {
            return read_gltf::load(path, true);
        }
        Ok((Self::load(path)?, false))
    }

    /// `technique`'s own settings from its table (its defaults where the file has none); a key
    /// the technique does not know is an error that names the table.
    pub fn technique_settings<T: serde::de::DeserializeOwned + Default>(
        &self,
        technique: &str,
    ) -> Result<T, String> {
        match self.techniques.get(technique) {
            None => Ok(T::default()),
            Some(table) => table
                .clone()
                .try_into()
                .map_err(|e| format!("[{technique}]: {}", e.to_string().trim())),
        }
    }

    /// The scene as a glTF 2.0 file's text (JSON, its one buffer embedded as a base64 `data:`
    /// URI, so the file stands alone), which [`SceneDescription::load`] reads back as this scene:
    ///
    /// - every object a node with one mesh, its triangles in world coordinates (the transform
    ///   applied: boxes cut as [`Shape::box_faces`], polygons into fans, zero-area triangles left
    ///   out) with normals, and texture coordinates where a mesh's material has a texture;
    /// - materials matte (metallic 0, roughness 1): a named material's `diffuse`, or a mesh
    ///   file's base colour, texture and emission, as the base colour (clamped to [0, 1] as glTF
    ///   requires); the Whitted fields (specular, reflect, transmit, ior) are left out;
    /// - the camera a node looking down its -z with its +y up: `target` becomes the point one
    ///   unit ahead and `up` is made square to the view (the same view); no aspect ratio (the
    ///   picture's decides), `znear` a thousandth of the scene's extent;
    /// - every light a `KHR_lights_punctual` light on a node (a spot and the sun shining down its
    ///   -z), its intensity photometric as the reader takes it: [`Intensity::Photometric`] as
    ///   it is, [`Intensity::Native`] read as radiometric and times [`LUMENS_PER_WATT`] (so
    ///   [`Intensity::radiometric`] gives the same back); colour times intensity, the brightest
    ///   channel 1 in the colour; a spot's `cone_deg` the outer angle and `cone_deg -
    ///   falloff_deg` the inner one (glTF wants inner < outer: a zero falloff is written one
    ///   float step wide);
    /// - each technique's settings in the scene's `extras`.
    ///
    /// A builtin mesh is a technique's, which the scene does not hold: replace it by its mesh
    /// first (quadray indirect's `builtins_as_meshes`), or it is an error.
    pub fn to_gltf(&self) -> Result<String, String> {
        write_gltf::write(self)
    }

    /// Writes [`SceneDescription::to_gltf`] to `path` (a `.gltf`), creating its folder.
    pub fn save_gltf(&self, path: &Path) -> Result<(), FileError> {
        let gltf_extension = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
        if !gltf_extension {
            return Err(FileError::new(
                path,
                "a scene is written as a .gltf (JSON, the buffer embedded)",
            ));
        }
        let text = self.to_gltf().map_err(|e| FileError::new(path, e))?;
        crate::write_text(path, &text)
    }

    /// Parses TOML scene text. `path` names the scene in errors, its directory is where mesh
    /// paths start, and its stem is the default name.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, FileError> {
        read_toml::parse(text, path).map_err(|reason| FileError::new(path, reason))
    }
}

/// The default name of a scene read from `path`.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into())
}

/// Checks what holds for every scene, whatever file it came from.
impl Camera {
    /// [`Camera::framing`]'s field of view.
    pub const FRAMING_FOV_Y_DEG: f32 = 45.0;

    /// A camera that sees all of `bounds` (min, max): looking at their middle along -z with +y
    /// up, from as far as puts their enclosing sphere inside [`Camera::FRAMING_FOV_Y_DEG`].
    pub fn framing((min, max): (Vec3, Vec3)) -> Self {
        let centre = min.midpoint(max);
        let radius = (0.5 * min.distance(max)).max(1e-3);
        let half_fov = (0.5 * Self::FRAMING_FOV_Y_DEG).to_radians();
        Self {
            position: centre + Vec3::Z * (radius / half_fov.sin()),
            target: centre,
            up: Vec3::Y,
            fov_y_deg: Self::FRAMING_FOV_Y_DEG,
        }
    }

    /// [`Camera::fov_y_deg`]: a picture needs some, a pinhole cannot reach 180.
    pub const FOV_Y: crate::settings::Limits<f32> = crate::settings::Limits::above(0.0, 179.0);

    /// The one check of a camera, whichever technique renders it: finite, within the coordinates
    /// a mesh may have, looking somewhere, its field of view within [`Camera::FOV_Y`].
    pub fn validate(&self) -> Result<(), String> {
        let c = self;
        if !(c.position.is_finite() && c.target.is_finite() && c.up.is_finite()) {
            return Err("camera: a coordinate is not finite".into());
        }
        if let Some((i, far)) = crate::mesh::FarCoordinate::find([c.position, c.target]) {
            return Err(format!("camera: {} {far}", ["position", "target"][i]));
        }
        if c.position.distance(c.target) < 1e-6 {
            return Err("camera: position and target are the same point".into());
        }
        if c.up.cross(c.target - c.position) == Vec3::ZERO {
            return Err("camera: up is zero or along the view".into());
        }
        Self::FOV_Y.check("camera: fov_y_deg", c.fov_y_deg)?;
        Ok(())
    }
}

impl Light {
    /// Where the light is: `None` for a directional light.
    pub fn position(&self) -> Option<Vec3> {
        match self.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } => Some(position),
            LightKind::Directional { .. } => None,
        }
    }

    /// Where the light aims: a spot's axis, the sun's direction; `None` for a point light.
    pub fn direction(&self) -> Option<Vec3> {
        match self.kind {
            LightKind::Spot { cone, .. } => Some(cone.direction),
            LightKind::Directional { direction } => Some(direction),
            LightKind::Point { .. } => None,
        }
    }

    /// Aims a spot or the sun along `direction`; `false` (and nothing changed) for a point light.
    pub fn aim(&mut self, direction: Vec3) -> bool {
        match &mut self.kind {
            LightKind::Spot { cone, .. } => cone.direction = direction,
            LightKind::Directional { direction: d } => *d = direction,
            LightKind::Point { .. } => return false,
        }
        true
    }

    /// Moves a point or spot light to `position`; `false` (and nothing changed) for the sun.
    pub fn place(&mut self, position: Vec3) -> bool {
        match &mut self.kind {
            LightKind::Point { position: p } | LightKind::Spot { position: p, .. } => *p = position,
            LightKind::Directional { .. } => return false,
        }
        true
    }

    /// The light's kind in a word (`point`, `spot`, `directional`), for messages.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            LightKind::Point { .. } => "point",
            LightKind::Spot { .. } => "spot",
            LightKind::Directional { .. } => "directional",
        }
    }

    /// The light turned `degrees` about the vertical axis through `pivot` (counter-clockwise
    /// seen from above): a point light moves, a spot moves and turns, the sun turns.
    pub fn turned(&self, degrees: f32, pivot: Vec3) -> Self {
        let turn = glam::Quat::from_rotation_y(degrees.to_radians());
        let kind = match self.kind {
            LightKind::Point { position } => LightKind::Point {
                position: pivot + turn * (position - pivot),
            },
            LightKind::Spot { position, cone } => LightKind::Spot {
                position,
                cone: Cone {
                    direction: turn * cone.direction,
                    ..cone
                },
            },
            LightKind::Directional { direction } => LightKind::Directional {
                direction: turn * direction,
            },
        };
        Self { kind, ..*self }
    }

    /// The one check of a light, whichever technique renders it: finite, not negative, within
    /// the coordinates a mesh may have, a direction that is not zero, a valid cone.
    pub fn validate(&self) -> Result<(), String> {
        let (Intensity::Native(i) | Intensity::Photometric(i)) = self.intensity;
        let what = self.describe();
        if !i.is_finite() {
            return Err(format!("{what}: intensity is not finite"));
        }
        if i.min_element() < 0.0 {
            return Err(format!("{what}: intensity is negative"));
        }
        match self.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. }
                if !position.is_finite() =>
            {
                Err(format!("{what}: position is not finite"))
            }
            // as far as a mesh's vertices may be: beyond, f32 projections lose the scene
            LightKind::Point { position } | LightKind::Spot { position, .. }
                if position.abs().max_element() > crate::mesh::MAX_COORDINATE =>
            {
                Err(format!(
                    "{what}: position is beyond {} in a coordinate",
                    crate::mesh::MAX_COORDINATE
                ))
            }
            LightKind::Spot { cone, .. } => cone.validate().map_err(|e| format!("{what}: {e}")),
            LightKind::Directional { direction } => {
                check_direction(direction).map_err(|e| format!("{what}: {e}"))
            }
            LightKind::Point { .. } => Ok(()),
        }
    }

    /// "point light at (x, y, z)", "directional light along (x, y, z)": the light in messages.
    pub fn describe(&self) -> String {
        match self.kind {
            LightKind::Point { position } | LightKind::Spot { position, .. } => {
                format!("{} light at {position}", self.kind_name())
            }
            LightKind::Directional { direction } => format!("directional light along {direction}"),
        }
    }
}

/// A direction must be finite and not zero.
fn check_direction(direction: Vec3) -> Result<(), String> {
    if direction.is_finite() && direction.length() > 1e-6 {
        Ok(())
    } else {
        Err("direction must be finite and not zero".into())
    }
}

impl Cone {
    /// [`Cone::cone_deg`]: a cone, at most a half-space.
    pub const CONE: crate::settings::Limits<f32> = crate::settings::Limits::above(0.0, 90.0);

    /// The one check of a spot's cone, whichever technique renders it: a finite axis that is not
    /// zero, the cone within [`Cone::CONE`], the falloff within the cone.
    pub fn validate(&self) -> Result<(), String> {
        check_direction(self.direction)?;
        Self::CONE.check("cone_deg", self.cone_deg)?;
        if !(self.falloff_deg >= 0.0 && self.falloff_deg <= self.cone_deg) {
            return Err(format!(
                "falloff_deg {} is not in [0, cone_deg]",
                self.falloff_deg
            ));
        }
        Ok(())
    }
}
