//! `quadray-bevy-gi` as a user runs it without a display (`--screenshot`): the Cornell box glTF
//! through Bevy's loader and renderer, with and without quadray's bounce. That the bounce is the
//! right light is `quadray-bevy`'s `gi.rs` (the plugin against `quadray indirect`); this holds the
//! program: it runs headless, writes its picture at the size asked, and the bounce brightens the
//! room and darkens nothing.

use std::path::Path;
use std::process::Command;

/// Runs the program with `--screenshot DIR/NAME.png --size 64x64 --rsm-size 64` and `extra`,
/// and reads the picture back.
fn screenshot(dir: &Path, name: &str, extra: &[&str]) -> image::RgbaImage {
    let path = dir.join(format!("{name}.png"));
    let run = Command::new(env!("CARGO_BIN_EXE_quadray-bevy-gi"))
        .args(["--screenshot", path.to_str().unwrap()])
        .args(["--size", "64x64", "--rsm-size", "64"])
        .args(extra)
        .output()
        .expect("run quadray-bevy-gi");
    assert!(
        run.status.success(),
        "quadray-bevy-gi {extra:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

#[test]
fn the_gi_program_adds_the_bounce_to_its_headless_picture() {
    let dir = std::env::temp_dir().join(format!("quadray-bevy-gi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // At once: each mostly waits on its own frames. The Cornell box's one light is a spot: with
    // only point lights giving the bounce, none does.
    let (lit, unlit, no_source) = std::thread::scope(|s| {
        let lit = s.spawn(|| screenshot(&dir, "bounce", &["--method", "reference"]));
        let unlit = s.spawn(|| screenshot(&dir, "no-bounce", &["--no-gi"]));
        let no_source = s.spawn(|| screenshot(&dir, "no-source", &["--gi-lights", "point"]));
        let join = |h: std::thread::ScopedJoinHandle<'_, image::RgbaImage>| h.join().unwrap();
        (join(lit), join(unlit), join(no_source))
    });
    assert!(
        no_source == unlit,
        "--gi-lights point marked the Cornell box's spot"
    );
    assert_eq!(lit.dimensions(), (64, 64));
    assert_eq!(unlit.dimensions(), (64, 64));
    let luma = |p: &image::Rgba<u8>| p.0[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
    let (mut brighter, mut darker) = (0, 0);
    for (a, b) in lit.pixels().zip(unlit.pixels()) {
        brighter += usize::from(luma(a) > luma(b));
        darker += usize::from(luma(a) < luma(b));
    }
    println!("{brighter} of 4096 pixels brighter with the bounce, {darker} darker");
    // Measured: every pixel (the room fills the picture).
    assert!(brighter >= 3900, "only {brighter} of 4096 pixels brighter");
    assert_eq!(darker, 0, "{darker} pixels darker with the bounce");
}

/// `--displaced` shows the pyramid material's surfaces (a displaced floor and wall beside a red
/// wall, lit by a spot) with the bounce: it brightens the picture and darkens nothing, as on the
/// Cornell box. `--displaced` with `--scene` is refused.
#[test]
fn the_gi_program_bounces_off_displaced_surfaces() {
    let dir =
        std::env::temp_dir().join(format!("quadray-bevy-gi-displaced-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (lit, unlit) = std::thread::scope(|s| {
        let lit = s.spawn(|| screenshot(&dir, "bounce", &["--displaced"]));
        let unlit = s.spawn(|| screenshot(&dir, "no-bounce", &["--displaced", "--no-gi"]));
        (lit.join().unwrap(), unlit.join().unwrap())
    });
    let luma = |p: &image::Rgba<u8>| p.0[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
    let (mut brighter, mut darker) = (0, 0);
    for (a, b) in lit.pixels().zip(unlit.pixels()) {
        brighter += usize::from(luma(a) > luma(b));
        darker += usize::from(luma(a) < luma(b));
    }
    println!(
        "displaced surfaces: {brighter} of 4096 pixels brighter with the bounce, {darker} darker"
    );
    assert!(brighter >= 3500, "only {brighter} of 4096 pixels brighter");
    assert_eq!(darker, 0, "{darker} pixels darker with the bounce");
    let run = Command::new(env!("CARGO_BIN_EXE_quadray-bevy-gi"))
        .args(["--displaced", "--scene", "x.gltf"])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("cannot be used with"));
}

/// `--scene` renders a glTF of the user's from outside the repository's assets (here the bundled
/// Cornell box copied elsewhere): the same picture as the bundled one. A flag the program does
/// not know, and a scene that is not there, not glTF or malformed, are refused by name.
#[test]
fn the_gi_program_renders_a_users_gltf_and_refuses_what_it_cannot_use() {
    let dir = std::env::temp_dir().join(format!("quadray-bevy-gi-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes");
    let copy = dir.join("my room.gltf");
    std::fs::copy(assets.join("cornell_spot.gltf"), &copy).unwrap();
    let (own, bundled) = std::thread::scope(|s| {
        let own = s.spawn(|| screenshot(&dir, "own", &["--scene", copy.to_str().unwrap()]));
        let bundled = s.spawn(|| screenshot(&dir, "bundled", &[]));
        (own.join().unwrap(), bundled.join().unwrap())
    });
    assert_eq!(own.dimensions(), (64, 64));
    let differing = own
        .pixels()
        .zip(bundled.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "{differing} pixels differ from the bundled scene's"
    );

    let refused = |args: &[&str], needle: &str| {
        let run = Command::new(env!("CARGO_BIN_EXE_quadray-bevy-gi"))
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains(needle),
            "{args:?}: `{needle}` not in {stderr}"
        );
    };
    refused(&["--scenee", "x.gltf"], "unexpected argument '--scenee'");
    refused(
        &["--scene", "/no/such/room.gltf"],
        "--scene /no/such/room.gltf: cannot read it",
    );
    refused(
        &["--scene", "room.obj"],
        "--scene room.obj: not a glTF scene (.gltf or .glb)",
    );
    let recursive = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/malformed/gltf2/RecursiveNodes/RecursiveNodes.gltf"
    );
    refused(&["--scene", recursive], "RecursiveNodes.gltf: node");
    refused(&["--size", "0x64"], "--size");
    refused(&["--frames", "5"], "--screenshot");
    refused(
        &["--gi-lights", "area"],
        "invalid value 'area' for '--gi-lights",
    );
    refused(&["--turn-node", "bend"], "\"bend\" is not NAME:DEGREES");
    refused(
        &["--turn-node", "bend:inf"],
        "\"inf\" in \"bend:inf\" is not a finite number of degrees",
    );
}

/// `--ev100` exposes the picture as Bevy's `Exposure` does, for Bevy's light and the bounce
/// alike (and Bevy's ambient light with them): the courtyard glTF with its sun 256 times dimmer
/// (4.27 lux, black at Bevy's default EV100 of 9.7) at 8 EV less is the courtyard's own picture
/// at the default, pixel for pixel. An EV100 out of its range is refused.
#[test]
fn the_gi_program_exposes_a_dim_sun_as_bright_as_a_strong_one() {
    let dir = std::env::temp_dir().join(format!("quadray-bevy-gi-ev100-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let courtyard =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/courtyard.gltf");
    let text = std::fs::read_to_string(&courtyard).unwrap();
    let (sun, dim_sun) = ("\"intensity\": 1092.8", "\"intensity\": 4.26875");
    assert_eq!(text.matches(sun).count(), 1, "the courtyard's sun");
    let dim = dir.join("dim courtyard.gltf");
    std::fs::write(&dim, text.replace(sun, dim_sun)).unwrap();
    let (strong, exposed) = std::thread::scope(|s| {
        let strong =
            s.spawn(|| screenshot(&dir, "strong", &["--scene", courtyard.to_str().unwrap()]));
        let exposed = s.spawn(|| {
            screenshot(
                &dir,
                "exposed",
                &["--scene", dim.to_str().unwrap(), "--ev100", "1.7"],
            )
        });
        (strong.join().unwrap(), exposed.join().unwrap())
    });
    let mean = strong
        .pixels()
        .flat_map(|p| &p.0[..3])
        .map(|&c| f64::from(c))
        .sum::<f64>()
        / (3 * strong.pixels().len()) as f64;
    // Measured: 61.6 (the dim sun at the default: 13.1).
    assert!(
        mean > 40.0,
        "the courtyard at the default exposure is dark: {mean:.1}"
    );
    let differing = strong
        .pixels()
        .zip(exposed.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differing, 0,
        "{differing} pixels differ from the strong sun's"
    );
    let run = Command::new(env!("CARGO_BIN_EXE_quadray-bevy-gi"))
        .args(["--ev100", "30"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("EV100 30 is outside -10..25"), "{stderr}");
}

/// The program reads a scene through quadray's loader first, so a glTF whose buffer lies outside
/// its folder (`..`, an absolute path) is refused by name before Bevy starts, as `quadray` does.
#[test]
fn the_gi_program_refuses_a_scene_that_reads_outside_its_folder() {
    let dir = std::env::temp_dir().join(format!("quadray-bevy-gi-outside-{}", std::process::id()));
    let folder = dir.join("scene");
    std::fs::create_dir_all(&folder).unwrap();
    let outside = dir.join("outside.bin");
    std::fs::write(&outside, [0u8; 36]).unwrap();
    for uri in ["../outside.bin", outside.to_str().unwrap()] {
        let scene = folder.join("room.gltf");
        let text = format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":36,"uri":"{uri}"}}]}}"#
        );
        std::fs::write(&scene, text).unwrap();
        let run = Command::new(env!("CARGO_BIN_EXE_quadray-bevy-gi"))
            .args(["--scene", scene.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{uri}: {stderr}");
        assert!(
            stderr.contains(&format!("room.gltf: refers to `{uri}`, outside the folder")),
            "{uri}: {stderr}"
        );
    }
}

/// The large scene has what games have beside its million triangles: its counts are the file's,
/// most of its lumps' materials take their base colour from one of its three 64x64 sRGB PNG
/// textures (the lumps with uvs), and one tube is skinned to three joints, the middle one the
/// `bend` that `--bend-node` bends, with a joint and weights for every vertex summing to one.
#[test]
fn the_large_scene_has_textures_and_a_skinned_mesh() {
    use quadray_bevy_programs::large_scene::{BENDER, write_large_scene};
    use serde_json::Value;
    let dir = std::env::temp_dir().join(format!("quadray-large-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.glb");
    let made = write_large_scene(&path, 3).unwrap();
    let glb = std::fs::read(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_end = 20 + word(12);
    let gltf: Value = serde_json::from_slice(&glb[20..json_end]).unwrap();
    let bin = &glb[json_end + 8..];
    let list = |key: &str| gltf[key].as_array().cloned().unwrap_or_default();
    let view = |index: &Value| {
        let v = &gltf["bufferViews"][index.as_u64().unwrap() as usize];
        let start = v["byteOffset"].as_u64().unwrap() as usize;
        &bin[start..start + v["byteLength"].as_u64().unwrap() as usize]
    };
    let accessor_bytes =
        |index: &Value| view(&gltf["accessors"][index.as_u64().unwrap() as usize]["bufferView"]);

    assert!(made.triangles >= 1_000_000, "{made:?}");
    assert_eq!(list("meshes").len(), made.meshes);
    assert_eq!(list("materials").len(), made.materials);
    let with_mesh = list("nodes")
        .iter()
        .filter(|n| n.get("mesh").is_some())
        .count();
    assert_eq!(with_mesh, made.nodes);

    assert_eq!(list("images").len(), 3);
    assert_eq!(made.images, 3);
    for image in list("images") {
        assert_eq!(image["mimeType"], "image/png");
        let png = image::load_from_memory(view(&image["bufferView"])).unwrap();
        assert_eq!((png.width(), png.height()), (64, 64));
    }
    let textured: Vec<usize> = list("materials")
        .iter()
        .enumerate()
        .filter(|(_, m)| m["pbrMetallicRoughness"]["baseColorTexture"]["index"].is_u64())
        .map(|(i, _)| i)
        .collect();
    assert_eq!(textured.len(), made.textured_materials);
    // every mesh but the ground (the first) and the skinned tube (the last)
    let lumps: Vec<Value> = list("meshes")[1..made.meshes - 1].to_vec();
    let textured_lumps = lumps
        .iter()
        .filter(|m| {
            let primitive = &m["primitives"][0];
            primitive["attributes"]["TEXCOORD_0"].is_u64()
                && textured.contains(&(primitive["material"].as_u64().unwrap() as usize))
        })
        .count();
    println!("{textured_lumps} of {} lumps textured", lumps.len());
    assert!(
        textured_lumps * 2 > lumps.len(),
        "only {textured_lumps} of {} lumps textured",
        lumps.len()
    );

    let skins = list("skins");
    assert_eq!(skins.len(), 1);
    let joints = skins[0]["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 3);
    assert_eq!(
        gltf["nodes"][joints[1].as_u64().unwrap() as usize]["name"],
        BENDER
    );
    assert_eq!(
        accessor_bytes(&skins[0]["inverseBindMatrices"]).len(),
        3 * 64
    );
    let skinned: Vec<Value> = list("nodes")
        .into_iter()
        .filter(|n| n.get("skin").is_some())
        .collect();
    assert_eq!(skinned.len(), 1);
    let mesh = &gltf["meshes"][skinned[0]["mesh"].as_u64().unwrap() as usize];
    let attributes = &mesh["primitives"][0]["attributes"];
    let vertices = gltf["accessors"][attributes["POSITION"].as_u64().unwrap() as usize]["count"]
        .as_u64()
        .unwrap() as usize;
    let index_count = gltf["accessors"][mesh["primitives"][0]["indices"].as_u64().unwrap() as usize]
        ["count"]
        .as_u64()
        .unwrap() as usize;
    assert_eq!(index_count / 3, made.skinned_triangles);
    assert!(made.skinned_triangles >= 2000, "{made:?}");
    let joint_bytes = accessor_bytes(&attributes["JOINTS_0"]);
    assert_eq!(joint_bytes.len(), vertices * 8);
    assert!(
        joint_bytes
            .chunks_exact(2)
            .all(|j| u16::from_le_bytes([j[0], j[1]]) < 3)
    );
    let weights: Vec<f32> = accessor_bytes(&attributes["WEIGHTS_0"])
        .chunks_exact(4)
        .map(|w| f32::from_le_bytes(w.try_into().unwrap()))
        .collect();
    assert_eq!(weights.len(), vertices * 4);
    assert!(
        weights
            .chunks_exact(4)
            .all(|w| (w.iter().sum::<f32>() - 1.0).abs() < 1e-5),
        "a skinned vertex's weights do not sum to one"
    );
    // the middle joint moves some of the tube
    let bent = weights
        .chunks_exact(4)
        .zip(joint_bytes.chunks_exact(8))
        .filter(|(w, j)| {
            (0..4).any(|k| w[k] > 0.0 && u16::from_le_bytes([j[2 * k], j[2 * k + 1]]) == 1)
        })
        .count();
    assert!(
        bent * 2 > vertices,
        "only {bent} of {vertices} vertices follow `{BENDER}`"
    );
}
