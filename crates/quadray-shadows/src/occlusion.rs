//! The occlusion interface every shadow-ray back end answers: the uniform grid here, the SAH
//! BVH ([`crate::bvh`]) and Intel Embree (`embree`, with the `embree` feature). The
//! tracer is generic over it, so a back end's query compiles into the shading loop with no call
//! through a pointer per ray.

use crate::geom::{ConvexPolygon, Ray};
use crate::grid::{CellLists, Grid, Mailbox};

/// Answers shadow rays: is anything hit between a point and a light?
pub trait Occluder: Sync {
    /// One thread's working memory for queries (the grid's mailbox; nothing for the others).
    type Scratch: Send;

    /// Fresh working memory for one thread.
    fn scratch(&self) -> Self::Scratch;

    /// Is any polygon but `skip` (the one the ray leaves) hit on `ray`? Stops at the first.
    fn occluded(&self, ray: &Ray, skip: Option<u32>, scratch: &mut Self::Scratch) -> bool;
}

/// Shadow rays through the uniform grid: 3DDDA from cell to cell, each polygon tested once per
/// ray (mailbox), stopping at the first hit.
#[derive(Clone, Copy)]
pub struct GridOccluder<'a> {
    /// The grid walked.
    pub grid: &'a Grid,
    /// The polygons registered in each of its cells.
    pub cells: &'a CellLists,
    /// The polygons, by the ids in `cells`.
    pub polygons: &'a [ConvexPolygon],
}

impl Occluder for GridOccluder<'_> {
    type Scratch = Mailbox;

    fn scratch(&self) -> Mailbox {
        Mailbox::new(self.polygons.len())
    }

    #[inline]
    fn occluded(&self, ray: &Ray, skip: Option<u32>, mailbox: &mut Mailbox) -> bool {
        self.grid
            .occluded(self.cells, self.polygons, ray, skip, mailbox)
    }
}

/// A borrowed back end answers as the back end.
impl<O: Occluder> Occluder for &O {
    type Scratch = O::Scratch;

    fn scratch(&self) -> O::Scratch {
        (**self).scratch()
    }

    #[inline]
    fn occluded(&self, ray: &Ray, skip: Option<u32>, scratch: &mut O::Scratch) -> bool {
        (**self).occluded(ray, skip, scratch)
    }
}
