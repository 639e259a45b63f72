//! The walk through the grid ([`OccupancyGrid::visible`], [`OccupancyGrid::walk`]), the CPU
//! twin of `occupancy.wgsl`'s `grid_visibility`: box by box along the segment, reading a word
//! a step as the GPU's walk does.

use super::{
    BRICK, END_CLEARANCE_CELLS, END_OFFSET_CELLS, MASK_WORDS, OccupancyGrid, SUBCELLS, SubCells,
    sub_bit, sub_cell,
};
use glam::{IVec3, UVec3, Vec3};

/// What a walk between two points found, and the words it fetched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Walk {
    /// Visible, blocked, or `None`: a moved end lies in a set cell.
    pub visible: Option<bool>,
    /// Words fetched: one each time the walk enters a brick it has not just read (and in a
    /// grid of two levels, one for where a brick's sub-cells start, the first time the walk
    /// enters a set cell of the brick, and one each time it enters a half of a set cell's
    /// sub-cells it has not just read).
    pub fetches: u32,
    /// Cells and sub-cells the segment crossed up to the answer (what a grid of a word a cell
    /// would have fetched).
    pub cells: u32,
    /// Steps of the walk's loop: a box crossed (an empty brick, a cell, a sub-cell), or a word
    /// read that the next step needs (its work on a GPU, beside the fetches).
    pub steps: u32,
}

impl OccupancyGrid {
    /// Whether sub-cell `s` (in sub-cell units, [`SUBCELLS`] a cell) holds a piece of a
    /// triangle: its cell's, in a grid of one level.
    pub fn subcell_occupied(&self, s: IVec3) -> bool {
        let mut reader = WordReader::new(self);
        let c = s.div_euclid(IVec3::splat(SUBCELLS as i32));
        reader.occupied(c) && (self.sub.is_none() || reader.sub_occupied(s))
    }

    /// Whether the segment from `x` (a receiver, normal `n`) to `xp` (a VPL or cluster, normal
    /// `np`, of any length: a cluster's mean normal is shorter) crosses no set cell, its ends
    /// moved [`END_OFFSET_CELLS`] off their surfaces (an end whose normal is shorter than 0.1
    /// stays); `None` where a moved end lies in a set cell (another surface within two cells
    /// of it: in a corner, under a box) or the walk enters a set cell within
    /// [`END_CLEARANCE_CELLS`] of an end, which the grid cannot judge. Crosses the boxes the
    /// segment passes through, in order: a brick whose word is zero, a cell whose bit is not
    /// set, or a sub-cell of a set one, a box a step.
    pub fn visible(&self, x: Vec3, n: Vec3, xp: Vec3, np: Vec3) -> Option<bool> {
        self.walk(x, n, xp, np).visible
    }

    /// [`Self::visible`] with the words the walk fetched, as the GPU's walk counts them: the
    /// word last read is kept, so a brick costs one fetch however many of its cells are crossed.
    pub fn walk(&self, x: Vec3, n: Vec3, xp: Vec3, np: Vec3) -> Walk {
        let mut reader = WordReader::new(self);
        let visible = self.walk_cells(x, n, xp, np, &mut reader);
        Walk {
            visible,
            fetches: reader.fetches,
            cells: reader.cells,
            steps: reader.steps,
        }
    }

