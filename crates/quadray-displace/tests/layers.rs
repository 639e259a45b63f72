//! The crate's modules in layers with a one-way import order: every path a source file names
//! with `crate::` or `super::` (in `use` lines and in code, not in comments) must lead to a module
//! of its own layer or one below. A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first. `gpu` and the crate root are the facades that re-export
/// the layers below them; the accuracy measure reads the renderer's frames, the contract test
/// sits on top.
const LAYERS: &[&[&str]] = &[
    &["heightmap"],
    // the crate's error, defined in lib.rs, names the height map's
    &["DisplaceError"],
    &["pyramid"],
    &["reference", "cone"],
    &["method"],
    &["settings"],
    &["scene"],
    &["maps", "primary_rays"],
    &["search_cost"],
    &["gpu::trace", "gpu::height_pyramid"],
    &["gpu::pyramid_build"],
    &["gpu::surface_pass"],
    &["gpu::renderer"],
    &["gpu"],
    &["accuracy"],
    &["gpu::wgsl_contract"],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(
        env!("CARGO_MANIFEST_DIR"),
        LAYERS,
        &[("", "lib.rs"), ("gpu", "gpu/mod.rs")],
    );
}
