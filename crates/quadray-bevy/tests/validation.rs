//! Bevy's frame with quadray's passes under the Khronos validation layer with synchronization
//! validation: the material's traced main pass, its prepasses and G-buffer, its light loop and
//! shadow pass, and the GI plugin's passes (one light and three kinds at once, a camera that waits
//! for what Bevy draws). Those tests run only here, once, in a child process with the layer, so
//! that the suite does not run them twice; the child's failures and the layer's messages fail this
//! test.

/// The tests the child runs (each ignored in the parent, its reason naming this module).
const UNDER_THE_LAYER: [&str; 7] = [
    "hits::bevy_hits_agree_with_the_cpu_ground_truth",
    "prepass::prepass_and_gbuffer_hold_the_traced_surface",
    "self_shadow::each_light_is_hidden_by_the_height_field_on_its_own",
    "shadows::the_displaced_surface_casts_its_traced_shadow",
    "gi::plugin_matches_quadray_and_adds_light_only_where_it_should",
    "gi::plugin_gathers_the_sun_a_point_light_and_a_spot_as_quadray_does",
    "gi::a_still_camera_gathers_what_bevy_draws_later",
];

#[test]
fn every_pass_passes_the_layer() {
    let mut rerun = std::process::Command::new(std::env::current_exe().unwrap());
    rerun
        .args(["--ignored", "--exact", "--test-threads", "2"])
        .args(UNDER_THE_LAYER);
    match quadray_gpu::validation::run_under_layer(&mut rerun, "the Bevy tests under the layer") {
        Ok(output) => {
            let log = String::from_utf8_lossy(&output.stdout);
            let passed = UNDER_THE_LAYER
                .iter()
                .filter(|name| log.contains(&format!("test {name} ... ok")))
                .count();
            assert_eq!(passed, UNDER_THE_LAYER.len(), "{log}");
        }
        Err(problem) => panic!("{problem}"),
    }
}
