// Per-tile cuts (Lightcuts, Walter et al. 2005, with the light quadtree as the light tree and a
// tile of 8x8 receivers in place of a pixel): one workgroup per tile refines the quadtree level
// by level from its root, splitting a node while the bound of what it gives any receiver of the
// tile (bound.wgsl, against each half of the tile's receivers) exceeds `tile_error` of the tile's
// estimated irradiance (the nodes of level `tile_start` summed at a few of its pixels), or with
// `tile_estimate`, below that level, while the bound and the node's estimated error at those
// pixels both do, down to single VPLs where needed, then every pixel of the tile sums the tile's
// list.

// Group 3, this pass's own: the per-tile cuts' lists (allocated by the first frame that draws
// them): each tile's node indices (`tile_capacity` slots a tile), and per tile the nodes it
// holds, the splits refused for want of room, the nodes whose error it estimated and the VPL
// evaluations that took
@group(3) @binding(0) var<storage, read_write> tile_cuts: array<u32>;
@group(3) @binding(1) var<storage, read_write> tile_sizes: array<vec4<u32>>;

// TILE (the tile's side) comes from the prelude
const TILE_PIXELS: u32 = TILE * TILE;

// the tile's receivers: position (EMPTY_BOX where none) and normal
var<workgroup> tile_x: array<vec3<f32>, TILE_PIXELS>;
var<workgroup> tile_n: array<vec3<f32>, TILE_PIXELS>;
// reductions over the tile's pixels: the receivers' box and normals (summed; w: how many), of
// the tile then of each half, each half's least cosine to its mean normal (x, y of reduce_n),
// and the coarse estimate at each quadrant's sample pixel
var<workgroup> reduce_lo: array<vec3<f32>, TILE_PIXELS>;
var<workgroup> reduce_hi: array<vec3<f32>, TILE_PIXELS>;
var<workgroup> reduce_n: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> reduce_e: array<vec4<f32>, TILE_PIXELS>;
// per quadrant of the tile, its first covered pixel (TILE_PIXELS: none): the estimate's
// sample pixels
var<workgroup> quadrant_pixel: array<atomic<u32>, 4>;
// the nodes of the level being refined and of the next (pyramid indices)
var<workgroup> frontier: array<array<u32, TILE_FRONTIER>, 2>;
var<workgroup> frontier_len: array<atomic<u32>, 2>;
var<workgroup> list_len: atomic<u32>;
// list slots promised: the list's nodes and the frontiers' (a split adds three), so that
// every node of a frontier can still be listed when the tile's capacity stops refinement
var<workgroup> reserved: atomic<u32>;
var<workgroup> refused: atomic<u32>;
// the nodes whose error was estimated (`tile_estimate`), and the VPL evaluations it took
var<workgroup> estimated_nodes: atomic<u32>;
var<workgroup> estimate_evaluations: atomic<u32>;
// a level's verdict on each node of its frontier, four bytes to a word: VERDICT_LIST,
// VERDICT_EMPTY, or the node wants a split and its bound is over the threshold by a factor of
// 2^(verdict - 1) or more; how many nodes want a split in each bin; the bin at or below which
// splits are refused (the one at it split while room is left)
const VERDICT_LIST: u32 = 0u;
const VERDICT_EMPTY: u32 = 255u;
const SPLIT_BINS: u32 = 16u;
var<workgroup> verdicts: array<atomic<u32>, TILE_FRONTIER / 4u>;
var<workgroup> split_bins: array<atomic<u32>, SPLIT_BINS>;
var<workgroup> split_cutoff: u32;
// work of the threads whose pixel lies outside the picture, counted with the tile's first pixel
var<workgroup> stray: array<atomic<u32>, 3>;

