//! The CPU's twin of the per-tile cuts ([`Method::QuadtreeTiles`]: `kernel.wgsl` with
//! the rules of `rule.wgsl`): the same phases, in f32 as there (the kernel: the
//! reference's [`vpl_kernel`] rounded to f32), over the quadtree's nodes and the G-buffer's
//! receivers read back. The receivers' box and groups, the coarse estimate and the threshold, the
//! refinement level by level (bound, estimate, split bins, the list's capacity), the far nodes
//! shared at the tile's corners. Each tile's list comes out in the twin's order (the shader's is
//! its threads'), with the nodes whose decision lay within [`TIE`] of its threshold, where f32
//! sums in another order may decide the other way.

use crate::frame::{CutNode, Receiver};
use crate::light::node::{CONE_SLACK, EMPTY_BOX};
#[cfg(doc)]
use crate::method::Method;
use crate::method::TileCriterion;
use crate::reference::{luminance, vpl_kernel};
use crate::settings::{Settings, TILE};
use crate::tiles::{NEAR_FIELD_SIZE, SPLIT_BINS, ZERO_ESTIMATE_SHARE};
use glam::{DVec3, Vec2, Vec3, Vec4};
use std::f32::consts::PI;

/// A decision whose quantity lies within this fraction of its threshold is a tie.
pub const TIE: f32 = 1e-5;

/// A tile's pixels.
pub const TILE_PIXELS: usize = (TILE * TILE) as usize;
const CORNERS: [usize; 4] = [
    0,
    TILE as usize - 1,
    TILE_PIXELS - TILE as usize,
    TILE_PIXELS - 1,
];

/// What the twin reads, as the renderer reads it back.
pub struct TileInput<'a> {
    /// The quadtree's nodes, finest level first (`Renderer::read_nodes`).
    pub nodes: &'a [[[f32; 4]; 3]],
    /// Their bounds (`Renderer::read_node_bounds`).
    pub bounds: &'a [[[f32; 4]; 2]],
    /// The G-buffer's receivers, row by row (`Renderer::read_receivers`).
    pub receivers: &'a [Option<Receiver>],
    /// The settings the frame was drawn with.
    pub settings: &'a Settings,
    /// The kernel's clamp (the scene's `r_min`).
    pub r_min: f32,
}

/// One tile's cut.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TileCut {
    /// The listed nodes.
    pub nodes: Vec<CutNode>,
    /// Per listed node, whether it is shared at the tile's corners.
    pub shared: Vec<bool>,
    /// Splits refused for want of room in the list.
    pub refused: u32,
    /// Nodes whose error was estimated.
    pub estimated: u32,
    /// The VPL evaluations the estimates took.
    pub estimate_evaluations: u32,
    /// Whether the tile's coarse estimate was zero, its threshold taken from the start level's
    /// bounds (`ZERO_ESTIMATE_SHARE` of them).
    pub zero_estimate: bool,
    /// Nodes whose split, near field, nearest receiver or sharing was a tie ([`TIE`]).
    pub ties: Vec<CutNode>,
}

/// Every tile's cut, row by row.
pub fn tile_cuts(input: &TileInput) -> Vec<TileCut> {
    let (tx, ty) = input.settings.tiles();
    (0..ty)
        .flat_map(|y| (0..tx).map(move |x| (x, y)))
        .map(|(x, y)| Tile::new(input, x, y).map_or_else(TileCut::default, |t| t.cut()))
        .collect()
}

/// Each quadrant's sample pixel of a tile whose pixels (row-major) are `covered`: its first
/// covered one.
pub fn sample_pixels(covered: &[bool; TILE_PIXELS]) -> [Option<usize>; 4] {
    let half = TILE as usize / 2;
    let quadrant = |p: usize| (p % TILE as usize) / half + 2 * (p / (TILE_PIXELS / 2));
    std::array::from_fn(|q| (0..TILE_PIXELS).find(|&p| covered[p] && quadrant(p) == q))
}

/// The squared diagonal over which a node's box may hold the near field.
fn near_field_size(r_min: f32) -> f32 {
    NEAR_FIELD_SIZE * NEAR_FIELD_SIZE * r_min * r_min
}

