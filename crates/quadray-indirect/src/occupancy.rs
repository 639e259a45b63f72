//! The scene's occupancy grid, which indirect shadows walk between a receiver and a cluster
//! ([`crate::Settings::shadow_grid`]): a cell is set where a triangle of the scene overlaps it, so
//! a wall, a shelf or a slab blocks whatever the camera and the light see of it. The walk
//! ([`OccupancyGrid::visible`]) is the CPU twin of `wgsl/occupancy.wgsl`'s `grid_visibility`; both
//! start and end two cells off the surfaces along their normals, so that a surface never hides
//! its own points. The bits are stored a brick of [`BRICK`] cells to a word, so that a walk
//! fetches a word a brick it passes through, not a cell (an empty brick is a zero word).

use crate::scene::Vertex;
use glam::{IVec3, UVec3, Vec3};

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

/// What a walk between two points found, and the words it fetched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Walk {
    /// Visible, blocked, or `None`: a moved end lies in a set cell.
    pub visible: Option<bool>,
    /// Words fetched: one each time the walk enters a brick it has not just read.
    pub fetches: u32,
    /// Cells tested (what a grid of a word a cell would have fetched).
    pub cells: u32,
}

/// Cubic cells over a box, one bit a cell: set where a triangle overlaps the cell.
#[derive(Clone, Debug, PartialEq)]
pub struct OccupancyGrid {
    dims: UVec3,
    origin: Vec3,
    cell: f32,
    bits: Vec<u32>,
}

impl OccupancyGrid {
    /// The grid of `triangles` with `cells` cells along the longest side of their bounds, and a
    /// margin of [`END_OFFSET_CELLS`] + 1 cells all round (so a moved end stays inside).
    pub fn of_triangles(triangles: &[[Vertex; 3]], cells: u32) -> Self {
        let (lo, hi) =
            crate::scene::bounds_of(triangles.iter().flatten().map(|v| Vec3::from(v.position)));
        let (lo, hi) = if lo.cmple(hi).all() {
            (lo, hi)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        let cell = ((hi - lo).max_element() / cells.max(1) as f32).max(1e-6);
        let margin = END_OFFSET_CELLS + 1.0;
        let origin = lo - Vec3::splat(margin * cell);
        let cells = (((hi - lo) / cell).ceil() + Vec3::splat(2.0 * margin + 1.0)).as_uvec3();
        let bricks = (cells + BRICK - 1) / BRICK;
        let mut grid = Self {
            dims: bricks * BRICK,
            origin,
            cell,
            bits: vec![0; bricks.element_product() as usize],
        };
        for t in triangles {
            grid.add_triangle(t.map(|v| (Vec3::from(v.position) - origin) / cell));
        }
        grid
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

    /// Whether the segment from `x` (a receiver, normal `n`) to `xp` (a VPL or cluster, normal
    /// `np`, of any length: a cluster's mean normal is shorter) crosses no set cell, its ends
    /// moved [`END_OFFSET_CELLS`] off their surfaces (an end whose normal is shorter than 0.1
    /// stays); `None` where a moved end lies in a set cell (another surface within two cells
    /// of it: in a corner, under a box) or the walk enters a set cell within
    /// [`END_CLEARANCE_CELLS`] of an end, which the grid cannot judge. Visits the cells the
    /// segment passes through, in order (a 3D DDA).
    pub fn visible(&self, x: Vec3, n: Vec3, xp: Vec3, np: Vec3) -> Option<bool> {
        self.walk(x, n, xp, np).visible
    }

    /// [`Self::visible`] with the words the walk fetched, as the GPU's walk counts them: the
    /// word last read is kept, so a brick costs one fetch however many of its cells are crossed.
    pub fn walk(&self, x: Vec3, n: Vec3, xp: Vec3, np: Vec3) -> Walk {
        let mut reader = WordReader {
            grid: self,
            word: None,
            fetches: 0,
            cells: 0,
        };
        let visible = self.walk_cells(x, n, xp, np, &mut reader);
        Walk {
            visible,
            fetches: reader.fetches,
            cells: reader.cells,
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
        let a = self.to_grid(x, n);
        let b = self.to_grid(xp, np);
        let d = b - a;
        let mut c = a.floor().as_ivec3();
        let end = b.floor().as_ivec3();
        if reader.occupied(c) || reader.occupied(end) {
            return None;
        }
        let step = IVec3::new(sign(d.x), sign(d.y), sign(d.z));
        let t_delta = Vec3::new(inverse(d.x), inverse(d.y), inverse(d.z));
        // the segment parameter of the clearance at each end
        let clearance = END_CLEARANCE_CELLS / d.length().max(1e-6);
        let mut t_max = Vec3::new(
            first_crossing(a.x, d.x),
            first_crossing(a.y, d.y),
            first_crossing(a.z, d.z),
        );
        // a segment crosses at most one cell a face it passes: the bound of the walk
        for _ in 0..=self.dims.x + self.dims.y + self.dims.z {
            if c == end {
                break;
            }
            // the parameter where the walk enters its next cell
            let entered = t_max.min_element();
            if t_max.x <= t_max.y && t_max.x <= t_max.z {
                c.x += step.x;
                t_max.x += t_delta.x;
            } else if t_max.y <= t_max.z {
                c.y += step.y;
                t_max.y += t_delta.y;
            } else {
                c.z += step.z;
                t_max.z += t_delta.z;
            }
            if t_max.min_element() > 1.0 && c != end {
                // past the end in floating point: the end's cell is the last one
                c = end;
            }
            if reader.occupied(c) {
                return (clearance < entered && entered < 1.0 - clearance).then_some(false);
            }
        }
        Some(true)
    }

    /// The grid as the gather reads it: [`HEADER_WORDS`] words (the dimensions, a pad, the
    /// origin and the cell's side as `f32` bits), then a word a [`BRICK`], brick (x, y, z) at
    /// word `x + bricks.x * (y + bricks.y * z)`.
    pub fn gpu_words(&self) -> Vec<u32> {
        let mut words = vec![
            self.dims.x,
            self.dims.y,
            self.dims.z,
            0,
            self.origin.x.to_bits(),
            self.origin.y.to_bits(),
            self.origin.z.to_bits(),
            self.cell.to_bits(),
        ];
        words.extend_from_slice(&self.bits);
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

    /// Sets every cell the triangle (in grid units) overlaps. A cell is the half-open
    /// [i, i + 1): a plane on a cell boundary sets the cells above it only.
    fn add_triangle(&mut self, t: [Vec3; 3]) {
        if !t.iter().all(|v| v.is_finite()) {
            return;
        }
        let lo = t[0].min(t[1]).min(t[2]).floor().as_ivec3().max(IVec3::ZERO);
        let hi = t[0]
            .max(t[1])
            .max(t[2])
            .floor()
            .as_ivec3()
            .min(self.dims.as_ivec3() - 1);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let c = IVec3::new(x, y, z);
                    // the box [i - 1e-5, i + 1 - 1e-4]: a plane at i is in, one at i + 1 out
                    let centre = c.as_vec3() + Vec3::splat(0.5 - 5.5e-5);
                    if triangle_overlaps_box(t, centre, Vec3::splat(0.5 - 4.5e-5)) {
                        let (word, bit) = self.index(c).expect("clamped to the grid");
                        self.bits[word] |= 1 << bit;
                    }
                }
            }
        }
    }
}

/// A walk's reads of the grid: the last word fetched, how many were, and the cells tested.
struct WordReader<'a> {
    grid: &'a OccupancyGrid,
    word: Option<(usize, u32)>,
    fetches: u32,
    cells: u32,
}

