//! Every GPU path under the Khronos validation layer with synchronization validation
//! (`quadray_gpu::validation`): software drivers forgive a missing barrier or an image in the
//! wrong layout, hardware does not. Each test fails on any error or warning of the layer that the
//! allow-list does not cover, naming its VUID, and fails if the layer did not run at all.

use quadray_gpu::validation::run_under_layer;
use quadray_test_support::examples::example_program;
use std::process::{Command, Output};

/// Runs `command` under the layer; panics with the layer's messages or the failure.
fn assert_clean(command: &mut Command, what: &str) -> Output {
    run_under_layer(command.env("RUST_BACKTRACE", "0"), what).unwrap_or_else(|e| panic!("{e}"))
}

/// `quadray smoke`: the displacement pyramid's GPU build, every displacement method (LOD, self
/// shadows), every indirect-light method pass by pass and timed, indirect shadows,
/// sub-sampling, the temporal filter with a moving camera and light, the output pass in each
/// format, the cut view.
#[test]
fn every_pass_of_quadray_smoke_passes_the_layer() {
    let output = assert_clean(
        Command::new(env!("CARGO_BIN_EXE_quadray")).args(["smoke", "--size", "16"]),
        "quadray smoke",
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    let cases = Command::new(env!("CARGO_BIN_EXE_quadray"))
        .args(["smoke", "--list"])
        .output()
        .unwrap();
    for case in String::from_utf8_lossy(&cases.stdout).lines() {
        let timed = format!("{case}/timed: done in ");
        let untimed = ["indirect-temporal", "indirect-output", "indirect-cut-view"];
        let last = if untimed.contains(&case) {
            format!("{case}/")
        } else {
            timed
        };
        assert!(stdout.contains(&last), "no `{last}` in {stdout}");
    }
}

/// Both examples a user copies that use the GPU (their own wgpu code and quadray's passes on
/// their device), each run as its program; `quadray indirect`'s sequence with the light and the
/// camera moving, filtered and not (its defaults: timed frames, the reference, the cut).
#[test]
fn the_examples_and_quadray_indirect_pass_the_layer() {
    let dir = crate::common::scratch("validation-examples");
    for example in ["displaced_quad", "gi_gbuffer"] {
        assert_clean(
            Command::new(example_program(example)).arg(dir.join(format!("{example}.png"))),
            &format!("example {example}"),
        );
    }
    let picture = crate::common::scratch("validation-indirect").join("indirect.png");
    assert_clean(
        Command::new(env!("CARGO_BIN_EXE_quadray"))
            .args([
                "indirect",
                "--size",
                "32x32",
                "--rsm-size",
                "32",
                "--frames",
                "2",
            ])
            .args(["--light-orbit", "3", "--camera-orbit", "2", "--out"])
            .arg(&picture),
        "quadray indirect --light-orbit --camera-orbit",
    );
}
