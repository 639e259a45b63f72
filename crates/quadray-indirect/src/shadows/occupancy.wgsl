// The scene's occupancy grid walked between a receiver and a cluster (indirect shadows): the
// twin of the CPU's `OccupancyGrid::walk` (occupancy.rs), step for step and fetch for fetch.
// Accessors: `occupancy_dims() -> vec3<u32>` (zero: no grid; multiples of OCCUPANCY_BRICK),
// `occupancy_levels() -> u32` (1, or 2 with each set cell's sub-cells after the bits),
// `occupancy_origin() -> vec3<f32>`, `occupancy_cell() -> f32` and `occupancy_word(i: u32) -> u32`
// (a word a brick of OCCUPANCY_BRICK cells, brick (x, y, z) at word x + bricks.x * (y + bricks.y
// * z), its cell (x, y, z) at bit x + 4 * (y + 4 * z)).

// (OCCUPANCY_END_OFFSET, the cells a segment's ends are moved off their surfaces along the
// normals, OCCUPANCY_END_CLEARANCE, the cells from an end within which a set cell leaves the walk
// undecided, OCCUPANCY_BRICK and OCCUPANCY_SUBCELLS come from the prelude)

// A walk's reads of the grid: the last word read (its index + 1, 0 before the first; its bits),
// the held brick's first sub-cells (+ 1, 0 until read) and the last word of sub-cells read (its
// index + 1; its bits). A brick costs one fetch however many of its cells the walk crosses.
struct OccupancyHeld {
    word: u32,
    bits: u32,
    first: u32,
    sub_word: u32,
    sub_bits: u32,
}

// The walks' loop steps (a box crossed, or a word read that the next step needs), as the CPU
// twin counts them (`Walk::steps`).
var<private> walk_steps: u32;

const OUTSIDE_GRID = 0xffffffffu;

// What a step of the walk reads (`grid_visibility`).
const READ_NONE = 0u;
const READ_BRICK = 1u;
const READ_FIRST = 2u;
const READ_SUB = 3u;

// The index of the word of cell `c`'s brick (OUTSIDE_GRID outside the grid).
fn brick_word(c: vec3<i32>, d: vec3<u32>) -> u32 {
    if (any(c < vec3<i32>(0)) || any(vec3<u32>(c) >= d)) {
        return OUTSIDE_GRID;
    }
    let bricks = d / OCCUPANCY_BRICK;
    let b = vec3<u32>(c) / OCCUPANCY_BRICK;
    return b.x + bricks.x * (b.y + bricks.y * b.z);
}

// Cell `c`'s bit in its brick's word.
fn cell_bit(c: vec3<i32>) -> u32 {
    let l = vec3<u32>(c) % OCCUPANCY_BRICK;
    return l.x + OCCUPANCY_BRICK.x * (l.y + OCCUPANCY_BRICK.y * l.z);
}

// Whether cell `c` is set (outside the grid: no).
fn occupied(c: vec3<i32>, dims: vec3<u32>, held: ptr<function, OccupancyHeld>) -> bool {
    let word = brick_word(c, dims);
    if (word == OUTSIDE_GRID) {
        return false;
    }
    if ((*held).word != word + 1u) {
        fetches++;
        (*held).word = word + 1u;
        (*held).bits = occupancy_word(word);
        (*held).first = 0u;
    }
    return (((*held).bits >> cell_bit(c)) & 1u) == 1u;
}

// In a grid of two levels of `count` bricks, the sub-cells of a brick's set cells follow a word
// a brick, the index of its first set cell's, two words a set cell, sub-cell (x, y, z) in word
// z / 2 at bit x + 4 * (y + 4 * (z % 2)): the word of sub-cell `s` (sub-cell units) of the set
// cell of bit `bit` of the held brick whose first sub-cells are held, and its bit.
fn sub_word(s: vec3<i32>, bit: u32, count: u32, held: OccupancyHeld) -> u32 {
    let rank = held.first - 1u + countOneBits(held.bits & ((1u << bit) - 1u));
    return 2u * count + 2u * rank + (u32(s.z) % OCCUPANCY_SUBCELLS) / 2u;
}

