//! The scene description: every bundled scene file, the two older TOML spellings against the
//! canonical one, the bundled glTF scene, a glTF file without a camera framed, and bad input (malformed glTF, no camera, transforms
//! that overflow, bad values) refused with the file named, never a panic.

use glam::{Mat4, Vec3};
use quadray_core::scene::{Intensity, Light, LightKind, SceneDescription, Shape, Transform};
use std::path::{Path, PathBuf};

use crate::common;

use common::{asset, scratch};

fn refused(path: &Path) -> String {
    match SceneDescription::load(path) {
        Ok(_) => panic!("{} loaded, expected an error", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_bundled_scene_file_loads() {
    // (file, lights, spot lights, objects, named materials)
    let expected = [
        ("atrium.toml", 1, 1, 1, 0),
        ("cornell.toml", 1, 1, 1, 0),
        ("cornell_buddha.toml", 1, 1, 2, 1),
        ("cornell_bunny.toml", 1, 1, 2, 1),
        ("cornell_lights.gltf", 3, 1, 1, 0),
        ("cornell_obj.toml", 1, 1, 1, 0),
        ("cornell_spot.gltf", 1, 1, 1, 0),
        ("courtyard.gltf", 1, 0, 1, 0),
        ("courtyard.toml", 1, 0, 11, 4),
        ("example-gi.toml", 1, 1, 10, 10),
        ("example-hst.toml", 2, 0, 5, 4),
        ("lamplit_room.gltf", 3, 0, 1, 0),
        ("lamplit_room.toml", 3, 0, 14, 4),
        ("leak.toml", 1, 1, 9, 2),
        ("shadows-buddha.toml", 3, 0, 2, 1),
        ("shadows-bunny.toml", 3, 0, 2, 1),
        ("shadows-cornell.toml", 3, 0, 1, 0),
        ("shadows-demo.toml", 2, 0, 4, 3),
        ("skinned_bar.gltf", 1, 1, 1, 0),
        ("textured_floor.gltf", 1, 1, 1, 0),
        ("visibility-corridor.toml", 1, 1, 10, 3),
        ("visibility-door.gltf", 1, 1, 1, 0),
        ("visibility-door.toml", 1, 1, 11, 4),
        ("visibility-gap.toml", 1, 1, 7, 3),
        ("visibility-pillars.toml", 1, 1, 11, 3),
        ("visibility-shelf.toml", 1, 1, 6, 4),
        ("visibility-storeys.toml", 1, 1, 11, 4),
    ];
    // (the textures beside the scenes are not scenes)
    let mut files: Vec<String> = std::fs::read_dir(asset("scenes"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| !name.ends_with(".png"))
        .collect();
    files.sort();
    let listed: Vec<&str> = expected.iter().map(|e| e.0).collect();
    assert_eq!(
        files, listed,
        "every scene file in assets/scenes is checked here"
    );
    for (file, lights, spots, objects, materials) in expected {
        let d = SceneDescription::load(&asset("scenes").join(file)).unwrap();
        assert_eq!(d.lights.len(), lights, "{file}");
        let spot_count = d.lights.iter().filter(|l| l.kind_name() == "spot").count();
        assert_eq!(spot_count, spots, "{file}");
        assert_eq!(d.objects.len(), objects, "{file}");
        assert_eq!(d.materials.len(), materials, "{file}");
    }
}

#[test]
fn the_older_spellings_read_as_the_canonical_one() {
    let canonical = r#"
        [camera]
        position = [0.5, 0.5, 2.4]
        target = [0.5, 0.5, 0.0]
        fov_y_deg = 39.0
        [[lights]]
        position = [0.5, 0.97, 0.85]
        intensity = [2.0, 2.0, 2.0]
        direction = [-0.25, -1.0, -0.55]
        cone_deg = 55.0
        falloff_deg = 15.0
        [[objects]]
        builtin = "room"
        albedo = [0.5, 0.5, 0.5]
        [[objects]]
        mesh = "../meshes/cornell_box/cornell_box.obj"
        scale = 0.002
        rotate_y_deg = 180.0
    "#;
    // The indirect dialect: one `[light]`, `[[mesh]]` entries with `path`, `fov_deg`.
    let indirect = canonical
        .replace("fov_y_deg", "fov_deg")
        .replace("[[lights]]", "[light]")
        .replace("[[objects]]", "[[mesh]]")
        .replace("mesh = ", "path = ");
    let raytrace = canonical
        .replace("position = [0.5, 0.5, 2.4]", "eye = [0.5, 0.5, 2.4]")
        .replace("target =", "look_at =")
        .replace("mesh = ", "path = ");
    let file = asset("scenes/new.toml");
    let a = SceneDescription::from_toml(canonical, &file).unwrap();
    for other in [&indirect, &raytrace] {
        let b = SceneDescription::from_toml(other, &file).unwrap();
        assert_eq!(a.camera, b.camera);
        assert_eq!(a.lights, b.lights);
        assert_eq!(a.materials, b.materials);
        assert_eq!(a.name, "new");
        for (x, y) in a.objects.iter().zip(&b.objects) {
            assert_eq!((x.transform, x.material), (y.transform, y.material));
        }
    }
    let Shape::Mesh { model, .. } = &a.objects[1].shape else {
        panic!("object 1 is the mesh file");
    };
    assert_eq!(model.triangle_count(), 36);
    assert_eq!(a.objects[0].transform, Transform::IDENTITY);
}

/// A technique's own settings: its table, or the older top-level keys, read the same; a key in
/// both places, or one the technique does not know, is refused with the table named.
#[test]
fn technique_tables_and_their_older_top_level_keys_read_the_same() {
    #[derive(serde::Deserialize, Default, Debug, PartialEq, Clone, Copy)]
    #[serde(deny_unknown_fields)]
    struct Raytrace {
        ambient: Option<Vec3>,
        background: Option<Vec3>,
    }
    let body = "[camera]\nposition = [0, 0, 2]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
                [[objects]]\nbox = { min = [0, 0, 0], max = [1, 1, 1] }\nalbedo = [0.5, 0.5, 0.5]\n";
    let file = asset("scenes/new.toml");
    let read = |head: &str| SceneDescription::from_toml(&format!("{head}\n{body}"), &file);
    let table = read("[raytrace]\nambient = [0.1, 0.2, 0.3]").unwrap();
    let older = read("ambient = [0.1, 0.2, 0.3]").unwrap();
    let expected = Raytrace {
        ambient: Some(Vec3::new(0.1, 0.2, 0.3)),
        background: None,
    };
    for scene in [&table, &older] {
        assert_eq!(
            scene.technique_settings::<Raytrace>("raytrace"),
            Ok(expected)
        );
    }
    // none: the technique's defaults
    assert_eq!(
        read("").unwrap().technique_settings::<Raytrace>("raytrace"),
        Ok(Raytrace::default())
    );
    let twice =
        read("ambient = [0.1, 0.1, 0.1]\n[raytrace]\nambient = [0.2, 0.2, 0.2]").unwrap_err();
    assert!(twice.to_string().contains("both"), "{twice}");
    assert!(twice.to_string().contains("new.toml"), "{twice}");
    let unknown = read("[raytrace]\nambiant = [0.1, 0.1, 0.1]").unwrap();
    let err = unknown
        .technique_settings::<Raytrace>("raytrace")
        .unwrap_err();
    assert!(
        err.contains("[raytrace]") && err.contains("ambiant"),
        "{err}"
    );
}

#[test]
fn the_bundled_gltf_scene_has_the_camera_and_spot_of_cornell_toml() {
    let gltf = SceneDescription::load(&asset("scenes/cornell_spot.gltf")).unwrap();
    let toml = SceneDescription::load(&asset("scenes/cornell.toml")).unwrap();
    assert_eq!(gltf.name, "cornell_spot");
    let (c, t) = (gltf.camera, toml.camera);
    assert!(c.position.abs_diff_eq(t.position, 1e-6), "{c:?}");
    let (forward, expected) = (c.target - c.position, (t.target - t.position).normalize());
    assert!(forward.abs_diff_eq(expected, 1e-6), "{c:?}");
    assert!(c.up.abs_diff_eq(Vec3::Y, 1e-6));
    assert!((c.fov_y_deg - t.fov_y_deg).abs() < 1e-4);
    let spot_of = |l: Light| match l.kind {
        LightKind::Spot { position, cone } => (position, cone),
        _ => panic!("{l:?} is not a spot"),
    };
    let (light, (position, spot)) = (gltf.lights[0], spot_of(gltf.lights[0]));
    let (expected_position, expected) = spot_of(toml.lights[0]);
    assert!(position.abs_diff_eq(expected_position, 1e-6));
    assert!(
        spot.direction
            .abs_diff_eq(expected.direction.normalize(), 1e-5),
        "{spot:?}"
    );
    assert!((spot.cone_deg - expected.cone_deg).abs() < 1e-4);
    assert!((spot.falloff_deg - expected.falloff_deg).abs() < 1e-4);
    assert_eq!(light.intensity, Intensity::Photometric(Vec3::splat(1366.0)));
    assert_eq!(light.intensity.radiometric(), Vec3::splat(2.0));
    // The room (10 triangles) and one block mesh placed twice by node transforms (10 each).
    let Shape::Mesh { model, .. } = &gltf.objects[0].shape else {
        panic!("a glTF scene is one mesh object");
    };
    assert_eq!(model.triangle_count(), 30);
    let (lo, hi) = model.bounds();
    assert!(lo.abs_diff_eq(Vec3::ZERO, 1e-6) && hi.abs_diff_eq(Vec3::ONE, 1e-6));
}

/// A glTF file without a camera (the Blender Cornell box) is refused as a scene, and on request
/// framed: the camera looks at the meshes' middle, sees every corner of their bounds and the
/// bounds fill at least half of the picture's height; a file with a camera keeps its own.
#[test]
fn a_gltf_scene_without_a_camera_is_framed_on_request() {
    let glb = asset("meshes/cornell_box_gltf/cornell-box.glb");
    let err = refused(&glb);
    assert!(err.contains("cornell-box.glb: no camera"), "{err}");
    let (scene, framed) = SceneDescription::load_framing(&glb).unwrap();
    assert!(framed);
    let Shape::Mesh { model, .. } = &scene.objects[0].shape else {
        panic!("a glTF scene is one mesh object");
    };
    let (lo, hi) = model.bounds();
    let c = scene.camera;
    let axis = (c.target - c.position).normalize();
    assert!(axis.abs_diff_eq(Vec3::NEG_Z, 1e-6) && c.target.abs_diff_eq(lo.midpoint(hi), 1e-6));
    for i in 0..8 {
        let corner = Shape::box_corner(lo, hi, i);
        let degrees = axis.angle_between(corner - c.position).to_degrees();
        assert!(
            degrees < 0.5 * c.fov_y_deg,
            "corner {corner}: {degrees} deg off the axis"
        );
    }
    // and fills the picture: the bounds' sphere just fits the field of view, so the bounds span
    // at least half of the picture's height (measured 64%; a camera twice as far, about 30%)
    let view_proj = Mat4::perspective_rh(c.fov_y_deg.to_radians(), 1.0, 0.01, 100.0)
        * Mat4::look_at_rh(c.position, c.target, c.up);
    let heights = (0..8).map(|i| view_proj.project_point3(Shape::box_corner(lo, hi, i)).y);
    let (low, high) = heights.fold((f32::MAX, f32::MIN), |(l, h), y| (l.min(y), h.max(y)));
    let share = 0.5 * (high - low);
    println!("the bounds span {share} of the picture's height");
    assert!(
        (0.5..=1.0).contains(&share),
        "the bounds span {share} of the picture's height"
    );
    let bundled = asset("scenes/cornell_spot.gltf");
    let (own, framed) = SceneDescription::load_framing(&bundled).unwrap();
    assert!(!framed);
    assert_eq!(own.camera, SceneDescription::load(&bundled).unwrap().camera);
}

/// The bundled glTF scene's JSON, changed by `edit`, written to `dir/name`.
fn edited_gltf(dir: &Path, name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
    let text = std::fs::read_to_string(asset("scenes/cornell_spot.gltf")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut json);
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string(&json).unwrap()).unwrap();
    path
}

/// A technique's settings in the glTF scene's `extras` read as its TOML table; other extras are
/// left alone, and a technique's that is no table is refused with the file named.
#[test]
fn technique_settings_come_from_the_gltf_scenes_extras() {
    #[derive(serde::Deserialize, Default, Debug, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Indirect {
        r_min: Option<f32>,
    }
    let dir = scratch("gltf-extras");
    let path = edited_gltf(&dir, "extras.gltf", |j| {
        j["scenes"][0]["extras"] =
            serde_json::json!({"indirect": {"r_min": 0.1}, "blender_prop": [1, 2]});
    });
    let scene = SceneDescription::load(&path).unwrap();
    assert_eq!(
        scene.technique_settings::<Indirect>("indirect"),
        Ok(Indirect { r_min: Some(0.1) })
    );
    assert!(!scene.techniques.contains_key("raytrace"));
    let bad = edited_gltf(&dir, "bad-extras.gltf", |j| {
        j["scenes"][0]["extras"] = serde_json::json!({"raytrace": 3});
    });
    let err = refused(&bad);
    assert!(
        err.contains("bad-extras.gltf") && err.contains("raytrace"),
        "{err}"
    );
}

/// glTF's three punctual lights, each read with its kind, its place or direction (spot and
/// directional lights shine down their node's -z) and its photometric intensity.
#[test]
fn gltf_point_spot_and_directional_lights_are_read() {
    let dir = scratch("gltf-lights");
    let path = edited_gltf(&dir, "lights.gltf", |j| {
        let lights = &mut j["extensions"]["KHR_lights_punctual"]["lights"];
        lights
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({"type": "directional", "intensity": 683.0}));
        lights
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({"type": "point", "intensity": 2.0, "color": [1, 0, 0]}));
        let nodes = j["nodes"].as_array_mut().unwrap();
        // the sun turned 90 degrees about x: its -z becomes -y, straight down
        nodes.push(
            serde_json::json!({"rotation": [-0.70710677, 0, 0, 0.70710677],
            "extensions": {"KHR_lights_punctual": {"light": 1}}}),
        );
        nodes.push(serde_json::json!({"translation": [0.25, 0.5, 0.75],
            "extensions": {"KHR_lights_punctual": {"light": 2}}}));
        let count = nodes.len();
        let roots = j["scenes"][0]["nodes"].as_array_mut().unwrap();
        roots.extend([serde_json::json!(count - 2), serde_json::json!(count - 1)]);
    });
    let scene = SceneDescription::load(&path).unwrap();
    let kinds: Vec<_> = scene.lights.iter().map(Light::kind_name).collect();
    assert_eq!(kinds, ["spot", "directional", "point"]);
    let LightKind::Directional { direction } = scene.lights[1].kind else {
        unreachable!()
    };
    assert!(direction.abs_diff_eq(Vec3::NEG_Y, 1e-5), "{direction}");
    assert_eq!(scene.lights[1].intensity.radiometric(), Vec3::ONE);
    assert_eq!(scene.lights[2].position(), Some(Vec3::new(0.25, 0.5, 0.75)));
    assert_eq!(
        scene.lights[2].intensity,
        Intensity::Photometric(Vec3::new(2.0, 0.0, 0.0))
    );
}

