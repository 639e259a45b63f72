//! The scene's occupancy grid, which indirect shadows walk between a receiver and a cluster
//! ([`crate::Settings::shadow_grid`]): a cell is set where a triangle of the scene overlaps it, so
//! a wall, a shelf or a slab blocks whatever the camera and the light see of it. The walk
//! ([`OccupancyGrid::visible`]) is the CPU twin of `occupancy.wgsl`'s `grid_visibility`; both
//! start and end two cells off the surfaces along their normals, so that a surface never hides
//! its own points. The bits are stored a brick of [`BRICK`] cells to a word, so that a walk
//! fetches a word a brick it passes through, not a cell (an empty brick is a zero word). A grid
//! of two levels ([`OccupancyGrid::two_level`]) also holds, for each set cell, which of its
//! [`SUBCELLS`]^3 sub-cells a triangle overlaps: the walk crosses the set cells sub-cell by
//! sub-cell, so an opening is narrowed by a sub-cell, not a cell, on each side, at the cost of
//! the cells in empty space.

use crate::scene::Vertex;
use glam::{IVec3, UVec3, Vec3};
use std::collections::HashMap;
use triangle_box::{TriangleBoxTest, count_subcells, floor};

mod triangle_box;

/// Cells a segment's ends are moved off their surfaces along the normals: past every cell a
/// plane through the end may overlap (a cell's diagonal is sqrt(3) sides).
pub const END_OFFSET_CELLS: f32 = 2.0;

/// A set cell the walk enters within this many cells of either (moved) end makes the walk
/// undecided, as an end lying on another surface's plane does: a receiver on the edge where a
/// wall meets the ceiling, moved off the ceiling, lies in the wall's plane (on a cell boundary,
/// rounded to the free side), and would otherwise see the wall block everything. A margin for
/// rounding only: half a cell lowered the leak scene's gain with the one cut from 8.5x to 7.1x,
/// as more walks fell back on the depth maps.
pub const END_CLEARANCE_CELLS: f32 = 0.05;

/// Words before the bits in [`OccupancyGrid::gpu_words`]: the dimensions (and a pad), the origin
/// and the cell's side.
pub const HEADER_WORDS: usize = 8;

/// The cells of a brick, one word of bits: cell (x, y, z) of a brick at bit `x + 4 * (y + 4 * z)`.
/// The grid's dimensions are multiples of it.
pub const BRICK: UVec3 = UVec3::new(4, 4, 2);

/// Sub-cells along each side of a set cell in a grid of two levels: a cell's 4x4x4 sub-cells
/// take two words, each a brick of 4x4x2 ([`BRICK`]) sub-cells.
pub const SUBCELLS: u32 = 4;

/// Words a set cell's sub-cells take in a grid of two levels.
pub const MASK_WORDS: usize = 2;

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

/// Cubic cells over a box, one bit a cell: set where a triangle overlaps the cell; in a grid of
/// two levels, with the same for the [`SUBCELLS`]^3 sub-cells of each set cell. The grid counts
/// the triangles over each set cell (each set sub-cell), so that triangles are added and
/// removed ([`Self::add`], [`Self::remove`]) at a cost in proportion to them, and a grid so
/// updated equals the one made from its triangles at once over the same bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct OccupancyGrid {
    dims: UVec3,
    origin: Vec3,
    cell: f32,
    /// The bounds the grid was made over (its margin around them).
    bounds: (Vec3, Vec3),
    bits: Vec<u32>,
    /// Two levels: per brick, the index of the sub-cells of its first set cell (the set cells
    /// before it counted); then [`MASK_WORDS`] a set cell, in the order of the bricks and bits.
    sub: Option<SubCells>,
    counts: Counts,
}

/// What [`OccupancyGrid::add_tracked`] counted: per cell (by its bit index) its count and, with
/// two levels, per sub-cell (its bit in the cell's masks), how many of the triangles overlap it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Footprint {
    /// The cells, in the order the triangles first overlapped them.
    cells: Vec<usize>,
    /// [`Self::per_cell`] counts a cell, in the order of `cells`.
    counts: Vec<u32>,
    /// Counts a cell: one (one level) or [`SUBCELL_COUNT`] (two).
    per_cell: usize,
}