    fn walk_cells(
        &self,
        x: Vec3,
        n: Vec3,
        xp: Vec3,
        np: Vec3,
        reader: &mut WordReader,
    ) -> Option<bool> {
        let a_cells = self.to_grid(x, n);
        let b_cells = self.to_grid(xp, np);
        // the end first: the walk goes on from its word
        if reader.occupied_at(b_cells) {
            return None;
        }
        let a = a_cells * SUBCELLS as f32;
        let d = (b_cells - a_cells) * SUBCELLS as f32;
        let forward = d.cmpgt(Vec3::ZERO);
        let still = d.cmpeq(Vec3::ZERO);
        let inverse = Vec3::ONE / Vec3::select(still, Vec3::ONE, d);
        // the segment parameter of the clearance at each end
        let clearance = END_CLEARANCE_CELLS / (b_cells - a_cells).length().max(1e-6);
        let blocked_at = |entered: f32| clearance < entered && entered < 1.0 - clearance;
        // a step a sub-cell face crossed (the ends lie within two cells of the grid), and two
        // reads a cell at most
        let bound = 3 * SUBCELLS * (self.dims.element_sum() + 6);
        let mut s = a.floor().as_ivec3();
        let mut entered = 0.0;
        reader.cells += 1;
        for _ in 0..bound {
            reader.steps += 1;
            let shift = match reader.step_box(s) {
                StepBox::Read => continue,
                StepBox::Set => return blocked_at(entered).then_some(false),
                StepBox::Free(shift) => shift,
            };
            let lo = (s >> shift) << shift;
            let hi = lo + (IVec3::ONE << shift);
            let exit = Vec3::select(
                still,
                Vec3::INFINITY,
                (IVec3::select(forward, hi, lo).as_vec3() - a) * inverse,
            );
            let t = exit.min_element();
            if t > 1.0 {
                // the end is in the box
                break;
            }
            // the box across the face the segment leaves by (ties: x, then y), kept beside the
            // box against rounding
            let mut next = (a + d * t).floor().as_ivec3().clamp(lo, hi - 1);
            let across = IVec3::select(forward, hi, lo - 1);
            let axis = if exit.x <= exit.y && exit.x <= exit.z {
                0
            } else if exit.y <= exit.z {
                1
            } else {
                2
            };
            next[axis] = across[axis];
            // the cells entered (a walk of a cell a step would have tested each)
            let cells = |s: IVec3| s.div_euclid(IVec3::splat(SUBCELLS as i32));
            reader.cells += (cells(next) - cells(s)).abs().element_sum() as u32;
            s = next;
            entered = t;
        }
        Some(true)
    }

    /// A segment's end in grid units, moved off its surface.
    pub(super) fn to_grid(&self, p: Vec3, n: Vec3) -> Vec3 {
        let off = if n.length() > 0.1 {
            n.normalize() * END_OFFSET_CELLS
        } else {
            Vec3::ZERO
        };
        (p - self.origin) / self.cell + off
    }
}

/// A walk's reads of the grid: the last word fetched, how many were, and the cells tested.
struct WordReader<'a> {
    grid: &'a OccupancyGrid,
    word: Option<(usize, u32)>,
    /// The held brick's first sub-cells, once read.
    first: Option<u32>,
    /// The last word of sub-cells fetched.
    sub_word: Option<(usize, u32)>,
    fetches: u32,
    cells: u32,
    steps: u32,
}

