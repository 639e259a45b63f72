//! The methods `quadray displace --method` accepts and what each is measured against.

use crate::reference::Surface;
use std::fmt;
use std::str::FromStr;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The paper: top-down pyramid traversal with node crossing (sections 3.2, 4).
    Pyramid,
    /// After a node crossing go one level up (maximum mipmaps / quadtree displacement mapping).
    PyramidAscend,
    /// Section 3.3: the bilinear surface, on the conservative pyramid.
    PyramidBilinear,
    Bump,
    /// Parallax mapping with offset limiting.
    Parallax,
    /// Parallax occlusion mapping: linear search, secant between the last two samples.
    Pom,
    /// Relief mapping: linear search, then binary search.
    Relief,
    /// A real grid mesh displaced by the map (figure 20).
    Mesh,
}

impl Method {
    pub const ALL: [Method; 8] = [
        Method::Pyramid,
        Method::PyramidAscend,
        Method::PyramidBilinear,
        Method::Bump,
        Method::Parallax,
        Method::Pom,
        Method::Relief,
        Method::Mesh,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Pyramid => "pyramid",
            Method::PyramidAscend => "pyramid-ascend",
            Method::PyramidBilinear => "pyramid-bilinear",
            Method::Bump => "bump",
            Method::Parallax => "parallax",
            Method::Pom => "pom",
            Method::Relief => "relief",
            Method::Mesh => "mesh",
        }
    }

    /// The value of the shader's METHOD override constant.
    pub(crate) fn shader_id(self) -> f64 {
        Self::ALL.iter().position(|&m| m == self).expect("listed") as f64
    }

    /// The surface whose exact intersection is this method's ground truth: the pyramid methods
    /// trace point-sampled columns; the baselines sample bilinearly, as engines do.
    pub fn truth(self) -> Surface {
        match self {
            Method::Pyramid | Method::PyramidAscend => Surface::Point,
            _ => Surface::Bilinear,
        }
    }

    /// Methods that trace a ray per pixel and can be checked against the ground truth pixel by
    /// pixel (the mesh is rasterised; its "ray" is the camera's).
    pub fn traces_rays(self) -> bool {
        self != Method::Mesh
    }

    pub fn uses_conservative_pyramid(self) -> bool {
        self == Method::PyramidBilinear
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
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|m| m.name()).collect();
                format!("unknown method `{s}` (one of: {})", names.join(", "))
            })
    }
}
