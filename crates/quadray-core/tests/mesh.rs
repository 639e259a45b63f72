//! Mesh loading: the bundled assets, small files written here with known contents, and every file
//! in assets/malformed.

use glam::{Mat4, Vec3};
use quadray_core::mesh::{FarCoordinate, MAX_COORDINATE, Mesh, MeshError, load_model};
use std::path::{Path, PathBuf};

use crate::common;

use common::{asset, scratch};

fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

fn assert_close(actual: Vec3, expected: Vec3, tolerance: f32) {
    assert!(
        actual.abs_diff_eq(expected, tolerance),
        "{actual} != {expected} (tolerance {tolerance})"
    );
}

fn error_message(path: &Path) -> String {
    match load_model(path) {
        Ok(model) => panic!(
            "{} loaded ({} triangles), expected an error",
            path.display(),
            model.triangle_count()
        ),
        Err(e) => e.to_string(),
    }
}

/// Checks every vertex normal is unit length; returns the fraction of triangle corners whose
/// vertex normal is further than `min_cos` from the triangle's geometric normal (its winding).
fn normals_against_winding(mesh: &Mesh, min_cos: f32) -> f64 {
    assert_eq!(mesh.normals.len(), mesh.positions.len(), "{}", mesh.name);
    for n in &mesh.normals {
        assert!((n.length() - 1.0).abs() < 1e-4, "{}: normal {n}", mesh.name);
    }
    let mut against = 0;
    for &[a, b, c] in &mesh.indices {
        let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
        let face = (pb - pa).cross(pc - pa).normalize();
        against += [a, b, c]
            .iter()
            .filter(|&&i| mesh.normals[i as usize].dot(face) < min_cos)
            .count();
    }
    against as f64 / (3 * mesh.indices.len()) as f64
}

#[test]
fn cornell_box_obj() {
    let model = load_model(&asset("meshes/cornell_box/cornell_box.obj")).unwrap();
    // 18 quads (front_wall's face is commented out), each split in two.
    assert_eq!(model.triangle_count(), 36);
    let names: Vec<&str> = model.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "floor",
            "light",
            "ceiling",
            "back_wall",
            "green_wall",
            "red_wall",
            "short_block",
            "tall_block"
        ]
    );
    let (lo, hi) = model.bounds();
    assert_close(lo, Vec3::ZERO, 1e-4);
    assert_close(hi, Vec3::new(556.0, 548.8, 559.2), 1e-3);

    let material_of = |mesh: &str| {
        let mesh = model.meshes.iter().find(|m| m.name == mesh).unwrap();
        &model.materials[mesh.material]
    };
    let light = material_of("light");
    assert_eq!(light.name, "light");
    assert_eq!(light.emission, Vec3::splat(20.0), "Ka is the emission");
    assert_eq!(light.base_color, Vec3::ONE);
    assert_eq!(material_of("floor").emission, Vec3::ZERO);
    assert_eq!(material_of("red_wall").base_color, Vec3::X);
    assert_eq!(material_of("green_wall").base_color, Vec3::Y);
    assert_eq!(material_of("back_wall").transmission, 0.0);

    // No vertex is shared between quads, so generated normals are the face normals: the light
    // and ceiling face down, the floor up.
    for mesh in &model.meshes {
        assert_eq!(normals_against_winding(mesh, 0.9999), 0.0, "{}", mesh.name);
    }
    let light = model.meshes.iter().find(|m| m.name == "light").unwrap();
    assert!(
        light
            .normals
            .iter()
            .all(|n| n.abs_diff_eq(Vec3::NEG_Y, 1e-6))
    );
    assert!(light.uvs.is_none());
}

