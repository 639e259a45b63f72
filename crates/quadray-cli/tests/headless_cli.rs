//! Headless commands print nothing but their own output: creating the Vulkan instance must not
//! make Mesa probe window systems (without a display that prints an error that is none).

use std::process::Command;

#[test]
fn headless_commands_do_not_probe_window_systems() {
    let run = Command::new(env!("CARGO_BIN_EXE_quadray"))
        .arg("adapter")
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .expect("run quadray");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "quadray adapter: {stderr}");
    assert!(
        !stderr.contains("XDG_RUNTIME_DIR"),
        "window-system probing leaked into stderr: {stderr}"
    );
}
