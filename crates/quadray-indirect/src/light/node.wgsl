// The light quadtree's node layout and pyramid addressing, and the work counters every module
// adds to. Engine-neutral: no bindings, no accessors.

// One light cluster (a level-0 node is one RSM texel = one VPL).
//   flux.rgb: summed flux, flux.w: number of texels that see geometry
//   pos.xyz: mean position, pos.w: mean RSM depth (light-axis distance / scene extent)
//   normal.xyz: renormalised mean normal, normal.w: 1 when the cluster is valid
// The work one invocation did, for the counts the stats report (see `WorkCounts`): VPLs or
// clusters summed, and texels or node records read (G-buffer, RSM, quadtree, low-resolution
// samples). The shading passes store them per pixel; elsewhere they are dropped.
var<private> evaluations: u32;
var<private> fetches: u32;
// Upper bounds of a node's contribution evaluated (per-tile cuts).
var<private> bound_evaluations: u32;

struct Node {
    flux: vec4<f32>,
    pos: vec4<f32>,
    normal: vec4<f32>,
}

// What bounds a node's contribution (per-tile cuts): the box of its VPLs' positions and a cone
// holding their normals (axis: the node's mean normal). Empty nodes hold an empty box (lo > hi).
//   lo.xyz, hi.xyz: the box's corners; lo.w: cosine of the normal cone's half-angle
struct NodeBounds {
    lo: vec4<f32>,
    hi: vec4<f32>,
}

// (EMPTY_BOX, an empty box's lo, and CONE_SLACK, a normal cone's widening, come from the
// prelude)

struct ClusterParams {
    rsm_size: u32,
    // number of levels: log2(rsm_size) + 1
    levels: u32,
    start_level: u32,
    limit_level: u32,
    recursive: u32,
    flux_weighted: u32,
    depth_threshold: f32,
    normal_threshold: f32,
}

// SLICE, LEVEL_SLICE (items one dispatch of a long sum covers), MAX_LEVELS and PI come from the
// prelude generated from Rust (contract.rs).

struct Level {
    level: u32,
}

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
