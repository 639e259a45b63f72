// The per-tile cut's rules (Lightcuts, Walter et al. 2005, with the light quadtree as the light
// tree and a tile of TILE x TILE receivers in place of a pixel): how a tile's receivers group,
// the bound and the threshold a node is held to, when the estimate decides instead (outside a
// node's near field), the bins that order splits, and which listed nodes are shared at the
// tile's corners. The CPU's twin is `twin.rs`. Needs node.wgsl, kernel.wgsl, bound.wgsl.
// Accessors: `load_node` (as cut_rule.wgsl); `fn tile_position(p: u32) -> vec3<f32>` and
// `fn tile_normal(p: u32) -> vec3<f32>`, receiver p of the tile (row-major; an uncovered one at
// EMPTY_BOX); `fn tile_sample(q: u32) -> u32`, the sample pixel of quadrant q (its first covered
// pixel, TILE_PIXELS where none).

// (TILE, NEAR_FIELD_SIZE, EMPTY_BOX, CONE_SLACK, SPLIT_BINS and ZERO_ESTIMATE_SHARE come from
// the prelude)
const TILE_PIXELS: u32 = TILE * TILE;
const CORNERS: array<u32, 4> = array<u32, 4>(0u, TILE - 1u, TILE_PIXELS - TILE, TILE_PIXELS - 1u);

// The tile's receivers in two groups, its box halved across its longest side (a tile on a depth
// discontinuity gets two boxes without the gap between them): each group's box, the axis of its
// normals and the cosine of the cone around it that holds them.
struct TileGroups {
    lo: array<vec3<f32>, 2>,
    hi: array<vec3<f32>, 2>,
    axis: array<vec3<f32>, 2>,
    cone: vec2<f32>,
}

// The group of a receiver at `x` in the tile's box [lo, hi].
fn receiver_group(x: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> u32 {
    let extent = hi - lo;
    let axis = select(select(2u, 1u, extent.y >= extent.z), 0u, extent.x >= max(extent.y, extent.z));
    return select(0u, 1u, x[axis] >= 0.5 * (lo[axis] + hi[axis]));
}

// A group's normal axis from its summed normals.
fn group_axis(sum_n: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0, 0.0, 1.0), normalize(sum_n), length(sum_n) > 0.0);
}

// The groups' cone cosines from their least cosines to their axes, widened past acos's rounding.
fn group_cone(least_cos: vec2<f32>) -> vec2<f32> {
    return cos(min(acos(clamp(least_cos, vec2<f32>(-1.0), vec2<f32>(1.0))) + CONE_SLACK, vec2<f32>(PI)));
}

// A node's light (luminance) at each quadrant's sample pixel: its share of the coarse estimate.
fn coarse_light(node: Node, r_min: f32) -> vec4<f32> {
    var e = vec4<f32>(0.0);
    for (var q = 0u; q < 4u; q++) {
        let p = tile_sample(q);
        if (p < TILE_PIXELS) {
            e[q] += luminance(vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, tile_position(p), tile_normal(p), r_min));
        }
    }
    return e;
}

// The threshold a node's bound is held to: `tile_error` of the mean of the sample pixels'
// coarse estimates (`summed` per quadrant; their least refined more for as little error), or
// where that is zero, of ZERO_ESTIMATE_SHARE of `bounded`, the start level's nodes' bounds at
// the tile's receivers summed.
fn tile_threshold(tile_error: f32, summed: vec4<f32>, bounded: f32) -> f32 {
    var total = 0.0;
    var samples = 0.0;
    for (var q = 0u; q < 4u; q++) {
        if (tile_sample(q) < TILE_PIXELS) {
            total += summed[q];
            samples += 1.0;
        }
    }
    let estimate = total / samples;
    return tile_error * select(estimate, ZERO_ESTIMATE_SHARE * bounded, estimate == 0.0);
}

// What a node may give any receiver of the tile: the larger of its bounds for the two groups.
fn tile_bound(node: Node, b: NodeBounds, g: TileGroups, r_min: f32) -> f32 {
    return max(
        node_bound(node.flux.rgb, b, node.normal.xyz, g.lo[0], g.hi[0], g.axis[0], g.cone.x, r_min),
        node_bound(node.flux.rgb, b, node.normal.xyz, g.lo[1], g.hi[1], g.axis[1], g.cone.y, r_min),
    );
}

// Whether a node holds its kernel's near field for this tile: a receiver of the tile lies within
// `r_min` of the node's box and the box is more than NEAR_FIELD_SIZE times `r_min` across. There
// the kernel's clamp falls inside the node, and its children's sum can agree with it however far
// both are from its VPLs' (columns standing on a lit floor: with the estimate alone the atrium's
// error stays at 0.046 rel. L1 whatever the tile error; CPU cut study), so the bound decides.
fn near_field(b: NodeBounds, r_min: f32) -> bool {
    let side = b.hi.xyz - b.lo.xyz;
    if (dot(side, side) <= NEAR_FIELD_SIZE * NEAR_FIELD_SIZE * r_min * r_min) {
        return false;
    }
    for (var p = 0u; p < TILE_PIXELS; p++) {
        let x = tile_position(p);
        if (x.x < EMPTY_BOX) {
            let gap = max(vec3<f32>(0.0), max(b.lo.xyz - x, x - b.hi.xyz));
            if (dot(gap, gap) < r_min * r_min) {
                return true;
            }
        }
    }
    return false;
}

