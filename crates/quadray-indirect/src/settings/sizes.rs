//! The sizes' checks that [`Settings::validate`] and the flags' parsers share: the picture's, the
//! RSM's and the shadow maps'.

use crate::settings::Settings;
use quadray_core::settings::Size;

/// The size check `validate()` and `--size` share.
pub(super) fn check_size(size: &Size) -> Result<(), String> {
    size.check(Settings::SIDE)
}

/// The RSM-size check `validate()` and `--rsm-size` share: a power of two within
/// [`Settings::RSM_SIZE`].
pub(super) fn check_rsm_size(size: u32) -> Result<u32, String> {
    if size.is_power_of_two() && Settings::RSM_SIZE.contains(size) {
        Ok(size)
    } else {
        Err(format!(
            "RSM size {size} must be a power of two in {}",
            Settings::RSM_SIZE
        ))
    }
}

/// The shadow-map check `validate()` and `--shadow-map-size` share: a power of two within
/// [`Settings::SHADOW_MAP_SIZE`].
pub(super) fn check_shadow_map_size(size: u32) -> Result<u32, String> {
    if size.is_power_of_two() && Settings::SHADOW_MAP_SIZE.contains(size) {
        Ok(size)
    } else {
        Err(format!(
            "shadow map size {size} must be a power of two in {}",
            Settings::SHADOW_MAP_SIZE
        ))
    }
}

impl Settings {
    /// `--size`'s parser (`WxH`, each side within [`Settings::SIDE`]), also for a program with a
    /// command line of its own.
    pub fn parse_size(text: &str) -> Result<Size, String> {
        quadray_core::settings::checked(check_size)(text)
    }

    /// `--rsm-size`'s parser (a power of two within [`Settings::RSM_SIZE`]), likewise.
    pub fn parse_rsm_size(text: &str) -> Result<u32, String> {
        check_rsm_size(Settings::RSM_SIZE.parser()(text)?)
    }

    /// `--shadow-map-size`'s parser (a power of two within [`Settings::SHADOW_MAP_SIZE`]).
    pub fn parse_shadow_map_size(text: &str) -> Result<u32, String> {
        check_shadow_map_size(Settings::SHADOW_MAP_SIZE.parser()(text)?)
    }
}
