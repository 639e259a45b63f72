//! Every mesh, scene and height-map loader on mutations of the bundled real files (bit flips, truncation,
//! huge counts, NaN and infinite numbers, out-of-range indices): each case must end in a clear
//! error or a valid model or scene; never a panic (the mesh loader's safety net catching one
//! counts as a panic), a hang, or an allocation the file's size does not justify.
//!
//! The suite runs a few hundred seeded cases per loader; the long run (10^4 per loader) is
//! `cargo test --release -p quadray-cli --test suite -- fuzz_loaders:: --ignored`. A share of
//! every loader's cases must still load, or the mutations would only ever exercise its first check.

use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use quadray_core::mesh::FarCoordinate;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Counts the bytes the current thread holds, and their peak, so that a case can be checked for
/// an allocation out of proportion to its file.
struct PeakAlloc;

thread_local! {
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; the counters are thread-local cells.
unsafe impl GlobalAlloc for PeakAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = LIVE.try_with(|live| {
            live.set(live.get() + layout.size() as isize);
            let _ = PEAK.try_with(|peak| peak.set(peak.get().max(live.get())));
        });
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        let _ = LIVE.try_with(|live| live.set(live.get() - layout.size() as isize));
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: PeakAlloc = PeakAlloc;

/// The least share of a loader's mutated cases that must still load (the long run: 8-15%, the
/// MTL 100%): below it the mutations break every file before the loader gets far into it.
const MIN_VALID_SHARE: f64 = 0.04;

/// The bytes a case may hold at its peak beyond what it held before: generous for the parsed
/// model (a few dozen bytes per byte of file), far below what a claimed count of 2^32 asks for.
fn allocation_budget(file_len: usize) -> isize {
    (64 * file_len + (32 << 20)) as isize
}

/// One change to a file's bytes; positions are taken modulo the length.
#[derive(Clone, Debug)]
enum Mutation {
    FlipBit(usize, u8),
    Truncate(usize),
    /// Replaces the number (a run of digits) at or after a position with one of [`NUMBERS`].
    Number(usize, usize),
    /// Overwrites four bytes with a huge count, -1 or a NaN/inf bit pattern.
    Word(usize, usize),
    /// Repeats a slice of the file in place (duplicated lines, elements, chunks).
    Repeat(usize, usize),
}

const NUMBERS: [&str; 10] = [
    "4294967295",
    "18446744073709551616",
    "-1",
    "-2147483648",
    "nan",
    "inf",
    "-inf",
    "1e39",
    "0",
    "99999999",
];
const WORDS: [u32; 6] = [
    0xFFFF_FFFF,
    0x7FFF_FFFF,
    0x7FC0_0000, // NaN
    0x7F80_0000, // +inf
    0x1000_0000,
    0,
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(p, b)| Mutation::FlipBit(p, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 0..NUMBERS.len()).prop_map(|(p, n)| Mutation::Number(p, n)),
        (any::<usize>(), 0..WORDS.len()).prop_map(|(p, w)| Mutation::Word(p, w)),
        (any::<usize>(), 1usize..64).prop_map(|(p, n)| Mutation::Repeat(p, n)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    let at = |p: usize| p % bytes.len();
    match *m {
        Mutation::FlipBit(p, bit) => {
            let i = at(p);
            bytes[i] ^= 1 << bit;
        }
        Mutation::Truncate(p) => bytes.truncate(at(p)),
        Mutation::Number(p, n) => {
            let start = at(p);
            let Some(first) = bytes[start..].iter().position(u8::is_ascii_digit) else {
                return;
            };
            let first = start + first;
            let end = first
                + bytes[first..]
                    .iter()
                    .position(|b| !b.is_ascii_digit())
                    .unwrap_or(bytes.len() - first);
            bytes.splice(first..end, NUMBERS[n].bytes());
        }
        Mutation::Word(p, w) => {
            let i = at(p).min(bytes.len().saturating_sub(4));
            let end = (i + 4).min(bytes.len());
            bytes[i..end].copy_from_slice(&WORDS[w].to_le_bytes()[..end - i]);
        }
        Mutation::Repeat(p, n) => {
            let i = at(p);
            let slice = bytes[i..(i + n).min(bytes.len())].to_vec();
            bytes.splice(i..i, slice);
        }
    }
}

/// A loader under test: the file it is given (name in the case's folder) and what it returns.
struct Loader {
    name: &'static str,
    seeds: Vec<(String, Vec<u8>)>,
    /// Loads the file; Ok(true) for a valid result, Ok(false) for a clear error, Err(message)
    /// for a defect.
    load: fn(&Path) -> Result<bool, String>,
}

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

fn read(path: &str) -> Vec<u8> {
    std::fs::read(assets().join(path)).unwrap()
}

/// The Cornell box as PLY, ASCII and binary: no PLY is bundled.
fn ply_seeds() -> Vec<(String, Vec<u8>)> {
    let model =
        quadray_core::mesh::load_model(&assets().join("meshes/cornell_box/cornell_box.obj"))
            .unwrap();
    let (mut positions, mut faces) = (Vec::new(), Vec::new());
    for mesh in &model.meshes {
        let base = positions.len() as u32;
        positions.extend(mesh.positions.iter().copied());
        faces.extend(mesh.indices.iter().map(|t| t.map(|i| i + base)));
    }
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
             property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
            positions.len(),
            faces.len()
        )
    };
    let mut ascii = header("ascii");
    for p in &positions {
        ascii += &format!("{} {} {}\n", p.x, p.y, p.z);
    }
    for f in &faces {
        ascii += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    let mut binary = header("binary_little_endian").into_bytes();
    for p in &positions {
        for c in p.to_array() {
            binary.extend(c.to_le_bytes());
        }
    }
    for f in &faces {
        binary.push(3);
        for i in f {
            binary.extend((*i as i32).to_le_bytes());
        }
    }
    vec![
        ("ascii.ply".into(), ascii.into_bytes()),
        ("binary.ply".into(), binary),
    ]
}

/// A valid model has every coordinate within `MAX_COORDINATE`, every index in range and every
/// material present.
fn mesh_loader(path: &Path) -> Result<bool, String> {
    match quadray_core::mesh::load_model(path) {
        Ok(model) => {
            for mesh in &model.meshes {
                let n = mesh.positions.len() as u32;
                if FarCoordinate::find(mesh.positions.iter().copied()).is_some()
                    || mesh.indices.iter().flatten().any(|&i| i >= n)
                    || mesh.material >= model.materials.len()
                {
                    return Err(format!("invalid model accepted: {mesh:?}"));
                }
            }
            Ok(true)
        }
        Err(e) => clear(&e.to_string(), path),
    }
}

/// A valid scene has every coordinate of its shapes, placed, within `MAX_COORDINATE`.
fn scene_description_loader(path: &Path) -> Result<bool, String> {
    use quadray_core::scene::{SceneDescription, Shape};
    match SceneDescription::load(path) {
        Ok(scene) => {
            for (o, object) in scene.objects.iter().enumerate() {
                let to_world = object.transform.matrix();
                let points: Vec<Vec3> = match &object.shape {
                    Shape::Mesh { model, .. } => model
                        .meshes
                        .iter()
                        .flat_map(|m| m.positions.iter().map(|&p| to_world.transform_point3(p)))
                        .collect(),
                    Shape::Box { min, max } => vec![*min, *max],
                    Shape::Polygons(polygons) => polygons.concat(),
                    Shape::Builtin(_) => Vec::new(),
                };
                if let Some((v, c)) = FarCoordinate::find(points) {
                    return Err(format!("object {o}: vertex {v}: {c}, accepted"));
                }
            }
            Ok(true)
        }
        Err(e) => clear(&e.to_string(), path),
    }
}

/// The shadows scene file: loading, then the checks `quadray raytrace` makes before rendering.
fn shadows_scene_loader(path: &Path) -> Result<bool, String> {
    match quadray_shadows::Scene::load(path) {
        Ok(scene) => match scene.validate() {
            Ok(()) => Ok(true),
            Err(e) => clear(&format!("{}: {e}", path.display()), path),
        },
        Err(e) => clear(&e.to_string(), path),
    }
}

/// Height maps: the 8-bit interlaced PNG bundled (348x348, traced as stored), and, cut from the
/// bundled 16-bit Puget Sound map to keep cases fast, a 16-bit PNG and a float EXR (none is
/// bundled).
fn height_map_seeds() -> Vec<(String, Vec<u8>)> {
    let full = image::load_from_memory(&read("heightmaps/puget_sound/ps_height_1k.png")).unwrap();
    let crop = full.crop_imm(300, 400, 64, 64);
    let encode = |image: image::DynamicImage, format| {
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write_to(&mut bytes, format).unwrap();
        bytes.into_inner()
    };
    vec![
        (
            "cube_depth.png".into(),
            read("heightmaps/bevy_parallax/cube_depth.png"),
        ),
        (
            "height16.png".into(),
            encode(crop.to_luma16().into(), image::ImageFormat::Png),
        ),
        (
            "height.exr".into(),
            encode(crop.to_rgb32f().into(), image::ImageFormat::OpenExr),
        ),
    ]
}

/// The height-map loader as `quadray displace` calls it, in two of its conventions: a white-is-
/// high map resampled to a square power of two (`--resample`), and a depth photo as stored.
fn height_map_loader(path: &Path) -> Result<bool, String> {
    use quadray_core::image_in::MAX_SIDE;
    use quadray_displace::heightmap::{Convention, Fit, HeightMap};
    let mut valid = false;
    for (convention, fit) in [
        (Convention::Height, Fit::Resample),
        (Convention::DepthPhoto, Fit::Exact),
    ] {
        match HeightMap::load(path, convention, fit) {
            Ok(map) => {
                let (w, h) = (map.width, map.height);
                let resampled_square = fit == Fit::Exact || (w == h && w.is_power_of_two());
                if !resampled_square
                    || !(1..=MAX_SIDE).contains(&w)
                    || !(1..=MAX_SIDE).contains(&h)
                    || map.depth.len() != w as usize * h as usize
                    || map.depth.iter().any(|d| !(0.0..=1.0).contains(d))
                {
                    return Err(format!("invalid map accepted: {w}x{h}"));
                }
                valid = true;
            }
            Err(e) => {
                clear(&e.to_string(), path)?;
            }
        }
    }
    Ok(valid)
}

/// An error is clear when it names the file and did not come from a caught panic.
fn clear(message: &str, path: &Path) -> Result<bool, String> {
    let name = path.file_name().unwrap().to_string_lossy();
    if message.contains("panicked") {
        Err(format!("a panic: {message}"))
    } else if !message.contains(&*name) {
        Err(format!("the error does not name the file: {message}"))
    } else {
        Ok(false)
    }
}

fn loaders() -> Vec<Loader> {
    let scene = |p: &str| (p.rsplit('/').next().unwrap().to_string(), read(p));
    vec![
        Loader {
            name: "OBJ",
            seeds: vec![(
                "cornell_box.obj".into(),
                read("meshes/cornell_box/cornell_box.obj"),
            )],
            load: mesh_loader,
        },
        Loader {
            name: "MTL (through OBJ)",
            seeds: vec![(
                "cornell_box.mtl".into(),
                read("meshes/cornell_box/cornell_box.mtl"),
            )],
            load: |mtl| mesh_loader(&mtl.with_file_name("cornell_box.obj")),
        },
        Loader {
            name: "PLY",
            seeds: ply_seeds(),
            load: mesh_loader,
        },
        Loader {
            name: "glTF/GLB",
            seeds: vec![
                (
                    "cornell-box.glb".into(),
                    read("meshes/cornell_box_gltf/cornell-box.glb"),
                ),
                scene("scenes/cornell_spot.gltf"),
            ],
            load: mesh_loader,
        },
        Loader {
            name: "scene TOML and glTF (quadray_core::scene)",
            seeds: ["cornell.toml", "atrium.toml", "cornell_spot.gltf"]
                .map(|s| scene(&format!("scenes/{s}")))
                .to_vec(),
            load: scene_description_loader,
        },
        Loader {
            name: "shadows scene file",
            seeds: [
                "example-hst.toml",
                "shadows-demo.toml",
                "shadows-cornell.toml",
            ]
            .map(|s| scene(&format!("scenes/{s}")))
            .to_vec(),
            load: shadows_scene_loader,
        },
        // Last, so that the loaders before keep their seeds and cases.
        Loader {
            name: "height map (PNG 8/16-bit, EXR)",
            seeds: height_map_seeds(),
            load: height_map_loader,
        },
    ]
}

/// The case's folder: `scenes/` for the file, with the Cornell box's mesh files where the bundled
/// scenes expect them (`../meshes/cornell_box/`) and beside it (an OBJ's MTL).
fn case_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("quadray-fuzz-{}", std::process::id()));
    let meshes = dir.join("meshes/cornell_box");
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::create_dir_all(&meshes).unwrap();
    for f in ["cornell_box.obj", "cornell_box.mtl"] {
        let bytes = read(&format!("meshes/cornell_box/{f}"));
        std::fs::write(meshes.join(f), &bytes).unwrap();
        std::fs::write(dir.join("scenes").join(f), &bytes).unwrap();
    }
    dir.join("scenes")
}