#[test]
fn cornell_box_glb() {
    let model = load_model(&asset("meshes/cornell_box_gltf/cornell-box.glb")).unwrap();
    assert_eq!(model.triangle_count(), 1040);
    assert_eq!(model.meshes.len(), 7);
    for mesh in &model.meshes {
        assert_eq!(mesh.uvs.as_ref().map(Vec::len), Some(mesh.positions.len()));
    }
    let find = |name: &str| model.materials.iter().find(|m| m.name == name).unwrap();
    assert_eq!(find("EmissiveMaterial").emission, Vec3::ONE);
    assert_eq!(find("GreenMaterial").base_color, Vec3::Y);
    assert_eq!(find("RedMaterial").base_color, Vec3::X);
    assert_eq!(find("MonkeyMaterial").base_color, Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(find("WhiteMaterial").emission, Vec3::ZERO);
    let emitters = model
        .meshes
        .iter()
        .filter(|m| model.materials[m.material].emission != Vec3::ZERO)
        .count();
    assert_eq!(emitters, 1, "only the light emits");
    // The file's normals face the way the triangles wind. They are smooth: corner-averaged on the
    // walls (cos 1/sqrt(3) at the corners) and, on Suzanne, a few just past perpendicular to a
    // neighbouring face.
    for mesh in &model.meshes {
        let (min_cos, allowed) = if mesh.name.starts_with("Suzanne") {
            (0.0, 0.01)
        } else {
            (0.5, 0.0)
        };
        let against = normals_against_winding(mesh, min_cos);
        assert!(against <= allowed, "{}: {against}", mesh.name);
    }

    // Ground truth for the node hierarchy, from the file's JSON: every node only translates, so
    // each mesh's bounds are its POSITION accessor's min/max plus its ancestors' translations.
    let glb = std::fs::read(asset("meshes/cornell_box_gltf/cornell-box.glb")).unwrap();
    let json_length = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_length]).unwrap();
    let vec3 = |v: &serde_json::Value| {
        Vec3::from_slice(
            &v.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap() as f32)
                .collect::<Vec<_>>(),
        )
    };
    let nodes = json["nodes"].as_array().unwrap();
    let parent_of = |child: usize| {
        nodes.iter().position(|n| {
            n["children"]
                .as_array()
                .is_some_and(|c| c.iter().any(|i| i.as_u64() == Some(child as u64)))
        })
    };
    for (index, node) in nodes.iter().enumerate() {
        assert!(node.get("rotation").is_none() && node.get("scale").is_none());
        let mut offset = Vec3::ZERO;
        let mut at = Some(index);
        while let Some(i) = at {
            offset += nodes[i].get("translation").map_or(Vec3::ZERO, vec3);
            at = parent_of(i);
        }
        let json_mesh = &json["meshes"][node["mesh"].as_u64().unwrap() as usize];
        let accessor = &json["accessors"][json_mesh["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize];
        let name = format!("{}/0", json_mesh["name"].as_str().unwrap());
        let mesh = model.meshes.iter().find(|m| m.name == name).unwrap();
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        assert_close(lo, vec3(&accessor["min"]) + offset, 1e-5);
        assert_close(hi, vec3(&accessor["max"]) + offset, 1e-5);
    }
}

#[test]
fn stanford_bunny_obj_loads_fast() {
    let path = asset("meshes/stanford_bunny/stanford-bunny.obj");
    let (model, time) = quadray_core::stats::time_cpu(5, || load_model(&path).unwrap());
    println!(
        "stanford-bunny.obj: median {:.1} ms (p10 {:.1}, p90 {:.1}, {} runs)",
        time.median_ms, time.p10_ms, time.p90_ms, time.samples
    );
    assert_eq!(model.triangle_count(), 69_451);
    // tobj keeps the vertices the faces use (not all 35,947 in the file): count them here.
    let text = std::fs::read_to_string(&path).unwrap();
    let used: std::collections::HashSet<&str> = text
        .lines()
        .filter_map(|line| line.strip_prefix("f "))
        .flat_map(|face| face.split_whitespace())
        .map(|corner| corner.split('/').next().unwrap())
        .collect();
    assert_eq!(model.meshes[0].positions.len(), used.len());
    let (lo, hi) = model.bounds();
    assert_close(lo, Vec3::new(-0.0947, 0.0330, -0.0619), 1e-3);
    assert_close(hi, Vec3::new(0.0610, 0.1873, 0.0588), 1e-3);
    // Smooth generated normals on a scan: on the same side as nearly all their faces (the scan
    // has a few folded triangles).
    let against = normals_against_winding(&model.meshes[0], 0.0);
    println!(
        "stanford-bunny.obj: {:.4}% of corners against their face",
        against * 100.0
    );
    assert!(against < 1e-3, "{against}");
    if !cfg!(debug_assertions) {
        assert!(time.median_ms < 500.0, "too slow: {} ms", time.median_ms);
    }
}

#[test]
fn obj_materials_and_fallbacks() {
    let dir = scratch("obj_materials");
    let mtl = "newmtl glass\nKd 0.5\nKs 0.25 0.5 0.75\nNs 64\nNi 1.33\nd 0.25\nKa 9 9 9\nKe 0 2 0\n\
               newmtl veil\nTr 0.3\n";
    write(&dir, "scene.mtl", mtl);
    let obj = "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
               usemtl glass\nf 1/1 2/2 3/3\nusemtl veil\nf -3 -2 -1\nusemtl nowhere\nf 1 3 2\n";
    let model = load_model(&write(&dir, "scene.obj", obj)).unwrap();
    assert_eq!(model.meshes.len(), 3);
    let glass = &model.materials[model.meshes[0].material];
    assert_eq!(glass.name, "glass");
    assert_eq!(glass.base_color, Vec3::splat(0.5), "one-value Kd is grey");
    assert_eq!(glass.specular, Vec3::new(0.25, 0.5, 0.75));
    assert_eq!(glass.shininess, 64.0);
    assert_eq!(glass.ior, 1.33);
    assert_eq!(glass.transmission, 0.75);
    assert_eq!(glass.emission, Vec3::Y * 2.0, "Ke wins over Ka");
    // OBJ's v points up the image; Mesh uses glTF's top-left origin.
    let uvs = model.meshes[0].uvs.as_ref().unwrap();
    assert_eq!(uvs[2], glam::Vec2::new(0.0, 0.0));
    let veil = &model.materials[model.meshes[1].material];
    assert!((veil.transmission - 0.3).abs() < 1e-6);
    assert_eq!(veil.ior, 1.5);
    let unknown = &model.materials[model.meshes[2].material];
    assert_eq!(*unknown, quadray_core::mesh::Material::default());

    // A broken (tobj would panic on `Kd 1 1`) or missing material library is not fatal.
    write(&dir, "broken.mtl", "newmtl a\nKd 1 1\n");
    let broken = "mtllib broken.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    let model = load_model(&write(&dir, "broken.obj", broken)).unwrap();
    assert_eq!(
        model.materials[model.meshes[0].material].base_color,
        Vec3::ONE
    );
    let missing = "mtllib absent.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    let model = load_model(&write(&dir, "missing.obj", missing)).unwrap();
    assert_eq!(model.triangle_count(), 1);
}

#[test]
fn obj_validation() {
    let dir = scratch("obj_validation");
    let nan = write(&dir, "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    let message = error_message(&nan);
    assert!(
        message.contains("nan.obj") && message.contains("vertex 1"),
        "{message}"
    );

    // Two good triangles, one with a repeated vertex, one with zero area (collinear): the bad
    // ones are dropped, not fatal.
    let degenerate = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\nf 1 2 4\nf 3 2 1\n";
    let model = load_model(&write(&dir, "degenerate.obj", degenerate)).unwrap();
    assert_eq!(model.meshes[0].indices.len(), 2);
    // Only degenerate faces: nothing left.
    let only_bad = write(&dir, "only_bad.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    assert!(error_message(&only_bad).contains("no triangles"));

    // UTF-16 little-endian without a byte-order mark is refused too.
    let utf16: Vec<u8> = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
        .encode_utf16()
        .flat_map(u16::to_le_bytes)
        .collect();
    let message = error_message(&write(&dir, "utf16le.obj", utf16));
    assert!(
        message.contains("utf16le.obj") && message.contains("UTF-16"),
        "{message}"
    );
}

/// A coordinate no f32 pipeline can use is refused, the message naming the file, the vertex, its
/// value and the limit; a vertex at the limit still loads.
#[test]
fn far_coordinates_are_refused_by_name() {
    let dir = scratch("far_coordinates");
    let obj =
        |far: &str| format!("o far\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv {far} 1 0\nf 1 2 3\nf 2 4 3\n");
    let path = write(&dir, "far.obj", obj("1e38"));
    assert_eq!(
        error_message(&path),
        format!(
            "{}: mesh `far` vertex 3: x = 1e38 is outside the limit |coordinate| <= 1e7",
            path.display()
        )
    );
    assert!(matches!(
        load_model(&path),
        Err(MeshError::FarVertex {
            vertex: 3,
            coordinate: FarCoordinate {
                axis: 'x',
                value: 1e38
            },
            ..
        })
    ));
    let at_limit = write(&dir, "at_limit.obj", obj(&(-MAX_COORDINATE).to_string()));
    assert_eq!(load_model(&at_limit).unwrap().triangle_count(), 2);

    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
               property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
               end_header\n0 0 0\n1 0 0\n0 -1e20 0\n3 0 1 2\n";
    let message = error_message(&write(&dir, "far.ply", ply));
    assert!(
        message.contains("far.ply") && message.contains("vertex 2: y = -1e20 is outside"),
        "{message}"
    );
}

const PLY_HEADER_END: &str = "element face 3\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn ply_ascii_and_binary() {
    let dir = scratch("ply");
    // A unit square as one quad (fan-triangulated), a face with a repeated vertex (dropped) and a
    // two-vertex face (dropped).
    let ascii = format!(
        "ply\nformat ascii 1.0\ncomment a square\nelement vertex 4\nproperty float x\n\
         property float y\nproperty float z\nproperty float nx\nproperty float ny\n\
         property float nz\n{PLY_HEADER_END}0 0 0 0 0 2\n1 0 0 0 0 2\n1 1 0 0 0 2\n0 1 0 0 0 2\n\
         4 0 1 2 3\n3 0 0 1\n2 0 1\n"
    );
    let model = load_model(&write(&dir, "square.ply", ascii)).unwrap();
    let mesh = &model.meshes[0];
    assert_eq!(mesh.indices, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert!(
        mesh.normals.iter().all(|n| *n == Vec3::Z),
        "file normals, normalised"
    );

    // The same square in binary, doubles and no normals, with an extra element to skip.
    let mut binary = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\n\
         property double y\nproperty double z\nelement extra 1\nproperty short tag\n\
         {PLY_HEADER_END}"
    )
    .into_bytes();
    for [x, y] in [[0.0f64, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
        for v in [x, y, 0.0] {
            binary.extend(v.to_le_bytes());
        }
    }
    binary.extend(7i16.to_le_bytes());
    for face in [&[0i32, 1, 2, 3][..], &[0, 0, 1], &[0, 1]] {
        binary.push(face.len() as u8);
        for i in face {
            binary.extend(i.to_le_bytes());
        }
    }
    let path = write(&dir, "square_binary.ply", &binary);
    let model = load_model(&path).unwrap();
    let mesh = &model.meshes[0];
    assert_eq!(mesh.indices, [[0, 1, 2], [0, 2, 3]]);
    assert!(mesh.normals.iter().all(|n| *n == Vec3::Z), "generated");

    // Truncated payload and an index past the vertices are errors naming the file.
    let truncated = write(&dir, "truncated.ply", &binary[..binary.len() - 5]);
    assert!(error_message(&truncated).contains("truncated.ply"));
    let bad_index = binary.len() - 4 - 4 - 1 - 4;
    binary[bad_index..bad_index + 4].copy_from_slice(&9i32.to_le_bytes());
    let message = error_message(&write(&dir, "bad_index.ply", &binary));
    assert!(
        message.contains("bad_index.ply") && message.contains("index 9"),
        "{message}"
    );
}

#[test]
fn gltf_node_transforms_and_primitive_modes() {
    let dir = scratch("gltf");
    // One triangle (0,0,0) (1,0,0) (0,1,0), as a list and as a strip, placed by a parent node
    // (translate x+10) and a child node (scale -2 along x: a mirror).
    let mut buffer = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        buffer.extend(v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        buffer.extend(i.to_le_bytes());
    }
    use base64::Engine;
    let data = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let gltf = |nodes: &str, mode: u32| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":{nodes},
            "meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":{mode}}}]}}],
            "accessors":[
              {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}},
              {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
            "buffers":[{{"byteLength":44,"uri":"data:application/octet-stream;base64,{data}"}}]}}"#
        )
    };
    let placed = r#"[{"translation":[10,0,0],"children":[1]},{"scale":[-2,1,1],"mesh":0}]"#;
    for (name, mode) in [("list.gltf", 4), ("strip.gltf", 5), ("fan.gltf", 6)] {
        let model = load_model(&write(&dir, name, gltf(placed, mode))).unwrap();
        let mesh = &model.meshes[0];
        assert_eq!(mesh.name, "tri/0");
        assert_eq!(
            mesh.positions,
            [
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(8.0, 0.0, 0.0),
                Vec3::new(10.0, 1.0, 0.0)
            ],
            "{name}"
        );
        // The mirror flips the winding back so the face normal stays +z.
        assert_eq!(mesh.indices, [[0, 2, 1]], "{name}");
        assert!(mesh.normals.iter().all(|n| *n == Vec3::Z), "{name}");
        assert_eq!(model.materials[mesh.material], Default::default());
    }

    // A node's scale can carry a vertex in range beyond the limit.
    let huge = r#"[{"scale":[1e8,1,1],"mesh":0}]"#;
    let message = error_message(&write(&dir, "huge.gltf", gltf(huge, 4)));
    assert!(
        message.contains("huge.gltf") && message.contains("vertex 1: x = 1e8 is outside"),
        "{message}"
    );

    let cycle = r#"[{"children":[1]},{"children":[0],"mesh":0}]"#;
    let message = error_message(&write(&dir, "cycle.gltf", gltf(cycle, 4)));
    assert!(
        message.contains("cycle.gltf") && message.contains("node 0"),
        "{message}"
    );
    // A chain far deeper than any call stack allows still loads (no recursion).
    let depth = 100_000;
    let chain: Vec<String> = (0..depth)
        .map(|i| match i + 1 < depth {
            true => format!(r#"{{"children":[{}]}}"#, i + 1),
            false => r#"{"mesh":0}"#.to_owned(),
        })
        .collect();
    let deep = write(
        &dir,
        "deep.gltf",
        gltf(&format!("[{}]", chain.join(",")), 4),
    );
    assert_eq!(load_model(&deep).unwrap().triangle_count(), 1);
}