impl WordReader<'_> {
    fn new(grid: &OccupancyGrid) -> WordReader<'_> {
        WordReader {
            grid,
            word: None,
            first: None,
            sub_word: None,
            fetches: 0,
            cells: 0,
            steps: 0,
        }
    }

    /// Whether the point `p` (grid units) lies in a set cell, and with two levels in a set
    /// sub-cell of it.
    fn occupied_at(&mut self, p: Vec3) -> bool {
        self.occupied(p.floor().as_ivec3())
            && (self.grid.sub.is_none()
                || self.sub_occupied((p * SUBCELLS as f32).floor().as_ivec3()))
    }

    /// Whether sub-cell `s` (sub-cell units) is set, its cell being set (the word of the cell
    /// held).
    fn sub_occupied(&mut self, s: IVec3) -> bool {
        self.cells += 1;
        if self.first.is_none() {
            self.read_first();
        }
        self.read_sub_word(s) >> sub_bit(sub_cell(s)).1 & 1 == 1
    }

    /// The box the walk at sub-cell `s` may cross in one step, reading at most one word, as the
    /// GPU's walk does (its loop has one read): the brick's where another is held; in a set
    /// cell of a grid of two levels, where the brick's sub-cells start, then the half of the
    /// cell's sub-cells, each at a step of its own where not held.
    fn step_box(&mut self, s: IVec3) -> StepBox {
        let c = s.div_euclid(IVec3::splat(SUBCELLS as i32));
        let Some((index, bit)) = self.grid.index(c) else {
            return StepBox::Free(CELL_SHIFT);
        };
        let two_levels = self.grid.sub.is_some();
        if self.word.is_none_or(|(held, _)| held != index) {
            let bits = self.read_brick(index);
            if two_levels && bits >> bit & 1 == 1 {
                return StepBox::Read;
            }
        }
        let bits = self.word.expect("the brick is held").1;
        if bits >> bit & 1 == 0 {
            return StepBox::Free(if bits == 0 { BRICK_SHIFT } else { CELL_SHIFT });
        }
        if !two_levels {
            return StepBox::Set;
        }
        if self.first.is_none() {
            self.read_first();
            return StepBox::Read;
        }
        if self.sub_occupied(s) {
            StepBox::Set
        } else {
            StepBox::Free(UVec3::ZERO)
        }
    }

    /// Reads the word of the brick at `index`.
    fn read_brick(&mut self, index: usize) -> u32 {
        self.fetches += 1;
        let bits = self.grid.bits[index];
        self.word = Some((index, bits));
        self.first = None;
        bits
    }

    /// Reads where the held brick's sub-cells start.
    fn read_first(&mut self) {
        let (index, _) = self.word.expect("the brick is held");
        self.fetches += 1;
        self.first = Some(self.sub_cells().first[index]);
    }

    /// The word of sub-cell `s` of a set cell of the held brick (read where another is held).
    fn read_sub_word(&mut self, s: IVec3) -> u32 {
        let (_, bits) = self.word.expect("the brick is held");
        let first = self.first.expect("the brick's first sub-cells are read");
        let c = s.div_euclid(IVec3::splat(SUBCELLS as i32));
        let (_, bit) = self.grid.index(c).expect("a set cell is in the grid");
        let rank = first + (bits & ((1u32 << bit) - 1)).count_ones();
        let word = rank as usize * MASK_WORDS + sub_bit(sub_cell(s)).0;
        match self.sub_word {
            Some((held, mask)) if held == word => mask,
            _ => {
                self.fetches += 1;
                let mask = self.sub_cells().masks[word];
                self.sub_word = Some((word, mask));
                mask
            }
        }
    }

    fn sub_cells(&self) -> &SubCells {
        self.grid.sub.as_ref().expect("a grid of two levels")
    }

    fn occupied(&mut self, c: IVec3) -> bool {
        self.cells += 1;
        let Some((index, bit)) = self.grid.index(c) else {
            return false;
        };
        let bits = match self.word {
            Some((held, bits)) if held == index => bits,
            _ => self.read_brick(index),
        };
        bits >> bit & 1 == 1
    }
}

/// What a step of the walk may cross from its sub-cell ([`WordReader::step_box`]).
enum StepBox {
    /// Nothing: the step read a word that the sub-cell's verdict needs before the next one.
    Read,
    /// The sub-cell (with one level, the cell) is set.
    Set,
    /// The box around the sub-cell, its side 2^shift sub-cells along each axis, is free.
    Free(UVec3),
}

/// A step's box in sub-cells: a cell's, a brick's (powers of two).
const CELL_SHIFT: UVec3 = UVec3::splat(SUBCELLS.trailing_zeros());
const BRICK_SHIFT: UVec3 = UVec3::new(
    BRICK.x.trailing_zeros() + SUBCELLS.trailing_zeros(),
    BRICK.y.trailing_zeros() + SUBCELLS.trailing_zeros(),
    BRICK.z.trailing_zeros() + SUBCELLS.trailing_zeros(),
);

#[cfg(test)]
mod tests {
    use super::super::tests::{floor_and_wall, quad};
    use super::*;

