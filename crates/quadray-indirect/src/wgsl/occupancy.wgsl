// The scene's occupancy grid walked between a receiver and a cluster (indirect shadows): the
// twin of the CPU's `OccupancyGrid::walk` (src/occupancy.rs), step for step and fetch for fetch.
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

// The walks' loop steps (a cell, a sub-cell, or an empty brick crossed in one step), as the CPU
// twin counts them (`Walk::steps`).
var<private> walk_steps: u32;

const OUTSIDE_GRID = 0xffffffffu;

// The index of the word of cell `c`'s brick (OUTSIDE_GRID outside the grid).
fn brick_word(c: vec3<i32>) -> u32 {
    let d = occupancy_dims();
    if (any(c < vec3<i32>(0)) || any(vec3<u32>(c) >= d)) {
        return OUTSIDE_GRID;
    }
    let bricks = d / OCCUPANCY_BRICK;
    let b = vec3<u32>(c) / OCCUPANCY_BRICK;
    return b.x + bricks.x * (b.y + bricks.y * b.z);
}

// Whether the walk holds cell `c`'s brick's word and it is zero: no cell of the brick is set.
fn in_empty_brick(c: vec3<i32>, held: OccupancyHeld) -> bool {
    let word = brick_word(c);
    return word != OUTSIDE_GRID && held.word == word + 1u && held.bits == 0u;
}

// Whether cell `c` is set (outside the grid: no).
fn occupied(c: vec3<i32>, held: ptr<function, OccupancyHeld>) -> bool {
    let word = brick_word(c);
    if (word == OUTSIDE_GRID) {
        return false;
    }
    let l = vec3<u32>(c) % OCCUPANCY_BRICK;
    if ((*held).word != word + 1u) {
        fetches++;
        (*held).word = word + 1u;
        (*held).bits = occupancy_word(word);
        (*held).first = 0u;
    }
    let bit = l.x + OCCUPANCY_BRICK.x * (l.y + OCCUPANCY_BRICK.y * l.z);
    return (((*held).bits >> bit) & 1u) == 1u;
}

// Whether sub-cell `s` (sub-cell units) of a grid of two levels is set, its cell being set and
// its cell's word held: the sub-cells of a brick's set cells follow a word a brick, the index of
// its first set cell's, two words a set cell, sub-cell (x, y, z) in word z / 2 at bit
// x + 4 * (y + 4 * (z % 2)).
fn sub_occupied(s: vec3<i32>, held: ptr<function, OccupancyHeld>) -> bool {
    let bricks = occupancy_dims() / OCCUPANCY_BRICK;
    let count = bricks.x * bricks.y * bricks.z;
    let c = vec3<u32>(s) / OCCUPANCY_SUBCELLS;
    let l = vec3<u32>(s) % OCCUPANCY_SUBCELLS;
    if ((*held).first == 0u) {
        fetches++;
        (*held).first = occupancy_word(count + (*held).word - 1u) + 1u;
    }
    let lc = c % OCCUPANCY_BRICK;
    let bit = lc.x + OCCUPANCY_BRICK.x * (lc.y + OCCUPANCY_BRICK.y * lc.z);
    let rank = (*held).first - 1u + countOneBits((*held).bits & ((1u << bit) - 1u));
    let word = 2u * count + 2u * rank + l.z / 2u;
    if ((*held).sub_word != word + 1u) {
        fetches++;
        (*held).sub_word = word + 1u;
        (*held).sub_bits = occupancy_word(word);
    }
    let b = l.x + 4u * (l.y + 4u * (l.z % 2u));
    return (((*held).sub_bits >> b) & 1u) == 1u;
}

// Whether the point `p` (grid units) lies in a set cell, and with two levels in a set sub-cell.
fn occupied_at(p: vec3<f32>, held: ptr<function, OccupancyHeld>) -> bool {
    if (!occupied(vec3<i32>(floor(p)), held)) {
        return false;
    }
    return occupancy_levels() == 1u || sub_occupied(vec3<i32>(floor(p * f32(OCCUPANCY_SUBCELLS))), held);
}

// A segment's end in grid units, moved off its surface (an end whose normal is shorter than 0.1
// stays: a cluster of many directions).
fn occupancy_end(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let l = length(n);
    let off = select(vec3<f32>(0.0), n / max(l, 1e-6) * OCCUPANCY_END_OFFSET, l > 0.1);
    return (p - occupancy_origin()) / occupancy_cell() + off;
}

