//! The crate's modules in layers with a one-way import order (the check of
//! `quadray_test_support::layering`). A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first; the crate root (`run`, the report) on top with the unit
/// tests. The clocks lib.rs defines name nothing of the crate and sit at the bottom.
const LAYERS: &[&[&str]] = &[
    &["ticks", "process_cpu_s", "thread_cpu_s"],
    &[
        "clip",
        "scene",
        "scene::file",
        "scene::lookalikes",
        "settings",
    ],
    &["grid"],
    &["cost", "occlusion", "shadow"],
    &["embree", "stats"],
    &["decide", "prepare"],
    &["trace"],
    &["pilot"],
    &["", "tests"],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(env!("CARGO_MANIFEST_DIR"), LAYERS, &[("", "lib.rs")]);
}
