//! Today's baseline: a binned-SAH bounding volume hierarchy over the polygons, with an occlusion
//! query that stops at the first blocking polygon.

use crate::geom::{Aabb, ConvexPolygon, Ray};
use crate::occlusion::Occluder;
use glam::Vec3;

const BINS: usize = 12;
const LEAF_SIZE: usize = 4;

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first polygon in `order`; inner: the right child (the left one follows the node).
    start: u32,
    /// Polygons in a leaf, 0 for an inner node.
    count: u32,
}

/// A SAH BVH over convex polygons.
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl Bvh {
    /// Builds the hierarchy over `polygons` (degenerate ones left out), binned SAH splits.
    pub fn build(polygons: &[ConvexPolygon]) -> Bvh {
        let boxes: Vec<Aabb> = polygons.iter().map(|p| p.bounds()).collect();
        let centres: Vec<Vec3> = boxes.iter().map(|b| b.centre()).collect();
        let mut order: Vec<u32> = (0..polygons.len() as u32)
            .filter(|&i| !polygons[i as usize].is_degenerate())
            .collect();
        let mut nodes = Vec::with_capacity(2 * order.len().max(1));
        let n = order.len();
        build_node(&mut nodes, &mut order, 0, n, &boxes, &centres);
        Bvh { nodes, order }
    }

    /// Is any polygon of `polygons` (those the BVH was built on) but `skip` hit on the ray?
    pub fn occluded(&self, polygons: &[ConvexPolygon], ray: &Ray, skip: Option<u32>) -> bool {
        let (o, d, t_min, t_max) = (ray.origin, ray.dir, ray.t_min, ray.t_max);
        let inv_d = d.recip();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.bounds.clip_ray(o, inv_d, t_min, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                let ids = &self.order[node.start as usize..(node.start + node.count) as usize];
                if ids.iter().any(|&id| {
                    Some(id) != skip
                        && polygons[id as usize]
                            .intersect(o, d, t_min, t_max)
                            .is_some()
                }) {
                    return true;
                }
            } else {
                let me = stack[top] as usize;
                stack[top] = me as u32 + 1;
                stack[top + 1] = node.start;
                top += 2;
            }
        }
        false
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

fn build_node(
    nodes: &mut Vec<Node>,
    order: &mut [u32],
    start: usize,
    end: usize,
    boxes: &[Aabb],
    centres: &[Vec3],
) -> usize {
    let ids = &mut order[start..end];
    let bounds = ids
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]));
    let me = nodes.len();
    nodes.push(Node {
        bounds,
        start: start as u32,
        count: ids.len() as u32,
    });
    if ids.len() <= LEAF_SIZE {
        return me;
    }
    let cb = ids
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.grow(centres[i as usize]));
    let mut best: Option<(f32, usize, f32)> = None; // (cost, axis, split position)
    for axis in 0..3 {
        let (lo, ext) = (cb.min[axis], cb.extent()[axis]);
        if ext <= 0.0 {
            continue;
        }
        let bin_of = |c: Vec3| (((c[axis] - lo) / ext * BINS as f32) as usize).min(BINS - 1);
        let mut bins = [(Aabb::EMPTY, 0usize); BINS];
        for &i in ids.iter() {
            let b = &mut bins[bin_of(centres[i as usize])];
            b.0 = b.0.union(boxes[i as usize]);
            b.1 += 1;
        }
        for split in 1..BINS {
            let side = |r: std::ops::Range<usize>| {
                bins[r]
                    .iter()
                    .fold((Aabb::EMPTY, 0), |(b, n), (bb, nn)| (b.union(*bb), n + nn))
            };
            let (lb, ln) = side(0..split);
            let (rb, rn) = side(split..BINS);
            if ln == 0 || rn == 0 {
                continue;
            }
            let cost = lb.surface_area() * ln as f32 + rb.surface_area() * rn as f32;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, lo + ext * split as f32 / BINS as f32));
            }
        }
    }
    let leaf_cost = bounds.surface_area() * ids.len() as f32;
    let Some((cost, axis, pos)) = best else {
        return me;
    };
    if cost >= leaf_cost && ids.len() <= 4 * LEAF_SIZE {
        return me;
    }
    let mut mid = 0;
    for i in 0..ids.len() {
        if centres[ids[i] as usize][axis] < pos {
            ids.swap(i, mid);
            mid += 1;
        }
    }
    if mid == 0 || mid == ids.len() {
        mid = ids.len() / 2;
    }
    build_node(nodes, order, start, start + mid, boxes, centres);
    let right = build_node(nodes, order, start + mid, end, boxes, centres);
    nodes[me].start = right as u32;
    nodes[me].count = 0;
    me
}
