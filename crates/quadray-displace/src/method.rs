//! The methods `quadray displace --method` accepts, each described once in [`DESCRIPTIONS`]: its
//! name, help line, ground truth and how a caption spells its budget. The command line's choices,
//! the captions and every benchmark's list of methods are read from there; the settings the demo
//! and the benchmarks run each with are [`crate::Settings`]'s (`Method::shown`, `Method::timed`).

use crate::reference::Surface;
use std::fmt;
use std::str::FromStr;

/// A way to find where a view ray meets the height field. The variants' order is the shader-id
/// order and the order of [`DESCRIPTIONS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// The paper: top-down pyramid traversal with node crossing (sections 3.2, 4).
    Pyramid,
    /// After a node crossing go one level up (maximum mipmaps / quadtree displacement mapping).
    PyramidAscend,
    /// Section 3.3: the bilinear surface, on the conservative pyramid.
    PyramidBilinear,
    /// Bump mapping: no search, only the shading normal changes.
    Bump,
    /// Parallax mapping with offset limiting.
    Parallax,
    /// Parallax occlusion mapping: linear search, secant between the last two samples.
    Pom,
    /// Relief mapping: linear search, then binary search.
    Relief,
    /// Relaxed cone step mapping (Policarpo & Oliveira, GPU Gems 3 ch. 18): cone steps on a
    /// precomputed cone map, then binary search.
    Cone,
    /// A real grid mesh displaced by the map (figure 20).
    Mesh,
}

/// How a caption spells the work a method may do per pixel (the settings it reads).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Budget {
    /// No budget: `pyramid`.
    None,
    /// Layers from head-on to grazing: `pom 1-16` (`pom 16` when fixed).
    Layers,
    /// Layers, then binary search steps: `relief 20-25+5`.
    LayersAndBinary,
    /// The maximum layer count as cone steps, then binary steps: `cone 15+8`.
    ConeSteps,
}

/// Everything quadray's programs need to know about a method.
#[derive(Clone, Debug, PartialEq)]
pub struct Description {
    /// The method described.
    pub method: Method,
    /// The name `--method` takes.
    pub name: &'static str,
    /// `--method`'s help for it.
    pub help: &'static str,
    /// The surface whose exact intersection is its ground truth: the pyramid methods trace
    /// point-sampled columns, and the cone map is built for them; the other baselines sample
    /// bilinearly, as engines do. `None`: no traced ray to compare pixel by pixel (the mesh is
    /// rasterised; its "ray" is the camera's).
    pub truth: Option<Surface>,
    /// Whether it searches the height field; bump mapping only bends the normal, so its hits are
    /// the flat surface's and an error heat map of them says nothing.
    pub searches: bool,
    /// Whether it traces the conservative pyramid (section 3.3) rather than the point one.
    pub conservative_pyramid: bool,
    /// How its caption spells its budget.
    pub budget: Budget,
}

/// Every method's description, in [`Method`]'s order.
pub const DESCRIPTIONS: [Description; 9] = [
    Description {
        method: Method::Pyramid,
        name: "pyramid",
        help: "the paper: top-down pyramid traversal with node crossing",
        truth: Some(Surface::Point),
        searches: true,
        conservative_pyramid: false,
        budget: Budget::None,
    },
    Description {
        method: Method::PyramidAscend,
        name: "pyramid-ascend",
        help: "after a node crossing go one level up (maximum mipmaps)",
        truth: Some(Surface::Point),
        searches: true,
        conservative_pyramid: false,
        budget: Budget::None,
    },
    Description {
        method: Method::PyramidBilinear,
        name: "pyramid-bilinear",
        help: "the bilinear surface, on the conservative pyramid",
        truth: Some(Surface::Bilinear),
        searches: true,
        conservative_pyramid: true,
        budget: Budget::None,
    },
    Description {
        method: Method::Bump,
        name: "bump",
        help: "bump mapping: no search, only the shading normal changes",
        truth: Some(Surface::Bilinear),
        searches: false,
        conservative_pyramid: false,
        budget: Budget::None,
    },
    Description {
        method: Method::Parallax,
        name: "parallax",
        help: "parallax mapping with offset limiting",
        truth: Some(Surface::Bilinear),
        searches: true,
        conservative_pyramid: false,
        budget: Budget::None,
    },
    Description {
        method: Method::Pom,
        name: "pom",
        help: "parallax occlusion mapping: linear search, secant between the last two samples",
        truth: Some(Surface::Bilinear),
        searches: true,
        conservative_pyramid: false,
        budget: Budget::Layers,
    },
    Description {
        method: Method::Relief,
        name: "relief",
        help: "relief mapping: linear search, then binary search",
        truth: Some(Surface::Bilinear),
        searches: true,
        conservative_pyramid: false,
        budget: Budget::LayersAndBinary,
    },
    Description {
        method: Method::Cone,
        name: "cone",
        help: "relaxed cone stepping, then binary search (builds its cone map first)",
        truth: Some(Surface::Point),
        searches: true,
        conservative_pyramid: false,
        budget: Budget::ConeSteps,
    },
    Description {
        method: Method::Mesh,
        name: "mesh",
        help: "a real grid mesh displaced by the map",
        truth: None,
        searches: false,
        conservative_pyramid: false,
        budget: Budget::None,
    },
];

// Each description sits at its method's index.
const _: () = {
    let mut i = 0;
    while i < DESCRIPTIONS.len() {
        let d = &DESCRIPTIONS[i];
        assert!(d.method as usize == i);
        i += 1;
    }
};

impl Method {
    /// Every method, in shader-id order.
    pub const ALL: [Method; DESCRIPTIONS.len()] = {
        let mut all = [Method::Pyramid; DESCRIPTIONS.len()];
        let mut i = 0;
        while i < all.len() {
            all[i] = DESCRIPTIONS[i].method;
            i += 1;
        }
        all
    };

    /// Everything about the method, from [`DESCRIPTIONS`].
    pub fn describe(self) -> &'static Description {
        &DESCRIPTIONS[self as usize]
    }

    /// The name `--method` takes.
    pub fn name(self) -> &'static str {
        self.describe().name
    }

    /// The method's id in WGSL: the value of the surface shader's METHOD override constant.
    pub fn shader_id(self) -> u32 {
        self as u32
    }

    /// WGSL constants naming every id, `const METHOD_PYRAMID_ASCEND: u32 = 1u;` and so on: the
    /// shaders compare METHOD with these, so the ids are spelled only here.
    pub fn wgsl_constants() -> String {
        Self::ALL
            .iter()
            .map(|m| {
                let name = m.name().to_uppercase().replace('-', "_");
                format!("const METHOD_{name}: u32 = {}u;\n", m.shader_id())
            })
            .collect()
    }

    /// See [`Description::truth`].
    pub fn truth(self) -> Option<Surface> {
        self.describe().truth
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "method")
    }
}

impl serde::Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

/// `--method`'s choices and their help, from [`DESCRIPTIONS`].
#[cfg(feature = "cli")]
impl clap::ValueEnum for Method {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.describe().help))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_are_unique() {
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>(), Ok(m));
            assert_eq!(
                Method::ALL.iter().filter(|o| o.name() == m.name()).count(),
                1
            );
        }
        assert!(
            "steep"
                .parse::<Method>()
                .unwrap_err()
                .contains("pyramid-ascend")
        );
    }

    #[test]
    fn every_preset_is_valid() {
        for m in Method::ALL {
            m.shown().validate().unwrap();
            m.timed().validate().unwrap();
        }
    }
}
