//! The command line's modules in layers with a one-way import order (the check of
//! `quadray_test_support::layering`). A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first: what a stats file was measured with, which every
/// subcommand that writes one names; the work items below the ray tracer's subcommand that
/// writes them and the merge that reads them; each technique's subcommand beside the others;
/// `main` on top. The spinner main.rs defines names nothing of the crate.
const LAYERS: &[&[&str]] = &[
    &["spinner", "provenance"],
    &["tiles"],
    &["raytrace"],
    &["merge", "displace", "indirect", "scene", "smoke"],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(env!("CARGO_MANIFEST_DIR"), LAYERS, &[("", "main.rs")]);
}