/// A [`Footprint`] being counted: where each cell's counts are, and the cell last counted in
/// (a mesh's next triangle is most often in its last one's cell).
struct Tally {
    footprint: Footprint,
    slots: HashMap<usize, usize, CellHash>,
    last: Option<(usize, usize)>,
}

impl Tally {
    fn new(per_cell: usize) -> Self {
        Self {
            footprint: Footprint {
                per_cell,
                ..Footprint::default()
            },
            slots: HashMap::default(),
            last: None,
        }
    }

    /// The counts of cell `index` (zeros where it was not counted in yet).
    fn cell(&mut self, index: usize) -> &mut [u32] {
        let slot = match self.last {
            Some((cell, slot)) if cell == index => slot,
            _ => {
                let f = &mut self.footprint;
                let slot = *self.slots.entry(index).or_insert_with(|| {
                    f.cells.push(index);
                    f.counts.resize(f.counts.len() + f.per_cell, 0);
                    f.cells.len() - 1
                });
                self.last = Some((index, slot));
                slot
            }
        };
        let n = self.footprint.per_cell;
        &mut self.footprint.counts[slot * n..(slot + 1) * n]
    }
}

#[derive(Clone, Debug, PartialEq)]
struct SubCells {
    first: Vec<u32>,
    masks: Vec<u32>,
}

/// The triangles over each set cell (by its bit index, `word * 32 + bit`): one level, a count a
/// cell; two levels, a count a sub-cell (at its bit in the cell's masks, `word * 32 + bit`).
#[derive(Clone, Debug, PartialEq)]
enum Counts {
    Cells(HashMap<usize, u32, CellHash>),
    SubCells(HashMap<usize, [u32; SUBCELL_COUNT], CellHash>),
}

/// Hashes a cell's index by one multiplication (the default hasher's cost was most of an
/// update's): the indices are the grid's own, not an adversary's.
type CellHash = std::hash::BuildHasherDefault<CellHasher>;

#[derive(Default)]
struct CellHasher(u64);

impl std::hash::Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn write_usize(&mut self, i: usize) {
        // Fibonacci hashing: the high bits, which hashbrown takes, mixed from every bit
        self.0 = (i as u64 ^ self.0).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

/// Sub-cells of a cell.
const SUBCELL_COUNT: usize = MASK_WORDS * 32;

/// Cells an update sets or clears before the sub-cells' words are compacted anew once at its
/// end rather than moved at each (a move costs a word a brick and the masks after the cell).
const FOLLOWED_FLIPS: usize = 256;

impl OccupancyGrid {
    /// The grid of `triangles` with `cells` cells along the longest side of their bounds, and a
    /// margin of [`END_OFFSET_CELLS`] + 1 cells all round (so a moved end stays inside).
    pub fn of_triangles(triangles: &[[Vertex; 3]], cells: u32) -> Self {
        Self::with_levels(triangles, cells, 1)
    }

    /// [`Self::of_triangles`] (`levels` 1) or [`Self::two_level`] (more):
    /// [`crate::Settings::shadow_grid_levels`].
    pub fn with_levels(triangles: &[[Vertex; 3]], cells: u32, levels: u32) -> Self {
        let bounds =
            crate::scene::bounds_of(triangles.iter().flatten().map(|v| Vec3::from(v.position)));
        let mut grid = Self::empty(bounds, cells, levels);
        grid.add(triangles);
        grid
    }

    /// [`Self::of_triangles`] with each set cell's [`SUBCELLS`]^3 sub-cells: a cell stays set
    /// where a triangle overlaps one of its sub-cells. Takes a word a brick and [`MASK_WORDS`]
    /// words a set cell beyond the grid's bits ([`crate::Settings::MAX_TWO_LEVEL_SHADOW_GRID`]
    /// bounds it).
    pub fn two_level(triangles: &[[Vertex; 3]], cells: u32) -> Self {
        Self::with_levels(triangles, cells, 2)
    }