/// The squared distance from `x` to the box [lo, hi].
fn gap(lo: Vec3, hi: Vec3, x: Vec3) -> f32 {
    (lo - x).max(x - hi).max(Vec3::ZERO).length_squared()
}

/// Whether a node with the box [lo, hi] holds its kernel's near field for `receivers`
/// (`near_field`): one lies within `r_min` of the box, and the box is more than
/// [`NEAR_FIELD_SIZE`] `r_min` across. There the bound, not the estimate, decides.
pub fn near_field(
    lo: Vec3,
    hi: Vec3,
    receivers: impl IntoIterator<Item = Vec3>,
    r_min: f32,
) -> bool {
    (hi - lo).length_squared() > near_field_size(r_min)
        && receivers
            .into_iter()
            .any(|x| gap(lo, hi, x) < r_min * r_min)
}

fn is_tie(quantity: f32, threshold: f32) -> bool {
    (quantity - threshold).abs() <= TIE * threshold.abs()
}

/// A node of the pyramid: its record and bounds (lo.w: its normal cone's cosine).
#[derive(Clone, Copy)]
struct Node {
    flux: Vec4,
    pos: Vec3,
    normal: Vec3,
    lo: Vec4,
    hi: Vec3,
}

impl Node {
    fn lit(&self) -> bool {
        self.flux.w > 0.5
    }

    /// `vpl_irradiance` at `x` (normal `n`).
    fn irradiance(&self, x: Vec3, n: Vec3, r_min: f32) -> Vec3 {
        let kernel = vpl_kernel(
            DVec3::from(x - self.pos),
            n.into(),
            self.normal.into(),
            r_min.into(),
        );
        self.flux.truncate() * (kernel / std::f64::consts::PI) as f32
    }
}

/// Reduces 64 values the way the shader's workgroup does, halving the stride.
fn tree<T: Copy>(mut v: [T; TILE_PIXELS], op: impl Fn(T, T) -> T) -> T {
    let mut stride = TILE_PIXELS / 2;
    while stride > 0 {
        for i in 0..stride {
            v[i] = op(v[i], v[i + stride]);
        }
        stride /= 2;
    }
    v[0]
}

/// The tile's receivers in two groups: each group's box, normal axis and cone cosine
/// (`TileGroups`).
struct Groups {
    lo: [Vec3; 2],
    hi: [Vec3; 2],
    axis: [Vec3; 2],
    cone: [f32; 2],
}

struct Tile<'a> {
    input: &'a TileInput<'a>,
    /// Per pixel, its receiver's position (EMPTY_BOX where none) and normal.
    x: [Vec3; TILE_PIXELS],
    n: [Vec3; TILE_PIXELS],
    covered: [bool; TILE_PIXELS],
    /// Per quadrant, its first covered pixel.
    samples: [Option<usize>; 4],
    ties: Vec<CutNode>,
}

impl<'a> Tile<'a> {
    /// Phases 0 and 1: the tile's receivers and sample pixels; `None` where it has none.
    fn new(input: &'a TileInput<'a>, tx: u32, ty: u32) -> Option<Self> {
        let size = input.settings.size;
        let mut x = [Vec3::splat(EMPTY_BOX); TILE_PIXELS];
        let mut n = [Vec3::ZERO; TILE_PIXELS];
        let mut covered = [false; TILE_PIXELS];
        for p in 0..TILE_PIXELS {
            let (px, py) = (tx * TILE + p as u32 % TILE, ty * TILE + p as u32 / TILE);
            let inside = px < size.width && py < size.height;
            let receiver = inside.then(|| input.receivers[(py * size.width + px) as usize]);
            if let Some(r) = receiver.flatten() {
                x[p] = r.position.into();
                n[p] = r.normal.into();
                covered[p] = true;
            }
        }
        let samples = sample_pixels(&covered);
        covered.contains(&true).then_some(Self {
            input,
            x,
            n,
            covered,
            samples,
            ties: Vec::new(),
        })
    }

    fn params(&self) -> (&'a Settings, f32) {
        (self.input.settings, self.input.r_min)
    }

    /// The pyramid's index of a node.
    fn index(&self, level: u32, x: u32, y: u32) -> usize {
        let side = self.input.settings.rsm_size;
        let offset: u32 = (0..level).map(|l| (side >> l).pow(2)).sum();
        (offset + y * (side >> level) + x) as usize
    }

