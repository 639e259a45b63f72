//! The uniform grid (Fujimoto's SEADS): resolution by a density rule, exact registration of convex
//! polygons in the cells they touch, 3DDDA traversal (Amanatides & Woo) and per-ray mailboxes.

use crate::clip::clip_slab;
use glam::Vec3;
use quadray_core::geom::{Aabb, Ray};
use rayon::prelude::*;

/// Cells per polygon of the density rule. The paper's four grids hold 42-54 cells per polygon
/// (74x32x67 for 3,781 polygons, 39x22x32 for 523, 22x14x19 for 113, 45x17x69 for 981).
pub const CELLS_PER_POLYGON: f32 = 50.0;
/// No grid gets more cells than this, whatever the scene.
pub const MAX_CELLS: f32 = 16.0e6;

/// The lists of ids registered in each cell, compressed row storage.
#[derive(Clone, Debug, Default)]
pub struct CellLists {
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl CellLists {
    #[inline]
    /// The ids registered in cell `c`.
    pub fn cell(&self, c: u32) -> &[u32] {
        &self.items[self.offsets[c as usize] as usize..self.offsets[c as usize + 1] as usize]
    }

    #[inline]
    /// How many ids cell `c` holds.
    pub fn count(&self, c: u32) -> u32 {
        self.offsets[c as usize + 1] - self.offsets[c as usize]
    }

    /// The offsets of rows `first..first + k` and the end of the last: row `first + i` holds
    /// `r[i + 1] - r[i]` ids.
    #[inline]
    pub fn row_bounds(&self, first: u32, k: u32) -> &[u32] {
        &self.offsets[first as usize..(first + k) as usize + 1]
    }

    /// Total number of (cell, id) registrations.
    pub fn registrations(&self) -> usize {
        self.items.len()
    }
}

/// A set of cells, one bit each: small enough to stay in cache while a ray walks.
#[derive(Clone, Debug)]
pub struct CellSet {
    bits: Vec<u64>,
}

impl CellSet {
    /// An empty set of `cells` cells.
    pub fn new(cells: usize) -> Self {
        Self {
            bits: vec![0; cells.div_ceil(64)],
        }
    }

    /// Adds cell `c`.
    pub fn insert(&mut self, c: u32) {
        self.bits[c as usize / 64] |= 1 << (c % 64);
    }

    #[inline]
    /// Whether cell `c` is in the set.
    pub fn contains(&self, c: u32) -> bool {
        self.bits[c as usize / 64] & (1 << (c % 64)) != 0
    }
}

/// The cells of a [`CellSet`] that a walk crossed, in order. The buffer is as long as the
/// longest walk, so that noting a cell takes no jump on whether it is in the set: that changes
/// from cell to cell as a ray walks, and every walk asks it of every cell.
#[derive(Clone, Debug)]
pub struct CellRecord {
    cells: Vec<u32>,
    len: usize,
}

impl CellRecord {
    /// An empty record for walks through `grid`.
    pub fn new(grid: &Grid) -> Self {
        Self {
            cells: vec![0; grid.res.iter().sum::<u32>() as usize + 1],
            len: 0,
        }
    }

    /// Forgets the cells noted.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// The cells noted since the last [`Self::clear`].
    pub fn cells(&self) -> &[u32] {
        &self.cells[..self.len]
    }

    #[inline]
    pub(crate) fn note(&mut self, set: &CellSet, c: u32) {
        self.cells[self.len] = c;
        self.len += set.contains(c) as usize;
    }
}

/// A per-ray "bucket": an id already tested on this ray is not tested again.
#[derive(Clone, Debug)]
pub struct Mailbox {
    stamps: Vec<u32>,
    current: u32,
}

impl Mailbox {
    /// A mailbox for ids `0..ids`.
    pub fn new(ids: usize) -> Self {
        Self {
            stamps: vec![0; ids],
            current: 0,
        }
    }

    /// Starts a new ray.
    pub fn next_ray(&mut self) {
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.stamps.fill(0);
            self.current = 1;
        }
    }

    /// Starts a new ray that never tests `skip` (the polygon it leaves).
    pub fn start_ray(&mut self, skip: Option<u32>) {
        self.next_ray();
        if let Some(s) = skip {
            self.first_visit(s);
        }
    }

    /// Marks `id` as tested on this ray; true the first time.
    #[inline]
    pub fn first_visit(&mut self, id: u32) -> bool {
        let s = &mut self.stamps[id as usize];
        let fresh = *s != self.current;
        *s = self.current;
        fresh
    }
}

/// Closest intersection along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The ray parameter of the hit.
    pub t: f32,
    /// The polygon hit.
    pub polygon: u32,
}

