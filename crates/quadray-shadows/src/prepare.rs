//! What is built before rendering: the polygons, the grid and its cell lists, and the shadow
//! polygons, BVH or Embree scene the shadow scheme needs.

use crate::cost::{FollowUp, SceneStats};
use crate::grid::{CellLists, Grid};
use crate::occlusion::{BvhOccluder, GridOccluder};
use crate::scene::Scene;
use crate::shadow::ShadowVolumes;
use quadray_core::geom::{Aabb, Bvh, ConvexPolygon};
use rayon::prelude::*;
use std::sync::OnceLock;

/// How shadows are decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    /// A shadow ray through the grid per light, stopping at the first occluder.
    Conventional,
    /// Depth counts carried along every ray segment.
    Volume,
    /// The hybrid switch with threshold N_th.
    Hst {
        /// N_th: the most shadow polygons a segment may cross for the depth count to be used.
        nth: f32,
    },
    /// A shadow ray through the SAH BVH.
    Bvh,
    /// A shadow ray as an Embree occlusion query (`embree` feature; the grid's without it).
    Embree,
}

/// Everything built before rendering: polygons, grid, shadow polygons, BVH.
pub struct Prepared {
    /// The scene prepared.
    pub scene: Scene,
    /// Its faces as polygons, in face order.
    pub polygons: Vec<ConvexPolygon>,
    /// The uniform grid over the polygons and the eye.
    pub grid: Grid,
    /// The polygons registered in each cell.
    pub cells: CellLists,
    /// The shadow polygons of every light (volume and HST schemes).
    pub volumes: Option<ShadowVolumes>,
    /// The SAH BVH (bvh scheme).
    pub bvh: Option<Bvh>,
    /// The Embree scene (embree scheme).
    #[cfg(feature = "embree")]
    pub embree: Option<crate::embree::EmbreeScene>,
    /// CPU seconds spent building the grid (always) and the shadow polygons or BVH the scheme
    /// needs.
    pub preprocess_s: f64,
    /// The part of `preprocess_s` spent on the shadow polygons.
    pub shadow_volumes_s: f64,
    /// Smallest ray parameter counted as a hit of a ray leaving a surface (scaled to the scene).
    pub eps: f32,
    /// The same for shadow rays: much smaller, so a polygon that a shadow ray crosses right next to
    /// its start (a concave corner) counts, as it does for the depth count. Depth counts take
    /// every crossing after the segment's start.
    pub shadow_eps: f32,
    /// Scene statistics of the cost model, computed once on first use ([`crate::pilot`]).
    pub(crate) stats: OnceLock<SceneStats>,
    /// The follow-up statistics of the extended N_th, measured once on first use.
    pub(crate) follow_up: OnceLock<FollowUp>,
}

impl Prepared {
    /// Builds the grid, and the shadow polygons or hierarchy `scheme` needs. The scene is taken
    /// as it is: [`crate::prepare()`] validates it first.
    pub fn new(scene: Scene, scheme: Scheme) -> Prepared {
        let start = crate::process_cpu_s();
        let polygons = scene.polygons();
        // The grid holds the eye too, so the eye's depth count describes every eye ray's start.
        let bounds = polygons
            .iter()
            .fold(Aabb::EMPTY, |b, p| b.union(p.bounds()))
            .grow(scene.camera.position);
        let grid = Grid::for_polygons(bounds, polygons.len());
        let cells = grid.register(polygons.par_iter().map(|p| p.vertices.as_slice()));
        let volumes_start = crate::process_cpu_s();
        let volumes = matches!(scheme, Scheme::Volume | Scheme::Hst { .. })
            .then(|| ShadowVolumes::build(&scene, &polygons, &grid));
        let shadow_volumes_s = crate::process_cpu_s() - volumes_start;
        let bvh = (scheme == Scheme::Bvh).then(|| Bvh::build(&polygons));
        let eps = bounds.extent().length() * 1e-5;
        #[cfg(feature = "embree")]
        let embree =
            (scheme == Scheme::Embree).then(|| crate::embree::EmbreeScene::build(&polygons, eps));
        Prepared {
            eps,
            shadow_eps: bounds.extent().length() * 1e-7,
            scene,
            polygons,
            grid,
            cells,
            volumes,
            bvh,
            #[cfg(feature = "embree")]
            embree,
            preprocess_s: crate::process_cpu_s() - start,
            shadow_volumes_s,
            stats: OnceLock::new(),
            follow_up: OnceLock::new(),
        }
    }

    /// Shadow rays through the grid.
    pub fn grid_occluder(&self) -> GridOccluder<'_> {
        GridOccluder {
            grid: &self.grid,
            cells: &self.cells,
            polygons: &self.polygons,
        }
    }

    /// Shadow rays through the BVH, when it was built.
    pub fn bvh_occluder(&self) -> Option<BvhOccluder<'_>> {
        self.bvh.as_ref().map(|bvh| BvhOccluder {
            bvh,
            polygons: &self.polygons,
        })
    }
}
