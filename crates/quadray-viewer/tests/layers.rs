//! The viewer's modules in layers with a one-way import order (the check of
//! `crates/quadray-indirect/tests/layering.rs`): the shared controls below the two views, the
//! views below the command line, the window above them, `main` on top.

#[path = "../../quadray-indirect/tests/layering.rs"]
mod layering;

use std::path::Path;

const LAYERS: &[&[&str]] = &[
    &["widgets"],
    &["displace_view", "indirect_view"],
    &["args"],
    &["app"],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let wrong = layering::upward_imports(&src, LAYERS, &[("", "main.rs")]);
    assert!(wrong.is_empty(), "{wrong:#?}");
}