#[test]
fn transformed_model() {
    let model = load_model(&asset("meshes/cornell_box/cornell_box.obj")).unwrap();
    let mirror = Mat4::from_scale(Vec3::new(-0.001, 0.001, 0.001));
    let moved = model.clone().transformed(mirror);
    let (lo, hi) = moved.bounds();
    assert_close(lo, Vec3::new(-0.556, 0.0, 0.0), 1e-6);
    assert_close(hi, Vec3::new(0.0, 0.5488, 0.5592), 1e-6);
    assert_eq!(moved.triangle_count(), model.triangle_count());
    for mesh in &moved.meshes {
        assert_eq!(normals_against_winding(mesh, 0.9999), 0.0, "{}", mesh.name);
    }
}

#[test]
fn unsupported_and_missing_files() {
    let message = error_message(&asset("meshes/cornell_box/cornell_box.mtl"));
    assert!(message.contains("cornell_box.mtl") && message.contains("unsupported"));
    let missing = error_message(&asset("meshes/nothing_here.obj"));
    assert!(missing.contains("nothing_here.obj") && missing.contains("cannot read"));
}

/// Cutting valid files short at many points gives errors or smaller models, never a panic.
#[test]
fn truncated_files_never_panic() {
    let dir = scratch("truncated");
    for source in [
        "meshes/cornell_box_gltf/cornell-box.glb",
        "meshes/cornell_box/cornell_box.obj",
    ] {
        let bytes = std::fs::read(asset(source)).unwrap();
        let name = Path::new(source).file_name().unwrap().to_str().unwrap();
        for cut in (0..bytes.len()).step_by(bytes.len() / 97 + 1) {
            let path = write(&dir, name, &bytes[..cut]);
            if let Err(e) = load_model(&path) {
                assert!(e.to_string().contains(name), "{e}");
            }
        }
    }
}

