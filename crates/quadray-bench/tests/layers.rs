//! The crate's modules in layers with a one-way import order (the check of
//! `quadray_test_support::layering`). A new file must be given its layer in [`LAYERS`].

use quadray_test_support::layering::assert_layered;

/// Every module, by layer, bottom first: the tables and plots; what each technique's tables
/// share (the displacement bench's measuring context, the GI's scene runs at equal error and
/// its frame-to-frame change, the ray tracer's measurements) and the demo pictures; the tables
/// and figures on them; each technique's facade, which runs them; the crate root.
const LAYERS: &[&[&str]] = &[
    &["report"],
    &[
        "displace::measure",
        "displace::demo",
        "indirect::equal_error",
        "indirect::temporal",
        "indirect::demo",
        "shadows::measure",
    ],
    &[
        "displace::timing",
        "displace::accuracy",
        "indirect::cut_study",
        "indirect::tables",
        "indirect::run",
        "shadows::demo",
        "shadows::tables",
    ],
    &["displace", "indirect", "shadows"],
    &[""],
];

#[test]
fn every_module_imports_only_its_layer_or_below() {
    assert_layered(
        env!("CARGO_MANIFEST_DIR"),
        LAYERS,
        &[
            ("", "lib.rs"),
            ("displace", "displace/mod.rs"),
            ("indirect", "indirect/mod.rs"),
            ("shadows", "shadows/mod.rs"),
        ],
    );
}
