//! The relaxed cone map of relaxed cone step mapping (Policarpo & Oliveira, GPU Gems 3, ch. 18),
//! built exactly for the point-sampled height field (flat-topped texel columns, the surface the
//! pyramid methods trace).
//!
//! A ray going down can only leave the solid through a wall between a column `a` and a deeper
//! neighbour `b`, at a depth in `[d_a, d_b)`, moving from `a`'s side to `b`'s. The relaxed cone
//! of texel `s` has its apex on `s`'s top at the texel centre `c` and holds no such exit of a ray
//! from `c`: ratio = min over exit walls `W` with `d_a < d_s` and `c` on `a`'s side of
//! `dist(c, W) / (d_s - d_a)`, in uv units per unit of depth. (The chapter's builder shoots rays
//! from above the centre through every texel and marches each to its exit; the walls give the
//! cone for every ray from there, not only those through texel centres.) A cone step from above
//! the centre never crosses an exit: after it the ray is still above the surface, or it entered
//! the solid once and the first intersection lies in that step, where the binary search finds it.
//! The shader steps from wherever the ray is over the texel, as the chapter does, so an exit
//! within about half a texel of the centre can be crossed: that, and the fixed step count, are
//! the method's errors. (A cone valid for every apex in the texel would be 0 wherever a higher
//! neighbour has a deeper neighbour beside the texel's corner, and stall the ray there.)
//!
//! The build is branch and bound over a min-depth pyramid of the texels that have an exit wall: a
//! node whose nearest point and shallowest exit cannot give a ratio below the best so far is
//! skipped, so a texel visits only the nodes around the exits that bound its cone.

use crate::heightmap::HeightMap;
use crate::pyramid::{Addressing, Pyramid};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// The ratio stored where no exit bounds the cone (a flat map): a step then reaches the texel's
/// top, as an unbounded cone would, while every product in the shader stays finite.
pub const UNBOUNDED_RATIO: f32 = 1.0e6;

/// Per texel, its depth and its relaxed cone ratio.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeMap {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Row-major `[depth, cone ratio]`, the ratio in uv units per unit of depth.
    pub texels: Vec<[f32; 2]>,
}

// The exit walls of a texel, as bits: its neighbour at +x, -x, +y, -y is deeper, or (on a
// clamped map) off the map, where rays leave it.
const PLUS_X: u8 = 1;
const MINUS_X: u8 = 2;
const PLUS_Y: u8 = 4;
const MINUS_Y: u8 = 8;

/// The map with the addressing its rays use, in texel units.
struct Field<'a> {
    map: &'a HeightMap,
    addressing: Addressing,
    width: i64,
    height: i64,
}

