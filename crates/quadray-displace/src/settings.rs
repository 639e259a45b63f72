//! The one set of displacement parameters the library, `quadray displace` and the viewer share.
//! Each is declared once, here: its field, its doc comment (the `--help` text), its default in
//! [`Settings::DEFAULT`] and its valid values in a [`Limits`] const that both
//! [`Settings::validate`] and the flag's parser use. With the `cli` feature the struct is
//! `quadray displace`'s clap arguments; `Settings::to_args` spells them back, and a round-trip
//! test parses them again.

use crate::method::Method;
use quadray_core::settings::{Limits, Size};
use std::fmt;
use std::str::FromStr;

/// Finest level the traversal may reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Lod {
    /// From screen-space derivatives of the texture coordinate, as mip selection does (3.4).
    Auto,
    /// A fixed level (0: the map's own texels).
    Level(u32),
}

impl fmt::Display for Lod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Lod::Auto => f.write_str("auto"),
            Lod::Level(l) => write!(f, "{l}"),
        }
    }
}

impl FromStr for Lod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Lod::Auto),
            n => n
                .parse()
                .map(Lod::Level)
                .map_err(|_| format!("`{s}` is not `auto` or a level")),
        }
    }
}

/// POM / relief layer counts, from head-on (`min`) to grazing (`max`); written `MIN,MAX`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Layers {
    /// Layers head-on.
    pub min: u32,
    /// Layers at grazing angles (cone stepping's cone steps).
    pub max: u32,
}

impl Layers {
    /// Either count.
    pub const COUNT: Limits<u32> = Limits::closed(1, 4096).interactive(1, 256);

    /// Both counts within [`Layers::COUNT`], `min` not above `max`.
    pub fn check(&self) -> Result<(), String> {
        let c = Self::COUNT;
        if c.contains(self.min) && c.contains(self.max) && self.min <= self.max {
            Ok(())
        } else {
            Err(format!(
                "layers {self} must satisfy {} <= min <= max <= {}",
                c.min, c.max
            ))
        }
    }
}

impl fmt::Display for Layers {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{}", self.min, self.max)
    }
}

impl FromStr for Layers {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (min, max) = quadray_core::parse_pair(s, ',', "MIN,MAX")?;
        Ok(Self { min, max })
    }
}

/// The size check `validate()` and `--size` share.
fn check_size(size: &Size) -> Result<(), String> {
    size.check(Settings::SIDE)
}

/// Everything a frame depends on besides the map and the surface.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Settings {
    /// The search (or the mesh baseline).
    #[cfg_attr(
        feature = "cli",
        arg(long, value_enum, default_value_t = Settings::DEFAULT.method)
    )]
    pub method: Method,
    /// Angle between the view direction at the surface centre and the normal, degrees.
    #[cfg_attr(feature = "cli", arg(
        long = "view-angle",
        default_value_t = Settings::DEFAULT.view_angle_deg,
        value_parser = Settings::VIEW_ANGLE.parser(),
    ))]
    pub view_angle_deg: f32,
    /// Frame size in pixels, WxH.
    #[serde(flatten)]
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.size,
        value_parser = quadray_core::settings::checked(check_size),
    ))]
    pub size: Size,
    /// Texture units per unit of depth (Bevy's default 0.1).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.depth_scale,
        value_parser = Settings::DEPTH_SCALE.parser(),
    ))]
    pub depth_scale: f32,
    /// POM / relief layers MIN,MAX (head-on .. grazing). Bevy: 1,16; Godot: 8,32; three.js:
    /// 20,25. Cone stepping takes MAX as its number of cone steps.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.layers,
        value_parser = quadray_core::settings::checked(Layers::check),
    ))]
    pub layers: Layers,
    /// Relief mapping's and cone stepping's binary search steps (three.js: 5).
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.binary_steps,
        value_parser = Settings::BINARY_STEPS.parser(),
    ))]
    pub binary_steps: u32,
    /// Finest pyramid level: `auto` (from screen-space derivatives) or a level number.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Settings::DEFAULT.lod))]
    pub lod: Lod,
    /// Self-shadowing by tracing from the light.
    #[cfg_attr(feature = "cli", arg(long))]
    pub shadows: bool,
    /// Camera azimuth around the surface normal, degrees (the benchmark keeps the default; the
    /// viewer moves it).
    #[cfg_attr(feature = "cli", arg(
        long = "azimuth",
        default_value_t = Settings::DEFAULT.azimuth_deg,
        value_parser = Settings::AZIMUTH.parser(),
        allow_negative_numbers = true,
    ))]
    pub azimuth_deg: f32,
    /// Camera distance as a multiple of the surface's default.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.zoom,
        value_parser = Settings::ZOOM.parser(),
    ))]
    pub zoom: f32,
    /// The light's azimuth around the surface normal, degrees.
    #[cfg_attr(feature = "cli", arg(
        long = "light-azimuth",
        default_value_t = Settings::DEFAULT.light_azimuth_deg,
        value_parser = Settings::AZIMUTH.parser(),
        allow_negative_numbers = true,
    ))]
    pub light_azimuth_deg: f32,
    /// Colour pixels by the iterations their search took (0..64: black, red, yellow, white).
    #[cfg_attr(feature = "cli", arg(long))]
    pub show_iterations: bool,
}