fn sub_bit(s: vec3<i32>) -> u32 {
    let l = vec3<u32>(s) % OCCUPANCY_SUBCELLS;
    return l.x + 4u * (l.y + 4u * (l.z % 2u));
}

// Whether sub-cell `s` (sub-cell units) of a grid of two levels of `count` bricks is set, its
// cell being set and its cell's word held.
fn sub_occupied(s: vec3<i32>, count: u32, held: ptr<function, OccupancyHeld>) -> bool {
    let bit = cell_bit(s >> vec3<u32>(countTrailingZeros(OCCUPANCY_SUBCELLS)));
    if ((*held).first == 0u) {
        fetches++;
        (*held).first = occupancy_word(count + (*held).word - 1u) + 1u;
    }
    let word = sub_word(s, bit, count, *held);
    if ((*held).sub_word != word + 1u) {
        fetches++;
        (*held).sub_word = word + 1u;
        (*held).sub_bits = occupancy_word(word);
    }
    return (((*held).sub_bits >> sub_bit(s)) & 1u) == 1u;
}

// Whether the point `p` (grid units) lies in a set cell, and with two levels in a set sub-cell.
fn occupied_at(p: vec3<f32>, dims: vec3<u32>, count: u32, held: ptr<function, OccupancyHeld>) -> bool {
    if (!occupied(vec3<i32>(floor(p)), dims, held)) {
        return false;
    }
    return occupancy_levels() == 1u || sub_occupied(vec3<i32>(floor(p * f32(OCCUPANCY_SUBCELLS))), count, held);
}

// A segment's end in grid units, moved off its surface (an end whose normal is shorter than 0.1
// stays: a cluster of many directions).
fn occupancy_end(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let l = length(n);
    let off = select(vec3<f32>(0.0), n / max(l, 1e-6) * OCCUPANCY_END_OFFSET, l > 0.1);
    return (p - occupancy_origin()) / occupancy_cell() + off;
}

// What the grid says of a segment: it crosses no set cell, it crosses one, or it cannot tell, as
// an end (moved off its surface) lies in a set cell or within OCCUPANCY_END_CLEARANCE of one on
// the way: another surface within two or three cells of it, in a corner or under a box, where a
// depth map must judge instead.
const GRID_BLOCKED = 0u;
const GRID_VISIBLE = 1u;
const GRID_UNKNOWN = 2u;

