//! Tile structure in a picture's error that the truth lacks: how much more the error (method -
//! truth) changes across the boundaries of the per-tile cuts' tiles (every 8 pixels, both
//! axes) than between the other neighbours, away from geometric edges, over the same figure for
//! the brute force over every VPL, which has no tiles: 1.0 = no more tile structure than that.
//!
//! Two measures of the change ([`Order`]): the error's step between two neighbours, and how much
//! its slope changes at them (a bend). An error interpolated across each tile from values at its
//! corners is continuous at the boundaries but bends there: a seam the eye sees that steps alone
//! miss.
//!
//! Measure it on the float images, not on the 8-bit pictures `quadray indirect` writes. There the
//! dark room's light takes a few levels (on the leak scene, 256x128, 64^2 RSM, half the unlit
//! pixels are below level 16), so one level of rounding is 6% of the value or more: it
//! counts as a geometric edge (28% of the unlit pixels left out, 24% on the floats) or bends the
//! error everywhere, and the tone curve flattens what is left. The per-tile cuts with indirect
//! shadows there: bends 1.34 from the PNGs, 2.74 from the floats (steps 0.86 and 1.00).

use crate::settings::TILE;

/// Neighbours whose values differ by more than this fraction of the larger are on an edge:
/// smooth indirect light changes by a few percent a pixel, a corner or a shadow by far more.
const EDGE_STEP: f32 = 0.25;
/// ... of the larger plus this fraction of the image's mean, so that the near-black's relative
/// noise is no edge.
const EDGE_FLOOR: f32 = 0.05;
/// The most [`TileStructure::ratio`] says: an error constant inside the tiles.
const MAX_RATIO: f64 = 1e6;

/// What [`TileStructure::ratio`] compares between two neighbours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// The error's step from one to the other: a jump.
    Step,
    /// How much the error's slope changes at the two pixels (the steps before, between and
    /// after them on their line): a jump, or a change of slope at the boundary.
    Bend,
}

impl Order {
    /// Both, in order.
    pub const ALL: [Order; 2] = [Order::Step, Order::Bend];
}

/// The pixels of a picture that the ratios look at: those off the geometric edges.
pub struct TileStructure<'a> {
    width: usize,
    truth: &'a [[f32; 3]],
    /// Per pixel: not on a geometric edge (and finite).
    smooth: Vec<bool>,
}

impl<'a> TileStructure<'a> {
    /// The pixels of a `width` x `height` picture (rows top down) off the edges of `truth` (the
    /// ground truth's indirect light) and of `edges_of` (pictures of the same view without
    /// tiles: the direct light, the brute force; the edges the truth lacks, where it is dark on
    /// both sides); `None` where the images are not that size.
    pub fn new(
        width: u32,
        height: u32,
        truth: &'a [[f32; 3]],
        edges_of: &[&[[f32; 3]]],
    ) -> Option<Self> {
        let (width, height) = (width as usize, height as usize);
        let pixels = width.checked_mul(height)?;
        let images = || std::iter::once(truth).chain(edges_of.iter().copied());
        if pixels == 0 || images().any(|image| image.len() != pixels) {
            return None;
        }
        let finite = |p: usize| images().all(|image| image[p].iter().all(|v| v.is_finite()));
        let mut smooth: Vec<bool> = (0..pixels).map(finite).collect();
        let level = |p: &[f32; 3]| p.iter().map(|v| v.abs()).sum::<f32>();
        for image in images() {
            let levels = image.iter().map(level).filter(|l| l.is_finite());
            let mean = levels.sum::<f32>() / pixels as f32;
            for Pair { a, b, .. } in neighbours(width, height) {
                let larger = level(&image[a]).max(level(&image[b]));
                if difference(&image[a], &image[b]) > EDGE_STEP * (larger + EDGE_FLOOR * mean) {
                    smooth[a] = false;
                    smooth[b] = false;
                }
            }
        }
        Some(Self {
            width,
            truth,
            smooth,
        })
    }

