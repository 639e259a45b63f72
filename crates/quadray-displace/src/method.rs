//! The methods `quadray displace --method` accepts and what each is measured against.

use crate::reference::Surface;
use std::fmt;
use std::str::FromStr;

/// A way to find where a view ray meets the height field.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
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

impl Method {
    /// Every method, in shader-id order.
    pub const ALL: [Method; 9] = [
        Method::Pyramid,
        Method::PyramidAscend,
        Method::PyramidBilinear,
        Method::Bump,
        Method::Parallax,
        Method::Pom,
        Method::Relief,
        Method::Cone,
        Method::Mesh,
    ];

    /// The name `--method` takes.
    pub fn name(self) -> &'static str {
        match self {
            Method::Pyramid => "pyramid",
            Method::PyramidAscend => "pyramid-ascend",
            Method::PyramidBilinear => "pyramid-bilinear",
            Method::Bump => "bump",
            Method::Parallax => "parallax",
            Method::Pom => "pom",
            Method::Relief => "relief",
            Method::Cone => "cone",
            Method::Mesh => "mesh",
        }
    }

    /// The method's id in WGSL: the value of the surface shader's METHOD override constant.
    pub fn shader_id(self) -> u32 {
        Self::ALL.iter().position(|&m| m == self).expect("listed") as u32
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

    /// The surface whose exact intersection is this method's ground truth: the pyramid methods
    /// trace point-sampled columns, and the cone map is built for them; the other baselines
    /// sample bilinearly, as engines do.
    pub fn truth(self) -> Surface {
        match self {
            Method::Pyramid | Method::PyramidAscend | Method::Cone => Surface::Point,
            _ => Surface::Bilinear,
        }
    }

    /// Methods that trace a ray per pixel and can be checked against the ground truth pixel by
    /// pixel (the mesh is rasterised; its "ray" is the camera's).
    pub fn traces_rays(self) -> bool {
        self != Method::Mesh
    }

    /// Methods that trace the conservative pyramid (section 3.3) rather than the point one.
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
        quadray_core::parse_named(s, &Self::ALL, Self::name, "method")
    }
}