// The estimated error of keeping a node (at `at` of level `level`, `size` nodes a side) rather
// than its four children: the largest luminance of the difference of their irradiances at the
// tile's sample pixels (a node that lights none of them, e.g. one on the other wall of a tile
// spanning a corner, is kept: taking the bound there split most floor nodes for floor tiles,
// 0.031 rel L1 at 583 evaluations a pixel against 341 on the Cornell box).
fn estimated_error(node: Node, at: u32, size: u32, level: u32) -> f32 {
    let xy = vec2<u32>(at % size, at / size);
    var children: array<Node, 4>;
    for (var c = 0u; c < 4u; c++) {
        fetches++;
        children[c] = nodes[node_index(params, level - 1u, xy * 2u + vec2<u32>(c & 1u, c >> 1u))];
    }
    // the sample pixels, and the tile's receiver nearest the node (where the kernel is steepest)
    var nearest = 0u;
    for (var p = 1u; p < TILE_PIXELS; p++) {
        let d = tile_x[p] - node.pos.xyz;
        let e = tile_x[nearest] - node.pos.xyz;
        if (dot(d, d) < dot(e, e)) {
            nearest = p;
        }
    }
    var error = 0.0;
    for (var q = 0u; q < 5u; q++) {
        let p = select(nearest, atomicLoad(&quadrant_pixel[min(q, 3u)]), q < 4u);
        if (p < TILE_PIXELS) {
            let own = vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, tile_x[p], tile_n[p], terms.r_min);
            var sum = vec3<f32>(0.0);
            for (var c = 0u; c < 4u; c++) {
                if (children[c].flux.w > 0.5) {
                    sum += vpl_irradiance(children[c].flux.rgb, children[c].pos.xyz, children[c].normal.xyz, tile_x[p], tile_n[p], terms.r_min);
                }
            }
            error = max(error, abs(luminance(own - sum)));
        }
    }
    return error;
}

// Whether a node holds its kernel's near field for this tile: a receiver of the tile lies within
// `r_min` of the node's box and the box is more than NEAR_FIELD_SIZE (from the prelude) times
// `r_min` across. There the kernel's clamp falls inside the node, and its children's sum can
// agree with it however far both are from its VPLs' (columns standing on a lit floor: with the
// estimate alone the atrium's error stays at 0.046 rel. L1 whatever the tile error; CPU cut
// study), so the bound decides.
fn near_field(b: NodeBounds, r_min: f32) -> bool {
    let side = b.hi.xyz - b.lo.xyz;
    if (dot(side, side) <= NEAR_FIELD_SIZE * NEAR_FIELD_SIZE * r_min * r_min) {
        return false;
    }
    for (var p = 0u; p < TILE_PIXELS; p++) {
        let x = tile_x[p];
        if (x.x < EMPTY_BOX) {
            let gap = max(vec3<f32>(0.0), max(b.lo.xyz - x, x - b.hi.xyz));
            if (dot(gap, gap) < r_min * r_min) {
                return true;
            }
        }
    }
    return false;
}

// Receiver sharing (`tile_share` > 0, Multidimensional Lightcuts' idea with the tile as the
// receiver cluster): a node of the tile's list farther than `tile_share` times the diagonal of
// the tile's receivers' box, and in front of the planes of the tile's four corner receivers, is
// evaluated once per corner as vector irradiance (linear in the receiver's normal) and
// interpolated bilinearly over the tile: its light varies slowly across the tile.
const SHARED: u32 = 0x80000000u;
const CORNERS: array<u32, 4> = array<u32, 4>(0u, TILE - 1u, TILE_PIXELS - TILE, TILE_PIXELS - 1u);
var<workgroup> shared_count: atomic<u32>;
var<workgroup> shared_total: u32;

fn all_corners_covered() -> bool {
    for (var c = 0u; c < 4u; c++) {
        if (tile_x[CORNERS[c]].x >= EMPTY_BOX) {
            return false;
        }
    }
    return true;
}