impl Field<'_> {
    fn depth(&self, x: i64, y: i64) -> f32 {
        self.map.at(x as u32, y as u32)
    }

    /// The exit wall bits of texel (x, y) (in the map).
    fn exits(&self, x: i64, y: i64) -> u8 {
        let d = self.depth(x, y);
        let mut bits = 0;
        for (bit, dx, dy) in [
            (PLUS_X, 1, 0),
            (MINUS_X, -1, 0),
            (PLUS_Y, 0, 1),
            (MINUS_Y, 0, -1),
        ] {
            let (nx, ny) = (x + dx, y + dy);
            let inside = (0..self.width).contains(&nx) && (0..self.height).contains(&ny);
            let deeper = match self.addressing {
                Addressing::Clamp if !inside => true,
                _ => {
                    let nx = self.addressing.texel(nx, self.width as u32);
                    let ny = self.addressing.texel(ny, self.height as u32);
                    self.map.at(nx, ny) > d
                }
            };
            if deeper {
                bits |= bit;
            }
        }
        bits
    }

    /// The copies of the map whose exits can bound a cone: the tiled neighbours of a wrapped map
    /// (the nearest copy of any texel is among them), only the map itself for a clamped one.
    fn copies(&self) -> Vec<(i64, i64)> {
        match self.addressing {
            Addressing::Wrap => (-1..=1)
                .flat_map(|j| (-1..=1).map(move |i| (i * self.width, j * self.height)))
                .collect(),
            Addressing::Clamp => vec![(0, 0)],
        }
    }

    /// The uv distance of `gx`, `gy` half texels.
    fn uv_distance(&self, gx: i64, gy: i64) -> f32 {
        let u = gx as f32 / (2 * self.width) as f32;
        let v = gy as f32 / (2 * self.height) as f32;
        (u * u + v * v).sqrt()
    }

    /// The smallest ratio the exits of texel `a` (at absolute position `ax`, `ay`: possibly in a
    /// neighbouring copy) give the cone of texel (`sx`, `sy`) of depth `ds`, or `None`.
    fn texel_ratio(&self, (sx, sy): (i64, i64), ds: f32, (ax, ay): (i64, i64)) -> Option<f32> {
        let (x, y) = (ax.rem_euclid(self.width), ay.rem_euclid(self.height));
        let da = self.depth(x, y);
        if da >= ds {
            return None;
        }
        let exits = self.exits(x, y);
        // In half texels: from the centre s + 1/2 to the span [a, a + 1] of the wall across the
        // other axis.
        let across = |s: i64, a: i64| (2 * (a - s).abs() - 1).max(0);
        // (exit bit, the centre on a's side, gap along x, gap along y) for the walls at
        // x = ax + 1, x = ax, y = ay + 1, y = ay.
        let walls = [
            (PLUS_X, sx <= ax, 2 * (ax - sx) + 1, across(sy, ay)),
            (MINUS_X, sx >= ax, 2 * (sx - ax) + 1, across(sy, ay)),
            (PLUS_Y, sy <= ay, across(sx, ax), 2 * (ay - sy) + 1),
            (MINUS_Y, sy >= ay, across(sx, ax), 2 * (sy - ay) + 1),
        ];
        walls
            .into_iter()
            .filter(|&(bit, side, _, _)| exits & bit != 0 && side)
            .map(|(_, _, gx, gy)| self.uv_distance(gx, gy) / (ds - da))
            .reduce(f32::min)
    }
}

impl ConeMap {
    /// The relaxed cone map of `map` for rays that wrap or clamp as `addressing` says.
    pub fn build(map: &HeightMap, addressing: Addressing) -> Self {
        Self::build_with_progress(map, addressing, || {})
    }

    /// As [`ConeMap::build`], calling `row_done` (from the build's threads) as each of the
    /// map's rows is finished, so that a caller can show progress: the build takes seconds at
    /// 1024^2 and minutes from 4096^2 on a few cores (BENCHMARKS.md).
    pub fn build_with_progress(
        map: &HeightMap,
        addressing: Addressing,
        row_done: impl Fn() + Sync,
    ) -> Self {
        Self::build_unless_cancelled(map, addressing, row_done, &AtomicBool::new(false))
            .expect("never cancelled")
    }

    /// As [`ConeMap::build_with_progress`], with rows left unbuilt once `cancelled` is set; then
    /// `None`. A build takes minutes on big maps, and a viewer that moved on drops it.
    fn build_unless_cancelled(
        map: &HeightMap,
        addressing: Addressing,
        row_done: impl Fn() + Sync,
        cancelled: &AtomicBool,
    ) -> Option<Self> {
        let field = Field {
            map,
            addressing,
            width: i64::from(map.width),
            height: i64::from(map.height),
        };
        // Min depth over the texels with an exit; 1 (never above any texel) for the others.
        let exit_depths: Vec<f32> = (0..field.height)
            .flat_map(|y| (0..field.width).map(move |x| (x, y)))
            .map(|(x, y)| {
                if field.exits(x, y) != 0 {
                    field.depth(x, y)
                } else {
                    1.0
                }
            })
            .collect();
        let exit_map = HeightMap::from_depths(
            Path::new("cone map exits"),
            map.width,
            map.height,
            exit_depths,
        )
        .expect("depths of a valid map");
        let pyramid = Pyramid::build(&exit_map);
        let copies = field.copies();
        let texels = (0..field.height)
            .into_par_iter()
            .flat_map_iter(|y| {
                if cancelled.load(Ordering::Relaxed) {
                    return Vec::new();
                }
                let mut search = Search::default();
                let row: Vec<[f32; 2]> = (0..field.width)
                    .map(|x| {
                        let ds = field.depth(x, y);
                        [ds, search.best_ratio(&field, &pyramid, &copies, (x, y), ds)]
                    })
                    .collect();
                row_done();
                row
            })
            .collect();
        if cancelled.load(Ordering::Relaxed) {
            return None;
        }
        Some(Self {
            width: map.width,
            height: map.height,
            texels,
        })
    }