    /// A grid with no triangle yet over `bounds` (min, max; empty bounds, min above max, as a
    /// point at the origin), `cells` cells along their longest side and `levels` levels, as
    /// [`Self::with_levels`] makes for triangles of those bounds.
    pub fn empty(bounds: (Vec3, Vec3), cells: u32, levels: u32) -> Self {
        let (lo, hi) = if bounds.0.cmple(bounds.1).all() {
            bounds
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        let cell = ((hi - lo).max_element() / cells.max(1) as f32).max(1e-6);
        let margin = END_OFFSET_CELLS + 1.0;
        let origin = lo - Vec3::splat(margin * cell);
        let cells = (((hi - lo) / cell).ceil() + Vec3::splat(2.0 * margin + 1.0)).as_uvec3();
        let bricks = (cells + BRICK - 1) / BRICK;
        let two_levels = levels > 1;
        let brick_count = bricks.element_product() as usize;
        Self {
            dims: bricks * BRICK,
            origin,
            cell,
            bounds: (lo, hi),
            bits: vec![0; brick_count],
            sub: two_levels.then(|| SubCells {
                first: vec![0; brick_count],
                masks: Vec::new(),
            }),
            counts: if two_levels {
                Counts::SubCells(HashMap::default())
            } else {
                Counts::Cells(HashMap::default())
            },
        }
    }

    /// The bounds the grid was made over: triangles within them are in the grid, with its
    /// margin around them.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Adds `triangles`: sets the cells (and sub-cells) they overlap.
    pub fn add(&mut self, triangles: &[[Vertex; 3]]) {
        self.update(triangles, true);
    }

    /// Removes `triangles`, added before ([`Self::add`] or the constructors) to this grid: a
    /// cell (a sub-cell) no other triangle overlaps is cleared.
    pub fn remove(&mut self, triangles: &[[Vertex; 3]]) {
        self.update(triangles, false);
    }

    /// Adds `triangles` as [`Self::add`] does, and returns what they counted in each cell (each
    /// sub-cell), so that [`Self::remove_footprint`] takes them out again without testing them
    /// against the cells anew: an object that moves costs its new triangles' tests alone.
    pub fn add_tracked(&mut self, triangles: &[[Vertex; 3]]) -> Footprint {
        let footprint = self.tally(triangles);
        self.count(&footprint, true);
        footprint
    }

    /// Takes out of this grid the triangles [`Self::add_tracked`] added to it and returned
    /// `footprint` for: a cell (a sub-cell) no other triangle overlaps is cleared, as
    /// [`Self::remove`] of those triangles would.
    pub fn remove_footprint(&mut self, footprint: &Footprint) {
        self.count(footprint, false);
    }

    /// Counts `triangles` in or out, and sets and clears the cells that gained their first or
    /// lost their last triangle.
    fn update(&mut self, triangles: &[[Vertex; 3]], added: bool) {
        let footprint = self.tally(triangles);
        self.count(&footprint, added);
    }

    /// What `triangles` count in each cell and sub-cell they overlap.
    fn tally(&self, triangles: &[[Vertex; 3]]) -> Footprint {
        let per_cell = match self.counts {
            Counts::Cells(_) => 1,
            Counts::SubCells(_) => SUBCELL_COUNT,
        };
        let mut tally = Tally::new(per_cell);
        let to_grid = |v: &Vertex| (Vec3::from(v.position) - self.origin) / self.cell;
        for t in triangles {
            self.tally_triangle([to_grid(&t[0]), to_grid(&t[1]), to_grid(&t[2])], &mut tally);
        }
        tally.footprint
    }

    /// Counts `footprint` in (`added`) or out, cell by cell, and sets and clears the cells
    /// that gained their first or lost their last triangle. The sub-cells' words follow each
    /// change (a set cell's words inserted at its place, the bricks after it moved on by one)
    /// while few cells are set or cleared; past [`FOLLOWED_FLIPS`] they are compacted anew
    /// once, at the end.
    fn count(&mut self, footprint: &Footprint, added: bool) {
        let mut flips = 0;
        // (a default footprint has no cells and no counts a cell)
        let per_cell = footprint.per_cell.max(1);
        for (&index, n) in footprint
            .cells
            .iter()
            .zip(footprint.counts.chunks_exact(per_cell))
        {
            // (a cell a triangle overlapped in none of its sub-cells is as it was)
            if n.iter().all(|&n| n == 0) {
                continue;
            }
            let (word, bit) = (index / 32, (index % 32) as u32);
            let step = |count: u32, n: u32| {
                if added {
                    count + n
                } else {
                    count.saturating_sub(n)
                }
            };
            let (set, masks_changed) = match &mut self.counts {
                Counts::Cells(counts) => {
                    let count = counts.entry(index).or_insert(0);
                    *count = step(*count, n[0]);
                    (*count > 0, false)
                }
                Counts::SubCells(counts) => {
                    let cell = counts.entry(index).or_insert([0; SUBCELL_COUNT]);
                    let mut changed = false;
                    for (count, &n) in cell.iter_mut().zip(n).filter(|(_, n)| **n > 0) {
                        let was = *count > 0;
                        *count = step(*count, n);
                        changed |= was != (*count > 0);
                    }
                    let set = still_set(cell, changed, self.bits[word] >> bit & 1 == 1);
                    (set, changed)
                }
            };
            if !set {
                self.forget(index);
            }
            self.follow(index, set, masks_changed, &mut flips);
        }
        if flips > FOLLOWED_FLIPS {
            self.compact();
        }
    }

    /// Sets or clears cell `index`'s bit to `set` and, while `flips` (the cells set or cleared
    /// so far) is at most [`FOLLOWED_FLIPS`], the sub-cells' words with it (its masks anew where
    /// `masks_changed`).
    fn follow(&mut self, index: usize, set: bool, masks_changed: bool, flips: &mut usize) {
        let (word, bit) = (index / 32, (index % 32) as u32);
        if set != (self.bits[word] >> bit & 1 == 1) {
            self.bits[word] ^= 1 << bit;
            *flips += 1;
            if *flips <= FOLLOWED_FLIPS {
                self.follow_flip(word, bit, set);
            }
        } else if set && masks_changed && *flips <= FOLLOWED_FLIPS {
            self.follow_masks(word, bit);
        }
    }

    /// Drops cell `index`'s counts (no triangle over it any more).
    fn forget(&mut self, index: usize) {
        match &mut self.counts {
            Counts::Cells(counts) => counts.remove(&index).map(|_| ()),
            Counts::SubCells(counts) => counts.remove(&index).map(|_| ()),
        };
    }

    /// A set cell's place among the set cells (its words in the sub-cells' masks).
    fn rank(&self, sub: &SubCells, word: usize, bit: u32) -> usize {
        (sub.first[word] + (self.bits[word] & ((1u32 << bit) - 1)).count_ones()) as usize
    }

    /// The sub-cells' words after cell (`word`, `bit`) was set (its masks inserted) or cleared.
    fn follow_flip(&mut self, word: usize, bit: u32, set: bool) {
        let (Some(mut sub), Counts::SubCells(counts)) = (self.sub.take(), &self.counts) else {
            return;
        };
        let at = self.rank(&sub, word, bit) * MASK_WORDS;
        if set {
            let masks = masks_of(&counts[&(word * 32 + bit as usize)]);
            sub.masks.splice(at..at, masks);
            sub.first[word + 1..].iter_mut().for_each(|f| *f += 1);
        } else {
            sub.masks.drain(at..at + MASK_WORDS);
            sub.first[word + 1..].iter_mut().for_each(|f| *f -= 1);
        }
        self.sub = Some(sub);
    }

    /// The masks of set cell (`word`, `bit`) from its counts.
    fn follow_masks(&mut self, word: usize, bit: u32) {
        let (Some(mut sub), Counts::SubCells(counts)) = (self.sub.take(), &self.counts) else {
            return;
        };
        let at = self.rank(&sub, word, bit) * MASK_WORDS;
        sub.masks[at..at + MASK_WORDS]
            .copy_from_slice(&masks_of(&counts[&(word * 32 + bit as usize)]));
        self.sub = Some(sub);
    }

    /// The sub-cells' words anew from the set cells' counts.
    fn compact(&mut self) {
        let (Some(sub), Counts::SubCells(counts)) = (&mut self.sub, &self.counts) else {
            return;
        };
        let mut count = 0;
        sub.masks.clear();
        for (word, &w) in self.bits.iter().enumerate() {
            sub.first[word] = count;
            count += w.count_ones();
            let mut rest = w;
            while rest != 0 {
                let bit = rest.trailing_zeros();
                rest &= rest - 1;
                sub.masks
                    .extend(masks_of(&counts[&(word * 32 + bit as usize)]));
            }
        }
    }

    /// Whether the grid has two levels ([`Self::two_level`]).
    pub fn is_two_level(&self) -> bool {
        self.sub.is_some()
    }

    /// Cells along x, y and z.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// The side of a cell (world units).
    pub fn cell(&self) -> f32 {
        self.cell
    }

    /// Whether cell `c` holds a piece of a triangle (outside the grid: no).
    pub fn occupied(&self, c: IVec3) -> bool {
        self.index(c)
            .is_some_and(|(word, bit)| self.bits[word] >> bit & 1 == 1)
    }

    /// How many cells are set.
    pub fn occupied_count(&self) -> u32 {
        self.bits.iter().map(|w| w.count_ones()).sum()
    }

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

    /// The grid as the gather reads it: [`HEADER_WORDS`] words (the dimensions, the levels, the
    /// origin and the cell's side as `f32` bits), then a word a [`BRICK`], brick (x, y, z) at
    /// word `x + bricks.x * (y + bricks.y * z)`; with two levels then a word a brick, the index
    /// of its first set cell's sub-cells, and [`MASK_WORDS`] words a set cell, its sub-cell
    /// (x, y, z) in word `z / 2` at bit `x + 4 * (y + 4 * (z % 2))`.
    pub fn gpu_words(&self) -> Vec<u32> {
        let mut words = vec![
            self.dims.x,
            self.dims.y,
            self.dims.z,
            if self.sub.is_some() { 2 } else { 1 },
            self.origin.x.to_bits(),
            self.origin.y.to_bits(),
            self.origin.z.to_bits(),
            self.cell.to_bits(),
        ];
        words.extend_from_slice(&self.bits);
        if let Some(sub) = &self.sub {
            words.extend_from_slice(&sub.first);
            words.extend_from_slice(&sub.masks);
        }
        words
    }

    /// A segment's end in grid units, moved off its surface.
    fn to_grid(&self, p: Vec3, n: Vec3) -> Vec3 {
        let off = if n.length() > 0.1 {
            n.normalize() * END_OFFSET_CELLS
        } else {
            Vec3::ZERO
        };
        (p - self.origin) / self.cell + off
    }

    /// Cell `c`'s word and bit (outside the grid: none).
    fn index(&self, c: IVec3) -> Option<(usize, u32)> {
        if c.cmplt(IVec3::ZERO).any() || c.cmpge(self.dims.as_ivec3()).any() {
            return None;
        }
        let (c, bricks) = (c.as_uvec3(), self.dims / BRICK);
        let (b, l) = (c / BRICK, c % BRICK);
        let word = b.x + bricks.x * (b.y + bricks.y * b.z);
        Some((word as usize, l.x + BRICK.x * (l.y + BRICK.y * l.z)))
    }

    /// Counts the triangle (in grid units) in `tally`'s every cell it overlaps (with two
    /// levels, in every sub-cell of those).
    fn tally_triangle(&self, t: [Vec3; 3], tally: &mut Tally) {
        if !t.iter().all(|v| v.is_finite()) {
            return;
        }
        let test = TriangleBoxTest::new(t);
        let lo = floor(t[0].min(t[1]).min(t[2])).max(IVec3::ZERO);
        let hi = floor(t[0].max(t[1]).max(t[2])).min(self.dims.as_ivec3() - 1);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let c = IVec3::new(x, y, z);
                    // the box [i - 1e-5, i + 1 - 1e-4]: a plane at i is in, one at i + 1 out
                    let centre = c.as_vec3() + Vec3::splat(0.5 - 5.5e-5);
                    if !test.overlaps(centre, Vec3::splat(0.5 - 4.5e-5)) {
                        continue;
                    }
                    let (word, bit) = self.index(c).expect("clamped to the grid");
                    let counts = tally.cell(word * 32 + bit as usize);
                    if self.sub.is_some() {
                        count_subcells(&test, c, counts);
                    } else {
                        counts[0] += 1;
                    }
                }
            }
        }
    }
}