    /// The mean change ([`Order`]) of `image - truth` across tile boundaries over its mean
    /// change between the other neighbours, over the pairs whose pixels (and for a bend the
    /// pixels on either side) are all off the edges; at most `MAX_RATIO`. `None` where `image`
    /// is not the picture's size, where either kind of pair is missing or where the error does
    /// not change at all.
    pub fn ratio(&self, image: &[[f32; 3]], order: Order) -> Option<f64> {
        if image.len() != self.truth.len() {
            return None;
        }
        let height = self.truth.len() / self.width;
        let error =
            |p: usize| -> [f32; 3] { std::array::from_fn(|c| image[p][c] - self.truth[p][c]) };
        let change = |pair: &Pair| -> Option<f32> {
            let (a, b) = (error(pair.a), error(pair.b));
            let step = |c: usize| b[c] - a[c];
            let sum = |f: &dyn Fn(usize) -> f32| (0..3).map(|c| f(c).abs()).sum::<f32>();
            let (pixels, change) = match order {
                Order::Step => ([pair.a, pair.b, pair.a, pair.b], sum(&step)),
                Order::Bend => {
                    let (before, after) = (pair.before?, pair.after?);
                    let (p, q) = (error(before), error(after));
                    // the slope's change at a plus its change at b
                    let bend = |c: usize| {
                        (step(c) - (a[c] - p[c])).abs() + ((q[c] - b[c]) - step(c)).abs()
                    };
                    ([before, pair.a, pair.b, after], sum(&bend))
                }
            };
            (pixels.iter().all(|&p| self.smooth[p]) && change.is_finite()).then_some(change)
        };
        // [across a boundary, elsewhere]: (sum of changes, pairs)
        let mut sums = [(0.0f64, 0u64); 2];
        for pair in neighbours(self.width, height) {
            if let Some(change) = change(&pair) {
                let sum = &mut sums[usize::from(!pair.across)];
                sum.0 += f64::from(change);
                sum.1 += 1;
            }
        }
        let [across, elsewhere] = sums.map(|(sum, n)| (n > 0).then(|| sum / n as f64));
        let (across, elsewhere) = (across?, elsewhere?);
        if across == 0.0 && elsewhere == 0.0 {
            return None;
        }
        Some((across / elsewhere.max(across / MAX_RATIO)).min(MAX_RATIO))
    }

    /// [`TileStructure::ratio`] of `method` over that of `brute_force` (every VPL, same scene
    /// and RSM): 1.0 = no more tile structure than a method without tiles. `None` where either
    /// has no ratio or the brute force's is 0 (its error changes only inside the tiles).
    pub fn blockiness(
        &self,
        method: &[[f32; 3]],
        brute_force: &[[f32; 3]],
        order: Order,
    ) -> Option<f64> {
        let (method, brute_force) = (self.ratio(method, order)?, self.ratio(brute_force, order)?);
        (brute_force > 0.0).then(|| method / brute_force)
    }
}

/// Two neighbours, `b` right of or below `a`, with the pixels before `a` and after `b` on their
/// line where the picture has them.
struct Pair {
    before: Option<usize>,
    a: usize,
    b: usize,
    after: Option<usize>,
    /// `b` starts a tile.
    across: bool,
}

/// Every pair of neighbours (left, right) and (above, below) of a `width` x `height` picture.
fn neighbours(width: usize, height: usize) -> impl Iterator<Item = Pair> {
    // b at `along` on a line of `len` pixels `stride` apart
    let pair = move |b: usize, along: usize, len: usize, stride: usize| Pair {
        before: (along >= 2).then(|| b - 2 * stride),
        a: b - stride,
        b,
        after: (along + 1 < len).then(|| b + stride),
        across: along.is_multiple_of(TILE as usize),
    };
    let rows =
        (0..height).flat_map(move |y| (1..width).map(move |x| pair(y * width + x, x, width, 1)));
    let columns = (width..width * height).map(move |b| pair(b, b / width, height, width));
    rows.chain(columns)
}