impl Method {
    /// The settings the demo and the accuracy tables show the method with: the budget an engine
    /// ships where one does.
    pub fn shown(self) -> Settings {
        match self {
            // As Bevy ships it: 16 layers at grazing angles down to 1 head-on.
            Method::Pom => Settings {
                layers: Layers { min: 1, max: 16 },
                method: self,
                ..Settings::DEFAULT
            },
            // As three.js's example ships it: 20..25 layers and 5 binary steps.
            Method::Relief => Settings {
                layers: Layers { min: 20, max: 25 },
                binary_steps: 5,
                method: self,
                ..Settings::DEFAULT
            },
            Method::Cone => RELAXED_CONE,
            _ => Settings {
                method: self,
                ..Settings::DEFAULT
            },
        }
    }

    /// The settings the timing tables run: the paper's 16 layers (and 5 binary steps) where
    /// layers count, the chapter's budget for cone stepping.
    pub fn timed(self) -> Settings {
        match self {
            Method::Cone => RELAXED_CONE,
            _ => Settings {
                layers: Layers { min: 16, max: 16 },
                binary_steps: 5,
                method: self,
                ..Settings::DEFAULT
            },
        }
    }
}

/// Relaxed cone step mapping with 15 cone steps and 8 binary steps: a fixed budget in the range
/// the chapter's shaders use.
const RELAXED_CONE: Settings = Settings {
    method: Method::Cone,
    layers: Layers { min: 15, max: 15 },
    binary_steps: 8,
    ..Settings::DEFAULT
};

impl Settings {
    /// Every parameter's default (the flags' defaults too).
    pub const DEFAULT: Settings = Settings {
        method: Method::Pyramid,
        view_angle_deg: 45.0,
        size: Size::new(512, 512),
        depth_scale: 0.1,
        layers: Layers { min: 8, max: 32 },
        binary_steps: 5,
        lod: Lod::Level(0),
        shadows: false,
        azimuth_deg: 30.0,
        zoom: 1.0,
        light_azimuth_deg: 30.0,
        show_iterations: false,
    };

    /// [`Settings::view_angle_deg`]: grazing, not beyond.
    pub const VIEW_ANGLE: Limits<f32> = Limits::closed(0.0, 89.0);
    /// Either side of [`Settings::size`].
    pub const SIDE: Limits<u32> = Limits::closed(1, 8192);
    /// [`Settings::depth_scale`]: a flat surface makes no search.
    pub const DEPTH_SCALE: Limits<f32> = Limits::above(0.0, 10.0).interactive(0.01, 0.5);
    /// [`Settings::binary_steps`].
    pub const BINARY_STEPS: Limits<u32> = Limits::closed(0, 64).interactive(0, 16);
    /// [`Settings::azimuth_deg`] and [`Settings::light_azimuth_deg`]: any finite angle.
    pub const AZIMUTH: Limits<f32> = Limits::closed(-f32::MAX, f32::MAX).interactive(-180.0, 180.0);
    /// [`Settings::zoom`].
    pub const ZOOM: Limits<f32> = Limits::closed(0.05, 20.0).interactive(0.2, 4.0);

    /// Refuses parameters that would make no picture or an absurd amount of work.
    pub fn validate(&self) -> Result<(), String> {
        Self::VIEW_ANGLE.check("view angle", self.view_angle_deg)?;
        check_size(&self.size)?;
        Self::DEPTH_SCALE.check("depth scale", self.depth_scale)?;
        self.layers.check()?;
        Self::BINARY_STEPS.check("binary steps", self.binary_steps)?;
        Self::AZIMUTH.check("azimuth", self.azimuth_deg)?;
        Self::ZOOM.check("zoom", self.zoom)?;
        Self::AZIMUTH.check("light azimuth", self.light_azimuth_deg)?;
        Ok(())
    }

    /// The `quadray displace` flags that render these settings (the viewer prints them beside its
    /// screenshots; the CLI's tests parse them back): every clap argument with its serde field's
    /// value.
    #[cfg(feature = "cli")]
    pub fn to_args(&self) -> Vec<String> {
        // serde flattens the size into `width` and `height`, writes the layers as `{min, max}`
        // and a fixed level as `{"level": n}`: their flags are `WxH`, `MIN,MAX` and `n`.
        quadray_core::settings::to_args(
            self,
            &[
                ("size", self.size.to_string()),
                ("layers", self.layers.to_string()),
                ("lod", self.lod.to_string()),
            ],
        )
    }

