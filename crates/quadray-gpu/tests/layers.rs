//! The crate's modules in layers with a one-way import order (the check of
//! `quadray_test_support::layering`). A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first. The device and its error, which lib.rs defines, come
/// first: the read-backs and the timer wait through it; the crate root re-exports on top.
const LAYERS: &[&[&str]] = &[
    &["Gpu", "GpuError", "Limit", "LimitNeed", "WAIT_BOUND_ENV"],
    &["readback", "target", "validation"],
    &["timer"],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(env!("CARGO_MANIFEST_DIR"), LAYERS, &[("", "lib.rs")]);
}