/// TOML's three lights: a position (point), a position with a cone (spot), a direction alone
/// (directional, its photometric intensity in lux); what is neither is refused by name.
#[test]
fn toml_lights_are_points_spots_or_the_sun_by_their_fields() {
    let head = "[camera]\nposition = [0, 0, 2]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
                [[objects]]\nbox = { min = [0, 0, 0], max = [1, 1, 1] }\nalbedo = [1, 1, 1]\n";
    let scene = |lights: &str| {
        SceneDescription::from_toml(&format!("{head}{lights}"), Path::new("lights.toml"))
    };
    let ok = scene(
        "[[lights]]\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n\
         [[lights]]\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ncone_deg = 30\n\
         candela = [683, 683, 683]\n\
         [[lights]]\ndirection = [0.1, -1, 0]\nlux = [683, 0, 0]\n",
    )
    .unwrap();
    let kinds: Vec<_> = ok.lights.iter().map(Light::kind_name).collect();
    assert_eq!(kinds, ["point", "spot", "directional"]);
    assert_eq!(
        ok.lights[2].intensity.radiometric(),
        Vec3::new(1.0, 0.0, 0.0)
    );
    assert_eq!(ok.lights[2].position(), None);
    for (lights, why) in [
        ("intensity = [1, 1, 1]", "give a `position`"),
        ("direction = [0, -1, 0]\ncandela = [1, 1, 1]", "`lux`"),
        ("direction = [0, 0, 0]\nintensity = [1, 1, 1]", "direction"),
        ("position = [0, 1, 0]\nlux = [1, 1, 1]", "`candela`"),
        (
            "position = [1e30, 0, 0]\nintensity = [1, 1, 1]",
            "position is beyond",
        ),
        (
            "direction = [0, -1, 0]\ncone_deg = 30\nintensity = [1, 1, 1]",
            "give a `position`",
        ),
    ] {
        let err = scene(&format!("[[lights]]\n{lights}\n"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("lights.toml") && err.contains(why),
            "{lights}: {err}"
        );
    }
}

/// A change made to the bundled glTF scene's JSON.
type Edit = fn(&mut serde_json::Value);

#[test]
fn bad_gltf_scenes_are_refused_with_the_file_named() {
    let dir = scratch("bad-gltf");
    let cases: [(&str, Edit, &str); 6] = [
        (
            "no-camera.gltf",
            |j| {
                j["nodes"][3].as_object_mut().unwrap().remove("camera");
            },
            "no camera",
        ),
        (
            "orthographic.gltf",
            |j| {
                j["cameras"][0] = serde_json::json!({"type": "orthographic",
                    "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}});
            },
            "perspective",
        ),
        (
            // 3e38 x 10 overflows f32: the light's world position is infinite.
            "overflow.gltf",
            |j| {
                j["nodes"][4]["translation"] = serde_json::json!([3e38, 0.0, 0.0]);
                j["nodes"].as_array_mut().unwrap().push(serde_json::json!(
                    {"scale": [10.0, 10.0, 10.0], "children": [4]}));
                j["scenes"][0]["nodes"] = serde_json::json!([0, 1, 2, 3, 5]);
            },
            "not finite",
        ),
        (
            "cone.gltf",
            |j| {
                j["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"]["innerConeAngle"] =
                    serde_json::json!(1.2);
            },
            "cone angles",
        ),
        (
            "light-index.gltf",
            |j| {
                j["nodes"][4]["extensions"]["KHR_lights_punctual"]["light"] =
                    serde_json::json!(4000000000u64);
            },
            "light",
        ),
        (
            "fov.gltf",
            |j| j["cameras"][0]["perspective"]["yfov"] = serde_json::json!(3.5),
            "fov_y_deg",
        ),
    ];
    for (name, edit, why) in cases {
        let path = edited_gltf(&dir, name, edit);
        let e = refused(&path);
        assert!(
            e.starts_with(&path.display().to_string()) && e.contains(why),
            "{name}: {e}"
        );
    }
}

#[test]
fn malformed_gltf_files_are_errors_as_scenes_too() {
    for file in [
        "gltf2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
        "gltf2/IncorrectVertexArrays/Cube.gltf",
        "gltf2/IndexOutOfRange/IndexOutOfRange.gltf",
        "gltf2/MissingBin/BoxTextured.gltf",
        "gltf2/RecursiveNodes/RecursiveNodes.gltf",
        "gltf2/TestNoRootNode/NoScene.gltf",
        "gltf2/wrongTypes/badArray.gltf",
        "gltf2/wrongTypes/badExtension.gltf",
        "gltf2/wrongTypes/badUint.gltf",
    ] {
        let path = asset("malformed").join(file);
        let e = refused(&path);
        assert!(e.starts_with(&path.display().to_string()), "{e}");
        // The file name once, not the loader's prefix again.
        assert_eq!(e.matches(&path.display().to_string()).count(), 1, "{e}");
    }
}

#[test]
fn bad_toml_values_are_refused_with_the_reason() {
    let good = std::fs::read_to_string(asset("scenes/shadows-demo.toml")).unwrap();
    let file = asset("scenes/bad.toml");
    let cases = [
        (
            "eye = [0.3, 1.6, 4.2]",
            "eye = [nan, 1.6, 4.2]",
            "not finite",
        ),
        ("fov_y_deg = 50", "fov_y_deg = 0", "fov_y_deg"),
        // as far as a mesh's vertices may be, and no further
        (
            "eye = [0.3, 1.6, 4.2]",
            "eye = [1e30, 1.6, 4.2]",
            "camera: position x = 1e30 is outside the limit |coordinate| <= 1e7",
        ),
        (
            "intensity = [0.7, 0.7, 0.7]",
            "candela = [1, 1, 1]\nintensity = [1, 1, 1]",
            "one of",
        ),
        (
            "intensity = [0.7, 0.7, 0.7]",
            "intensity = [-1, 1, 1]",
            "negative",
        ),
        (
            "intensity = [0.7, 0.7, 0.7]",
            "intensity = [1, 1, 1]\ncone_deg = 30",
            "spot light",
        ),
        ("ior = 1.5", "ior = 0", "ior"),
        (
            "material = \"glass\"",
            "material = \"glass\"\nscale = 2",
            "world coordinates",
        ),
        ("material = \"glass\"", "", "need a `material`"),
        (
            "max = [0.4, 1.1, 0.3]",
            "max = [-0.4, 1.1, 0.3]",
            "below max",
        ),
        (
            "material = \"glass\"",
            "material = \"glass\"\nbuiltin = \"room\"",
            "more than one",
        ),
        ("[[lights]]", "[[lamps]]", "lamps"),
        (
            "max = [0.4, 1.1, 0.3]",
            "max = [0.4, 1e38, 0.3]",
            "box max: y = 1e38 is outside the limit |coordinate| <= 1e7",
        ),
        (
            "[1.6, 0.0, -0.2], [1.2, 0.0, 0.5]]",
            "[1.6, 0.0, -2e7], [1.2, 0.0, 0.5]]",
            "polygon 0: vertex 1: z = -2e7 is outside the limit",
        ),
    ];
    for (from, to, why) in cases {
        assert!(good.contains(from), "{from}");
        let text = good.replacen(from, to, 1);
        let e = SceneDescription::from_toml(&text, &file)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&file.display().to_string()) && e.contains(why),
            "{why}: {e}"
        );
    }
}

#[test]
fn a_transform_that_carries_a_mesh_beyond_the_coordinate_limit_is_refused() {
    let file = asset("scenes/far.toml");
    let scene = |scale: &str| {
        format!(
            "[camera]\nposition = [0, 0, 5]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
             [[objects]]\nmesh = \"../meshes/cornell_box/cornell_box.obj\"\nscale = {scale}\n"
        )
    };
    assert!(SceneDescription::from_toml(&scene("1000"), &file).is_ok());
    let e = SceneDescription::from_toml(&scene("1e5"), &file)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("object 0: ")
            && e.contains("cornell_box.obj: mesh `floor` vertex 0: x = ")
            && e.ends_with(
                "is outside the limit |coordinate| <= 1e7, once the object's transform places it"
            ),
        "{e}"
    );
}

