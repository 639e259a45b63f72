//! The controls both views build their panels from, and the command-line words of a screenshot's
//! replay: below the views, which `app` draws.

use egui::emath::Numeric;
use quadray_core::settings::{Limits, Number};
use std::path::{Path, PathBuf};

/// A combo box that sets `value` to one of `choices`, each shown by `name`.
pub fn choice_box<T: Copy + PartialEq>(
    ui: &mut egui::Ui,
    label: &str,
    value: &mut T,
    choices: &[T],
    name: impl Fn(T) -> String,
) {
    egui::ComboBox::from_label(label)
        .selected_text(name(*value))
        .show_ui(ui, |ui| {
            for &choice in choices {
                ui.selectable_value(value, choice, name(choice));
            }
        });
}

/// A slider over the part of a setting's `limits` an interactive control spans, logarithmic when
/// that part spans two decades or more above zero.
pub fn limits_slider<'a, T: Number + Numeric>(
    value: &'a mut T,
    limits: Limits<T>,
    text: &str,
) -> egui::Slider<'a> {
    let (min, max) = limits.interactive_range();
    let decades = min.to_f64() > 0.0 && max.to_f64() / min.to_f64() >= 100.0;
    egui::Slider::new(value, min..=max)
        .logarithmic(decades)
        .text(text)
}

/// The path without `..`, so the screenshot's command line works from any directory.
pub fn absolute(path: PathBuf) -> PathBuf {
    std::fs::canonicalize(&path).unwrap_or(path)
}

/// A path as one POSIX shell word (single-quoted when it holds anything but plain characters).
pub fn shell_word(path: &Path) -> String {
    let text = path.display().to_string();
    let plain = |c: char| c.is_ascii_alphanumeric() || "/._-+,:=@%".contains(c);
    if !text.is_empty() && text.chars().all(plain) {
        text
    } else {
        format!("'{}'", text.replace('\'', r"'\''"))
    }
}