/// A uniform grid of cells over a box.
#[derive(Clone, Debug)]
pub struct Grid {
    /// The box the cells cover.
    pub bounds: Aabb,
    /// Cells along each axis.
    pub res: [u32; 3],
    /// One cell's size.
    pub cell_size: Vec3,
    inv_cell: Vec3,
}

impl Grid {
    /// The density rule: cubic cells, about [`CELLS_PER_POLYGON`] cells per polygon, at least one
    /// cell per axis. `bounds` is padded slightly so nothing lies on its faces.
    pub fn for_polygons(bounds: Aabb, polygons: usize) -> Grid {
        let bounds = pad(bounds);
        let e = bounds.extent();
        let cells = (CELLS_PER_POLYGON * polygons.max(1) as f32).min(MAX_CELLS);
        let h = (e.x * e.y * e.z / cells).cbrt();
        let axis = |x: f32| ((x / h).round() as u32).clamp(1, 1024);
        Grid::with_resolution(bounds, [axis(e.x), axis(e.y), axis(e.z)])
    }

    /// `res` cells over `bounds`.
    pub fn with_resolution(bounds: Aabb, res: [u32; 3]) -> Grid {
        let cell_size = bounds.extent() / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        Grid {
            bounds,
            res,
            cell_size,
            inv_cell: cell_size.recip(),
        }
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }

    #[inline]
    fn index(&self, c: [u32; 3]) -> u32 {
        (c[2] * self.res[1] + c[1]) * self.res[0] + c[0]
    }

    #[inline]
    fn coord(&self, axis: usize, x: f32) -> u32 {
        let i = ((x - self.bounds.min[axis]) * self.inv_cell[axis]).floor();
        (i.max(0.0) as u32).min(self.res[axis] - 1)
    }

    /// Calls `visit` with every cell the convex polygon touches (closed cells, padded by a small
    /// fraction of a cell so rounding never loses a cell). Exact: the polygon is clipped to each
    /// column of cells and the column's cells are those its clipped piece spans.
    pub fn cells_touched(&self, poly: &[Vec3], mut visit: impl FnMut(u32)) {
        if poly.is_empty() || poly.iter().any(|p| !p.is_finite()) {
            return;
        }
        let pad = self.cell_size * 1e-4;
        let (mut tmp, mut strip, mut piece) = (Vec::new(), Vec::new(), Vec::new());
        // A polygon reaching out of the grid (a shadow polygon, extruded far beyond it) is cut to
        // the grid first, so that its columns are chosen by the part that lies in cells.
        let mut inside = Vec::new();
        let mut b = Aabb::of_points(poly.iter().copied());
        let poly = if b.union(self.bounds) == self.bounds {
            poly
        } else {
            inside.extend_from_slice(poly);
            for axis in 0..3 {
                let (lo, hi) = (self.bounds.min[axis], self.bounds.max[axis]);
                clip_slab(
                    &inside,
                    axis,
                    lo - pad[axis],
                    hi + pad[axis],
                    &mut tmp,
                    &mut piece,
                );
                std::mem::swap(&mut inside, &mut piece);
            }
            b = Aabb::of_points(inside.iter().copied());
            &inside
        };
        if poly.is_empty() {
            return;
        }
        // Columns run along the polygon's longest axis: each column's cells come from one clip
        // of the polygon, so the fewer columns the cheaper (a long shadow polygon, or a wall,
        // is cut into a few long columns rather than many short ones).
        let c_axis = b.extent().max_position();
        let (a_axis, b_axis) = ((c_axis + 1) % 3, (c_axis + 2) % 3);
        // Keeps the part of `src` in the slab of cells `i` along `axis`; false when none is left.
        let clip_to_cells =
            |src: &[Vec3], axis: usize, i: u32, tmp: &mut _, out: &mut Vec<Vec3>| {
                let lo = self.bounds.min[axis] + i as f32 * self.cell_size[axis] - pad[axis];
                let hi = self.bounds.min[axis] + (i + 1) as f32 * self.cell_size[axis] + pad[axis];
                clip_slab(src, axis, lo, hi, tmp, out);
                !out.is_empty()
            };
        let range = |axis: usize, bx: &Aabb| {
            (
                self.coord(axis, bx.min[axis] - pad[axis]),
                self.coord(axis, bx.max[axis] + pad[axis]),
            )
        };
        let (i0, i1) = range(a_axis, &b);
        for i in i0..=i1 {
            if !clip_to_cells(poly, a_axis, i, &mut tmp, &mut strip) {
                continue;
            }
            let (j0, j1) = range(b_axis, &Aabb::of_points(strip.iter().copied()));
            for j in j0..=j1 {
                if !clip_to_cells(&strip, b_axis, j, &mut tmp, &mut piece) {
                    continue;
                }
                let (k0, k1) = range(c_axis, &Aabb::of_points(piece.iter().copied()));
                for k in k0..=k1 {
                    let mut c = [0; 3];
                    (c[a_axis], c[b_axis], c[c_axis]) = (i, j, k);
                    visit(self.index(c));
                }
            }
        }
    }