impl WordReader<'_> {
    fn occupied(&mut self, c: IVec3) -> bool {
        self.cells += 1;
        let Some((index, bit)) = self.grid.index(c) else {
            return false;
        };
        let bits = match self.word {
            Some((held, bits)) if held == index => bits,
            _ => {
                self.fetches += 1;
                let bits = self.grid.bits[index];
                self.word = Some((index, bits));
                bits
            }
        };
        bits >> bit & 1 == 1
    }
}

fn sign(v: f32) -> i32 {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

/// The segment parameter between two crossings of an axis's cell faces (never, along an axis
/// the segment does not move).
fn inverse(d: f32) -> f32 {
    if d == 0.0 {
        f32::INFINITY
    } else {
        1.0 / d.abs()
    }
}

/// The segment parameter at which it first crosses a face of the axis, from `a` moving `d`.
fn first_crossing(a: f32, d: f32) -> f32 {
    if d > 0.0 {
        (a.floor() + 1.0 - a) / d
    } else if d < 0.0 {
        (a - a.floor()) / -d
    } else {
        f32::INFINITY
    }
}

/// Whether triangle `t` overlaps the box of `centre` and `half` extents (the separating-axis
/// test of Akenine-Möller: the box's axes, the triangle's normal, and the nine cross products
/// of their edges).
fn triangle_overlaps_box(t: [Vec3; 3], centre: Vec3, half: Vec3) -> bool {
    let v = t.map(|p| p - centre);
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separates = |axis: Vec3| {
        if axis.length_squared() < 1e-12 {
            return false;
        }
        let p = v.map(|p| p.dot(axis));
        let r = half.dot(axis.abs());
        p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
    };
    for e in edges {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            if separates(axis.cross(e)) {
                return false;
            }
        }
    }
    if [Vec3::X, Vec3::Y, Vec3::Z].into_iter().any(separates) {
        return false;
    }
    !separates(edges[0].cross(edges[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(corners: [[f32; 3]; 4]) -> [[Vertex; 3]; 2] {
        let v = corners.map(|position| Vertex {
            position,
            normal: [0.0, 0.0, 1.0],
            albedo: [0.5; 3],
        });
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