    #[test]
    fn a_wall_blocks_and_the_gap_above_it_does_not() {
        let grid = OccupancyGrid::of_triangles(&floor_and_wall(0.5), 32);
        let up = Vec3::Y;
        let left = Vec3::new(0.2, 0.0, 0.5);
        let right = Vec3::new(0.8, 0.0, 0.5);
        assert_eq!(
            grid.visible(left, up, right, up),
            Some(false),
            "through the wall"
        );
        let above = grid.visible(left + 0.8 * up, up, right + 0.8 * up, up);
        assert_eq!(above, Some(true), "above it");
        let beside = grid.visible(left, up, left + Vec3::new(0.1, 0.3, 0.2), up);
        assert_eq!(beside, Some(true), "same side");
        // a plane sets the cells it passes through on its right: a point just right of it
        // starts in a set cell
        let corner = grid.visible(Vec3::new(0.51, 0.0, 0.5), up, right, up);
        assert_eq!(corner, None, "at the wall's foot");
    }

    #[test]
    fn a_walk_crosses_an_empty_brick_in_one_step() {
        for levels in [1, 2] {
            let grid = OccupancyGrid::with_levels(&floor_and_wall(0.5), 32, levels);
            // above the floor and left of the wall, through empty bricks only
            let (from, to) = (Vec3::new(0.02, 0.3, 0.4), Vec3::new(0.45, 0.4, 0.5));
            let free = grid.walk(from, Vec3::ZERO, to, Vec3::ZERO);
            assert_eq!(free.visible, Some(true), "{levels} levels");
            // a brick spans 4 cells along x and y and 2 along z
            assert!(free.steps * 2 <= free.cells, "{levels} levels: {free:?}");
            // on through the wall: blocked
            let across = grid.walk(from, Vec3::ZERO, to + Vec3::X * 0.5, Vec3::ZERO);
            assert_eq!(across.visible, Some(false), "{levels} levels");
        }
    }

    #[test]
    fn a_point_on_the_edge_of_two_surfaces_is_not_hidden_by_the_other() {
        // the wall's plane lies on a cell boundary (x = 0.5 with 32 cells) and sets the cells to
        // its right; a floor point of the right room on the edge, rounded to the wall's left,
        // starts in the free cell beside the wall's and crosses the wall's at once
        let grid = OccupancyGrid::of_triangles(&floor_and_wall(0.5), 32);
        let up = Vec3::Y;
        let edge = Vec3::new(0.5 - 1e-7, 0.0, 0.5);
        let across = Vec3::new(0.8, 0.0, 0.5);
        assert_eq!(
            grid.visible(edge, up, across, up),
            None,
            "undecided, not blocked"
        );
        // a real wall a few cells along the way still blocks
        let left = Vec3::new(0.3, 0.0, 0.5);
        assert_eq!(grid.visible(left, up, across, up), Some(false));
    }

    #[test]
    fn a_surface_does_not_hide_its_own_points_at_any_slope() {
        for deg in [0.0f32, 10.0, 33.0, 45.0, 71.0] {
            let (s, c) = deg.to_radians().sin_cos();
            // a plane through the origin, tilted about z; normal (-s, c, 0)
            let n = Vec3::new(-s, c, 0.0);
            let along = Vec3::new(c, s, 0.0);
            let t = quad([
                (-along - Vec3::Z).to_array(),
                (along - Vec3::Z).to_array(),
                (along + Vec3::Z).to_array(),
                (-along + Vec3::Z).to_array(),
            ]);
            let grid = OccupancyGrid::of_triangles(&t, 40);
            for k in -4..=4 {
                let x = along * (k as f32 * 0.1) + Vec3::Z * 0.13;
                let xp = -along * 0.3 + n * 0.5;
                assert_eq!(
                    grid.visible(x, n, xp, -n),
                    Some(true),
                    "{deg} deg, point {k}"
                );
            }
        }
    }

    #[test]
    fn no_triangles_make_a_grid_that_blocks_nothing() {
        let grid = OccupancyGrid::of_triangles(&[], 8);
        assert_eq!(grid.occupied_count(), 0);
        assert_eq!(
            grid.visible(Vec3::ZERO, Vec3::Y, Vec3::ONE, Vec3::Y),
            Some(true)
        );
    }
}