// Whether a node with bounds `b` is farther than `far` from the box [lo, hi] and wholly in front
// of every corner receiver.
fn shareable(b: NodeBounds, lo: vec3<f32>, hi: vec3<f32>, far: f32) -> bool {
    let gap = max(vec3<f32>(0.0), max(b.lo.xyz - hi, lo - b.hi.xyz));
    if (dot(gap, gap) <= far * far) {
        return false;
    }
    let centre = 0.5 * (b.lo.xyz + b.hi.xyz);
    let half = 0.5 * (b.hi.xyz - b.lo.xyz);
    for (var c = 0u; c < 4u; c++) {
        let n = tile_n[CORNERS[c]];
        if (dot(n, centre - tile_x[CORNERS[c]]) - dot(abs(n), half) <= 0.0) {
            return false;
        }
    }
    return true;
}

// Indirect shadows per tile: bit c set where the point `p` (a node's mean) is visible from the
// tile's corner receiver c (`visible`, shared.wgsl); a pixel on the corners' surface weighs each
// of its tile's nodes by the corners' visibility interpolated, so that a tile marches four
// shadow rays a node instead of one a pixel.
fn corner_visibility(p: vec3<f32>) -> u32 {
    var seen = 0u;
    for (var c = 0u; c < 4u; c++) {
        if (visible(tile_x[CORNERS[c]], p)) {
            seen |= 1u << c;
        }
    }
    return seen;
}

// The shared nodes' vector irradiance at each corner receiver (with indirect shadows, those the
// corner sees): a quarter of the workgroup per corner, each thread a share of the nodes, then
// summed per corner (one colour channel in each of the reduction arrays). Every invocation
// calls it.
fn gather_at_corners(local: u32, listed: u32, corner_shadows: bool) -> array<mat3x3<f32>, 4> {
    let x = tile_x[CORNERS[local % 4u]];
    var v = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    for (var i = local / 4u; i < listed; i += TILE_PIXELS / 4u) {
        let entry = frontier[0][i];
        if ((entry & SHARED) != 0u) {
            fetches++;
            let node = nodes[entry & ~SHARED];
            // (evaluated either way, as a pixel's own sum does before its shadow test)
            let seen = !corner_shadows || ((frontier[1][i] >> (local % 4u)) & 1u) == 1u;
            v += vpl_vector(node.flux.rgb, node.pos.xyz, node.normal.xyz, x, terms.r_min) * f32(seen);
        }
    }
    reduce_lo[local] = v[0];
    reduce_hi[local] = v[1];
    reduce_n[local] = vec4<f32>(v[2], 0.0);
    workgroupBarrier();
    for (var stride = TILE_PIXELS / 2u; stride >= 4u; stride >>= 1u) {
        if (local < stride) {
            reduce_lo[local] += reduce_lo[local + stride];
            reduce_hi[local] += reduce_hi[local + stride];
            reduce_n[local] += reduce_n[local + stride];
        }
        workgroupBarrier();
    }
    var corners: array<mat3x3<f32>, 4>;
    for (var c = 0u; c < 4u; c++) {
        corners[c] = mat3x3<f32>(reduce_lo[c], reduce_hi[c], reduce_n[c].xyz);
    }
    return corners;
}

// Stores every thread's counts: those outside the picture's with the tile's first pixel.
fn store_tile_counts(pixel: vec2<u32>, inside: bool, local: u32) {
    if (!inside) {
        atomicAdd(&stray[0], evaluations);
        atomicAdd(&stray[1], fetches);
        atomicAdd(&stray[2], bound_evaluations);
    }
    workgroupBarrier();
    if (local == 0u) {
        evaluations += atomicLoad(&stray[0]);
        fetches += atomicLoad(&stray[1]);
        bound_evaluations += atomicLoad(&stray[2]);
    }
    if (inside) {
        store_counts(pixel_index(pixel));
    }
}