/// Sum over the channels of |a - b|.
fn difference(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    (0..3).map(|c| (a[c] - b[c]).abs()).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadray_core::random::SplitMix;

    const W: u32 = 64;
    const H: u32 = 48;

    type Picture = Vec<[f32; 3]>;

    /// A smooth truth (a gradient) and direct light, and the truth with noise of `amount`.
    fn pictures(amount: f32, seed: u64) -> (Picture, Picture, Picture) {
        let truth: Picture = (0..W * H)
            .map(|p| [0.2 + 0.002 * (p % W) as f32 + 0.001 * (p / W) as f32; 3])
            .collect();
        let direct = vec![[0.5; 3]; truth.len()];
        let mut random = SplitMix(seed);
        let noisy = truth
            .iter()
            .map(|t| t.map(|v| v + amount * (random.next_f32() - 0.5)))
            .collect();
        (truth, direct, noisy)
    }

    /// `image` plus `f(x, y)` in every channel.
    fn plus(image: &[[f32; 3]], f: impl Fn(u32, u32) -> f32) -> Picture {
        let add = |(p, v): (usize, &[f32; 3])| v.map(|v| v + f(p as u32 % W, p as u32 / W));
        image.iter().enumerate().map(add).collect()
    }

    /// A small number per square of `side` pixels, different in neighbouring squares; the
    /// squares start at `shift`.
    fn squares(x: u32, y: u32, side: u32, shift: u32) -> f32 {
        let (i, j) = ((x + side - shift) / side, (y + side - shift) / side);
        ((i * 7 + j * 3) % 5) as f32
    }

    #[test]
    fn smooth_noise_has_no_tile_structure() {
        let (truth, direct, noisy) = pictures(0.01, 1);
        let (_, _, other) = pictures(0.01, 2);
        let structure = TileStructure::new(W, H, &truth, &[&direct]).unwrap();
        for order in Order::ALL {
            let ratio = structure.ratio(&noisy, order).unwrap();
            assert!((ratio - 1.0).abs() < 0.15, "{order:?}: {ratio}");
            let blockiness = structure.blockiness(&noisy, &other, order).unwrap();
            assert!((blockiness - 1.0).abs() < 0.2, "{order:?}: {blockiness}");
        }
    }

    #[test]
    fn an_error_in_tile_blocks_is_blocky() {
        let (truth, direct, noisy) = pictures(0.01, 3);
        let structure = TileStructure::new(W, H, &truth, &[&direct]).unwrap();
        let blocks = |shift| plus(&noisy, |x, y| 0.03 * squares(x, y, TILE, shift));
        for order in Order::ALL {
            let blockiness = structure.blockiness(&blocks(0), &noisy, order).unwrap();
            assert!(blockiness > 3.0, "{order:?}: {blockiness}");
            // the same blocks half a tile off the grid are no tile structure
            let off_grid = structure.blockiness(&blocks(TILE / 2), &noisy, order);
            assert!(off_grid.unwrap() < 1.0, "{order:?}: {off_grid:?}");
        }
        // a brute force with the same structure: none more than that
        for order in Order::ALL {
            assert_eq!(
                structure.blockiness(&blocks(0), &blocks(0), order),
                Some(1.0)
            );
        }
        // an error constant inside the tiles steps only across their boundaries
        let pure = plus(&truth, |x, y| 0.01 * squares(x, y, TILE, 0));
        assert_eq!(structure.ratio(&pure, Order::Step), Some(MAX_RATIO));
    }

    /// An error interpolated across each tile from values at its corners, the same value at
    /// the two pixels either side of a boundary: no step there, a bend.
    #[test]
    fn an_error_bent_at_the_tile_boundaries_is_blocky_in_bends_only() {
        let (truth, direct, noisy) = pictures(0.002, 4);
        let corner = |i: u32, j: u32| 0.1 * ((i * 7 + j * 3) % 5) as f32;
        let bent = plus(&noisy, |x, y| {
            let (i, j) = (x / TILE, y / TILE);
            let (u, v) = ((x % TILE) as f32, (y % TILE) as f32);
            let (u, v) = (u / (TILE - 1) as f32, v / (TILE - 1) as f32);
            let top = corner(i, j) * (1.0 - u) + corner(i + 1, j) * u;
            let bottom = corner(i, j + 1) * (1.0 - u) + corner(i + 1, j + 1) * u;
            top * (1.0 - v) + bottom * v
        });
        let structure = TileStructure::new(W, H, &truth, &[&direct]).unwrap();
        let steps = structure.blockiness(&bent, &noisy, Order::Step).unwrap();
        assert!(steps < 1.0, "{steps}");
        let bends = structure.blockiness(&bent, &noisy, Order::Bend).unwrap();
        assert!(bends > 3.0, "{bends}");
    }

    /// Edges of the truth or of the direct light on the tile grid change the error of every
    /// method there: they are left out, not counted as tile structure.
    #[test]
    fn geometric_edges_on_the_tile_grid_are_left_out() {
        let (truth, direct, noisy) = pictures(0.01, 5);
        // surfaces two tiles a side, some brighter: edges on some of the boundaries
        let scaled = |image: &[[f32; 3]], by: f32| -> Picture {
            let brighter = |p: usize| squares(p as u32 % W, p as u32 / W, 2 * TILE, 0) % 2.0 == 0.0;
            let lift =
                |(p, v): (usize, &[f32; 3])| if brighter(p) { v.map(|v| v * by) } else { *v };
            image.iter().enumerate().map(lift).collect()
        };
        // the truth twice as bright on them and the method 10% off it there; the same edges in
        // the direct light alone
        let (edged_truth, edged_direct) = (scaled(&truth, 2.0), scaled(&direct, 3.0));
        let in_truth = TileStructure::new(W, H, &edged_truth, &[&direct]).unwrap();
        let in_direct = TileStructure::new(W, H, &truth, &[&edged_direct]).unwrap();
        let counted = TileStructure::new(W, H, &truth, &[&direct]).unwrap();
        let off = scaled(&noisy, 1.2);
        for order in Order::ALL {
            let ratio = in_truth.ratio(&scaled(&noisy, 2.2), order).unwrap();
            assert!((ratio - 1.0).abs() < 0.2, "{order:?}: {ratio}");
            let ratio = in_direct.ratio(&off, order).unwrap();
            assert!((ratio - 1.0).abs() < 0.2, "{order:?}: {ratio}");
            // counted, they would be tile structure
            let ratio = counted.ratio(&off, order).unwrap();
            assert!(ratio > 1.5, "{order:?}: {ratio}");
        }
    }

    #[test]
    fn bad_input_gives_no_figure() {
        let (truth, direct, noisy) = pictures(0.01, 6);
        assert!(TileStructure::new(W, H + 1, &truth, &[&direct]).is_none());
        assert!(TileStructure::new(W, H, &truth, &[&direct[1..]]).is_none());
        assert!(TileStructure::new(0, 0, &[], &[]).is_none());
        assert!(TileStructure::new(u32::MAX, u32::MAX, &truth, &[]).is_none());
        let structure = TileStructure::new(W, H, &truth, &[&direct]).unwrap();
        let h = H as usize;
        let column = TileStructure::new(1, H, &truth[..h], &[]).unwrap();
        let pixel = TileStructure::new(1, 1, &truth[..1], &[]).unwrap();
        for order in Order::ALL {
            assert_eq!(structure.ratio(&noisy[1..], order), None);
            assert_eq!(structure.ratio(&truth, order), None, "no error, no change");
            // one column: its pairs cross boundaries and not
            assert!(column.ratio(&noisy[..h], order).is_some());
            // a single pixel has no neighbours
            assert_eq!(pixel.ratio(&noisy[..1], order), None);
        }
        // a brute force whose error changes only inside the tiles gives no figure
        let flat = vec![[0.25; 3]; truth.len()];
        let inside = plus(&flat, |x, _| if x % TILE == 4 { 0.25 } else { 0.0 });
        let structure = TileStructure::new(W, H, &flat, &[&direct]).unwrap();
        assert_eq!(structure.ratio(&inside, Order::Step), Some(0.0));
        assert_eq!(structure.blockiness(&noisy, &inside, Order::Step), None);
        // non-finite values are left out, not spread
        let mut broken = noisy.clone();
        broken[100] = [f32::NAN; 3];
        broken[200] = [f32::INFINITY; 3];
        let mut broken_truth = truth.clone();
        broken_truth[300] = [f32::NAN; 3];
        let structure = TileStructure::new(W, H, &broken_truth, &[&direct]).unwrap();
        for order in Order::ALL {
            assert!(structure.ratio(&broken, order).unwrap().is_finite());
        }
    }
}
