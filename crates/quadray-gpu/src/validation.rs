//! Runs a program under the Khronos validation layer (core and synchronization validation) and
//! reads what the layer printed. Software drivers forgive what hardware does not (a missing
//! barrier, an image in the wrong layout); the layer finds that class of bug on any driver,
//! lavapipe included. quadray's suite runs every GPU path through it; use it on your own program
//! the same way:
//!
//! ```no_run
//! let mut command = std::process::Command::new("target/release/quadray");
//! command.args(["smoke", "--size", "16"]);
//! if let Err(problem) = quadray_gpu::validation::run_under_layer(&mut command, "quadray smoke") {
//!     panic!("{problem}"); // a VUID and its message, one a line
//! }
//! ```

use std::path::{Path, PathBuf};
use std::process::Command;

/// The layer's settings: synchronization validation on, errors, warnings and its status line
/// printed to stdout.
pub fn settings_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("vk_layer_settings.txt")
}

/// Whether the Vulkan loader can find the layer in a standard place or in `VK_ADD_LAYER_PATH` /
/// `VK_LAYER_PATH` (Debian's package: `vulkan-validationlayers`).
pub fn layer_installed() -> bool {
    let listed = ["VK_ADD_LAYER_PATH", "VK_LAYER_PATH"]
        .into_iter()
        .filter_map(std::env::var_os)
        .flat_map(|paths| std::env::split_paths(&paths).collect::<Vec<_>>());
    let standard = [
        "/usr/share/vulkan/explicit_layer.d",
        "/usr/local/share/vulkan/explicit_layer.d",
        "/etc/vulkan/explicit_layer.d",
    ]
    .map(PathBuf::from);
    listed
        .chain(standard)
        .any(|dir| dir.join("VkLayer_khronos_validation.json").is_file())
}

/// Sets the environment that loads the layer with [`settings_file`] into `command`'s Vulkan
/// instances.
pub fn under_layer(command: &mut Command) -> &mut Command {
    command
        .env("VK_INSTANCE_LAYERS", "VK_LAYER_KHRONOS_validation")
        .env("VK_LAYER_SETTINGS_PATH", settings_file())
}