fn fuzz(cases_per_loader: u32) {
    let dir = case_dir();
    let mut report = Vec::new();
    for (l, loader) in loaders().iter().enumerate() {
        let config = Config {
            cases: cases_per_loader,
            failure_persistence: None,
            ..Config::default()
        };
        let seed = [l as u8 + 1; 32];
        let mut runner =
            TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
        let (valid, refused) = (Cell::new(0u32), Cell::new(0u32));
        let strategy = (
            0..loader.seeds.len(),
            proptest::collection::vec(mutation(), 1..4),
        );
        let result = runner.run(&strategy, |(seed, mutations)| {
            let (name, original) = &loader.seeds[seed];
            let mut bytes = original.clone();
            for m in &mutations {
                apply(&mut bytes, m);
            }
            let path = dir.join(name);
            std::fs::write(&path, &bytes).unwrap();
            let before = LIVE.with(Cell::get);
            PEAK.with(|p| p.set(before));
            let start = Instant::now();
            let outcome = std::panic::catch_unwind(|| (loader.load)(&path))
                .unwrap_or_else(|_| Err("a panic".into()));
            let (took, peak) = (start.elapsed(), PEAK.with(Cell::get) - before);
            // Restore the file other loaders of this case folder read (the MTL case's OBJ).
            std::fs::write(&path, original).unwrap();
            let outcome = outcome.and_then(|ok| {
                if took > Duration::from_secs(5) {
                    Err(format!("took {took:?}"))
                } else if peak > allocation_budget(bytes.len()) {
                    Err(format!("held {peak} bytes for a {} byte file", bytes.len()))
                } else {
                    Ok(ok)
                }
            });
            match outcome {
                Ok(true) => valid.set(valid.get() + 1),
                Ok(false) => refused.set(refused.get() + 1),
                Err(defect) => {
                    return Err(TestCaseError::fail(format!(
                        "{name} {mutations:?}: {defect}"
                    )));
                }
            }
            Ok(())
        });
        if let Err(e) = result {
            panic!("{}: {e}", loader.name);
        }
        assert!(
            f64::from(valid.get()) >= MIN_VALID_SHARE * f64::from(cases_per_loader),
            "{}: only {} of {cases_per_loader} mutated cases loaded",
            loader.name,
            valid.get()
        );
        report.push(format!(
            "{}: {} valid, {} refused",
            loader.name,
            valid.get(),
            refused.get()
        ));
    }
    println!("{}", report.join("\n"));
    std::fs::remove_dir_all(dir.parent().unwrap()).ok();
}

#[test]
fn loaders_survive_mutated_files() {
    fuzz(200);
}

#[test]
#[ignore = "the long run: 10^4 cases per loader, 40 s on 2 cores; run by hand before a release (BENCHMARKS.md, Fuzzed loaders)"]
fn loaders_survive_mutated_files_long() {
    fuzz(10_000);
}