    /// Registers every polygon (by its position in `polygons`) in the cells it touches.
    pub fn register<'a>(
        &self,
        polygons: impl IndexedParallelIterator<Item = &'a [Vec3]>,
    ) -> CellLists {
        self.register_rows(1, polygons.enumerate().map(|(id, p)| (id as u32, 0, p)))
    }

    /// Registers polygons in `slots` rows per cell: polygon `(id, slot, outline)` goes, as `id`,
    /// into row `cell * slots + slot` of every cell it touches. Several lists over the same
    /// cells (each light's shadow polygons) are built at once this way, cell-major, so that the
    /// rows of one cell share cache lines. Within a row, ids come in the order of `polygons`.
    pub fn register_rows<'a>(
        &self,
        slots: u32,
        polygons: impl IndexedParallelIterator<Item = (u32, u32, &'a [Vec3])>,
    ) -> CellLists {
        let per_polygon: Vec<(u32, Vec<u32>)> = polygons
            .map(|(id, slot, poly)| {
                let mut rows = Vec::new();
                self.cells_touched(poly, |c| rows.push(c * slots + slot));
                (id, rows)
            })
            .collect();
        // Counts into `offsets[row + 1]`, then starts; each row's start is moved along as it is
        // filled, which leaves it at the next row's start, so the offsets are shifted back.
        let mut offsets = vec![0u32; self.cell_count() * slots as usize + 1];
        for (_, rows) in &per_polygon {
            for &r in rows {
                offsets[r as usize + 1] += 1;
            }
        }
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        let mut items = vec![0u32; *offsets.last().unwrap() as usize];
        for (id, rows) in &per_polygon {
            for &r in rows {
                items[offsets[r as usize] as usize] = *id;
                offsets[r as usize] += 1;
            }
        }
        let rows = offsets.len() - 1;
        offsets.copy_within(..rows, 1);
        offsets[0] = 0;
        CellLists { offsets, items }
    }

    /// 3DDDA: visits the cells the ray crosses within `[t_min, t_max]`, in order, with the ray
    /// parameters where it enters and leaves each; `visit` returns true to stop.
    #[inline]
    pub fn walk(&self, ray: &Ray, mut visit: impl FnMut(u32, f32, f32) -> bool) {
        let (o, d, t_min, t_max) = (ray.origin, ray.dir, ray.t_min, ray.t_max);
        let inv_d = d.recip();
        let Some((t0, t1)) = self.bounds.clip_ray(o, inv_d, t_min, t_max) else {
            return;
        };
        let p = o + d * t0;
        let mut cell = [0u32; 3];
        let mut step = [0i32; 3];
        let mut t_next = [f32::INFINITY; 3];
        let mut t_delta = [f32::INFINITY; 3];
        for a in 0..3 {
            cell[a] = self.coord(a, p[a]);
            let cell_lo = self.bounds.min[a] + cell[a] as f32 * self.cell_size[a];
            if d[a] > 0.0 {
                step[a] = 1;
                t_next[a] = (cell_lo + self.cell_size[a] - o[a]) * inv_d[a];
                t_delta[a] = self.cell_size[a] * inv_d[a];
            } else if d[a] < 0.0 {
                step[a] = -1;
                t_next[a] = (cell_lo - o[a]) * inv_d[a];
                t_delta[a] = -self.cell_size[a] * inv_d[a];
            }
        }
        let mut t_enter = t0;
        loop {
            let axis = if t_next[0] < t_next[1] {
                if t_next[0] < t_next[2] { 0 } else { 2 }
            } else if t_next[1] < t_next[2] {
                1
            } else {
                2
            };
            let t_exit = t_next[axis].min(t1);
            if visit(self.index(cell), t_enter, t_exit) || t_next[axis] >= t1 {
                return;
            }
            let next = cell[axis] as i32 + step[axis];
            if next < 0 || next >= self.res[axis] as i32 {
                return;
            }
            cell[axis] = next as u32;
            t_enter = t_next[axis];
            t_next[axis] += t_delta[axis];
        }
    }
}

fn pad(b: Aabb) -> Aabb {
    let m = Vec3::splat(b.extent().max_element().max(1e-3) * 1e-3);
    Aabb {
        min: b.min - m,
        max: b.max + m,
    }
}
