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
//! the cells in empty space. The walk is in `occupancy/walk.rs`; which cells and sub-cells a
//! triangle overlaps, in `occupancy/triangle_box.rs`.

use crate::scene::Vertex;
use glam::{IVec3, UVec3, Vec3};
use std::collections::HashMap;
use triangle_box::{TriangleBoxTest, count_subcells, floor};

mod triangle_box;
mod walk;

pub use walk::Walk;

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

    /// The grid as the gather reads it: [`HEADER_WORDS`] words (the dimensions, the levels, the
    /// origin and the cell's side as `f32` bits), then a word a [`BRICK`], brick (x, y, z) at
    /// word `x + bricks.x * (y + bricks.y * z)`; with two levels then a word a brick, the index
    /// of its first set cell's sub-cells, and [`MASK_WORDS`] words a set cell, its sub-cell
    /// (x, y, z) in word `z / 2` at bit `x + 4 * (y + 4 * (z % 2))`.
    pub fn gpu_words(&self) -> Vec<u32> {
        let (header, parts) = self.gpu_word_parts();
        let mut words = header.to_vec();
        for part in parts {
            words.extend_from_slice(part);
        }
        words
    }

    /// [`Self::gpu_words`] in its parts, in order, without copying them into one: the header,
    /// the bricks' bits, and with two levels the bricks' first sub-cells and the masks (empty
    /// with one level).
    pub fn gpu_word_parts(&self) -> ([u32; HEADER_WORDS], [&[u32]; 3]) {
        let header = [
            self.dims.x,
            self.dims.y,
            self.dims.z,
            if self.sub.is_some() { 2 } else { 1 },
            self.origin.x.to_bits(),
            self.origin.y.to_bits(),
            self.origin.z.to_bits(),
            self.cell.to_bits(),
        ];
        let (first, masks) = self
            .sub
            .as_ref()
            .map_or((&[][..], &[][..]), |sub| (&sub.first[..], &sub.masks[..]));
        (header, [&self.bits, first, masks])
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

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn quad(corners: [[f32; 3]; 4]) -> [[Vertex; 3]; 2] {
        let v = corners.map(|position| Vertex::untextured(position, [0.0, 0.0, 1.0], [0.5; 3]));
        [[v[0], v[1], v[2]], [v[0], v[2], v[3]]]
    }

    /// A floor (y = 0, 0..1 in x and z) and a thin wall at x = 0.5 up to `wall_top`.
    pub(super) fn floor_and_wall(wall_top: f32) -> Vec<[Vertex; 3]> {
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
}