fn occupancy_inverse(d: f32) -> f32 {
    return select(1.0 / abs(d), 3.0e38, d == 0.0);
}

// The segment parameter where the segment from `a` moving `d` (one axis) reaches `face`.
fn occupancy_face_at(face: f32, a: f32, d: f32) -> f32 {
    return select((face - a) / d, 3.0e38, d == 0.0);
}

fn occupancy_first_crossing(a: f32, d: f32) -> f32 {
    if (d > 0.0) {
        return (floor(a) + 1.0 - a) / d;
    }
    if (d < 0.0) {
        return (a - floor(a)) / -d;
    }
    return 3.0e38;
}

// What the grid says of a segment: it crosses no set cell, it crosses one, or it cannot tell, as
// an end (moved off its surface) lies in a set cell or within OCCUPANCY_END_CLEARANCE of one on
// the way: another surface within two or three cells of it, in a corner or under a box, where a
// depth map must judge instead.
const GRID_BLOCKED = 0u;
const GRID_VISIBLE = 1u;
const GRID_UNKNOWN = 2u;

// The sub-cell face the segment from `a` moving `d` (sub-cell units) crosses next from sub-cell
// `s`.
fn occupancy_face(s: i32, a: f32, d: f32) -> f32 {
    if (d > 0.0) {
        return (f32(s) + 1.0 - a) / d;
    }
    if (d < 0.0) {
        return (f32(s) - a) / d;
    }
    return 3.0e38;
}

// A walk's way through the sub-cells of a set cell: the sub-cell it is in, the parameter where
// it entered it, and the DDA's state.
struct SubWalk {
    s: vec3<i32>,
    entered: f32,
    lo: vec3<i32>,
    hi: vec3<i32>,
    step: vec3<i32>,
    t_max: vec3<f32>,
    t_delta: vec3<f32>,
}

// The segment from `a_cells` along `d_cells` (grid units) entering set cell `c` at parameter
// `entered`.
fn sub_walk(c: vec3<i32>, a_cells: vec3<f32>, d_cells: vec3<f32>, entered: f32) -> SubWalk {
    let k = f32(OCCUPANCY_SUBCELLS);
    let a = a_cells * k;
    let d = d_cells * k;
    let lo = c * i32(OCCUPANCY_SUBCELLS);
    let hi = lo + vec3<i32>(i32(OCCUPANCY_SUBCELLS) - 1);
    // the sub-cell entered, kept in the cell against rounding
    let s = clamp(vec3<i32>(floor(a + d * entered)), lo, hi);
    return SubWalk(
        s,
        entered,
        lo,
        hi,
        vec3<i32>(sign(d)),
        vec3<f32>(occupancy_face(s.x, a.x, d.x), occupancy_face(s.y, a.y, d.y), occupancy_face(s.z, a.z, d.z)),
        vec3<f32>(occupancy_inverse(d.x), occupancy_inverse(d.y), occupancy_inverse(d.z)),
    );
}

// Steps to the next sub-cell: whether it lies in the cell.
fn sub_step(w: ptr<function, SubWalk>) -> bool {
    let t = (*w).t_max;
    (*w).entered = min(t.x, min(t.y, t.z));
    if (t.x <= t.y && t.x <= t.z) {
        (*w).s.x += (*w).step.x;
        (*w).t_max.x += (*w).t_delta.x;
    } else if (t.y <= t.z) {
        (*w).s.y += (*w).step.y;
        (*w).t_max.y += (*w).t_delta.y;
    } else {
        (*w).s.z += (*w).step.z;
        (*w).t_max.z += (*w).t_delta.z;
    }
    return all((*w).s >= (*w).lo) && all((*w).s <= (*w).hi);
}

