//! The crate's modules in layers with a one-way import order: every path a source file names
//! with `crate::` or `super::` (in `use` lines and in code, not in comments) must lead to a module
//! of its own layer or one below. A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first. The feature folders' `mod.rs` (`tiles`, `shadows`, ...)
/// hold their constants and sit low; the crate root re-exports the layers below it; the test-only
/// modules sit on top, beside it.
const LAYERS: &[&[&str]] = &[
    // the crate's error, defined in lib.rs but naming nothing of the crate
    &["IndirectError", "shader_struct"],
    &["method", "frame"],
    &["settings", "settings::cluster", "settings::sizes"],
    &["scene", "scene::builtin", "scene::textures"],
    &[
        "light",
        "light::node",
        "tiles",
        "shadows",
        "gathers",
        "direct",
        "output",
    ],
    &[
        "shadows::occupancy",
        "shadows::occupancy::triangle_box",
        "shadows::occupancy::walk",
    ],
    &["gathers::samples"],
    &[
        "reference",
        "picture",
        "tiles::blockiness",
        "tiles::deblock",
    ],
    &["tiles::twin"],
    &["contract"],
    &["wgsl"],
    &["light::view"],
    &["light::rsm"],
    &["gbuffer", "direct::shadow_map"],
    &["light::quadtree"],
    &["gathers::resources"],
    &["output::upsample", "shadows::corners"],
    &[
        "gathers::cut",
        "gathers::passes",
        "tiles::pass",
        "gathers::rsm_sampling",
        "gathers::brute_force",
        "gathers::decode",
        "output::temporal",
    ],
    &["gathers::gather"],
    &["output::pass", "direct::pass"],
    &["renderer"],
    &[
        "shader_tests",
        "settings::rules",
        "light::bound_tests",
        "shadows::occupancy_tests",
    ],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(env!("CARGO_MANIFEST_DIR"), LAYERS, &[("", "lib.rs")]);
}