/// What each file in assets/malformed gives: Ok(triangles) or Err(part of the message). Every
/// file is listed (the test fails on an unlisted one); all messages must name the file.
const MALFORMED: &[(&str, Result<usize, &str>)] = &[
    (
        "gltf2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
        Err("vertex 0: x = -inf is outside the limit"),
    ),
    (
        "gltf2/IncorrectVertexArrays/Cube.bin",
        Err("unsupported mesh format"),
    ),
    (
        "gltf2/IncorrectVertexArrays/Cube.gltf",
        Err("not a multiple of 3"),
    ),
    (
        "gltf2/IndexOutOfRange/AllIndicesOutOfRange.bin",
        Err("unsupported mesh format"),
    ),
    (
        "gltf2/IndexOutOfRange/AllIndicesOutOfRange.gltf",
        Err("index 65535 is out of range"),
    ),
    (
        "gltf2/IndexOutOfRange/IndexOutOfRange.bin",
        Err("unsupported mesh format"),
    ),
    (
        "gltf2/IndexOutOfRange/IndexOutOfRange.gltf",
        Err("index 255 is out of range"),
    ),
    ("gltf2/MissingBin/BoxTextured.gltf", Err("BoxTextured0.bin")),
    (
        "gltf2/RecursiveNodes/RecursiveNodes.gltf",
        Err("node 0 is reached twice"),
    ),
    (
        "gltf2/TestNoRootNode/NoScene.gltf",
        Err("scene: Index out of bounds"),
    ),
    (
        "gltf2/TestNoRootNode/SceneWithoutNodes.gltf",
        Err("no triangles"),
    ),
    (
        "gltf2/wrongTypes/BoxTextured0.bin",
        Err("unsupported mesh format"),
    ),
    (
        "gltf2/wrongTypes/CesiumLogoFlat.png",
        Err("unsupported mesh format"),
    ),
    (
        "gltf2/wrongTypes/badArray.gltf",
        Err("expected a sequence at line 44"),
    ),
    // The glTF parser checks KHR_texture_transform's shape (a feature Bevy's loader enables too)
    (
        "gltf2/wrongTypes/badExtension.gltf",
        Err("expected struct TextureTransform at line 130"),
    ),
    (
        "gltf2/wrongTypes/badNumber.gltf",
        Err("expected f32 at line 132"),
    ),
    (
        "gltf2/wrongTypes/badObject.gltf",
        Err("expected an array of length 4 at line 125"),
    ),
    (
        "gltf2/wrongTypes/badString.gltf",
        Err("expected a string at line 12"),
    ),
    ("gltf2/wrongTypes/badUint.gltf", Err("integer `-1`")),
    ("obj/box_UTF16BE.obj", Err("UTF-16")),
    ("obj/box_without_lineending.obj", Ok(12)),
    ("obj/empty.obj", Err("no triangles")),
    (
        "obj/issue-140-zero-face-idx.mtl",
        Err("unsupported mesh format"),
    ),
    (
        "obj/issue-140-zero-face-idx.obj",
        Err("face vertex index out of bounds"),
    ),
    ("obj/malformed.obj", Err("face vertex index out of bounds")),
    ("obj/malformed2.obj", Err("invalid polygon")),
    // `3.1+e2` is not a number.
    ("obj/number_formats.obj", Err("position parse error")),
    // `1.#IND` is not a number (the nan/inf lines before it parse, and would fail validation).
    ("obj/test-nan.obj", Err("position parse error")),
];

