//! A scene written as glTF (`SceneDescription::to_gltf`) is the scene it was written from as
//! quadray indirect builds it: the same triangles in the same order (positions, normals,
//! albedo), lights, camera and `r_min`, for every bundled scene kind: the sun over polygons and
//! boxes, point lights, a spot, a builtin mesh (written as its mesh), a mesh file placed by a
//! transform, glTF scenes in, and a glTF mesh file with a node tree and an emissive material.

use glam::Vec3;
use quadray_core::scene::SceneDescription;
use quadray_indirect::Scene;
use quadray_indirect::scene::{builtins_as_meshes, scenes_dir};
use std::path::PathBuf;

fn scratch() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("quadray-indirect-gltf-export");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The Blender Cornell box of the bundled meshes (nodes with children, an emissive light
/// panel), placed by a transform and lit by a point light.
const BLENDER_BOX: &str = r#"
[camera]
position = [0.0, 1.0, 4.0]
target = [0.0, 1.0, 0.0]
fov_y_deg = 45.0
[[lights]]
position = [0.0, 1.6, 0.5]
intensity = [1.0, 0.9, 0.8]
[[objects]]
mesh = "../meshes/cornell_box_gltf/cornell-box.glb"
scale = 1.1
rotate_y_deg = 10.0
translate = [0.0, 1.0, 0.0]
"#;

fn same(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    a.abs_diff_eq(b, tolerance * a.abs().max_element().max(1.0))
}

#[test]
fn written_scenes_build_the_same_triangles_lights_and_camera() {
    let dir = scratch();
    let mut scenes: Vec<(String, SceneDescription)> = [
        "courtyard.toml",
        "lamplit_room.toml",
        "leak.toml",
        "cornell.toml",
        "cornell_obj.toml",
        "cornell_spot.gltf",
        "cornell_lights.gltf",
    ]
    .iter()
    .map(|f| {
        let d = SceneDescription::load(&scenes_dir().join(f)).unwrap();
        (f.to_string(), d)
    })
    .collect();
    let blender = SceneDescription::from_toml(BLENDER_BOX, &scenes_dir().join("blender.toml"));
    scenes.push(("blender box".into(), blender.unwrap()));
    for (file, description) in scenes {
        let path = dir.join(format!("{file}.gltf"));
        builtins_as_meshes(&description)
            .unwrap()
            .save_gltf(&path)
            .unwrap();
        let (a, b) = (
            Scene::from_description(&description).unwrap(),
            Scene::load(&path).unwrap(),
        );
        // the reader drops triangles of no area, as the writer does
        let area = |t: &&[quadray_indirect::scene::Vertex; 3]| {
            let [p, q, r] = t.map(|v| Vec3::from(v.position));
            (q - p).cross(r - p) != Vec3::ZERO
        };
        let expected: Vec<_> = a.triangles.iter().filter(area).collect();
        assert_eq!(expected.len(), b.triangles.len(), "{file}: triangles");
        for (i, (s, t)) in expected.iter().zip(&b.triangles).enumerate() {
            for (u, v) in s.iter().zip(t) {
                let vec = |x: [f32; 3]| Vec3::from(x);
                let ok = same(vec(u.position), vec(v.position), 1e-6)
                    && same(vec(u.normal), vec(v.normal), 1e-6)
                    && u.albedo == v.albedo;
                assert!(ok, "{file}: triangle {i}: {u:?} came back as {v:?}");
            }
        }
        assert_eq!(a.lights.len(), b.lights.len(), "{file}: lights");
        for (l, m) in a.lights.iter().zip(&b.lights) {
            let dir = |l: &quadray_indirect::scene::Light| l.direction().map(Vec3::normalize);
            let (i, j) = (l.intensity.radiometric(), m.intensity.radiometric());
            let ok = l.kind_name() == m.kind_name()
                && l.position() == m.position()
                && dir(l).zip(dir(m)).is_none_or(|(d, e)| same(d, e, 1e-5))
                && same(i, j, 1e-6);
            assert!(ok, "{file}: {l:?} came back as {m:?}");
        }
        let (c, d) = (a.camera, b.camera);
        let forward = |c: quadray_indirect::scene::Camera| (c.target - c.position).normalize();
        assert!(
            c.position == d.position && same(forward(c), forward(d), 1e-5),
            "{file}: {c:?} came back as {d:?}"
        );
        assert_eq!(a.r_min, b.r_min, "{file}");
    }
}
