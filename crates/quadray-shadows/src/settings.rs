//! What a user configures of a render: the shadow scheme, HST's threshold, the picture's size,
//! samples and recursion depth, and the rule that refuses settings that make no picture. Plain
//! values: the tracer, `quadray raytrace`, the benchmarks and the example all take this one type.
//!
//! Each parameter is declared once, here: its field, its doc comment (the `--help` text), its
//! default in [`Settings::DEFAULT`] and its valid values in a [`Limits`] const that both
//! [`Settings::validate`] and the flag's parser use. With the `cli` feature the struct is
//! `quadray raytrace`'s clap arguments; `Settings::to_args` spells them back (the tiles'
//! fingerprint), and a round-trip test parses them again.

use quadray_core::settings::{Limits, Size};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// How the HST threshold is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Nth {
    /// Equation 12 from measured machine constants and the scene's statistics.
    Auto,
    /// This N_th.
    Fixed(f32),
}

impl Nth {
    /// A fixed threshold within [`Settings::NTH`].
    pub fn check(&self) -> Result<(), String> {
        match self {
            Nth::Auto => Ok(()),
            Nth::Fixed(n) => Settings::NTH.check("N_th", *n).map(|_| ()),
        }
    }
}

impl fmt::Display for Nth {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Nth::Auto => f.write_str("auto"),
            Nth::Fixed(n) => write!(f, "{n}"),
        }
    }
}

impl FromStr for Nth {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Nth::Auto),
            n => n
                .trim()
                .parse()
                .map(Nth::Fixed)
                .map_err(|_| format!("`{s}` is not `auto` or a number")),
        }
    }
}

/// The shadow scheme asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SchemeChoice {
    /// A shadow ray per light through the grid.
    Conventional,
    /// Shadow volumes: depth counts carried along every ray segment.
    Volume,
    /// The hybrid switch (HST) with threshold N_th.
    Hst,
    /// A shadow ray per light through a SAH BVH.
    Bvh,
    /// Embree occlusion rays; needs the `embree` feature.
    Embree,
}

impl SchemeChoice {
    /// Every scheme, in the order the CLI lists them.
    pub const ALL: [SchemeChoice; 5] = [
        SchemeChoice::Conventional,
        SchemeChoice::Volume,
        SchemeChoice::Hst,
        SchemeChoice::Bvh,
        SchemeChoice::Embree,
    ];

    /// The scheme's name on the command line and in the stats (`--shadows`).
    pub fn name(self) -> &'static str {
        match self {
            SchemeChoice::Conventional => "conventional",
            SchemeChoice::Volume => "volume",
            SchemeChoice::Hst => "hst",
            SchemeChoice::Bvh => "bvh",
            SchemeChoice::Embree => "embree",
        }
    }
}

impl FromStr for SchemeChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match quadray_core::parse_named(s, &Self::ALL, Self::name, "shadow scheme")? {
            SchemeChoice::Embree if !cfg!(feature = "embree") => {
                Err("this quadray was built without Embree (cargo build --features embree)".into())
            }
            scheme => Ok(scheme),
        }
    }
}

impl fmt::Display for SchemeChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The size check `validate()` and `--size` share.
fn check_size(size: &Size) -> Result<(), String> {
    size.check(Settings::SIDE)
}

/// One render's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Settings {
    /// Shadow scheme: hst, volume, conventional, bvh, or embree (built with --features embree).
    #[cfg_attr(
        feature = "cli",
        arg(long = "shadows", default_value_t = Settings::DEFAULT.scheme)
    )]
    pub scheme: SchemeChoice,
    /// HST threshold: auto (the cost model's prediction) or a number.
    #[serde(skip)] // the stats write it as `nth.asked`, beside the N_th predicted and used
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.nth,
        value_parser = quadray_core::settings::checked(Nth::check),
        allow_negative_numbers = true,
    ))]
    pub nth: Nth,
    /// Image size WxH.
    #[serde(flatten)]
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.size,
        value_parser = quadray_core::settings::checked(check_size),
    ))]
    pub size: Size,
    /// Samples per pixel.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.spp,
        value_parser = Settings::SPP.parser(),
    ))]
    pub spp: u32,
    /// Recursion depth of reflection and refraction.
    #[cfg_attr(feature = "cli", arg(
        long,
        default_value_t = Settings::DEFAULT.depth,
        value_parser = Settings::DEPTH.parser(),
    ))]
    pub depth: u32,
    /// Also run the conventional test at every shading point and count disagreements.
    #[cfg_attr(feature = "cli", arg(long))]
    pub check: bool,
}

