//! The occlusion interface every shadow-ray back end answers: the uniform grid and the SAH BVH
//! (quadray-core's [`Bvh`]) here, and Intel Embree (`embree`, with the `embree` feature). The
//! tracer is generic over it, so a back end's query compiles into the shading loop with no call
//! through a pointer per ray.

use crate::grid::{CellLists, CellRecord, CellSet, Grid, Hit, Mailbox};
use quadray_core::geom::{Bvh, ConvexPolygon, Ray};

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

impl GridOccluder<'_> {
    /// Closest polygon hit on the ray, never `skip` (the polygon the ray starts on). With
    /// `record`, the walked cells that are in its set are noted in it (the cells of the ray
    /// segment that hold shadow polygons, for N_s: a bit test per cell, in the walk that visits
    /// them anyway).
    pub fn closest_hit(
        &self,
        ray: &Ray,
        skip: Option<u32>,
        mailbox: &mut Mailbox,
        mut record: Option<(&CellSet, &mut CellRecord)>,
    ) -> Option<Hit> {
        let (o, d, t_min, t_max) = (ray.origin, ray.dir, ray.t_min, ray.t_max);
        mailbox.start_ray(skip);
        let mut best: Option<Hit> = None;
        self.grid.walk(ray, |c, _, t_exit| {
            if let Some((set, cells)) = &mut record {
                cells.note(set, c);
            }
            for &id in self.cells.cell(c) {
                if mailbox.first_visit(id) {
                    let limit = best.map_or(t_max, |h| h.t);
                    if let Some(t) = self.polygons[id as usize].intersect(o, d, t_min, limit) {
                        best = Some(Hit { t, polygon: id });
                    }
                }
            }
            best.is_some_and(|h| h.t <= t_exit)
        });
        best
    }
}

impl Occluder for GridOccluder<'_> {
    type Scratch = Mailbox;

    fn scratch(&self) -> Mailbox {
        Mailbox::new(self.polygons.len())
    }

    #[inline]
    fn occluded(&self, ray: &Ray, skip: Option<u32>, mailbox: &mut Mailbox) -> bool {
        let (o, d, t_min, t_max) = (ray.origin, ray.dir, ray.t_min, ray.t_max);
        mailbox.start_ray(skip);
        let mut blocked = false;
        self.grid.walk(ray, |c, _, _| {
            blocked = self.cells.cell(c).iter().any(|&id| {
                mailbox.first_visit(id)
                    && self.polygons[id as usize]
                        .intersect(o, d, t_min, t_max)
                        .is_some()
            });
            blocked
        });
        blocked
    }
}

/// Shadow rays through a [`Bvh`] built on `polygons`.
#[derive(Clone, Copy)]
pub struct BvhOccluder<'a> {
    /// The hierarchy.
    pub bvh: &'a Bvh,
    /// The polygons it was built on.
    pub polygons: &'a [ConvexPolygon],
}

impl Occluder for BvhOccluder<'_> {
    type Scratch = ();

    fn scratch(&self) {}

    #[inline]
    fn occluded(&self, ray: &Ray, skip: Option<u32>, _: &mut ()) -> bool {
        self.bvh.occluded(self.polygons, ray, skip)
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