fn files_under(dir: &Path, root: &Path, out: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files_under(&path, root, out);
        } else {
            let relative = path.strip_prefix(root).unwrap();
            out.push(relative.to_str().unwrap().replace('\\', "/"));
        }
    }
}

#[test]
fn every_malformed_file() {
    let root = asset("malformed");
    let mut on_disk = Vec::new();
    files_under(&root, &root, &mut on_disk);
    on_disk.sort();
    let mut listed: Vec<String> = MALFORMED.iter().map(|(f, _)| f.to_string()).collect();
    listed.sort();
    assert_eq!(
        listed, on_disk,
        "MALFORMED must list exactly the files on disk"
    );

    for (file, expected) in MALFORMED {
        let path = root.join(file);
        let name = path.file_name().unwrap().to_str().unwrap();
        match (load_model(&path), expected) {
            (Ok(model), Ok(triangles)) => assert_eq!(model.triangle_count(), *triangles, "{file}"),
            (Err(e), Err(part)) => {
                let message = e.to_string();
                assert!(message.contains(name), "{file}: {message}");
                assert!(message.contains(part), "{file}: {message}");
            }
            (got, _) => panic!("{file}: expected {expected:?}, got {got:?}"),
        }
    }
}

#[test]
fn error_variants_are_typed() {
    let path = asset("malformed/gltf2/RecursiveNodes/RecursiveNodes.gltf");
    assert!(matches!(
        load_model(&path),
        Err(MeshError::NodeCycle { node: 0, .. })
    ));
    let path = asset("malformed/obj/empty.obj");
    assert!(matches!(
        load_model(&path),
        Err(MeshError::NoTriangles { .. })
    ));
}