/// Runs `command` under the layer and checks it: it succeeded, the layer ran, and it printed no
/// error or warning that [`ALLOWED`] does not cover. The error says which, for `what`.
pub fn run_under_layer(command: &mut Command, what: &str) -> Result<std::process::Output, String> {
    if !layer_installed() {
        return Err(format!(
            "{what}: the Khronos validation layer is not installed (scripts/setup.sh: \
             vulkan-validationlayers)"
        ));
    }
    let output = under_layer(command)
        .output()
        .map_err(|e| format!("{what}: cannot start: {e}"))?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    LayerReport::parse(&stdout).check(what)?;
    if !output.status.success() {
        return Err(format!(
            "{what} failed ({}): {stdout}{}",
            output.status,
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    Ok(output)
}

/// Messages that are the layer's own fault, not quadray's, each with its reason: (VUID, a text
/// the message contains, why it is allowed).
pub const ALLOWED: &[(&str, &str, &str)] = &[
    (
        "VUID-VkDeviceCreateInfo-pNext-pNext",
        "unknown VkStructureType (1000506000)",
        "Debian 12's layer (1.3.239) predates VK_KHR_cooperative_matrix (1.3.255), whose feature \
         struct wgpu chains on drivers that have it (NVIDIA 580 with Bevy's features)",
    ),
    (
        "VUID_Undefined",
        "Device Extension VK_KHR_cooperative_matrix is not supported by this layer",
        "the same extension, which that layer cannot validate",
    ),
];

/// One message of the layer.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerMessage {
    /// The VUID, e.g. `UNASSIGNED-CoreValidation-DrawState-InvalidImageLayout`.
    pub vuid: String,
    /// `ERROR`, `WARN`, `PERF` or `INFO`.
    pub severity: String,
    /// The whole message, its object lines included.
    pub text: String,
}

impl LayerMessage {
    /// The allow-list entry that covers this message, if any.
    pub fn allowed(&self) -> Option<&'static str> {
        ALLOWED
            .iter()
            .find(|(vuid, needle, _)| self.vuid == *vuid && self.text.contains(needle))
            .map(|(_, _, why)| *why)
    }
}

/// What the layer printed into a program's output.
#[derive(Clone, Debug, Default)]
pub struct LayerReport {
    /// The layer's status line was there: it ran.
    pub active: bool,
    /// ... with synchronization validation enabled.
    pub synchronization: bool,
    /// Every message but the status line.
    pub messages: Vec<LayerMessage>,
}

impl LayerReport {
    /// Reads the layer's messages out of `stdout`: each starts with `VUID(SEVERITY / TYPE):` and
    /// goes on over indented lines.
    pub fn parse(stdout: &str) -> LayerReport {
        let mut report = LayerReport::default();
        let mut current: Option<LayerMessage> = None;
        for line in stdout.lines() {
            if let Some((vuid, severity)) = message_head(line) {
                report.take(current.take());
                current = Some(LayerMessage {
                    vuid: vuid.into(),
                    severity: severity.into(),
                    text: line.into(),
                });
            } else if let Some(message) = current.as_mut() {
                if line.starts_with(char::is_whitespace) || line.is_empty() {
                    message.text.push('\n');
                    message.text.push_str(line);
                } else {
                    report.take(current.take());
                }
            }
        }
        report.take(current);
        report
    }

    fn take(&mut self, message: Option<LayerMessage>) {
        let Some(message) = message else { return };
        if message.vuid == "UNASSIGNED-khronos-validation-createinstance-status-message" {
            self.active = true;
            self.synchronization |= message
                .text
                .lines()
                .any(|l| l.contains("Current Enables") && l.contains("SYNCHRONIZATION"));
        } else {
            self.messages.push(message);
        }
    }

    /// The errors and warnings that no [`ALLOWED`] entry covers.
    pub fn unexpected(&self) -> Vec<&LayerMessage> {
        self.messages
            .iter()
            .filter(|m| m.severity != "INFO" && m.allowed().is_none())
            .collect()
    }

    /// `Ok` when the layer ran with synchronization validation and printed nothing unexpected;
    /// else what went wrong, for `what` (the program or test that ran).
    pub fn check(&self, what: &str) -> Result<(), String> {
        if !(self.active && self.synchronization) {
            return Err(format!(
                "{what}: the validation layer's status line with synchronization validation is \
                 missing: the layer did not run (scripts/setup.sh installs vulkan-validationlayers)"
            ));
        }
        match self.unexpected().len() {
            0 => Ok(()),
            n => Err(format!(
                "{what}: {n} validation messages:\n{}",
                self.describe_unexpected()
            )),
        }
    }

    /// One line per unexpected message: its VUID and the start of its text.
    pub fn describe_unexpected(&self) -> String {
        self.unexpected()
            .iter()
            .map(|m| {
                let text: String = m.text.chars().take(600).collect();
                format!("{} ({}): {text}", m.vuid, m.severity)
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

/// `VUID(SEVERITY / TYPE): msgNum: ...` -> (VUID, SEVERITY), also after other text on the line
/// (the test harness's `test name ... ` before a message printed during the test).
fn message_head(line: &str) -> Option<(&str, &str)> {
    let (head, _) = line.split_once("): msgNum:")?;
    let (before, kind) = head.rsplit_once('(')?;
    let (severity, _) = kind.split_once(" / ")?;
    let vuid = before.rsplit(char::is_whitespace).next()?;
    (!vuid.is_empty()).then_some((vuid, severity))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the layer printed for the displacement pyramid's build before it was split into one
    /// pass per level (lavapipe, 1.3.239), between two lines of quadray's own output.
    const BEFORE_THE_FIX: &str = "\
UNASSIGNED-khronos-validation-createinstance-status-message(INFO / SPEC): msgNum: -671457468 - Validation Information: [ UNASSIGNED-khronos-validation-createinstance-status-message ] Object 0: handle = 0x5654e2e43b80, type = VK_OBJECT_TYPE_INSTANCE; | MessageID = 0xd7fa5f44 | Khronos Validation Layer Active:
    Settings File: Found at /tmp/vk_layer_settings.txt specified by environment variable (VK_LAYER_SETTINGS_PATH).
    Current Enables: VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION.
    Current Disables: None.

    Objects: 1
        [0] 0x5654e2e43b80, type: 1, name: NULL
llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, llvmpipe Mesa 22.3.6 (LLVM 15.0.6)) (waits bounded at 1800s)
UNASSIGNED-CoreValidation-DrawState-InvalidImageLayout(ERROR / SPEC): msgNum: 1303270965 - Validation Error: [ UNASSIGNED-CoreValidation-DrawState-InvalidImageLayout ] Object 0: handle = 0x564c96c698c0, type = VK_OBJECT_TYPE_COMMAND_BUFFER; | MessageID = 0x4dae5635 | vkQueueSubmit(): pSubmits[0].pCommandBuffers[5] command buffer VkCommandBuffer 0x564c96c698c0[] expects VkImage 0x230000000023[] (subresource: aspectMask 0x1 array layer 0, mip level 1) to be in layout VK_IMAGE_LAYOUT_GENERAL--instead, current layout is VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL.
    Objects: 1
        [0] 0x564c96c698c0, type: 6, name: NULL
VUID_Undefined(WARN / SPEC): msgNum: 2044605652 - Validation Warning: [ VUID_Undefined ] Object 0: handle = 0x55d6397177b0, type = VK_OBJECT_TYPE_DEVICE; | MessageID = 0x79de34d4 | Device Extension VK_KHR_cooperative_matrix is not supported by this layer.  Using this extension may adversely affect validation results and/or produce undefined behavior.
    Objects: 1
        [0] 0x55d6397177b0, type: 3, name: NULL
displace-pyramid-build/point: done in 26.8 ms
test examples::gi_gbuffer ... VUID_Undefined(WARN / SPEC): msgNum: 1 - Validation Warning: [ VUID_Undefined ] | Something else.
";

    #[test]
    fn the_layers_messages_are_read_and_the_allowed_ones_set_apart() {
        let report = LayerReport::parse(BEFORE_THE_FIX);
        assert!(report.active && report.synchronization);
        let vuids: Vec<_> = report.messages.iter().map(|m| m.vuid.as_str()).collect();
        assert_eq!(
            vuids,
            [
                "UNASSIGNED-CoreValidation-DrawState-InvalidImageLayout",
                "VUID_Undefined",
                "VUID_Undefined"
            ]
        );
        let unexpected = report.unexpected();
        assert_eq!(unexpected.len(), 2);
        assert!(unexpected[1].text.ends_with("Something else."));
        assert!(unexpected[0].text.contains("mip level 1"));
        assert!(unexpected[0].text.ends_with("name: NULL"));
        assert!(report.describe_unexpected().starts_with(
            "UNASSIGNED-CoreValidation-DrawState-InvalidImageLayout (ERROR): UNASSIGNED"
        ));
    }

    #[test]
    fn output_without_the_layer_reads_as_inactive() {
        let report = LayerReport::parse("displace-pyramid-build/point: done in 26.8 ms\n");
        assert!(!report.active && report.messages.is_empty());
    }
}