/// A TOML scene's meshes lie in its folder or beside it (`scenes/` and `meshes/` under one
/// folder): a mesh path that leaves the folder above (`..` further up, an absolute path) is
/// refused by name; a bare mesh file is no scene, and the refusal says what to give.
#[test]
fn a_toml_scene_reads_meshes_only_beside_it_and_a_mesh_file_is_no_scene() {
    let dir = scratch("toml-outside").join("project");
    let (scenes, meshes) = (dir.join("scenes"), dir.join("meshes"));
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::create_dir_all(&meshes).unwrap();
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(meshes.join("triangle.obj"), triangle).unwrap();
    std::fs::write(dir.join("../triangle.obj"), triangle).unwrap();
    let scene = |mesh: &str| {
        let path = scenes.join("scene.toml");
        let text = format!(
            "[camera]\nposition = [0.5, 0.5, 3.0]\ntarget = [0.5, 0.5, 0.0]\nfov_y_deg = 40.0\n\
             [[lights]]\nposition = [0.5, 0.5, 2.0]\nintensity = [1.0, 1.0, 1.0]\n\
             [[objects]]\nmesh = {mesh:?}\n"
        );
        std::fs::write(&path, text).unwrap();
        path
    };
    SceneDescription::load(&scene("../meshes/triangle.obj")).unwrap();
    let absolute = meshes.join("triangle.obj");
    for mesh in ["../../triangle.obj", absolute.to_str().unwrap()] {
        let error = refused(&scene(mesh));
        assert!(
            error.ends_with(&format!(
                "scene.toml: object 0: mesh `{mesh}`, outside the folder {}: files are read \
                 only inside the scene's folder (--allow-outside-paths reads it)",
                scenes.join("..").display()
            )),
            "{error}"
        );
    }
    let error = refused(&meshes.join("triangle.obj"));
    assert!(
        error.ends_with(
            "triangle.obj: a mesh file, not a scene: give a scene that places it \
                         with a camera and a light (TOML: [camera], [[lights]] and [[objects]] \
                         mesh = \"FILE\", see docs/scenes.md), or a glTF file with a camera and \
                         a light"
        ),
        "{error}"
    );
}
