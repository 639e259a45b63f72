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
    choices_combo(egui::ComboBox::from_label(label), ui, value, choices, name);
}

/// [`choice_box`] under its `label` ([`named`]).
pub fn named_choice_box<T: Copy + PartialEq>(
    ui: &mut egui::Ui,
    label: &str,
    value: &mut T,
    choices: &[T],
    name: impl Fn(T) -> String,
) {
    named(ui, true, label, |ui| {
        choices_combo(
            egui::ComboBox::from_id_salt(label),
            ui,
            value,
            choices,
            name,
        )
    });
}

fn choices_combo<T: Copy + PartialEq>(
    combo: egui::ComboBox,
    ui: &mut egui::Ui,
    value: &mut T,
    choices: &[T],
    name: impl Fn(T) -> String,
) {
    combo.selected_text(name(*value)).show_ui(ui, |ui| {
        for &choice in choices {
            ui.selectable_value(value, choice, name(choice));
        }
    });
}

/// `control` under its `name` on a line of its own, which wraps at the panel's width: for names
/// too long to stand beside a slider or a combo box, whose own text does not wrap and would be
/// cut at the panel's edge. Disabled, both are greyed.
pub fn named<R>(
    ui: &mut egui::Ui,
    enabled: bool,
    name: &str,
    control: impl FnOnce(&mut egui::Ui) -> R,
) -> R {
    ui.add_enabled_ui(enabled, |ui| {
        ui.label(name);
        control(ui)
    })
    .inner
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