// The box of the positions and the summed normals (w: how many) of the tile's receivers where
// `member`, left in reduce_lo[0], reduce_hi[0] and reduce_n[0]. Every invocation calls it.
fn reduce_receivers(local: u32, r: Receiver, member: bool) {
    reduce_lo[local] = select(vec3<f32>(EMPTY_BOX), r.x, member);
    reduce_hi[local] = select(vec3<f32>(-EMPTY_BOX), r.x, member);
    reduce_n[local] = select(vec4<f32>(0.0), vec4<f32>(r.n, 1.0), member);
    workgroupBarrier();
    for (var stride = TILE_PIXELS / 2u; stride > 0u; stride >>= 1u) {
        if (local < stride) {
            reduce_lo[local] = min(reduce_lo[local], reduce_lo[local + stride]);
            reduce_hi[local] = max(reduce_hi[local], reduce_hi[local + stride]);
            reduce_n[local] += reduce_n[local + stride];
        }
        workgroupBarrier();
    }
}

@compute @workgroup_size(TILE, TILE)
fn indirect_tiles(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) tile_xy: vec3<u32>,
) {
    let inside = id.x < viewer.width && id.y < viewer.height;
    var r: Receiver;
    if (inside) {
        r = receiver(id.xy);
    }
    // an uncovered pixel far away: never the one nearest a node
    tile_x[local] = select(vec3<f32>(EMPTY_BOX), r.x, r.covered);
    tile_n[local] = r.n;
    if (local < 4u) {
        atomicStore(&quadrant_pixel[local], TILE_PIXELS);
    }
    if (local < 3u) {
        atomicStore(&stray[local], 0u);
    }
    if (local < SPLIT_BINS) {
        atomicStore(&split_bins[local], 0u);
    }
    for (var i = local; i < TILE_FRONTIER / 4u; i += TILE_PIXELS) {
        atomicStore(&verdicts[i], 0u);
    }
    if (local == 0u) {
        atomicStore(&frontier_len[1], 0u);
        atomicStore(&list_len, 0u);
        atomicStore(&refused, 0u);
        atomicStore(&estimated_nodes, 0u);
        atomicStore(&estimate_evaluations, 0u);
    }
    // (its first barrier also publishes the stores above before the atomicMin below)
    reduce_receivers(local, r, r.covered);
    if (r.covered) {
        atomicMin(&quadrant_pixel[(local % TILE) / (TILE / 2u) + 2u * (local / (TILE_PIXELS / 2u))], local);
    }
    let tile = tile_xy.y * shade.tiles_x + tile_xy.x;
    if (workgroupUniformLoad(&reduce_n[0]).w == 0.0) {
        // nothing to light: no light either (the last frame's may be there)
        if (inside) {
            add_indirect(pixel_index(id.xy), vec4<f32>(0.0));
        }
        if (local == 0u) {
            tile_sizes[tile] = vec4<u32>(0u);
        }
        store_tile_counts(id.xy, inside, local);
        return;
    }
    // two groups of receivers, the tile's box halved across its longest side: a tile on a
    // depth discontinuity (an edge in front of a far wall) gets two boxes without the gap
    // between them, and a node's bound is the larger of the two groups'
    let extent = reduce_hi[0] - reduce_lo[0];
    let split_axis = select(select(2u, 1u, extent.y >= extent.z), 0u, extent.x >= max(extent.y, extent.z));
    let middle = 0.5 * (reduce_lo[0][split_axis] + reduce_hi[0][split_axis]);
    let group = select(0u, 1u, r.x[split_axis] >= middle);
    var group_lo: array<vec3<f32>, 2>;
    var group_hi: array<vec3<f32>, 2>;
    var group_axis: array<vec3<f32>, 2>;
    for (var g = 0u; g < 2u; g++) {
        workgroupBarrier();
        reduce_receivers(local, r, r.covered && group == g);
        group_lo[g] = reduce_lo[0];
        group_hi[g] = reduce_hi[0];
        let sum_n = reduce_n[0].xyz;
        group_axis[g] = select(vec3<f32>(0.0, 0.0, 1.0), normalize(sum_n), length(sum_n) > 0.0);
    }
    workgroupBarrier();
    // each group's least cosine to its axis (x: group 0, y: group 1)
    let cos_own = select(1.0, dot(r.n, group_axis[group]), r.covered);
    reduce_n[local] = vec4<f32>(select(1.0, cos_own, group == 0u), select(1.0, cos_own, group == 1u), 0.0, 0.0);

    // the coarse estimate: the nodes of level `tile_start` at each quadrant's sample pixel
    let start = shade.tile_start;
    let start_side = level_size(params, start);
    let start_nodes = start_side * start_side;
    let first = level_offset(params, start);
    var e = vec4<f32>(0.0);
    for (var i = local; i < start_nodes; i += TILE_PIXELS) {
        fetches++;
        let node = nodes[first + i];
        if (node.flux.w > 0.5) {
            for (var q = 0u; q < 4u; q++) {
                let p = atomicLoad(&quadrant_pixel[q]);
                if (p < TILE_PIXELS) {
                    e[q] += luminance(vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, tile_x[p], tile_n[p], terms.r_min));
                }
            }
        }
    }
    reduce_e[local] = e;
    // refinement starts from the root, so that far tiles may keep clusters coarser than the
    // estimate's
    let root = params.levels - 1u;
    if (local == 0u) {
        frontier[0][0] = level_offset(params, root);
        atomicStore(&frontier_len[0], 1u);
        atomicStore(&reserved, 1u);
    }
    workgroupBarrier();
    for (var stride = TILE_PIXELS / 2u; stride > 0u; stride >>= 1u) {
        if (local < stride) {
            reduce_e[local] += reduce_e[local + stride];
            reduce_n[local] = min(reduce_n[local], reduce_n[local + stride]);
        }
        workgroupBarrier();
    }
    // the mean of the sample pixels' estimates (their least refined more for as little error)
    var total = 0.0;
    var samples = 0.0;
    for (var q = 0u; q < 4u; q++) {
        if (atomicLoad(&quadrant_pixel[q]) < TILE_PIXELS) {
            total += reduce_e[0][q];
            samples += 1.0;
        }
    }
    total /= samples;
    let threshold = shade.tile_error * total;
    let least_cos = reduce_n[0].xy;
    let group_cos = cos(min(acos(clamp(least_cos, vec2<f32>(-1.0), vec2<f32>(1.0))) + CONE_SLACK, vec2<f32>(PI)));

    // refinement, one level a step: first every node's verdict (empty, listed, or the bin of
    // how far its bound exceeds the threshold), then as many splits as the list has room for,
    // the nodes of the highest bins first (Lightcuts splits the largest bound first)
    for (var step = 0u; step <= root; step++) {
        let level = root - step;
        let current = step & 1u;
        let next = current ^ 1u;
        let count = atomicLoad(&frontier_len[current]);
        let size = level_size(params, level);
        let offset = level_offset(params, level);
        for (var i = local; i < count; i += TILE_PIXELS) {
            let index = frontier[current][i];
            fetches++;
            let node = nodes[index];
            var verdict = VERDICT_LIST;
            if (node.flux.w < 0.5) {
                verdict = VERDICT_EMPTY;
                atomicSub(&reserved, 1u);
            } else if (level > 0u) {
                fetches++;
                let b = bounds[index];
                let bound = max(
                    node_bound(node.flux.rgb, b, node.normal.xyz, group_lo[0], group_hi[0], group_axis[0], group_cos.x, terms.r_min),
                    node_bound(node.flux.rgb, b, node.normal.xyz, group_lo[1], group_hi[1], group_axis[1], group_cos.y, terms.r_min),
                );
                // a node under the threshold by its bound cannot matter; over it, the estimate
                // decides below the start level (above it a node's children are as coarse as
                // itself, so their sum agrees with it however far both are from the truth:
                // 0.10 rel L1 at 204 evaluations a pixel on the Cornell box, 0.031 at 341 from
                // the start level down); at a tile error of 0 the bound alone, so that every VPL
                // that may light the tile is on its own; in a node's near field (`near_field`)
                // the bound alone
                var excess = bound;
                if (bound > threshold && shade.tile_estimate == 1u && level < start && threshold > 0.0 && !near_field(b, terms.r_min)) {
                    let before = evaluations;
                    excess = estimated_error(node, index - offset, size, level);
                    atomicAdd(&estimated_nodes, 1u);
                    atomicAdd(&estimate_evaluations, evaluations - before);
                }
                if (excess > threshold) {
                    // bins of powers of two of excess / threshold, 1..SPLIT_BINS
                    let bin = 1u + u32(clamp(floor(log2(excess / threshold)), 0.0, f32(SPLIT_BINS - 1u)));
                    atomicAdd(&split_bins[bin - 1u], 1u);
                    verdict = bin;
                }
            }
            atomicOr(&verdicts[i / 4u], verdict << (8u * (i % 4u)));
        }
        workgroupBarrier();
        if (local == 0u) {
            // the bins above the cutoff all fit and have their room reserved here; the cutoff
            // bin's nodes split while room is left
            var room = (shade.tile_capacity - atomicLoad(&reserved)) / 3u;
            var granted = 0u;
            split_cutoff = 0u;
            for (var bin = SPLIT_BINS; bin > 0u; bin--) {
                let wanted = atomicLoad(&split_bins[bin - 1u]);
                if (wanted > room) {
                    split_cutoff = bin;
                    break;
                }
                room -= wanted;
                granted += wanted;
            }
            atomicAdd(&reserved, 3u * granted);
        }
        workgroupBarrier();
        let cutoff = split_cutoff;
        for (var i = local; i < count; i += TILE_PIXELS) {
            let verdict = (atomicLoad(&verdicts[i / 4u]) >> (8u * (i % 4u))) & 255u;
            if (verdict == VERDICT_EMPTY) {
                continue;
            }
            let index = frontier[current][i];
            var split = verdict > cutoff;
            if (verdict == cutoff && cutoff > 0u) {
                split = atomicAdd(&reserved, 3u) + 3u <= shade.tile_capacity;
                if (!split) {
                    atomicSub(&reserved, 3u);
                }
            }
            if (verdict != VERDICT_LIST && !split) {
                atomicAdd(&refused, 1u);
            }
            if (split) {
                let at = index - offset;
                let xy = vec2<u32>(at % size, at / size);
                let slot = atomicAdd(&frontier_len[next], 4u);
                for (var c = 0u; c < 4u; c++) {
                    let child = xy * 2u + vec2<u32>(c & 1u, c >> 1u);
                    frontier[next][slot + c] = node_index(params, level - 1u, child);
                }
            } else {
                tile_cuts[tile * shade.tile_capacity + atomicAdd(&list_len, 1u)] = index;
            }
        }
        workgroupBarrier();
        if (local == 0u) {
            atomicStore(&frontier_len[current], 0u);
        }
        if (local < SPLIT_BINS) {
            atomicStore(&split_bins[local], 0u);
        }
        for (var i = local; i < TILE_FRONTIER / 4u; i += TILE_PIXELS) {
            atomicStore(&verdicts[i], 0u);
        }
        workgroupBarrier();
    }

    // the gather: the list copied once into workgroup memory (the frontier's, free now), far
    // nodes marked to be shared, with indirect shadows each node's visibility from the tile's
    // corners, then every pixel sums its nodes
    storageBarrier();
    let listed = atomicLoad(&list_len);
    let base = tile * shade.tile_capacity;
    let tile_lo = min(group_lo[0], group_lo[1]);
    let tile_hi = max(group_hi[0], group_hi[1]);
    let corners_covered = all_corners_covered();
    let sharing = shade.tile_share > 0.0 && corners_covered;
    let corner_shadows = shade.shadow_steps > 0u && corners_covered;
    // how far a shared node must be from the tile's receivers' box
    let far = shade.tile_share * length(tile_hi - tile_lo);
    if (local == 0u) {
        atomicStore(&shared_count, 0u);
    }
    workgroupBarrier();
    for (var i = local; i < listed; i += TILE_PIXELS) {
        fetches++;
        var index = tile_cuts[base + i];
        if (corner_shadows) {
            fetches++;
            frontier[1][i] = corner_visibility(nodes[index].pos.xyz);
        }
        if (sharing) {
            fetches++;
            if (shareable(bounds[index], tile_lo, tile_hi, far)) {
                index |= SHARED;
                atomicAdd(&shared_count, 1u);
            }
        }
        frontier[0][i] = index;
    }
    workgroupBarrier();
    if (local == 0u) {
        shared_total = atomicLoad(&shared_count);
    }
    let shared_nodes = workgroupUniformLoad(&shared_total);
    var corner_vectors: array<mat3x3<f32>, 4>;
    if (shared_nodes > 0u) {
        corner_vectors = gather_at_corners(local, listed, corner_shadows);
    }
    var irradiance = vec3<f32>(0.0);
    if (r.covered) {
        // where the pixel lies on the corners' bilinear patch it takes the shared nodes
        // interpolated (else, across a depth edge, it evaluates them too), and with shadows the
        // visibility of the corners on its own surface (none: it marches its own shadow rays)
        let t = vec2<f32>(f32(local % TILE), f32(local / TILE)) / f32(TILE - 1u);
        let w = vec4<f32>((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
        var on_patch = false;
        var seen_weights = vec4<f32>(0.0);
        if (corners_covered) {
            var x = vec3<f32>(0.0);
            for (var c = 0u; c < 4u; c++) {
                let corner = CORNERS[c];
                x += w[c] * tile_x[corner];
                let same_surface = dot(tile_n[corner], r.n) > shade.normal_agreement
                    && abs(dot(r.x - tile_x[corner], tile_n[corner])) < terms.plane_agreement;
                seen_weights[c] = select(0.0, max(w[c], 1e-3), same_surface);
            }
            on_patch = distance(x, r.x) <= terms.plane_agreement;
            if (on_patch) {
                seen_weights = w;
            }
        }
        let seen_total = seen_weights.x + seen_weights.y + seen_weights.z + seen_weights.w;
        let corner_seen = corner_shadows && seen_total > 0.0;
        seen_weights /= max(seen_total, 1e-6);
        if (shared_nodes > 0u && on_patch) {
            var v = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
            for (var c = 0u; c < 4u; c++) {
                v += corner_vectors[c] * w[c];
            }
            irradiance += max(vec3<f32>(0.0), r.n * v);
        }
        for (var i = 0u; i < listed; i++) {
            let entry = frontier[0][i];
            if ((entry & SHARED) == 0u || !on_patch) {
                fetches++;
                let node = nodes[entry & ~SHARED];
                if (corner_seen) {
                    let seen = vec4<f32>((vec4<u32>(frontier[1][i]) >> vec4<u32>(0u, 1u, 2u, 3u)) & vec4<u32>(1u));
                    irradiance += dot(seen_weights, seen) * vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, r.x, r.n, terms.r_min);
                } else {
                    irradiance += node_irradiance(node, r);
                }
            }
        }
    }
    if (inside) {
        add_indirect(pixel_index(id.xy), vec4<f32>(r.albedo / PI * irradiance, 0.0));
    }
    if (local == 0u) {
        refused_splits = atomicLoad(&refused);
        tile_sizes[tile] = vec4<u32>(listed, refused_splits, atomicLoad(&estimated_nodes), atomicLoad(&estimate_evaluations));
    }
    store_tile_counts(id.xy, inside, local);
}
