//! The crate's modules in layers with a one-way import order (the check of
//! `crates/quadray-indirect/tests/layering.rs`). A new file must be given its layer in [`LAYERS`].

use crate::layering::assert_layered;

/// Every module, by layer, bottom first: the pyramid image and the indirect light's main-world
/// side, then its render-world side, the plugin that adds both, the material at the root.
const LAYERS: &[&[&str]] = &[
    &["pyramid_image", "gi::scene"],
    &["gi::render"],
    &["gi"],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(
        env!("CARGO_MANIFEST_DIR"),
        LAYERS,
        &[("", "lib.rs"), ("gi", "gi/mod.rs")],
    );
}
