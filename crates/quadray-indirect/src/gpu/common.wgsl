// Shared by every pass that reads clusters: the node layout, pyramid addressing, the VPL kernel
// and the top-down cut rule. Concatenated in front of cluster.wgsl and every gather pass.

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

// An empty box's lo (its hi is the negative): any box joined with it is that box.
const EMPTY_BOX: f32 = 1e30;
// Widens a normal cone's half-angle (radians) past f32's rounding in acos near 1, so that the
// cone still holds every VPL normal.
const CONE_SLACK: f32 = 1e-3;

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

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Irradiance at x (normal n) from a VPL or cluster of flux `flux` at xp (normal np), with the
// 1/r^4 clamped at r_min (the spec's kernel; the reference uses the same). A diffuse VPL radiates
// flux / pi * cos: the 1/pi the spec's formula (after the RSM paper) leaves out is put back so
// that indirect and direct light are on the same scale; errors are ratios and do not change.
fn vpl_irradiance(flux: vec3<f32>, xp: vec3<f32>, np: vec3<f32>, x: vec3<f32>, n: vec3<f32>, r_min: f32) -> vec3<f32> {
    evaluations++;
    let d = x - xp;
    let d2 = max(dot(d, d), r_min * r_min);
    return flux * (max(0.0, dot(np, d)) * max(0.0, dot(n, -d)) / (PI * d2 * d2));
}

// The vector irradiance at x from a VPL or cluster: `vpl_irradiance` without the receiver's
// cosine, one column a colour channel, so that transpose(V) * n is `vpl_irradiance` for every
// receiver normal n that faces the VPL (per-tile cuts gather far clusters this way once per
// tile corner and interpolate).
fn vpl_vector(flux: vec3<f32>, xp: vec3<f32>, np: vec3<f32>, x: vec3<f32>, r_min: f32) -> mat3x3<f32> {
    evaluations++;
    let d = x - xp;
    let d2 = max(dot(d, d), r_min * r_min);
    let v = -d * (max(0.0, dot(np, d)) / (PI * d2 * d2));
    return mat3x3<f32>(v * flux.r, v * flux.g, v * flux.b);
}