// The segment from `x` (a receiver, normal `n`) to `xp` (a cluster, normal `np`) through the
// grid, in sub-cell units, bounded by the grid's dimensions: each step crosses the box it is in,
// an empty brick, a cell of an unset bit or a free sub-cell of a set one, to the next along the
// segment, and reads at most one word: the brick's where another is held; in a set cell of a
// grid of two levels, where the brick's sub-cells start, and the half of the cell's sub-cells
// the walk is in, each at a step of its own where not held (lavapipe runs every read in the
// loop's body at every step, taken or not: one read site instead of three took the indirect
// pass with shadows to 0.9x the time).
fn grid_visibility(x: vec3<f32>, n: vec3<f32>, xp: vec3<f32>, np: vec3<f32>) -> u32 {
    let a_cells = occupancy_end(x, n);
    let b_cells = occupancy_end(xp, np);
    let dims = occupancy_dims();
    let bricks = dims / OCCUPANCY_BRICK;
    let count = bricks.x * bricks.y * bricks.z;
    var held = OccupancyHeld(0u, 0u, 0u, 0u, 0u);
    // the end first: the walk goes on from its word
    if (occupied_at(b_cells, dims, count, &held)) {
        return GRID_UNKNOWN;
    }
    let a = a_cells * f32(OCCUPANCY_SUBCELLS);
    let d = (b_cells - a_cells) * f32(OCCUPANCY_SUBCELLS);
    let forward = d > vec3<f32>(0.0);
    let still = d == vec3<f32>(0.0);
    let inverse = 1.0 / select(d, vec3<f32>(1.0), still);
    // the segment parameter of the clearance at each end
    let clearance = OCCUPANCY_END_CLEARANCE / max(length(b_cells - a_cells), 1e-6);
    let two_levels = occupancy_levels() == 2u;
    // boxes are powers of two in sub-cells: a box's corner is its sub-cell shifted down and up
    let cell_shift = vec3<u32>(countTrailingZeros(OCCUPANCY_SUBCELLS));
    let brick_shift = countTrailingZeros(OCCUPANCY_BRICK) + cell_shift;
    // a step a sub-cell face crossed (the ends lie within two cells of the grid), and two reads
    // a cell at most
    let bound = 3u * OCCUPANCY_SUBCELLS * (dims.x + dims.y + dims.z + 6u);
    var s = vec3<i32>(floor(a));
    var entered = 0.0;
    for (var i = 0u; i < bound; i++) {
        walk_steps++;
        let c = s >> cell_shift;
        let word = brick_word(c, dims);
        let inside = word != OUTSIDE_GRID;
        let bit = cell_bit(c);
        let brick_held = inside && held.word == word + 1u;
        let in_set_cell = two_levels && brick_held && ((held.bits >> bit) & 1u) == 1u;
        let sub = sub_word(s, bit, count, held);
        var what = READ_NONE;
        var read = word;
        if (inside && !brick_held) {
            what = READ_BRICK;
        } else if (in_set_cell && held.first == 0u) {
            what = READ_FIRST;
            read = count + word;
        } else if (in_set_cell && held.sub_word != sub + 1u) {
            what = READ_SUB;
            read = sub;
        }
        if (what != READ_NONE) {
            fetches++;
            let value = occupancy_word(read);
            if (what == READ_BRICK) {
                held.word = word + 1u;
                held.bits = value;
                held.first = 0u;
            } else if (what == READ_FIRST) {
                held.first = value + 1u;
            } else {
                held.sub_word = sub + 1u;
                held.sub_bits = value;
            }
        }
        let cell_set = inside && ((held.bits >> bit) & 1u) == 1u;
        if (cell_set && two_levels && (what == READ_BRICK || what == READ_FIRST)) {
            // its sub-cells at the next step
            continue;
        }
        var shift = brick_shift;
        if (cell_set) {
            if (!two_levels || ((held.sub_bits >> sub_bit(s)) & 1u) == 1u) {
                return select(GRID_UNKNOWN, GRID_BLOCKED, clearance < entered && entered < 1.0 - clearance);
            }
            shift = vec3<u32>(0u);
        } else if (!inside || held.bits != 0u) {
            shift = cell_shift;
        }
        let lo = (s >> shift) << shift;
        let hi = lo + (vec3<i32>(1) << shift);
        let exit = select((vec3<f32>(select(lo, hi, forward)) - a) * inverse, vec3<f32>(3.0e38), still);
        let t = min(exit.x, min(exit.y, exit.z));
        if (t > 1.0) {
            // the end is in the box
            break;
        }
        // the box across the face the segment leaves by (ties: x, then y), kept beside the box
        // against rounding
        var next = clamp(vec3<i32>(floor(a + d * t)), lo, hi - vec3<i32>(1));
        let across = select(lo - vec3<i32>(1), hi, forward);
        if (exit.x <= exit.y && exit.x <= exit.z) {
            next.x = across.x;
        } else if (exit.y <= exit.z) {
            next.y = across.y;
        } else {
            next.z = across.z;
        }
        s = next;
        entered = t;
    }
    return GRID_VISIBLE;
}
