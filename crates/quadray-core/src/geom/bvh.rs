//! A binned-SAH bounding volume hierarchy over convex polygons, with an occlusion query that
//! stops at the first blocking polygon (the ray tracer's baseline for shadow rays, the indirect
//! ground truth's visibility) and a nearest-hit query (the indirect reference's surfaces).

use super::{Aabb, ConvexPolygon, Ray};
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
    // inlined: compiled in the tracing crate at its optimisation level (see Cargo.toml)
    #[inline]
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

    /// The nearest polygon of `polygons` (those the BVH was built on) the ray hits, and the
    /// ray's parameter there.
    pub fn closest(&self, polygons: &[ConvexPolygon], ray: &Ray) -> Option<(u32, f32)> {
        let (o, d, t_min) = (ray.origin, ray.dir, ray.t_min);
        let inv_d = d.recip();
        let mut best: Option<(u32, f32)> = None;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let t_max = best.map_or(ray.t_max, |(_, t)| t);
            let node = &self.nodes[stack[top] as usize];
            if node.bounds.clip_ray(o, inv_d, t_min, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                for &id in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    let t_max = best.map_or(ray.t_max, |(_, t)| t);
                    if let Some(t) = polygons[id as usize].intersect(o, d, t_min, t_max) {
                        best = Some((id, t));
                    }
                }
            } else {
                let me = stack[top] as usize;
                stack[top] = me as u32 + 1;
                stack[top + 1] = node.start;
                top += 2;
            }
        }
        best
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::SplitMix;

    /// Occlusion through the hierarchy equals testing every polygon, skipped one included, on
    /// random rays among random triangles (enough of them for inner nodes and SAH splits), plus
    /// a degenerate one the build leaves out.
    #[test]
    fn occlusion_equals_brute_force() {
        let mut rng = SplitMix(3);
        let mut point = |scale: f32| {
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 * scale - scale
        };
        let mut polygons: Vec<ConvexPolygon> = (0..300)
            .map(|_| {
                let c = point(2.0);
                ConvexPolygon::new(vec![c + point(0.5), c + point(0.5), c + point(0.5)])
            })
            .collect();
        polygons.push(ConvexPolygon::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0]));
        let bvh = Bvh::build(&polygons);
        let mut hits = 0;
        for i in 0..2000 {
            let ray = Ray::segment(point(3.0), point(3.0), 0.0);
            let skip = (i % 3 == 0).then_some(i % 300);
            let brute = polygons.iter().enumerate().any(|(id, p)| {
                Some(id as u32) != skip
                    && p.intersect(ray.origin, ray.dir, 0.0, ray.t_max).is_some()
            });
            assert_eq!(bvh.occluded(&polygons, &ray, skip), brute, "ray {ray:?}");
            hits += usize::from(brute);
        }
        assert!(hits > 200 && hits < 1800, "{hits} of 2000 rays blocked");
    }
}
