//! A scene written as glTF (`SceneDescription::to_gltf`) reads back as the same scene: the
//! camera's view, every light (kind, place, direction, radiometric intensity, cone), the
//! materials and each technique's settings, for random lights and cameras and for the bundled
//! scenes; a mesh file's texture and emission come back too. What cannot be written is refused
//! by name. (The triangles are held to quadray indirect's own flattening in its tests.)

use glam::{Vec2, Vec3};
use proptest::prelude::*;
use quadray_core::image_out::Rgba8Image;
use quadray_core::mesh::{
    Material as MeshMaterial, Mesh, Model, TextureFilter, TextureSampler, TextureWrap,
};
use quadray_core::scene::{
    Camera, Cone, Intensity, Light, LightKind, Material, Object, SceneDescription, Shape, Transform,
};
use std::path::{Path, PathBuf};

use crate::common::{asset, scratch};

/// `scene` written to `dir/name.gltf` and read back.
fn round_trip(scene: &SceneDescription, dir: &Path, name: &str) -> SceneDescription {
    let path = dir.join(format!("{name}.gltf"));
    scene.save_gltf(&path).unwrap();
    SceneDescription::load(&path).unwrap()
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    a.abs_diff_eq(b, tolerance * a.abs().max_element().max(1.0))
}

/// The same view: where the eye is, where it looks, up made square to the view, the field of
/// view (a glTF camera has no target: the reader puts it one unit ahead).
fn same_camera(a: &Camera, b: &Camera) -> Result<(), String> {
    let forward = |c: &Camera| (c.target - c.position).normalize();
    let up = |c: &Camera| {
        let right = forward(c).cross(c.up).normalize();
        right.cross(forward(c))
    };
    let same = close(a.position, b.position, 1e-6)
        && close(forward(a), forward(b), 1e-5)
        && close(up(a), up(b), 1e-5)
        && (a.fov_y_deg - b.fov_y_deg).abs() < 1e-4;
    same.then_some(())
        .ok_or_else(|| format!("camera {a:?} came back as {b:?}"))
}

/// The same light as a renderer sees it: kind, place, direction (normalised), radiometric
/// intensity, cone.
fn same_light(a: &Light, b: &Light) -> Result<(), String> {
    let direction = |l: &Light| l.direction().map(Vec3::normalize);
    let same_place = match (a.position(), b.position()) {
        (Some(p), Some(q)) => close(p, q, 1e-6),
        (p, q) => p == q,
    };
    let same_direction = match (direction(a), direction(b)) {
        (Some(d), Some(e)) => close(d, e, 1e-5),
        (d, e) => d == e,
    };
    let (i, j) = (a.intensity.radiometric(), b.intensity.radiometric());
    let same_cone = match (a.kind, b.kind) {
        (LightKind::Spot { cone: c, .. }, LightKind::Spot { cone: d, .. }) => {
            (c.cone_deg - d.cone_deg).abs() < 1e-4 && (c.falloff_deg - d.falloff_deg).abs() < 1e-4
        }
        _ => true,
    };
    let same = a.kind_name() == b.kind_name()
        && same_place
        && same_direction
        && i.abs_diff_eq(j, 1e-6 * i.max_element().max(1e-3))
        && same_cone;
    same.then_some(())
        .ok_or_else(|| format!("{a:?} came back as {b:?}"))
}

/// Camera, lights and settings of `a` and `b` the same.
fn same_scene(a: &SceneDescription, b: &SceneDescription) -> Result<(), String> {
    same_camera(&a.camera, &b.camera)?;
    if a.lights.len() != b.lights.len() {
        return Err(format!(
            "{} lights came back as {}",
            a.lights.len(),
            b.lights.len()
        ));
    }
    for (l, m) in a.lights.iter().zip(&b.lights) {
        same_light(l, m)?;
    }
    if a.techniques != b.techniques {
        return Err(format!(
            "{:?} came back as {:?}",
            a.techniques, b.techniques
        ));
    }
    Ok(())
}

/// What a written scene's materials are: per named material or mesh-file material its name,
/// base colour and emission (glTF's `white` for the shapes without one).
fn materials_of(scene: &SceneDescription) -> Vec<(String, Vec3, Vec3)> {
    let mut found = Vec::new();
    for object in &scene.objects {
        match (&object.shape, object.material) {
            (_, Some(m)) => {
                let (name, material) = &scene.materials[m];
                found.push((name.clone(), material.diffuse, Vec3::ZERO));
            }
            (Shape::Mesh { model, .. }, None) => {
                for mesh in &model.meshes {
                    let m = &model.materials[mesh.material];
                    found.push((m.name.clone(), m.base_color, m.emission));
                }
            }
            _ => found.push(("white".into(), Vec3::ONE, Vec3::ZERO)),
        }
    }
    sorted(found)
}