#[test]
fn gltf_base_color_texture_is_decoded() {
    // the textured box of the malformed set, its one malformed part (a texture transform that is
    // not an object) taken out
    let dir = asset("malformed/gltf2/wrongTypes");
    let fixed = scratch("gltf_base_color_texture_is_decoded");
    for file in ["BoxTextured0.bin", "CesiumLogoFlat.png"] {
        std::fs::copy(dir.join(file), fixed.join(file)).unwrap();
    }
    let text = std::fs::read_to_string(dir.join("badExtension.gltf")).unwrap();
    let text = text.replace(
        r#""KHR_texture_transform": "Not an object""#,
        r#""unused": {}"#,
    );
    std::fs::write(fixed.join("box.gltf"), text).unwrap();
    let model = load_model(&fixed.join("box.gltf")).unwrap();
    let texture = model.materials[model.meshes[0].material]
        .base_color_texture
        .as_ref()
        .expect("CesiumLogoFlat.png");
    // The PNG's IHDR chunk holds the true size.
    let png = std::fs::read(dir.join("CesiumLogoFlat.png")).unwrap();
    let be = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().unwrap());
    assert_eq!((texture.width, texture.height), (be(16), be(20)));
    assert_eq!(texture.pixels.len(), (be(16) * be(20)) as usize);
}