    /// The cone map as the texture `cone.wgsl` reads: Rg32Float, one mip, (depth, ratio).
    pub fn upload(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::Texture {
        quadray_gpu::texture_2d_with_data(
            device,
            queue,
            "cone map",
            (self.width, self.height),
            wgpu::TextureFormat::Rg32Float,
            bytemuck::cast_slice(&self.texels),
        )
    }
}

/// A cone map built on a thread of its own, so that an interactive program keeps drawing while it
/// builds (quadray's viewer shows its progress). Dropping the job stops the build: its thread
/// skips the rows not yet started and ends.
pub struct ConeMapJob {
    rows_done: Arc<AtomicU32>,
    rows: u32,
    cancelled: Arc<AtomicBool>,
    // `None` only once `finish` has taken it.
    thread: Option<std::thread::JoinHandle<Option<(ConeMap, f64)>>>,
}

impl ConeMapJob {
    /// Starts building the cone map of `map` for rays addressed as `addressing` says.
    pub fn spawn(map: HeightMap, addressing: Addressing) -> Self {
        let rows_done = Arc::new(AtomicU32::new(0));
        let cancelled = Arc::new(AtomicBool::new(false));
        let counter = Arc::clone(&rows_done);
        let stop = Arc::clone(&cancelled);
        let rows = map.height;
        let thread = std::thread::spawn(move || {
            let start = std::time::Instant::now();
            let row_done = || {
                counter.fetch_add(1, Ordering::Relaxed);
            };
            ConeMap::build_unless_cancelled(&map, addressing, row_done, &stop)
                .map(|cones| (cones, start.elapsed().as_secs_f64()))
        });
        Self {
            rows_done,
            rows,
            cancelled,
            thread: Some(thread),
        }
    }

    /// The fraction of the map's rows built so far, 0 to 1.
    pub fn progress(&self) -> f32 {
        self.rows_done.load(Ordering::Relaxed) as f32 / self.rows as f32
    }

    /// Whether the build has ended, so that [`ConeMapJob::finish`] returns at once.
    pub fn is_finished(&self) -> bool {
        self.thread.as_ref().is_none_or(|t| t.is_finished())
    }