    fn node(&self, at: CutNode) -> Node {
        let i = self.index(at.level, at.x, at.y);
        let [flux, pos, normal] = self.input.nodes[i];
        let [lo, hi] = self.input.bounds[i];
        Node {
            flux: flux.into(),
            pos: Vec4::from(pos).truncate(),
            normal: Vec4::from(normal).truncate(),
            lo: lo.into(),
            hi: Vec4::from(hi).truncate(),
        }
    }

    /// The box and summed normals of the receivers where `member`.
    fn reduce(&self, member: impl Fn(usize) -> bool) -> (Vec3, Vec3, Vec3) {
        let pick = |p: usize, v: Vec3, none: Vec3| if member(p) { v } else { none };
        let lo = tree(
            std::array::from_fn(|p| pick(p, self.x[p], Vec3::splat(EMPTY_BOX))),
            Vec3::min,
        );
        let hi = tree(
            std::array::from_fn(|p| pick(p, self.x[p], Vec3::splat(-EMPTY_BOX))),
            Vec3::max,
        );
        let sum = tree(
            std::array::from_fn(|p| pick(p, self.n[p], Vec3::ZERO)),
            |a, b| a + b,
        );
        (lo, hi, sum)
    }

    /// Phase 1: the two groups of receivers (`receiver_group`, `group_axis`, `group_cone`).
    fn groups(&self) -> Groups {
        let (lo, hi, _) = self.reduce(|p| self.covered[p]);
        let extent = hi - lo;
        let axis = if extent.x >= extent.y.max(extent.z) {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let middle = 0.5 * (lo[axis] + hi[axis]);
        let group = |p: usize| usize::from(self.x[p][axis] >= middle);
        let mut g = Groups {
            lo: [Vec3::ZERO; 2],
            hi: [Vec3::ZERO; 2],
            axis: [Vec3::ZERO; 2],
            cone: [0.0; 2],
        };
        for h in 0..2 {
            let (lo, hi, sum) = self.reduce(|p| self.covered[p] && group(p) == h);
            g.lo[h] = lo;
            g.hi[h] = hi;
            g.axis[h] = if sum.length() > 0.0 {
                sum.normalize()
            } else {
                Vec3::Z
            };
        }
        for h in 0..2 {
            let least = (0..TILE_PIXELS)
                .filter(|&p| self.covered[p] && group(p) == h)
                .map(|p| self.n[p].dot(g.axis[h]))
                .fold(1.0, f32::min);
            g.cone[h] = (least.clamp(-1.0, 1.0).acos() + CONE_SLACK).min(PI).cos();
        }
        g
    }

    /// Phase 2: the threshold, `tile_error` of the mean of the sample pixels' coarse estimates,
    /// or where that is zero of `ZERO_ESTIMATE_SHARE` of the start level's nodes' bounds at
    /// the tile's receivers (each thread's share of the start level's nodes summed as the
    /// shader's threads do).
    fn threshold(&self, g: &Groups) -> (f32, bool) {
        let (s, r_min) = self.params();
        let start = s.tile_start_level();
        let side = s.rsm_size >> start;
        let mut shares = [Vec4::ZERO; TILE_PIXELS];
        let mut bounded = [0.0; TILE_PIXELS];
        for i in 0..side * side {
            let node = self.node(CutNode {
                level: start,
                x: i % side,
                y: i / side,
            });
            if node.lit() {
                let light = |q: usize| {
                    self.samples[q].map_or(0.0, |p| {
                        luminance(node.irradiance(self.x[p], self.n[p], r_min))
                    })
                };
                shares[i as usize % TILE_PIXELS] += Vec4::from_array(std::array::from_fn(light));
                bounded[i as usize % TILE_PIXELS] += tile_bound(&node, g, r_min);
            }
        }
        let summed = tree(shares, |a, b| a + b);
        let (mut total, mut samples) = (0.0, 0.0);
        for q in 0..4 {
            if self.samples[q].is_some() {
                total += summed[q];
                samples += 1.0;
            }
        }
        let estimate = total / samples;
        let zero = estimate == 0.0;
        let estimate = if zero {
            ZERO_ESTIMATE_SHARE * tree(bounded, |a, b| a + b)
        } else {
            estimate
        };
        (s.tile_error_or_default() * estimate, zero)
    }

    /// [`near_field`] for the tile's receivers, noting a tie.
    fn near_field(&mut self, at: CutNode, node: &Node) -> bool {
        let r_min = self.input.r_min;
        let (lo, hi) = (node.lo.truncate(), node.hi);
        let covered = (0..TILE_PIXELS).filter(|&p| self.covered[p]);
        let size = (hi - lo).length_squared();
        let limit = near_field_size(r_min);
        if is_tie(size, limit)
            || (size > limit
                && covered
                    .clone()
                    .any(|p| is_tie(gap(lo, hi, self.x[p]), r_min * r_min)))
        {
            self.ties.push(at);
        }
        near_field(lo, hi, covered.map(|p| self.x[p]), r_min)
    }

    /// The estimated error of keeping a node rather than its children (`estimated_error`), and
    /// the VPL evaluations it took.
    fn estimated_error(&mut self, at: CutNode, node: &Node) -> (f32, u32) {
        let r_min = self.input.r_min;
        let children = [0, 1, 2, 3].map(|c| {
            self.node(CutNode {
                level: at.level - 1,
                x: 2 * at.x + (c & 1),
                y: 2 * at.y + (c >> 1),
            })
        });
        let distance = |p: usize| {
            let d = self.x[p] - node.pos;
            d.dot(d)
        };
        let mut nearest = 0;
        for p in 1..TILE_PIXELS {
            if distance(p) < distance(nearest) {
                nearest = p;
            }
        }
        let rival = |p: usize| self.covered[p] && p != nearest;
        if (0..TILE_PIXELS).any(|p| rival(p) && is_tie(distance(p), distance(nearest))) {
            self.ties.push(at);
        }
        let (mut error, mut evaluations) = (0.0f32, 0);
        for s in self.samples.into_iter().chain([Some(nearest)]).flatten() {
            let (x, n) = (self.x[s], self.n[s]);
            let own = node.irradiance(x, n, r_min);
            let lit = children.iter().filter(|c| c.lit());
            let sum: Vec3 = lit.clone().map(|c| c.irradiance(x, n, r_min)).sum();
            evaluations += 1 + lit.count() as u32;
            error = error.max(luminance(own - sum).abs());
        }
        (error, evaluations)
    }

    /// A node's split bin (`split_bin`), 0 where it is listed.
    fn split_bin(excess: f32, threshold: f32) -> u32 {
        if excess > threshold {
            1 + (excess / threshold)
                .log2()
                .floor()
                .clamp(0.0, (SPLIT_BINS - 1) as f32) as u32
        } else {
            0
        }
    }

    /// Phase 3, a node's verdict: `None` where empty, else its split bin.
    fn judge(&mut self, at: CutNode, g: &Groups, threshold: f32, cut: &mut TileCut) -> Option<u32> {
        let (s, r_min) = self.params();
        let node = self.node(at);
        if !node.lit() {
            return None;
        }
        if at.level == 0 {
            return Some(0);
        }
        let bound = tile_bound(&node, g, r_min);
        let mut excess = bound;
        let estimate = s.tile_criterion == TileCriterion::Estimate;
        let start = s.tile_start_level();
        if bound > threshold
            && estimate
            && at.level < start
            && threshold > 0.0
            && !self.near_field(at, &node)
        {
            let (error, evaluations) = self.estimated_error(at, &node);
            excess = error;
            cut.estimated += 1;
            cut.estimate_evaluations += evaluations;
        }
        if is_tie(bound, threshold) || is_tie(excess, threshold) {
            self.ties.push(at);
        }
        Some(Self::split_bin(excess, threshold))
    }

    /// Phases 2 to 4: the tile's cut.
    fn cut(mut self) -> TileCut {
        let s = self.input.settings;
        let capacity = s.tile_capacity_or_default();
        let groups = self.groups();
        let (threshold, zero_estimate) = self.threshold(&groups);
        let mut cut = TileCut {
            zero_estimate,
            ..TileCut::default()
        };
        let root = s.rsm_size.ilog2();
        let mut frontier = vec![CutNode {
            level: root,
            x: 0,
            y: 0,
        }];
        let mut reserved = 1;
        // phase 3: refinement, a level a step, the highest bins split first while room is left
        for level in (0..=root).rev() {
            let verdicts: Vec<Option<u32>> = frontier
                .iter()
                .map(|&at| self.judge(at, &groups, threshold, &mut cut))
                .collect();
            reserved -= verdicts.iter().filter(|v| v.is_none()).count() as u32;
            let mut room = (capacity - reserved) / 3;
            let mut cutoff = 0;
            for bin in (1..=SPLIT_BINS).rev() {
                let wanted = verdicts.iter().filter(|&&v| v == Some(bin)).count() as u32;
                if wanted > room {
                    cutoff = bin;
                    break;
                }
                room -= wanted;
                reserved += 3 * wanted;
            }
            let mut next = Vec::new();
            for (&at, verdict) in frontier.iter().zip(verdicts) {
                let Some(bin) = verdict else { continue };
                let mut split = bin > cutoff;
                if bin == cutoff && cutoff > 0 && reserved + 3 <= capacity {
                    reserved += 3;
                    split = true;
                }
                if bin > 0 && !split {
                    cut.refused += 1;
                }
                if split {
                    next.extend((0..4).map(|c| CutNode {
                        level: level - 1,
                        x: 2 * at.x + (c & 1),
                        y: 2 * at.y + (c >> 1),
                    }));
                } else {
                    cut.nodes.push(at);
                }
            }
            frontier = next;
        }
        // phase 4: the far nodes shared at the corners
        let corners = CORNERS.iter().all(|&c| self.covered[c]);
        let lo = groups.lo[0].min(groups.lo[1]);
        let hi = groups.hi[0].max(groups.hi[1]);
        cut.shared = cut
            .nodes
            .clone()
            .into_iter()
            .map(|at| corners && s.tile_share > 0.0 && self.shareable(at, lo, hi))
            .collect();
        self.ties.sort_by_key(|n| (n.level, n.y, n.x));
        self.ties.dedup();
        cut.ties = self.ties;
        cut
    }

    /// Whether a listed node is shared at the tile's corners (`shareable`).
    fn shareable(&mut self, at: CutNode, lo: Vec3, hi: Vec3) -> bool {
        let node = self.node(at);
        let (nlo, nhi) = (node.lo.truncate(), node.hi);
        let far = self.input.settings.tile_share * (hi - lo).length();
        let gap = (nlo - hi).max(lo - nhi).max(Vec3::ZERO);
        if is_tie(gap.dot(gap), far * far) {
            self.ties.push(at);
        }
        if gap.dot(gap) <= far * far {
            return false;
        }
        let centre = 0.5 * (nlo + nhi);
        let half = 0.5 * (nhi - nlo);
        CORNERS.iter().all(|&c| {
            let n = self.n[c];
            n.dot(centre - self.x[c]) - n.abs().dot(half) > 0.0
        })
    }
}

/// A bound of max(0, n . normalize(d)) over unit n within `half_cos` of `axis` and d in the box
/// [lo, hi] (bound.wgsl's `cone_box_cos_bound`).
fn cone_box_cos_bound(axis: Vec3, half_cos: f32, lo: Vec3, hi: Vec3) -> f32 {
    if half_cos <= 0.0 {
        return 1.0;
    }
    let centre = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    let helper = if axis.x.abs() > 0.7 { Vec3::Y } else { Vec3::X };
    let tx = axis.cross(helper).normalize();
    let ty = axis.cross(tx);
    let z_max = axis.dot(centre) + axis.abs().dot(half);
    let lateral = Vec2::new(tx.dot(centre), ty.dot(centre)).abs();
    let spread = Vec2::new(tx.abs().dot(half), ty.abs().dot(half));
    let reach = if z_max <= 0.0 {
        lateral + spread
    } else {
        (lateral - spread).max(Vec2::ZERO)
    };
    let least_cos = z_max / reach.extend(z_max).length().max(1e-30);
    if least_cos >= half_cos {
        return 1.0;
    }
    let half_sin = (1.0 - half_cos * half_cos).max(0.0).sqrt();
    (least_cos * half_cos + (1.0 - least_cos * least_cos).max(0.0).sqrt() * half_sin).max(0.0)
}

/// What a node may give any receiver of the tile: the larger of its bounds for the two groups
/// (rule.wgsl's `tile_bound`).
fn tile_bound(node: &Node, g: &Groups, r_min: f32) -> f32 {
    (0..2)
        .map(|h| {
            node_bound(
                node.flux.truncate(),
                node,
                g.lo[h],
                g.hi[h],
                g.axis[h],
                g.cone[h],
                r_min,
            )
        })
        .fold(0.0, f32::max)
}

/// A bound of the luminance of the irradiance a node gives any receiver in the box [lo, hi]
/// whose normal lies within `receiver_cos` of `receiver_axis` (bound.wgsl's `node_bound`).
fn node_bound(
    flux: Vec3,
    node: &Node,
    lo: Vec3,
    hi: Vec3,
    receiver_axis: Vec3,
    receiver_cos: f32,
    r_min: f32,
) -> f32 {
    let d_lo = lo - node.hi;
    let d_hi = hi - node.lo.truncate();
    let nearest = d_lo.max(-d_hi).max(Vec3::ZERO);
    let d2 = nearest.dot(nearest).max(r_min * r_min);
    let cos_vpl = cone_box_cos_bound(node.normal, node.lo.w, d_lo, d_hi);
    let cos_receiver = cone_box_cos_bound(receiver_axis, receiver_cos, -d_hi, -d_lo);
    luminance(flux) * cos_vpl * cos_receiver / (PI * d2)
}

#[cfg(test)]
mod tests {
    use super::cone_box_cos_bound;
    use glam::Vec3;
    use proptest::prelude::*;

