//! The crate's modules in layers with a one-way import order (the check of
//! `quadray_test_support::layering`). A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first; the crate root re-exports nothing and sits on top. The
/// items that lib.rs defines itself (the file error, the small parsers) are named at the bottom:
/// they name nothing of the crate.
const LAYERS: &[&[&str]] = &[
    &[
        "FileError",
        "parse_named",
        "parse_pair",
        "parse_size",
        "parse_vec3",
        "write_json",
        "write_text",
    ],
    &["random", "stats", "image_in"],
    &["geom", "geom::bvh", "settings", "settings::flags"],
    &["image_out"],
    &["mesh", "mesh::obj", "mesh::ply", "mesh::gltf"],
    &[
        "scene",
        "scene::read_gltf",
        "scene::read_toml",
        "scene::write_gltf",
    ],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(env!("CARGO_MANIFEST_DIR"), LAYERS, &[("", "lib.rs")]);
}