    /// The cone map and the seconds its build took, waiting for the build if it is still on.
    pub fn finish(mut self) -> (ConeMap, f64) {
        let thread = self.thread.take().expect("taken only here");
        thread
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            .expect("only a dropped job is cancelled")
    }
}

impl Drop for ConeMapJob {
    fn drop(&mut self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }
}

/// A pyramid node waiting to be searched: its bound (as bits), level, position and copy.
type Node = Reverse<(u32, usize, i64, i64, (i64, i64))>;

/// One row's search state, carried from texel to texel.
#[derive(Default)]
struct Search {
    heap: BinaryHeap<Node>,
    /// Where (in absolute texels, possibly in a neighbouring copy) the last texel's cone met
    /// its exit. Neighbouring texels mostly share it: its ratio for the next texel is a real
    /// exit's, an upper bound that prunes from the first node on, and the minimum stays the same.
    last_exit: Option<(i64, i64)>,
}

impl Search {
    /// Best-first branch and bound over the exit pyramid's nodes in every copy of the map.
    fn best_ratio(
        &mut self,
        field: &Field,
        pyramid: &Pyramid,
        copies: &[(i64, i64)],
        (sx, sy): (i64, i64),
        ds: f32,
    ) -> f32 {
        let top = pyramid.levels.len() - 1;
        // From the centre s + 1/2 to the node's closed span [lo, hi] on one axis, in half texels.
        let gap = |s: i64, lo: i64, hi: i64| (2 * lo - 2 * s - 1).max(2 * s + 1 - 2 * hi).max(0);
        // A lower bound on the ratio any exit in node (level, nx, ny) of a copy can give: its
        // nearest point over its shallowest exit. Positive floats order as their bits.
        let bound = |level: usize, (nx, ny): (i64, i64), (ox, oy): (i64, i64)| -> Option<u32> {
            let side = 1i64 << (level as u32);
            let (level_width, level_height) = pyramid.level_size(level as u32);
            if nx >= i64::from(level_width) || ny >= i64::from(level_height) {
                // A child past an axis the padded pyramid has already reduced to one node.
                return None;
            }
            let shallowest = pyramid.levels[level][(ny * i64::from(level_width) + nx) as usize];
            if shallowest >= ds {
                return None;
            }
            let (x0, y0) = (nx * side + ox, ny * side + oy);
            let d = field.uv_distance(gap(sx, x0, x0 + side), gap(sy, y0, y0 + side));
            Some((d / (ds - shallowest)).to_bits())
        };
        let mut best = UNBOUNDED_RATIO;
        let mut best_exit = None;
        if let Some(exit) = self.last_exit
            && let Some(r) = field.texel_ratio((sx, sy), ds, exit)
        {
            (best, best_exit) = (r, Some(exit));
        }
        let heap = &mut self.heap;
        heap.clear();
        for &copy in copies {
            if let Some(b) = bound(top, (0, 0), copy)
                && f32::from_bits(b) < best
            {
                heap.push(Reverse((b, top, 0i64, 0i64, copy)));
            }
        }
        while let Some(Reverse((b, level, nx, ny, copy))) = heap.pop() {
            if f32::from_bits(b) >= best {
                break;
            }
            if level == 0 {
                // Leaves beyond the map (of a pyramid padded to a power of two) are no texel.
                let exit = (nx + copy.0, ny + copy.1);
                let in_map = nx < field.width && ny < field.height;
                if let Some(r) = in_map
                    .then(|| field.texel_ratio((sx, sy), ds, exit))
                    .flatten()
                    && r < best
                {
                    (best, best_exit) = (r, Some(exit));
                }
                continue;
            }
            for (cx, cy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let child = (2 * nx + cx, 2 * ny + cy);
                if let Some(b) = bound(level - 1, child, copy)
                    && f32::from_bits(b) < best
                {
                    heap.push(Reverse((b, level - 1, child.0, child.1, copy)));
                }
            }
        }
        self.last_exit = best_exit.or(self.last_exit);
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::heightmap::random_map;

    /// Every exit wall of every texel in every copy, without pruning.
    fn brute_force(map: &HeightMap, addressing: Addressing) -> ConeMap {
        let (w, h) = (i64::from(map.width), i64::from(map.height));
        let field = Field {
            map,
            addressing,
            width: w,
            height: h,
        };
        let mut texels = Vec::new();
        for sy in 0..h {
            for sx in 0..w {
                let ds = field.depth(sx, sy);
                let mut best = UNBOUNDED_RATIO;
                for (ox, oy) in field.copies() {
                    for ay in 0..h {
                        for ax in 0..w {
                            if let Some(r) = field.texel_ratio((sx, sy), ds, (ax + ox, ay + oy)) {
                                best = best.min(r);
                            }
                        }
                    }
                }
                texels.push([ds, best]);
            }
        }
        ConeMap {
            width: map.width,
            height: map.height,
            texels,
        }
    }

    /// Pruning only skips nodes that cannot lower a ratio, and the bounds use the same float
    /// operations as the texels they bound: the ratios are bit-identical.
    #[test]
    fn pruned_build_equals_brute_force() {
        let cases = [
            ((8, 8), 1, 0),
            ((16, 16), 2, 2),
            ((16, 16), 3, 5),
            ((32, 32), 4, 3),
            ((2, 2), 5, 0),
            // Sizes that are not powers of two, and shapes whose padded pyramid reduces one
            // axis to a single node before the other.
            ((13, 5), 6, 3),
            ((3, 17), 7, 0),
            ((1, 9), 8, 2),
        ];
        for (size, seed, levels) in cases {
            let map = random_map(size.0, size.1, seed, levels);
            for addressing in [Addressing::Wrap, Addressing::Clamp] {
                let fast = ConeMap::build(&map, addressing);
                assert_eq!(
                    fast,
                    brute_force(&map, addressing),
                    "{size:?} seed {seed} {addressing:?}"
                );
            }
        }
    }

    #[test]
    fn a_cone_beside_a_raised_row_reaches_its_far_wall() {
        // One raised row (depth 0) across a tiled floor at depth 1: from the floor beside it, the
        // cone passes over the row's near wall (where rays enter it) to its far wall at y = 4,
        // 1.5 texels from the texel's centre, where rays leave it.
        let n = 8;
        let mut depth = vec![1.0; n * n];
        depth[3 * n..4 * n].fill(0.0);
        let map = HeightMap::from_depths(Path::new("row"), n as u32, n as u32, depth).unwrap();
        let cones = ConeMap::build(&map, Addressing::Wrap);
        assert_eq!(cones.texels[2 * n], [1.0, 1.5 / 8.0]);
        // On the row itself nothing is above the apex.
        assert_eq!(cones.texels[3 * n], [0.0, UNBOUNDED_RATIO]);
    }

    #[test]
    fn a_job_on_its_own_thread_builds_the_same_map_and_counts_every_row() {
        let map = random_map(24, 9, 11, 3);
        let job = ConeMapJob::spawn(map.clone(), Addressing::Clamp);
        while !job.is_finished() {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        assert_eq!(job.progress(), 1.0);
        let (cones, seconds) = job.finish();
        assert_eq!(cones, ConeMap::build(&map, Addressing::Clamp));
        assert!(seconds >= 0.0);
        let rows = AtomicU32::new(0);
        ConeMap::build_with_progress(&map, Addressing::Wrap, || {
            rows.fetch_add(1, Ordering::Relaxed);
        });
        assert_eq!(rows.into_inner(), 9);
    }

    #[test]
    fn a_dropped_job_stops_building() {
        let map = random_map(16, 256, 11, 3);
        let cancelled = AtomicBool::new(false);
        let rows = AtomicU32::new(0);
        let cones = ConeMap::build_unless_cancelled(
            &map,
            Addressing::Wrap,
            || {
                // cancelled once the first rows are done, as a viewer dropping its job would
                if rows.fetch_add(1, Ordering::Relaxed) == 2 {
                    cancelled.store(true, Ordering::Relaxed);
                }
            },
            &cancelled,
        );
        assert!(cones.is_none());
        assert!(
            rows.into_inner() < 256,
            "every row was built after the cancel"
        );
        // A job sets the flag when dropped: its build (seconds at 1024^2) ends without a map.
        let mut job = ConeMapJob::spawn(random_map(1024, 1024, 5, 4), Addressing::Wrap);
        let thread = job.thread.take().expect("running");
        drop(job);
        assert!(thread.join().unwrap().is_none());
    }

    #[test]
    fn a_flat_map_has_unbounded_cones() {
        let map = HeightMap::from_depths(Path::new("flat"), 4, 4, vec![0.5; 16]).unwrap();
        for addressing in [Addressing::Wrap, Addressing::Clamp] {
            let cones = ConeMap::build(&map, addressing);
            assert!(cones.texels.iter().all(|t| *t == [0.5, UNBOUNDED_RATIO]));
        }
    }
}
