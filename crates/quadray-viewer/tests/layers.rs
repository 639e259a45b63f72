//! The viewer's modules in layers with a one-way import order (the check of
//! `quadray_test_support::layering`): the shared controls below the two views, the
//! views below the command line, the window above them, `main` on top.

use quadray_test_support::layering::assert_layered;

const LAYERS: &[&[&str]] = &[
    &["widgets", "legibility"],
    &["displace_view", "indirect_view"],
    &["args"],
    &["app"],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(env!("CARGO_MANIFEST_DIR"), LAYERS, &[("", "main.rs")]);
}
