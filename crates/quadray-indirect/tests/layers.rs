//! The crate's modules in layers with a one-way import order: every path a source file names
//! with `crate::` or `super::` (in `use` lines and in code, not in comments) must lead to a module
//! of its own layer or one below. A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first. `gpu` and the crate root are the facades that re-export
/// the layers below them; the test-only modules sit on top, beside them.
const LAYERS: &[&[&str]] = &[
    // the crate's error, defined in lib.rs but naming nothing of the crate
    &["IndirectError"],
    &["settings"],
    &["frame"],
    &["scene", "scene::builtin"],
    &["occupancy"],
    &["baselines"],
    &["reference", "picture", "blockiness", "deblock"],
    &["tile_cut"],
    &["gpu::contract"],
    &["wgsl"],
    &["gpu::light"],
    &["gpu::rsm"],
    &["gpu::gbuffer"],
    &["gpu::quadtree"],
    &["gpu::gather::resources"],
    &["gpu::gather::upsample"],
    &[
        "gpu::gather::cut",
        "gpu::gather::passes",
        "gpu::gather::tiles",
        "gpu::gather::rsm_sampling",
        "gpu::gather::brute_force",
        "gpu::gather::direct",
        "gpu::gather::temporal",
    ],
    &["gpu::gather"],
    &["gpu::output"],
    &["gpu::renderer"],
    &["gpu"],
    &[
        "gpu::shader_tests",
        "gpu::bound_tests",
        "gpu::occupancy_tests",
    ],
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
