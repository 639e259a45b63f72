// The scene's occupancy grid walked between a receiver and a cluster (indirect shadows): the
// twin of the CPU's `OccupancyGrid::walk` (src/occupancy.rs), step for step and fetch for fetch.
// Accessors: `occupancy_dims() -> vec3<u32>` (zero: no grid; multiples of OCCUPANCY_BRICK),
// `occupancy_origin() -> vec3<f32>`, `occupancy_cell() -> f32` and `occupancy_word(i: u32) -> u32`
// (a word a brick of OCCUPANCY_BRICK cells, brick (x, y, z) at word x + bricks.x * (y + bricks.y
// * z), its cell (x, y, z) at bit x + 4 * (y + 4 * z)).

// (OCCUPANCY_END_OFFSET, the cells a segment's ends are moved off their surfaces along the
// normals, OCCUPANCY_END_CLEARANCE, the cells from an end within which a set cell leaves the walk
// undecided, and OCCUPANCY_BRICK come from the prelude)

// Whether cell `c` is set (outside the grid: no). `held` is the walk's last word read (x: its
// index + 1, 0 before the first; y: its bits): a brick costs one fetch however many of its
// cells the walk crosses.
fn occupied(c: vec3<i32>, held: ptr<function, vec2<u32>>) -> bool {
    let d = occupancy_dims();
    if (any(c < vec3<i32>(0)) || any(vec3<u32>(c) >= d)) {
        return false;
    }
    let bricks = d / OCCUPANCY_BRICK;
    let b = vec3<u32>(c) / OCCUPANCY_BRICK;
    let l = vec3<u32>(c) % OCCUPANCY_BRICK;
    let word = b.x + bricks.x * (b.y + bricks.y * b.z);
    if ((*held).x != word + 1u) {
        fetches++;
        *held = vec2<u32>(word + 1u, occupancy_word(word));
    }
    let bit = l.x + OCCUPANCY_BRICK.x * (l.y + OCCUPANCY_BRICK.y * l.z);
    return (((*held).y >> bit) & 1u) == 1u;
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

// The segment from `x` (a receiver, normal `n`) to `xp` (a cluster, normal `np`) through the
// grid: a 3D DDA over the cells it passes through, bounded by the grid's dimensions.
fn grid_visibility(x: vec3<f32>, n: vec3<f32>, xp: vec3<f32>, np: vec3<f32>) -> u32 {
    let a = occupancy_end(x, n);
    let b = occupancy_end(xp, np);
    let d = b - a;
    var c = vec3<i32>(floor(a));
    let end = vec3<i32>(floor(b));
    var held = vec2<u32>(0u);
    if (occupied(c, &held) || occupied(end, &held)) {
        return GRID_UNKNOWN;
    }
    let step = vec3<i32>(sign(d));
    let t_delta = vec3<f32>(occupancy_inverse(d.x), occupancy_inverse(d.y), occupancy_inverse(d.z));
    // the segment parameter of the clearance at each end
    let clearance = OCCUPANCY_END_CLEARANCE / max(length(d), 1e-6);
    var t_max = vec3<f32>(
        occupancy_first_crossing(a.x, d.x),
        occupancy_first_crossing(a.y, d.y),
        occupancy_first_crossing(a.z, d.z),
    );
    let dims = occupancy_dims();
    let bound = dims.x + dims.y + dims.z;
    for (var i = 0u; i <= bound; i++) {
        if (all(c == end)) {
            break;
        }
        // the parameter where the walk enters its next cell
        let entered = min(t_max.x, min(t_max.y, t_max.z));
        if (t_max.x <= t_max.y && t_max.x <= t_max.z) {
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
            return select(GRID_UNKNOWN, GRID_BLOCKED, clearance < entered && entered < 1.0 - clearance);
        }
    }
    return GRID_VISIBLE;
}