// Whether the estimate decides a node of `level` whose bound is over the threshold: with
// `tile_estimate`, below the start level (above it a node's children are as coarse as itself, so
// their sum agrees with it however far both are from the truth: 0.10 rel L1 at 204 evaluations a
// pixel on the Cornell box, 0.031 at 341 from the start level down), not at a tile error of 0 (so
// that every VPL that may light the tile is on its own), nor in the node's near field.
fn estimate_decides(estimate: bool, level: u32, start: u32, threshold: f32, b: NodeBounds, r_min: f32) -> bool {
    return estimate && level < start && threshold > 0.0 && !near_field(b, r_min);
}

// The estimated error of keeping a node (`at` of level `level`, `size` nodes a side) rather than
// its four children: the largest luminance of the difference of their irradiances at the tile's
// sample pixels and at its receiver nearest the node (where the kernel is steepest). A node that
// lights none of them, e.g. one on the other wall of a tile spanning a corner, is kept: taking the
// bound there split most floor nodes for floor tiles, 0.031 rel L1 at 583 evaluations a pixel
// against 341 on the Cornell box.
fn estimated_error(p: ClusterParams, node: Node, at: u32, size: u32, level: u32, r_min: f32) -> f32 {
    let xy = vec2<u32>(at % size, at / size);
    var children: array<Node, 4>;
    for (var c = 0u; c < 4u; c++) {
        fetches++;
        children[c] = load_node(node_index(p, level - 1u, xy * 2u + vec2<u32>(c & 1u, c >> 1u)));
    }
    var nearest = 0u;
    for (var q = 1u; q < TILE_PIXELS; q++) {
        let d = tile_position(q) - node.pos.xyz;
        let e = tile_position(nearest) - node.pos.xyz;
        if (dot(d, d) < dot(e, e)) {
            nearest = q;
        }
    }
    var error = 0.0;
    for (var q = 0u; q < 5u; q++) {
        let s = select(nearest, tile_sample(min(q, 3u)), q < 4u);
        if (s < TILE_PIXELS) {
            let x = tile_position(s);
            let n = tile_normal(s);
            let own = vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, x, n, r_min);
            var sum = vec3<f32>(0.0);
            for (var c = 0u; c < 4u; c++) {
                if (children[c].flux.w > 0.5) {
                    sum += vpl_irradiance(children[c].flux.rgb, children[c].pos.xyz, children[c].normal.xyz, x, n, r_min);
                }
            }
            error = max(error, abs(luminance(own - sum)));
        }
    }
    return error;
}

// A node's split bin, 1..SPLIT_BINS by powers of two of `excess` / `threshold` (its bound, or its
// estimated error where the estimate decides), or 0 where it is listed.
fn split_bin(excess: f32, threshold: f32) -> u32 {
    if (excess > threshold) {
        return 1u + u32(clamp(floor(log2(excess / threshold)), 0.0, f32(SPLIT_BINS - 1u)));
    }
    return 0u;
}

// Whether every corner of the tile has a receiver (far nodes are shared only then).
fn all_corners_covered() -> bool {
    for (var c = 0u; c < 4u; c++) {
        if (tile_position(CORNERS[c]).x >= EMPTY_BOX) {
            return false;
        }
    }
    return true;
}

// Receiver sharing (`tile_share` > 0, Multidimensional Lightcuts' idea with the tile as the
// receiver cluster): whether a listed node with bounds `b` is farther than `tile_share` times the
// diagonal of the tile's receivers' box [lo, hi] from that box, and wholly in front of every
// corner receiver. Its light varies slowly across the tile, so it is evaluated once per corner as
// vector irradiance (linear in the receiver's normal) and interpolated bilinearly.
fn shareable(b: NodeBounds, lo: vec3<f32>, hi: vec3<f32>, tile_share: f32) -> bool {
    let far = tile_share * length(hi - lo);
    let gap = max(vec3<f32>(0.0), max(b.lo.xyz - hi, lo - b.hi.xyz));
    if (dot(gap, gap) <= far * far) {
        return false;
    }
    let centre = 0.5 * (b.lo.xyz + b.hi.xyz);
    let half = 0.5 * (b.hi.xyz - b.lo.xyz);
    for (var c = 0u; c < 4u; c++) {
        let n = tile_normal(CORNERS[c]);
        if (dot(n, centre - tile_position(CORNERS[c])) - dot(abs(n), half) <= 0.0) {
            return false;
        }
    }
    return true;
}
