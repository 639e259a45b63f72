//! The valid values of a technique's numeric settings, declared once per setting: the library's
//! `validate()` checks a value with [`Limits::check`] and the command line's parser with
//! [`Limits::parser`], so the two cannot disagree.
//!
//! ```
//! use quadray_core::settings::Limits;
//! const ZOOM: Limits<f32> = Limits::closed(0.05, 20.0);
//! assert!(ZOOM.check("zoom", 1.5).is_ok());
//! assert_eq!(ZOOM.parser()("30").unwrap_err(), "30 is outside 0.05..=20");
//! ```
//!
//! With the `cli` feature, [`to_args`] spells any settings value back as the flags that parse to
//! it, from the settings' clap arguments and serde fields.

use std::fmt;
use std::str::FromStr;

#[cfg(feature = "cli")]
mod flags;
#[cfg(feature = "cli")]
pub use flags::{assert_flags_round_trip, flags_at_default, from_args, terminal_help, to_args};

/// A number a setting can hold.
pub trait Number: Copy + PartialOrd + fmt::Display + FromStr + Send + Sync + 'static {
    /// The number as messages write it.
    fn shown(self) -> String {
        self.to_string()
    }
}
impl Number for f32 {
    /// Huge values in scientific notation: `f32::MAX`, the bound of "any finite value", is
    /// 3.4028235e38 rather than 39 digits.
    fn shown(self) -> String {
        if self.abs() >= 1e7 {
            format!("{self:e}")
        } else {
            self.to_string()
        }
    }
}
impl Number for u32 {}

/// The values a numeric setting may take: `min..=max`, or `(min, max]` when the minimum itself
/// makes no picture (a zero depth scale). NaN is never inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits<T> {
    pub min: T,
    pub max: T,
    pub min_excluded: bool,
    /// The part of the range an interactive control spans, where the whole range is too wide to
    /// pick from (a threshold up to `f32::MAX`); `None`: all of it.
    pub interactive: Option<(T, T)>,
}

impl<T: Number> Limits<T> {
    /// `min..=max`.
    pub const fn closed(min: T, max: T) -> Self {
        Self {
            min,
            max,
            min_excluded: false,
            interactive: None,
        }
    }

    /// `(min, max]`: above `min`, at most `max`.
    pub const fn above(min: T, max: T) -> Self {
        Self {
            min,
            max,
            min_excluded: true,
            interactive: None,
        }
    }

    /// These limits with `min..=max` as the part an interactive control spans (the viewer's
    /// sliders).
    pub const fn interactive(self, min: T, max: T) -> Self {
        Self {
            interactive: Some((min, max)),
            ..self
        }
    }

    /// The range an interactive control spans: [`Limits::interactive`]'s, else the limits'.
    pub fn interactive_range(&self) -> (T, T) {
        self.interactive.unwrap_or((self.min, self.max))
    }

    pub fn contains(&self, value: T) -> bool {
        let above_min = if self.min_excluded {
            value > self.min
        } else {
            value >= self.min
        };
        above_min && value <= self.max
    }

    /// `value`, or an error naming it as `what` and saying where it must lie.
    pub fn check(&self, what: &str, value: T) -> Result<T, String> {
        self.admit(value).map_err(|e| format!("{what} {e}"))
    }

    fn admit(&self, value: T) -> Result<T, String> {
        if self.contains(value) {
            Ok(value)
        } else {
            Err(format!("{} is outside {self}", value.shown()))
        }
    }

    /// The command-line parser of the setting (clap takes it as `value_parser`): the number, if
    /// it lies within these limits.
    pub fn parser(self) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
        move |text: &str| {
            let value = text
                .trim()
                .parse::<T>()
                .map_err(|_| format!("`{text}` is not a number"))?;
            self.admit(value)
        }
    }
}

impl<T: Number> fmt::Display for Limits<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (min, max) = (self.min.shown(), self.max.shown());
        if self.min_excluded {
            write!(f, "({min}, {max}]")
        } else {
            write!(f, "{min}..={max}")
        }
    }
}

/// The command-line parser of a setting whose value is more than one number (`WxH`, `MIN,MAX`):
/// `V`'s own parsing, then `check`, the function the library's `validate()` calls.
pub fn checked<V>(
    check: fn(&V) -> Result<(), String>,
) -> impl Fn(&str) -> Result<V, String> + Clone + Send + Sync + 'static
where
    V: FromStr<Err = String> + 'static,
{
    move |text: &str| {
        let value = text.parse::<V>()?;
        check(&value)?;
        Ok(value)
    }
}

/// An image size, written `WxH` on command lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

impl Size {
    pub const fn new(width: u32, height: u32) -> Self {
        Self { width, height }
    }

    /// Both sides within `side`, or an error that names the size.
    pub fn check(&self, side: Limits<u32>) -> Result<(), String> {
        if side.contains(self.width) && side.contains(self.height) {
            Ok(())
        } else {
            Err(format!("size {self} has a side outside {side}"))
        }
    }
}

impl fmt::Display for Size {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

impl FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (width, height) = crate::parse_size(s)?;
        Ok(Self { width, height })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_limits_hold_both_ends_and_refuse_nan() {
        let l = Limits::closed(0.0f32, 89.0);
        assert!(l.contains(0.0) && l.contains(89.0));
        assert!(!l.contains(89.01) && !l.contains(-0.01) && !l.contains(f32::NAN));
        assert_eq!(
            l.check("view angle", 90.0).unwrap_err(),
            "view angle 90 is outside 0..=89"
        );
    }

    #[test]
    fn an_excluded_minimum_is_refused() {
        let l = Limits::above(0.0f32, 10.0);
        assert!(!l.contains(0.0) && l.contains(1e-6) && l.contains(10.0));
        assert_eq!(l.to_string(), "(0, 10]");
    }

    #[test]
    fn the_parser_refuses_text_and_values_outside() {
        let p = Limits::closed(1u32, 64).parser();
        assert_eq!(p(" 7"), Ok(7));
        assert_eq!(p("0").unwrap_err(), "0 is outside 1..=64");
        assert_eq!(p("x").unwrap_err(), "`x` is not a number");
        assert_eq!(p("-1").unwrap_err(), "`-1` is not a number");
        let f = Limits::closed(-f32::MAX, f32::MAX).parser();
        assert!(f("inf").is_err() && f("NaN").is_err());
        assert_eq!(f("-3.5"), Ok(-3.5));
        assert_eq!(
            f("-1e39").unwrap_err(),
            "-inf is outside -3.4028235e38..=3.4028235e38"
        );
    }

    #[test]
    fn sizes_read_back_what_they_write_and_check_both_sides() {
        let size: Size = "96x64".parse().unwrap();
        assert_eq!(
            (size, size.to_string()),
            (Size::new(96, 64), "96x64".into())
        );
        assert!("96".parse::<Size>().is_err());
        let side = Limits::closed(1, 8192);
        assert!(size.check(side).is_ok());
        assert!(
            Size::new(0, 10)
                .check(side)
                .unwrap_err()
                .contains("size 0x10")
        );
        assert!(Size::new(10, 8193).check(side).is_err());
    }
}