/// Materials in name, then colour order, each once.
fn sorted(mut materials: Vec<(String, Vec3, Vec3)>) -> Vec<(String, Vec3, Vec3)> {
    let key = |m: &(String, Vec3, Vec3)| (m.0.clone(), m.1.to_array(), m.2.to_array());
    materials.sort_by(|a, b| key(a).partial_cmp(&key(b)).expect("finite colours"));
    materials.dedup();
    materials
}

/// The one mesh object a glTF scene reads as.
fn model_of(scene: &SceneDescription) -> &Model {
    match &scene.objects[..] {
        [
            Object {
                shape: Shape::Mesh { model, .. },
                ..
            },
        ] => model,
        other => panic!("a glTF scene is one mesh object, not {other:?}"),
    }
}

/// Every bundled scene kind without a technique's builtin mesh (those are replaced by their mesh
/// first; quadray indirect's tests write them): the sun with polygons and boxes, point lights,
/// a spot, a mesh file placed by a transform, glTF scenes in (photometric lights, all three
/// kinds), and the ray tracer's Whitted materials.
#[test]
fn bundled_scenes_read_back_as_the_same_scene() {
    let dir = scratch("gltf-export-bundled");
    for file in [
        "courtyard.toml",
        "lamplit_room.toml",
        "leak.toml",
        "cornell_obj.toml",
        "cornell_spot.gltf",
        "cornell_lights.gltf",
        "shadows-demo.toml",
    ] {
        let scene = SceneDescription::load(&asset("scenes").join(file)).unwrap();
        let back = round_trip(&scene, &dir, file);
        same_scene(&scene, &back).unwrap_or_else(|e| panic!("{file}: {e}"));
        let model = model_of(&back);
        let used = model.meshes.iter().map(|m| &model.materials[m.material]);
        let written = sorted(
            used.map(|m| (m.name.clone(), m.base_color, m.emission))
                .collect(),
        );
        let clamped = materials_of(&scene)
            .into_iter()
            .map(|(name, base, emission)| (name, base.clamp(Vec3::ZERO, Vec3::ONE), emission))
            .collect();
        let expected = sorted(clamped);
        assert_eq!(written, expected, "{file}");
    }
}

fn finite_vec3(range: f32) -> impl Strategy<Value = Vec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A direction: random, or along an axis (the turn from -z is singular opposite it).
fn direction() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        finite_vec3(1.0).prop_filter("not zero", |d| d.length() > 0.05),
        Just(Vec3::NEG_Z),
        Just(Vec3::Z),
        Just(Vec3::Y),
        Just(Vec3::NEG_Y),
    ]
}

fn intensity() -> impl Strategy<Value = Intensity> {
    (finite_vec3(1.0), 0.0f32..5000.0, any::<bool>()).prop_map(|(c, scale, native)| {
        let v = c.abs() * scale;
        if native {
            Intensity::Native(v)
        } else {
            Intensity::Photometric(v)
        }
    })
}

/// Any light `Light::validate` accepts: a sharp cone (falloff 0) and a half-space (90
/// degrees) among the spots.
fn light() -> impl Strategy<Value = Light> {
    let cone = (
        prop_oneof![0.5f32..90.0, Just(90.0)],
        prop_oneof![0.0f32..1.0, Just(0.0), Just(1.0)],
    );
    (0..3, finite_vec3(100.0), direction(), cone, intensity()).prop_map(
        |(kind, position, direction, (cone_deg, falloff), intensity)| {
            let kind = match kind {
                0 => LightKind::Point { position },
                1 => LightKind::Spot {
                    position,
                    cone: Cone {
                        direction,
                        cone_deg,
                        falloff_deg: falloff * cone_deg,
                    },
                },
                _ => LightKind::Directional { direction },
            };
            Light { kind, intensity }
        },
    )
}

fn camera() -> impl Strategy<Value = Camera> {
    (finite_vec3(50.0), direction(), direction(), 1.0f32..179.0)
        .prop_filter("up not along the view", |(_, view, up, _)| {
            view.normalize().cross(up.normalize()).length() > 0.05
        })
        .prop_map(|(position, view, up, fov_y_deg)| Camera {
            position,
            target: position + view * 3.0,
            up,
            fov_y_deg,
        })
}

