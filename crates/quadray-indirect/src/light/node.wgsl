// The light quadtree's node layout and pyramid addressing, and the work counters every module
// adds to. Engine-neutral: no bindings, no accessors.

// `Node` (one cluster), `NodeBounds` (its box and normal cone), `ClusterParams` (the quadtree's
// settings) and `Level` (a per-dispatch slot) are declared in Rust and generated into the prelude
// (contract.rs), as are EMPTY_BOX, CONE_SLACK, SLICE, LEVEL_SLICE, MAX_LEVELS and PI.

// The work one invocation did, for the counts the stats report (see `WorkCounts`): VPLs or
// clusters summed, and texels or node records read (G-buffer, RSM, quadtree, low-resolution
// samples). The shading passes store them per pixel; elsewhere they are dropped.
var<private> evaluations: u32;
var<private> fetches: u32;
// Upper bounds of a node's contribution evaluated (per-tile cuts).
var<private> bound_evaluations: u32;

fn level_size(p: ClusterParams, level: u32) -> u32 {
    return p.rsm_size >> level;
}

// Index of the first node of `level` (levels are stored finest first): the geometric series
// S^2 (1 + 1/4 + ... ) over the finer levels, 4 (S^2 - s^2) / 3 with s the level's side. No loop:
// it runs in every cut test, and lavapipe counts loop iterations (see SLICE).
fn level_offset(p: ClusterParams, level: u32) -> u32 {
    let side = p.rsm_size >> min(level, 31u);
    return 4u * (p.rsm_size * p.rsm_size - side * side) / 3u;
}

fn node_index(p: ClusterParams, level: u32, xy: vec2<u32>) -> u32 {
    return level_offset(p, level) + xy.y * level_size(p, level) + xy.x;
}