    fn unit() -> impl Strategy<Value = Vec3> {
        (-1f32..1.0, -1f32..1.0, -1f32..1.0)
            .prop_filter_map("too short", |(x, y, z)| Vec3::new(x, y, z).try_normalize())
    }

    fn point() -> impl Strategy<Value = Vec3> {
        (-4f32..4.0, -4f32..4.0, -4f32..4.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4096))]

        /// No normal of the cone and direction of the box has a cosine above the bound, on
        /// either side of the axis's plane.
        #[test]
        fn cone_box_cos_bound_bounds_every_normal_and_direction(
            axis in unit(),
            half_angle in 0f32..1.6,
            corner in point(),
            size in (0f32..3.0, 0f32..3.0, 0f32..3.0),
            at in (0f32..=1.0, 0f32..=1.0, 0f32..=1.0),
            tilt in 0f32..=1.0,
            side in unit(),
        ) {
            let (lo, hi) = (corner, corner + Vec3::new(size.0, size.1, size.2));
            let d = lo + (hi - lo) * Vec3::new(at.0, at.1, at.2);
            prop_assume!(d.length() > 1e-3);
            let perpendicular = (side - axis * side.dot(axis)).try_normalize();
            prop_assume!(perpendicular.is_some());
            let angle = half_angle * tilt;
            let normal = axis * angle.cos() + perpendicular.unwrap() * angle.sin();
            let bound = cone_box_cos_bound(axis, half_angle.cos(), lo, hi);
            prop_assert!(normal.dot(d.normalize()).max(0.0) <= bound + 1e-5);
        }
    }

    /// Behind the axis's plane the bound falls with the angle: a narrow cone sees nothing of a
    /// box straight behind it and grazes one beside its plane (the cone's half-angle sine).
    #[test]
    fn behind_the_plane_the_bound_falls_with_the_angle() {
        let half_cos = 10f32.to_radians().cos();
        let behind = Vec3::new(-0.1, -0.1, -5.0)..Vec3::new(0.1, 0.1, -4.0);
        assert_eq!(
            cone_box_cos_bound(Vec3::Z, half_cos, behind.start, behind.end),
            0.0
        );
        let grazing = Vec3::new(10.0, -0.1, -0.01)..Vec3::new(11.0, 0.1, 0.0);
        let bound = cone_box_cos_bound(Vec3::Z, half_cos, grazing.start, grazing.end);
        assert!((bound - 10f32.to_radians().sin()).abs() < 1e-3, "{bound}");
    }
}