/// A mesh file reads only files in its own folder: a glTF buffer or an OBJ material library
/// reached by `..`, an absolute path or a link that points out is refused by name (and not
/// read); inside, links included, it is read.
#[test]
fn files_outside_a_mesh_file_s_folder_are_refused_by_name() {
    let dir = scratch("outside-paths");
    let folder = dir.join("scene");
    std::fs::create_dir_all(&folder).unwrap();
    let mut buffer = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        buffer.extend(v.to_le_bytes());
    }
    write(&dir, "outside.bin", &buffer);
    write(&folder, "inside.bin", &buffer);
    let gltf = quadray_test_support::gltf::triangle_with_buffer;
    let outside = dir.join("outside.bin");
    let _ = std::fs::remove_file(folder.join("out-link.bin"));
    let _ = std::fs::remove_file(folder.join("in-link.bin"));
    std::os::unix::fs::symlink(&outside, folder.join("out-link.bin")).unwrap();
    std::os::unix::fs::symlink("inside.bin", folder.join("in-link.bin")).unwrap();
    for uri in ["inside.bin", "in-link.bin", "./inside.bin"] {
        let model = load_model(&write(&folder, "in.gltf", gltf(uri))).unwrap();
        assert_eq!(model.triangle_count(), 1, "{uri}");
    }
    let absolute = outside.to_str().unwrap();
    for uri in [
        "../outside.bin",
        "../../../../../../../../etc/passwd",
        absolute,
        "out-link.bin",
        "sub/../../outside.bin",
    ] {
        let path = write(&folder, "out.gltf", gltf(uri));
        let error = error_message(&path);
        assert_eq!(
            error,
            format!(
                "{}: refers to `{uri}`, outside the folder {}: files are read only inside the \
                 scene's folder (--allow-outside-paths reads it)",
                path.display(),
                folder.display()
            )
        );
    }
    // an OBJ's material library outside is left unread, as a missing one is
    write(&dir, "outside.mtl", "newmtl a\nKd 0.5 0.5 0.5\n");
    write(&folder, "inside.mtl", "newmtl a\nKd 0.5 0.5 0.5\n");
    for (library, grey) in [("inside.mtl", 0.5), ("../outside.mtl", 1.0)] {
        let obj = format!("mtllib {library}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
        let model = load_model(&write(&folder, "lib.obj", obj)).unwrap();
        let colour = model.materials[model.meshes[0].material].base_color;
        assert_eq!(colour, Vec3::splat(grey), "{library}");
    }
}