/// A scene of one box with `camera` and `lights`.
fn boxed(camera: Camera, lights: Vec<Light>) -> SceneDescription {
    SceneDescription {
        name: "random".into(),
        camera,
        lights,
        materials: vec![("grey".into(), Material::diffuse(Vec3::splat(0.5)))],
        objects: vec![Object {
            shape: Shape::Box {
                min: Vec3::ZERO,
                max: Vec3::ONE,
            },
            transform: Transform::IDENTITY,
            material: Some(0),
        }],
        techniques: Default::default(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Whatever the lights and the camera, they come back as they were: the writer is the
    /// reader's inverse (units, cone angles, the -z a light and a camera look down).
    #[test]
    fn random_lights_and_cameras_come_back(
        camera in camera(),
        lights in proptest::collection::vec(light(), 0..4),
    ) {
        for l in &lights {
            prop_assume!(l.validate().is_ok());
        }
        let scene = boxed(camera, lights);
        let back = round_trip(&scene, &scratch_dir(), "random");
        prop_assert_eq!(same_scene(&scene, &back), Ok(()));
    }
}

/// One folder for every case of the property test (each case overwrites the file).
fn scratch_dir() -> PathBuf {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| scratch("gltf-export-random")).clone()
}

/// A mesh file's material comes back whole: base colour, its texture texel for texel with the
/// texture coordinates, emission (above 1 through `KHR_materials_emissive_strength`); the
/// transform is applied to the vertices.
#[test]
fn a_textured_emissive_mesh_comes_back() {
    let texture = Rgba8Image {
        width: 2,
        height: 2,
        pixels: vec![
            [255, 0, 0, 255],
            [0, 255, 0, 255],
            [0, 0, 255, 255],
            [9, 99, 199, 255],
        ],
    };
    let uvs = vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
    let sampler = TextureSampler {
        filter: TextureFilter::Nearest,
        wrap_u: TextureWrap::ClampToEdge,
        wrap_v: TextureWrap::MirroredRepeat,
    };
    let model = Model {
        meshes: vec![Mesh {
            name: "quad".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            normals: vec![Vec3::Z; 4],
            uvs: Some(uvs.clone()),
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material: 0,
        }],
        materials: vec![
            MeshMaterial {
                name: "lamp".into(),
                base_color: Vec3::new(0.5, 0.25, 1.0),
                base_color_texture: Some(texture.clone()),
                base_color_sampler: sampler,
                emission: Vec3::new(4.0, 2.0, 1.0),
                ..MeshMaterial::default()
            },
            MeshMaterial::default(),
        ],
    };
    let mut scene = boxed(
        Camera {
            position: Vec3::new(0.5, 0.5, 3.0),
            target: Vec3::splat(0.5),
            up: Vec3::Y,
            fov_y_deg: 40.0,
        },
        Vec::new(),
    );
    scene.objects = vec![Object {
        shape: Shape::Mesh {
            path: "quad.gltf".into(),
            model: Box::new(model),
        },
        transform: Transform {
            scale: 2.0,
            rotate_y_deg: 90.0,
            translate: Vec3::new(0.0, 1.0, 0.0),
        },
        material: None,
    }];
    let back = round_trip(&scene, &scratch("gltf-export-texture"), "quad");
    let model = model_of(&back);
    let mesh = &model.meshes[0];
    let material = &model.materials[mesh.material];
    assert_eq!(material.name, "lamp");
    assert_eq!(material.base_color, Vec3::new(0.5, 0.25, 1.0));
    assert_eq!(material.emission, Vec3::new(4.0, 2.0, 1.0));
    assert_eq!(material.base_color_texture.as_ref(), Some(&texture));
    assert_eq!(material.base_color_sampler, sampler);
    assert_eq!(mesh.uvs.as_ref(), Some(&uvs));
    // scaled 2, turned so that +x becomes -z, lifted 1
    assert!(
        close(mesh.positions[1], Vec3::new(0.0, 1.0, -2.0), 1e-6),
        "{:?}",
        mesh.positions
    );
    assert!(close(mesh.normals[0], Vec3::X, 1e-6), "{:?}", mesh.normals);
}

/// A builtin mesh (a technique's, not the scene's), a scene with no triangles and a file that is
/// not a `.gltf` are refused, each by name.
#[test]
fn what_cannot_be_written_is_refused_by_name() {
    let dir = scratch("gltf-export-refused");
    let cornell = SceneDescription::load(&asset("scenes/cornell.toml")).unwrap();
    let err = cornell.to_gltf().unwrap_err();
    assert!(
        err.contains("object 0") && err.contains("builtin `cornell`"),
        "{err}"
    );
    let mut empty = cornell.clone();
    empty.objects.clear();
    let err = empty.to_gltf().unwrap_err();
    assert!(err.contains("no triangles"), "{err}");
    let courtyard = SceneDescription::load(&asset("scenes/courtyard.toml")).unwrap();
    let glb = dir.join("courtyard.glb");
    let err = courtyard.save_gltf(&glb).unwrap_err().to_string();
    assert!(
        err.contains("courtyard.glb") && err.contains(".gltf"),
        "{err}"
    );
    assert!(!glb.exists());
}
