//! The crate's modules in layers with a one-way import order (the check of
//! `quadray_test_support::layering`). A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first: the pyramid image, the material at the root, the
/// displaced surfaces' triangles, the base colour textures, the skinned and morphed meshes'
/// poses and the indirect light's CPU times, its main-world side (which reads the materials and
/// those), then its render-world side by phase (the pipelines, the scene's triangles, the
/// lights' prepare, the RSM drawn from Bevy's meshes, the cameras' prepare, the passes), and the
/// plugin that adds both.
const LAYERS: &[&[&str]] = &[
    &["pyramid_image"],
    &[""],
    &["gi::cpu_time", "gi::displaced", "gi::textures", "gi::posed"],
    &["gi::scene"],
    &["gi::lights"],
    &["gi::render::pipelines"],
    &["gi::render::triangles"],
    &["gi::render::light"],
    &["gi::render::meshes"],
    &["gi::render::views"],
    &["gi::render::passes"],
    &["gi::render"],
    &["gi"],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(
        env!("CARGO_MANIFEST_DIR"),
        LAYERS,
        &[("", "lib.rs"), ("gi", "gi/mod.rs")],
    );
}