impl Settings {
    /// Every parameter's default (the flags' defaults too): HST at the predicted N_th, the
    /// paper's 512x480 pictures and recursion depth 5.
    pub const DEFAULT: Settings = Settings {
        scheme: SchemeChoice::Hst,
        nth: Nth::Auto,
        size: Size::new(512, 480),
        spp: 1,
        depth: 5,
        check: false,
    };

    /// A fixed [`Settings::nth`]: any finite count of shadow polygons.
    pub const NTH: Limits<f32> = Limits::closed(0.0, f32::MAX);
    /// Either side of [`Settings::size`].
    pub const SIDE: Limits<u32> = Limits::closed(1, 16384);
    /// [`Settings::spp`].
    pub const SPP: Limits<u32> = Limits::closed(1, 1024);
    /// [`Settings::depth`]: the tracer recurses once a level.
    pub const DEPTH: Limits<u32> = Limits::closed(0, 64);

    /// Refuses parameters that would make no picture or an absurd amount of work.
    pub fn validate(&self) -> Result<(), String> {
        self.nth.check()?;
        check_size(&self.size)?;
        Self::SPP.check("spp", self.spp)?;
        Self::DEPTH.check("depth", self.depth)?;
        Ok(())
    }

    /// The `quadray raytrace` flags that render these settings (the tiles of a job carry them as
    /// their fingerprint's readable part; the CLI's tests parse them back): every clap argument
    /// with its serde field's value.
    #[cfg(feature = "cli")]
    pub fn to_args(&self) -> Vec<String> {
        // serde flattens the size into `width` and `height` and skips N_th (the stats write
        // it beside the predicted one): their flags are `WxH` and `auto` or a number.
        quadray_core::settings::to_args(
            self,
            &[
                ("size", self.size.to_string()),
                ("nth", self.nth.to_string()),
            ],
        )
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
        let ok = Settings::DEFAULT;
        assert!(ok.validate().is_ok());
        let bad = [
            (
                Settings {
                    nth: Nth::Fixed(-1.0),
                    ..ok
                },
                "N_th -1",
                Settings::NTH.to_string(),
            ),
            (
                Settings {
                    nth: Nth::Fixed(f32::NAN),
                    ..ok
                },
                "N_th NaN",
                Settings::NTH.to_string(),
            ),
            (
                Settings {
                    size: Size::new(0, 10),
                    ..ok
                },
                "size 0x10",
                Settings::SIDE.to_string(),
            ),
            (
                Settings { spp: 0, ..ok },
                "spp 0",
                Settings::SPP.to_string(),
            ),
            (
                Settings { depth: 65, ..ok },
                "depth 65",
                Settings::DEPTH.to_string(),
            ),
        ];
        for (s, what, range) in bad {
            let e = s.validate().unwrap_err();
            assert!(e.starts_with(what) && e.ends_with(&range), "{e}");
        }
    }

    /// Settings with every field off its default and every switch on, and the defaults, come
    /// back through `to_args` and the clap arguments: a field left out of the flags, or written
    /// so that it parses otherwise, fails here (a new field first fails `flags_at_default`
    /// until it is given a value here).
    #[cfg(feature = "cli")]
    #[test]
    fn every_setting_comes_back_through_its_flags() {
        use quadray_core::settings::assert_flags_round_trip;
        let every = Settings {
            scheme: SchemeChoice::Volume,
            nth: Nth::Fixed(6.5),
            size: Size::new(96, 64),
            spp: 4,
            depth: 2,
            check: true,
        };
        assert!(every.validate().is_ok());
        assert_flags_round_trip(
            every,
            [Settings::DEFAULT],
            &Settings::DEFAULT.to_args(),
            Settings::to_args,
        );
    }

    #[test]
    fn names_read_back_what_they_write() {
        for scheme in SchemeChoice::ALL {
            if scheme != SchemeChoice::Embree || cfg!(feature = "embree") {
                assert_eq!(scheme.name().parse(), Ok(scheme));
            }
        }
        assert!(
            "raster"
                .parse::<SchemeChoice>()
                .unwrap_err()
                .starts_with("unknown shadow scheme")
        );
        for nth in [Nth::Auto, Nth::Fixed(6.0), Nth::Fixed(0.125)] {
            assert_eq!(nth.to_string().parse(), Ok(nth));
        }
        assert!("x".parse::<Nth>().is_err());
    }
}