// The segment from `x` (a receiver, normal `n`) to `xp` (a cluster, normal `np`) through the
// grid: a 3D DDA over the cells it passes through, bounded by the grid's dimensions, crossing an
// empty brick in one step, and with two levels over the sub-cells of the set cells among them.
fn grid_visibility(x: vec3<f32>, n: vec3<f32>, xp: vec3<f32>, np: vec3<f32>) -> u32 {
    let a = occupancy_end(x, n);
    let b = occupancy_end(xp, np);
    let d = b - a;
    var c = vec3<i32>(floor(a));
    let end = vec3<i32>(floor(b));
    var held = OccupancyHeld(0u, 0u, 0u, 0u, 0u);
    // the end first: the walk goes on from the start's word
    if (occupied_at(b, &held) || occupied_at(a, &held)) {
        return GRID_UNKNOWN;
    }
    let two_levels = occupancy_levels() == 2u;
    let step = vec3<i32>(sign(d));
    let t_delta = vec3<f32>(occupancy_inverse(d.x), occupancy_inverse(d.y), occupancy_inverse(d.z));
    // the segment parameter of the clearance at each end
    let clearance = OCCUPANCY_END_CLEARANCE / max(length(d), 1e-6);
    var t_max = vec3<f32>(
        occupancy_first_crossing(a.x, d.x),
        occupancy_first_crossing(a.y, d.y),
        occupancy_first_crossing(a.z, d.z),
    );
    // one loop, over the cells and, with two levels, the sub-cells of the set ones: lavapipe
    // caps the loop iterations of an invocation, the gather's sums and walks together, and a
    // loop nested here used up that cap even in the one-level walk, which never ran it
    var in_sub = false;
    var w: SubWalk;
    if (two_levels && occupied(c, &held)) {
        in_sub = true;
        w = sub_walk(c, a, d, 0.0);
    }
    let dims = occupancy_dims();
    let cells = dims.x + dims.y + dims.z + 1u;
    let bound = select(cells, cells * (3u * OCCUPANCY_SUBCELLS + 1u), two_levels);
    for (var i = 0u; i < bound; i++) {
        walk_steps++;
        if (in_sub) {
            if (w.entered <= 1.0) {
                if (sub_occupied(w.s, &held)) {
                    let at = max(w.entered, 0.0);
                    return select(GRID_UNKNOWN, GRID_BLOCKED, clearance < at && at < 1.0 - clearance);
                }
                if (sub_step(&w)) {
                    continue;
                }
            }
            // past the cell or the segment's end
            in_sub = false;
        }
        if (all(c == end)) {
            break;
        }
        // the parameter where the walk enters its next cell
        var entered = min(t_max.x, min(t_max.y, t_max.z));
        if (in_empty_brick(c, held)) {
            // an empty brick: on to the cell where the segment leaves it, in one step
            let lo = c / vec3<i32>(OCCUPANCY_BRICK) * vec3<i32>(OCCUPANCY_BRICK);
            let hi = lo + vec3<i32>(OCCUPANCY_BRICK);
            let exit = vec3<f32>(
                occupancy_face_at(f32(select(lo.x, hi.x, step.x > 0)), a.x, d.x),
                occupancy_face_at(f32(select(lo.y, hi.y, step.y > 0)), a.y, d.y),
                occupancy_face_at(f32(select(lo.z, hi.z, step.z > 0)), a.z, d.z),
            );
            entered = min(exit.x, min(exit.y, exit.z));
            if (entered > 1.0) {
                // the end's cell is in the brick
                break;
            }
            // the cell across the face it leaves by (ties as the DDA's), kept beside the brick
            // against rounding
            c = clamp(vec3<i32>(floor(a + d * entered)), lo, hi - vec3<i32>(1));
            if (exit.x <= exit.y && exit.x <= exit.z) {
                c.x = select(lo.x - 1, hi.x, step.x > 0);
            } else if (exit.y <= exit.z) {
                c.y = select(lo.y - 1, hi.y, step.y > 0);
            } else {
                c.z = select(lo.z - 1, hi.z, step.z > 0);
            }
            let next_face = vec3<f32>(c + max(step, vec3<i32>(0)));
            t_max = vec3<f32>(
                occupancy_face_at(next_face.x, a.x, d.x),
                occupancy_face_at(next_face.y, a.y, d.y),
                occupancy_face_at(next_face.z, a.z, d.z),
            );
        } else if (t_max.x <= t_max.y && t_max.x <= t_max.z) {
            c.x += step.x;
            t_max.x += t_delta.x;
        } else if (t_max.y <= t_max.z) {
            c.y += step.y;
            t_max.y += t_delta.y;
        } else {
            c.z += step.z;
            t_max.z += t_delta.z;
        }
        if (min(t_max.x, min(t_max.y, t_max.z)) > 1.0 && any(c != end)) {
            c = end;
        }
        if (occupied(c, &held)) {
            if (!two_levels) {
                return select(GRID_UNKNOWN, GRID_BLOCKED, clearance < entered && entered < 1.0 - clearance);
            }
            in_sub = true;
            w = sub_walk(c, a, d, entered);
        }
    }
    return GRID_VISIBLE;
}