/// Whether a cell of two levels is set after its sub-cells' counts changed: where no sub-cell
/// was set or cleared (`changed`), the cell is as it `was`.
fn still_set(cell: &[u32; SUBCELL_COUNT], changed: bool, was: bool) -> bool {
    if changed {
        cell.iter().any(|&n| n > 0)
    } else {
        was
    }
}

/// A set cell's [`MASK_WORDS`] words of sub-cells from its counts.
fn masks_of(counts: &[u32; SUBCELL_COUNT]) -> [u32; MASK_WORDS] {
    std::array::from_fn(|w| {
        (0..32).fold(0, |mask, b| mask | (u32::from(counts[w * 32 + b] > 0) << b))
    })
}

/// Sub-cell `l` (0..[`SUBCELLS`] each) of a cell: its word among the cell's [`MASK_WORDS`], and
/// its bit.
fn sub_bit(l: UVec3) -> (usize, u32) {
    ((l.z / 2) as usize, l.x + 4 * (l.y + 4 * (l.z % 2)))
}

/// Sub-cell `s`'s place in its cell (0..[`SUBCELLS`] each).
fn sub_cell(s: IVec3) -> UVec3 {
    s.rem_euclid(IVec3::splat(SUBCELLS as i32)).as_uvec3()
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
    use super::*;

    fn quad(corners: [[f32; 3]; 4]) -> [[Vertex; 3]; 2] {
        let v = corners.map(|position| Vertex::untextured(position, [0.0, 0.0, 1.0], [0.5; 3]));
        [[v[0], v[1], v[2]], [v[0], v[2], v[3]]]
    }

    /// A floor (y = 0, 0..1 in x and z) and a thin wall at x = 0.5 up to `wall_top`.
    fn floor_and_wall(wall_top: f32) -> Vec<[Vertex; 3]> {
        let mut t = quad([
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
        ])
        .to_vec();
        t.extend(quad([
            [0.5, 0.0, 0.0],
            [0.5, wall_top, 0.0],
            [0.5, wall_top, 1.0],
            [0.5, 0.0, 1.0],
        ]));
        t
    }

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
    fn grid_words_hold_the_header_and_every_set_cell() {
        let grid = OccupancyGrid::of_triangles(&floor_and_wall(0.5), 16);
        let words = grid.gpu_words();
        assert_eq!(&words[..3], &grid.dims().to_array());
        assert_eq!(f32::from_bits(words[7]), grid.cell());
        let set: u32 = words[HEADER_WORDS..].iter().map(|w| w.count_ones()).sum();
        assert_eq!(set, grid.occupied_count());
        assert!(set > 16 * 16, "the floor alone covers 16 x 16 cells: {set}");
    }

    /// A wall at x = 0.5 over the whole unit square with a slit 0.04 wide at z = 0.5, standing
    /// on a floor: narrower than a cell pair at 32 cells, four sub-cells wide.
    fn wall_with_a_slit() -> Vec<[Vertex; 3]> {
        let mut t = floor_and_wall(0.0)[..2].to_vec();
        for (z0, z1) in [(0.0, 0.48), (0.52, 1.0)] {
            t.extend(quad([
                [0.5, 0.0, z0],
                [0.5, 1.0, z0],
                [0.5, 1.0, z1],
                [0.5, 0.0, z1],
            ]));
        }
        t
    }

    #[test]
    fn two_levels_keep_a_slit_open_that_one_level_closes() {
        let t = wall_with_a_slit();
        let (one, two) = (
            OccupancyGrid::of_triangles(&t, 32),
            OccupancyGrid::two_level(&t, 32),
        );
        let up = Vec3::Y;
        let at = |z: f32, x: f32| Vec3::new(x, 0.3, z);
        // through the slit and through the wall beside it
        let slit = (at(0.5, 0.2), at(0.5, 0.8));
        let wall = (at(0.3, 0.2), at(0.3, 0.8));
        assert_eq!(
            one.visible(slit.0, up, slit.1, up),
            Some(false),
            "closed at one level"
        );
        assert_eq!(
            two.visible(slit.0, up, slit.1, up),
            Some(true),
            "open at two"
        );
        assert_eq!(
            two.visible(wall.0, up, wall.1, up),
            Some(false),
            "the wall blocks"
        );
        // a plane on a sub-cell's face sets the sub-cells above it only: the slit's edges at
        // z = 0.48 and 0.52 (sub-cells 61.44 and 66.56) leave sub-cells 62 to 65 free
        let column = |z: i32| two.subcell_occupied(IVec3::new(64 + 12, 40, z + 12));
        let free: Vec<i32> = (58..70).filter(|&z| !column(z)).collect();
        assert_eq!(free, vec![62, 63, 64, 65], "sub-cells of the slit");
        // the same set cells (each with a set sub-cell), two more words each
        assert_eq!(two.occupied_count(), one.occupied_count());
        let extra = two.gpu_words().len() - one.gpu_words().len();
        assert_eq!(
            extra,
            one.bits.len() + MASK_WORDS * one.occupied_count() as usize
        );
        // in empty space the walk costs what one level's does; it crosses the wall's set
        // cells sub-cell by sub-cell, fetching their words
        let left = (Vec3::new(0.1, 0.5, 0.2), Vec3::new(0.4, 0.6, 0.8));
        let (a, b) = (
            one.walk(left.0, up, left.1, up),
            two.walk(left.0, up, left.1, up),
        );
        assert_eq!((a.visible, b.visible), (Some(true), Some(true)));
        assert_eq!(a.fetches, b.fetches, "empty space");
        let (a, b) = (
            one.walk(slit.0, up, slit.1, up),
            two.walk(slit.0, up, slit.1, up),
        );
        assert!(b.fetches > a.fetches && b.cells > a.cells, "{a:?} {b:?}");
    }

    /// A small upright quad standing on the floor at `x` (sharing the floor's cells at its
    /// foot).
    fn post_at(x: f32) -> [[Vertex; 3]; 2] {
        quad([[x, 0.0, 0.2], [x, 0.3, 0.2], [x, 0.3, 0.4], [x, 0.0, 0.4]])
    }

    #[test]
    fn an_updated_grid_equals_the_grid_made_at_once() {
        for levels in [1, 2] {
            let scene = wall_with_a_slit();
            let (before, after) = (post_at(0.23), post_at(0.71));
            let with = |post: &[[Vertex; 3]; 2]| [scene.as_slice(), post].concat();
            let mut grid = OccupancyGrid::with_levels(&with(&before), 32, levels);
            let old = grid.gpu_words();
            grid.remove(&before);
            grid.add(&after);
            // the post's moves keep within the scene's bounds, so both grids have the same
            let at_once = OccupancyGrid::with_levels(&with(&after), 32, levels);
            assert_eq!(grid.bounds(), at_once.bounds(), "{levels} levels");
            assert_eq!(grid.gpu_words(), at_once.gpu_words(), "{levels} levels");
            // (not assert_eq: a grid's debug text is long)
            assert!(grid == at_once, "{levels} levels: the counts too");
            assert_ne!(grid.gpu_words(), old, "{levels} levels: the post moved");
            // a sub-cell's mask changing in a cell that stays set (the floor's, at the post's
            // foot) and cells set anew both happened: back again gives the first grid
            grid.remove(&after);
            grid.add(&before);
            assert_eq!(grid.gpu_words(), old, "{levels} levels");
            // a chip just above the floor, in the floor's cells: sub-cells set, no cell
            let chip = [[0.1, 0.02, 0.1], [0.15, 0.02, 0.1], [0.1, 0.02, 0.15]]
                .map(|position| Vertex::untextured(position, [0.0, 1.0, 0.0], [0.5; 3]));
            let cells = grid.occupied_count();
            grid.add(&[chip]);
            assert_eq!(grid.occupied_count(), cells, "{levels} levels: no cell set");
            let mut with_chip = with(&before);
            with_chip.push(chip);
            let chipped = OccupancyGrid::with_levels(&with_chip, 32, levels);
            assert!(grid == chipped, "{levels} levels");
            assert_eq!(grid.gpu_words() == old, levels == 1, "{levels} levels");
            grid.remove(&[chip]);
            assert_eq!(grid.gpu_words(), old, "{levels} levels");
            // the floor under the post stays set when the post leaves
            grid.remove(&before);
            let foot = grid.to_grid(Vec3::new(0.23, 0.01, 0.3), Vec3::ZERO);
            assert!(grid.occupied(foot.floor().as_ivec3()), "{levels} levels");
            grid.remove(&scene);
            assert_eq!(grid.occupied_count(), 0, "{levels} levels");
            let empty = OccupancyGrid::empty(at_once.bounds(), 32, levels);
            assert!(grid == empty, "{levels} levels");
            // the post taken out by its footprint, not its triangles: the same grids
            let mut tracked = empty.clone();
            tracked.add(&scene);
            let footprint = tracked.add_tracked(&before);
            let mut removed = tracked.clone();
            removed.remove(&before);
            tracked.remove_footprint(&footprint);
            assert!(tracked == removed, "{levels} levels: out by its footprint");
            let footprint = tracked.add_tracked(&after);
            assert!(tracked == at_once, "{levels} levels: in again");
            tracked.remove_footprint(&footprint);
            tracked.add(&before);
            assert_eq!(tracked.gpu_words(), old, "{levels} levels: back");
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