    /// What a picture of these settings is called: the method and the budget it was given
    /// (`pom 1-16`, `relief 16+5`, `cone 15+8`, `pyramid lod-auto`).
    pub fn caption(&self) -> String {
        use crate::method::Budget;
        let Layers { min, max } = self.layers;
        let layers = if min == max {
            max.to_string()
        } else {
            format!("{min}-{max}")
        };
        let mut caption = match self.method.describe().budget {
            Budget::None => self.method.to_string(),
            Budget::Layers => format!("{} {layers}", self.method),
            Budget::LayersAndBinary => format!("{} {layers}+{}", self.method, self.binary_steps),
            Budget::ConeSteps => format!("{} {max}+{}", self.method, self.binary_steps),
        };
        if self.lod == Lod::Auto {
            caption += " lod-auto";
        }
        caption
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each refusal names the parameter and its declared range.
    #[test]
    fn validate_uses_the_declared_limits() {
        let ok = Settings::default();
        assert!(ok.validate().is_ok());
        let bad = [
            (
                Settings {
                    view_angle_deg: 89.5,
                    ..ok.clone()
                },
                "view angle 89.5",
                Settings::VIEW_ANGLE.to_string(),
            ),
            (
                Settings {
                    size: Size::new(0, 10),
                    ..ok.clone()
                },
                "size 0x10",
                Settings::SIDE.to_string(),
            ),
            (
                Settings {
                    depth_scale: 0.0,
                    ..ok.clone()
                },
                "depth scale 0",
                Settings::DEPTH_SCALE.to_string(),
            ),
            (
                Settings {
                    layers: Layers { min: 9, max: 3 },
                    ..ok.clone()
                },
                "layers 9,3",
                format!(
                    "{} <= min <= max <= {}",
                    Layers::COUNT.min,
                    Layers::COUNT.max
                ),
            ),
            (
                Settings {
                    binary_steps: 65,
                    ..ok.clone()
                },
                "binary steps 65",
                Settings::BINARY_STEPS.to_string(),
            ),
            (
                Settings {
                    light_azimuth_deg: f32::INFINITY,
                    ..ok.clone()
                },
                "light azimuth inf",
                Settings::AZIMUTH.to_string(),
            ),
            (
                Settings {
                    zoom: f32::NAN,
                    ..ok.clone()
                },
                "zoom NaN",
                Settings::ZOOM.to_string(),
            ),
        ];
        for (s, what, range) in bad {
            let e = s.validate().unwrap_err();
            assert!(e.starts_with(what) && e.ends_with(&range), "{e}");
        }
    }

    /// Settings with every field off its default and every switch on, and the settings each
    /// method is shown and timed with, come back through `to_args` and the clap arguments: a
    /// field left out of the flags, or written so that it parses otherwise, fails here (a new
    /// field first fails `flags_at_default` until it is given a value here).
    #[cfg(feature = "cli")]
    #[test]
    fn every_setting_comes_back_through_its_flags() {
        use quadray_core::settings::assert_flags_round_trip;
        let every = Settings {
            method: Method::Relief,
            view_angle_deg: 60.5,
            size: Size::new(96, 64),
            depth_scale: 0.25,
            layers: Layers { min: 4, max: 40 },
            binary_steps: 7,
            lod: Lod::Auto,
            shadows: true,
            azimuth_deg: -120.25,
            zoom: 1.5,
            light_azimuth_deg: 200.0,
            show_iterations: true,
        };
        assert!(every.validate().is_ok());
        let shown = Method::ALL.into_iter().flat_map(|m| [m.shown(), m.timed()]);
        assert_flags_round_trip(
            every,
            std::iter::once(Settings::DEFAULT).chain(shown),
            &Settings::DEFAULT.to_args(),
            Settings::to_args,
        );
    }

    #[test]
    fn captions_name_the_budget() {
        let caption = |m: Method| m.shown().caption();
        assert_eq!(caption(Method::Pyramid), "pyramid");
        assert_eq!(caption(Method::Pom), "pom 1-16");
        assert_eq!(caption(Method::Relief), "relief 20-25+5");
        assert_eq!(caption(Method::Cone), "cone 15+8");
        assert_eq!(Method::Pom.timed().caption(), "pom 16");
        let auto = Settings {
            lod: Lod::Auto,
            ..Settings::DEFAULT
        };
        assert_eq!(auto.caption(), "pyramid lod-auto");
    }
}
