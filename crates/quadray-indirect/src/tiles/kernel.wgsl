// Per-tile cuts: one workgroup a tile of TILE x TILE receivers refines the light quadtree level
// by level from its root by the rules of rule.wgsl, down to single VPLs where needed,
// then every pixel of the tile sums the tile's list. One function a phase: the receivers' box
// and groups, the coarse estimate (the threshold), the refinement, the far clusters shared at
// the tile's corners, the per-pixel sum. The fused kernel (`indirect_tiles`, fused.wgsl) runs
// them all in one workgroup, the list in workgroup memory; the split passes (split.wgsl) build
// the list into storage, walk its shadow rays in a pass of their own and sum it in a third. Each
// defines the accessors of the list these phases read (`list_node`, `list_shadow`), of the
// shadow anchors' receivers (`anchor_position`, `anchor_normal`) and what becomes of each
// tile's shadow targets (`see_targets`). Every invocation calls every phase that holds a
// barrier, and each loop around a barrier counts to a workgroup-uniform bound.

// Group 3, this pass's own: the per-tile cuts' lists (allocated by the first frame that draws
// them): each tile's entries (`tile_capacity` slots a tile: a node's index, with indirect
// shadows its visibility target's slot, see ENTRY_INDEX), per tile the nodes it holds, the
// splits refused for want of room, the nodes whose error it estimated and the VPL evaluations
// that took, and with indirect shadows each tile's visibility targets (`tile_capacity` slots a
// tile: the node whose mean the tile's shadow rays go to)
@group(3) @binding(0) var<storage, read_write> tile_cuts: array<u32>;
@group(3) @binding(1) var<storage, read_write> tile_sizes: array<vec4<u32>>;
@group(3) @binding(2) var<storage, read_write> tile_targets: array<u32>;

// the tile's receivers: position (EMPTY_BOX where none) and normal
var<workgroup> tile_x: array<vec3<f32>, TILE_PIXELS>;
var<workgroup> tile_n: array<vec3<f32>, TILE_PIXELS>;
// reductions over the tile's pixels: the receivers' box and normals (summed; w: how many), of
// the tile then of each group, each group's least cosine to its axis (x, y of reduce_n), and
// the coarse estimate at each quadrant's sample pixel with the start level's bounds (x of
// reduce_lo)
var<workgroup> reduce_lo: array<vec3<f32>, TILE_PIXELS>;
var<workgroup> reduce_hi: array<vec3<f32>, TILE_PIXELS>;
var<workgroup> reduce_n: array<vec4<f32>, TILE_PIXELS>;
var<workgroup> reduce_e: array<vec4<f32>, TILE_PIXELS>;
// per quadrant of the tile, its first covered pixel (TILE_PIXELS: none): the estimate's
// sample pixels
var<workgroup> quadrant_pixel: array<atomic<u32>, 4>;
// per corner of the tile, its shadow anchors: the covered pixel nearest it (the corner itself
// where covered), then with shadows the nearest of the pixels on none of the first four's
// surfaces (`second_anchors`), as its squared distance in pixels << 8 | the pixel; how many
// pixels those are, and the anchor sets the tile walks from (1 or 2, `list_for_gather`)
var<workgroup> anchor_key: array<atomic<u32>, 8>;
var<workgroup> off_anchor_count: atomic<u32>;
var<workgroup> off_anchor_total: u32;
var<workgroup> anchor_sets: u32;
// The pixels off the first set's surfaces above which a tile walks from a second set too (four
// rays a target instead of one a pixel and target: lone pixels' walks were 9-12% of the
// indirect pass with shadows on the courtyard, leak and shelf scenes, the second set took the
// pass to 0.89-0.94x the time).
const SECOND_ANCHORS_FROM: u32 = 4u;
// the nodes of the level being refined and of the next (pyramid indices); then the list as the
// gather reads it (`list_for_gather`)
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
// VERDICT_EMPTY, or its split bin (`split_bin`); how many nodes want a split in each bin; the
// bin at or below which splits are refused (the one at it split while room is left)
const VERDICT_LIST: u32 = 0u;
const VERDICT_EMPTY: u32 = 255u;
var<workgroup> verdicts: array<atomic<u32>, TILE_FRONTIER / 4u>;
var<workgroup> split_bins: array<atomic<u32>, SPLIT_BINS>;
var<workgroup> split_cutoff: u32;
// work of the threads whose pixel lies outside the picture, counted with the tile's first pixel
var<workgroup> stray: array<atomic<u32>, 3>;
// a listed node shared at the corners (`shareable`) is marked in the gather's copy of the list
const SHARED: u32 = 0x80000000u;
var<workgroup> shared_count: atomic<u32>;
var<workgroup> shared_total: u32;
// Indirect shadows share their rays among a tile's clusters: a listed node whose ancestor is
// small seen from the tile's receivers (`tile_shadow_angle`, `is_shadow_target`) takes that
// ancestor's visibility, so that a tile walks once to each such ancestor's mean rather than to
// each of its listed descendants (BENCHMARKS.md). A frontier's or a list's entry is the node's index
// (ENTRY_INDEX, TILE_ENTRY_INDEX_BITS of them), and once an ancestor or the node itself
// became a target, ENTRY_TARGETED and the target's slot; the targets' nodes are in
// `tile_targets`, their visibility from the corners in `verdicts` once refinement is done.
const ENTRY_INDEX: u32 = (1u << TILE_ENTRY_INDEX_BITS) - 1u;
// (SHARED's bit: the gather's copy of the list is marked only once the entries are read)
const ENTRY_TARGETED: u32 = 0x80000000u;
var<workgroup> target_count: atomic<u32>;
// the lone pixels (`lone_sums`): how many, each row's pixel (a byte, four to a word), and the
// batches their walks take
var<workgroup> lone_count: atomic<u32>;
var<workgroup> lone_pixels: array<atomic<u32>, TILE_PIXELS / 4u>;
var<workgroup> lone_batches: u32;

// The accessors of rule.wgsl.
fn tile_position(p: u32) -> vec3<f32> {
    return tile_x[p];
}

fn tile_normal(p: u32) -> vec3<f32> {
    return tile_n[p];
}

fn tile_sample(q: u32) -> u32 {
    return atomicLoad(&quadrant_pixel[q]);
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

// The tile's list length, refused splits and estimates (`tile_sizes`); its refused splits count
// with its first pixel.
fn store_tile_sizes(tile: u32, local: u32) {
    if (local == 0u) {
        refused_splits = atomicLoad(&refused);
        tile_sizes[tile] = vec4<u32>(atomicLoad(&list_len), refused_splits, atomicLoad(&estimated_nodes), atomicLoad(&estimate_evaluations));
    }
}

// Phase 1, then, of every pass over a tile that has receivers (`tile_is_empty` false): the
// pixel's patch and the tile's shadow anchors (both sets). Every invocation calls it.
struct OpenTile {
    r: Receiver,
    corners_covered: bool,
    shape: PixelPatch,
    // the pixels off the first anchor set's surfaces (`second_anchors`)
    off_anchor: u32,
}

fn open_tile(local: u32, r: Receiver) -> OpenTile {
    var t: OpenTile;
    t.r = r;
    t.corners_covered = all_corners_covered();
    t.shape = pixel_patch(local, r, t.corners_covered);
    if (SHADOWS) {
        t.off_anchor = second_anchors(local, r, t.shape);
    }
    return t;
}

// Phases 1 to 4 of a tile that has receivers: its cut refined into `tile_cuts` (`list_len`
// entries), then the list for the gather (`list_for_gather`); how many nodes it shares at the
// corners. Every invocation calls it.
fn build_list(local: u32, tile: u32, t: OpenTile) -> u32 {
    let groups = receiver_groups(local, t.r);
    let threshold = coarse_threshold(local, groups);
    refine(local, tile, groups, threshold);
    storageBarrier();
    let listed = atomicLoad(&list_len);
    let sharing = shade.tile_share > 0.0 && t.corners_covered;
    return list_for_gather(local, tile, listed, groups, sharing, t.off_anchor);
}

// Phase 5: the pixel's indirect light from its tile's list of `listed` nodes, `shared_nodes`
// of them shared at the corners, its visibility known (`anchor_sets` and `target_count` set).
// Every invocation calls it.
fn sum_tile(pixel: vec2<u32>, inside: bool, local: u32, tile: u32, t: OpenTile, listed: u32, shared_nodes: u32) {
    let r = t.r;
    var shape = t.shape;
    var corner_vectors: array<mat3x3<f32>, 4>;
    if (shared_nodes > 0u) {
        corner_vectors = gather_at_corners(local, tile, listed);
    }
    let sets = workgroupUniformLoad(&anchor_sets);
    if (SHADOWS && sets == 2u && is_lone(r, shape)) {
        shape = second_patch(local, r, shape);
    }
    let lone = is_lone(r, shape);
    var irradiance = vec3<f32>(0.0);
    if (SHADOWS) {
        irradiance = lone_sums(local, tile, r, listed, lone);
    }
    if (r.covered && !lone) {
        irradiance = pixel_sum(tile, r, listed, shared_nodes > 0u, shape, corner_vectors);
    }
    if (inside) {
        add_indirect(pixel_index(pixel), vec4<f32>(r.albedo / PI * irradiance, 0.0));
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

// Phase 0: the pixel's receiver into the tile's, the workgroup's state cleared. Every
// invocation calls it.
fn load_tile(pixel: vec2<u32>, inside: bool, local: u32) -> Receiver {
    var r: Receiver;
    if (inside) {
        r = receiver(pixel);
    }
    // an uncovered pixel far away: never the one nearest a node
    tile_x[local] = select(vec3<f32>(EMPTY_BOX), r.x, r.covered);
    tile_n[local] = r.n;
    if (local < 4u) {
        atomicStore(&quadrant_pixel[local], TILE_PIXELS);
    }
    if (local < 8u) {
        atomicStore(&anchor_key[local], 0xffffffffu);
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
        atomicStore(&target_count, 0u);
        atomicStore(&off_anchor_count, 0u);
        atomicStore(&refused, 0u);
        atomicStore(&estimated_nodes, 0u);
        atomicStore(&estimate_evaluations, 0u);
    }
    return r;
}

// Phase 1: the receivers' box (left in reduce_lo[0], reduce_hi[0]), each quadrant's sample
// pixel and each corner's shadow anchor; whether the tile has no receiver. Every invocation
// calls it.
fn tile_is_empty(local: u32, r: Receiver) -> bool {
    // (its first barrier also publishes load_tile's stores before the atomicMin below)
    reduce_receivers(local, r, r.covered);
    if (r.covered) {
        atomicMin(&quadrant_pixel[(local % TILE) / (TILE / 2u) + 2u * (local / (TILE_PIXELS / 2u))], local);
        offer_anchor(local, 0u);
    }
    return workgroupUniformLoad(&reduce_n[0]).w == 0.0;
}

// Phase 1, then: the two groups of receivers, their boxes and normal cones (a node's bound is
// the larger of the two groups'). Every invocation calls it.
fn receiver_groups(local: u32, r: Receiver) -> TileGroups {
    let group = receiver_group(r.x, reduce_lo[0], reduce_hi[0]);
    var g: TileGroups;
    for (var h = 0u; h < 2u; h++) {
        workgroupBarrier();
        reduce_receivers(local, r, r.covered && group == h);
        g.lo[h] = reduce_lo[0];
        g.hi[h] = reduce_hi[0];
        g.axis[h] = group_axis(reduce_n[0].xyz);
    }
    workgroupBarrier();
    // each group's least cosine to its axis (x: group 0, y: group 1)
    let cos_own = select(1.0, dot(r.n, g.axis[group]), r.covered);
    reduce_n[local] = vec4<f32>(select(1.0, cos_own, group == 0u), select(1.0, cos_own, group == 1u), 0.0, 0.0);
    workgroupBarrier();
    for (var stride = TILE_PIXELS / 2u; stride > 0u; stride >>= 1u) {
        if (local < stride) {
            reduce_n[local] = min(reduce_n[local], reduce_n[local + stride]);
        }
        workgroupBarrier();
    }
    g.cone = group_cone(reduce_n[0].xy);
    return g;
}

// Phase 2: the coarse estimate, the nodes of level `tile_start` at each quadrant's sample pixel,
// and the threshold from it (from their bounds at the tile's receivers where it is zero). Every
// invocation calls it.
fn coarse_threshold(local: u32, g: TileGroups) -> f32 {
    let side = level_size(params, shade.tile_start);
    let first = level_offset(params, shade.tile_start);
    var e = vec4<f32>(0.0);
    var bounded = 0.0;
    for (var i = local; i < side * side; i += TILE_PIXELS) {
        fetches++;
        let node = nodes[first + i];
        if (node.flux.w > 0.5) {
            e += coarse_light(node, terms.r_min);
            fetches++;
            bounded += tile_bound(node, bounds[first + i], g, terms.r_min);
        }
    }
    reduce_e[local] = e;
    reduce_lo[local].x = bounded;
    workgroupBarrier();
    for (var stride = TILE_PIXELS / 2u; stride > 0u; stride >>= 1u) {
        if (local < stride) {
            reduce_e[local] += reduce_e[local + stride];
            reduce_lo[local].x += reduce_lo[local + stride].x;
        }
        workgroupBarrier();
    }
    return tile_threshold(shade.tile_error, reduce_e[0], reduce_lo[0].x);
}

// Phase 3: refinement, one level a step, from the root so that far tiles may keep clusters
// coarser than the estimate's: every node's verdict (`judge_level`), as many splits as the list
// has room for, the highest bins first (Lightcuts splits the largest bound first), then the
// splits made and the rest listed. Every invocation calls it.
fn refine(local: u32, tile: u32, g: TileGroups, threshold: f32) {
    let root = params.levels - 1u;
    if (local == 0u) {
        frontier[0][0] = level_offset(params, root);
        atomicStore(&frontier_len[0], 1u);
        atomicStore(&reserved, 1u);
    }
    workgroupBarrier();
    for (var step = 0u; step <= root; step++) {
        let level = root - step;
        let current = step & 1u;
        let count = atomicLoad(&frontier_len[current]);
        judge_level(local, tile, level, current, count, g, threshold);
        workgroupBarrier();
        if (local == 0u) {
            grant_splits();
        }
        workgroupBarrier();
        apply_verdicts(local, tile, level, current, count);
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
}

// A level's verdicts: empty, listed (under the threshold by its bound, or by its estimated error
// where the estimate decides), or the node's split bin.
fn judge_level(local: u32, tile: u32, level: u32, current: u32, count: u32, g: TileGroups, threshold: f32) {
    let size = level_size(params, level);
    let offset = level_offset(params, level);
    for (var i = local; i < count; i += TILE_PIXELS) {
        let entry = frontier[current][i];
        let index = entry & ENTRY_INDEX;
        fetches++;
        let node = nodes[index];
        var verdict = VERDICT_LIST;
        if (node.flux.w < 0.5) {
            verdict = VERDICT_EMPTY;
            atomicSub(&reserved, 1u);
        } else if (level > 0u) {
            fetches++;
            let b = bounds[index];
            if (SHADOWS && (entry & ENTRY_TARGETED) == 0u && is_shadow_target(node, b, g)) {
                let slot = atomicAdd(&target_count, 1u);
                tile_targets[tile * shade.tile_capacity + slot] = index;
                frontier[current][i] = entry | ENTRY_TARGETED | (slot << TILE_ENTRY_INDEX_BITS);
            }
            var excess = tile_bound(node, b, g, terms.r_min);
            if (excess > threshold && estimate_decides(shade.tile_estimate == 1u, level, shade.tile_start, threshold, b, terms.r_min)) {
                let before = evaluations;
                excess = estimated_error(params, node, index - offset, size, level, terms.r_min);
                atomicAdd(&estimated_nodes, 1u);
                atomicAdd(&estimate_evaluations, evaluations - before);
            }
            let bin = split_bin(excess, threshold);
            if (bin > 0u) {
                atomicAdd(&split_bins[bin - 1u], 1u);
                verdict = bin;
            }
        }
        atomicOr(&verdicts[i / 4u], verdict << (8u * (i % 4u)));
    }
}

// Whether a node (not empty) is its listed descendants' visibility target: its box's diagonal at
// most `tile_shadow_angle` times its distance from the receivers' box, MIXED_TARGET_ANGLE of
// that where the node is not valid (several surfaces).
fn is_shadow_target(node: Node, b: NodeBounds, g: TileGroups) -> bool {
    let lo = min(g.lo[0], g.lo[1]);
    let hi = max(g.hi[0], g.hi[1]);
    let gap = max(vec3<f32>(0.0), max(b.lo.xyz - hi, lo - b.hi.xyz));
    let angle = shade.tile_shadow_angle * select(MIXED_TARGET_ANGLE, 1.0, node.normal.w > 0.5);
    return angle > 0.0 && length(b.hi.xyz - b.lo.xyz) <= angle * length(gap);
}

// The bins above the cutoff all fit and have their room reserved here; the cutoff bin's nodes
// split while room is left (`apply_verdicts`).
fn grant_splits() {
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

// A level's splits into the next frontier, its other nodes into the tile's list.
fn apply_verdicts(local: u32, tile: u32, level: u32, current: u32, count: u32) {
    let size = level_size(params, level);
    let offset = level_offset(params, level);
    let next = current ^ 1u;
    let cutoff = split_cutoff;
    for (var i = local; i < count; i += TILE_PIXELS) {
        let verdict = (atomicLoad(&verdicts[i / 4u]) >> (8u * (i % 4u))) & 255u;
        if (verdict == VERDICT_EMPTY) {
            continue;
        }
        let entry = frontier[current][i];
        let index = entry & ENTRY_INDEX;
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
                frontier[next][slot + c] = node_index(params, level - 1u, child) | (entry & ~ENTRY_INDEX);
            }
        } else {
            tile_cuts[tile * shade.tile_capacity + atomicAdd(&list_len, 1u)] = entry;
        }
    }
}

// Phase 4: the list copied once into workgroup memory (the frontier's, free now), far nodes
// marked to be shared; with indirect shadows every listed node without a target its own (its
// slot in frontier[1]), and the tile's targets seen from its anchors (`see_targets`: one set,
// or the second too where more than SECOND_ANCHORS_FROM pixels are off the first set's
// surfaces, `off_anchor`); how many nodes are shared. Every invocation calls it.
fn list_for_gather(local: u32, tile: u32, listed: u32, g: TileGroups, sharing: bool, off_anchor: u32) -> u32 {
    let base = tile * shade.tile_capacity;
    let lo = min(g.lo[0], g.lo[1]);
    let hi = max(g.hi[0], g.hi[1]);
    if (local == 0u) {
        atomicStore(&shared_count, 0u);
    }
    workgroupBarrier();
    for (var i = local; i < listed; i += TILE_PIXELS) {
        fetches++;
        let entry = tile_cuts[base + i];
        var index = entry & ENTRY_INDEX;
        if (SHADOWS) {
            var slot = (entry & ~ENTRY_TARGETED) >> TILE_ENTRY_INDEX_BITS;
            if ((entry & ENTRY_TARGETED) == 0u) {
                slot = atomicAdd(&target_count, 1u);
                tile_targets[base + slot] = index;
            }
            frontier[1][i] = slot;
        }
        if (sharing) {
            fetches++;
            if (shareable(bounds[index], lo, hi, shade.tile_share)) {
                index |= SHARED;
                atomicAdd(&shared_count, 1u);
            }
        }
        frontier[0][i] = index;
    }
    if (SHADOWS) {
        // (the targets' nodes in storage, the verdicts cleared by refinement's last step)
        storageBarrier();
        let targets = atomicLoad(&target_count);
        // a second set where it walks fewer rays than its pixels would alone, and each target's
        // two bytes fit
        let sets = select(1u, 2u, off_anchor > SECOND_ANCHORS_FROM && 2u * targets <= TILE_FRONTIER);
        if (local == 0u) {
            anchor_sets = sets;
        }
        see_targets(local, tile, listed, targets, sets);
    }
    workgroupBarrier();
    if (local == 0u) {
        shared_total = atomicLoad(&shared_count);
    }
    return workgroupUniformLoad(&shared_total);
}

// A listed node's visibility as `list_shadow` gives it: its target's slot << 16, then its
// target's visibility byte from each anchor set (`corner_visibility`, the second set's in bits
// 8-15).
fn list_shadow_word(slot: u32, bytes: u32) -> u32 {
    return (slot << 16u) | bytes;
}

// Byte `i` of `verdicts`.
fn verdict_byte(i: u32) -> u32 {
    return (atomicLoad(&verdicts[i / 4u]) >> (8u * (i % 4u))) & 255u;
}

// Phase 4, then: the shared nodes' vector irradiance at each corner receiver (with indirect
// shadows, those the corner sees): a quarter of the workgroup per corner, each thread a share of
// the nodes, then summed per corner (one colour channel in each of the reduction arrays). Every
// invocation calls it.
fn gather_at_corners(local: u32, tile: u32, listed: u32) -> array<mat3x3<f32>, 4> {
    let x = tile_x[CORNERS[local % 4u]];
    var v = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    for (var i = local / 4u; i < listed; i += TILE_PIXELS / 4u) {
        let entry = list_node(tile, i);
        if ((entry & SHARED) != 0u) {
            fetches++;
            let node = nodes[entry & ~SHARED];
            // (evaluated either way, as a pixel's own sum does before its shadow test; a corner
            // the node does not face had no ray, and gets no light from it)
            let seen = !SHADOWS || ((list_shadow(tile, i) >> (local % 4u)) & 1u) == 1u;
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

// Phase 5: a covered pixel's sum of its tile's list (a lone one's is `lone_sums`'). On the
// corners' patch it takes the shared nodes interpolated from `corner_vectors`, and with shadows
// each node's target's visibility from the anchors on its own surface, interpolated.
fn pixel_sum(tile: u32, r: Receiver, listed: u32, shared_nodes: bool, shape: PixelPatch, corner_vectors: array<mat3x3<f32>, 4>) -> vec3<f32> {
    var irradiance = vec3<f32>(0.0);
    if (shared_nodes && shape.on_patch) {
        var v = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
        for (var c = 0u; c < 4u; c++) {
            v += corner_vectors[c] * shape.w[c];
        }
        irradiance += max(vec3<f32>(0.0), r.n * v);
    }
    for (var i = 0u; i < listed; i++) {
        let entry = list_node(tile, i);
        if ((entry & SHARED) == 0u || !shape.on_patch) {
            fetches++;
            let node = nodes[entry & ~SHARED];
            var seen = 1.0;
            if (SHADOWS) {
                let bits = vec4<u32>((list_shadow(tile, i) >> (8u * shape.anchor_set)) & 255u) >> vec4<u32>(0u, 1u, 2u, 3u);
                let lit = shape.seen_weights * vec4<f32>((bits >> vec4<u32>(4u)) & vec4<u32>(1u));
                let lit_total = lit.x + lit.y + lit.z + lit.w;
                // (no corner on the pixel's surface faces the node: the node lies nearly in
                // that surface's plane, and its little light there counts as seen)
                if (lit_total > 0.0) {
                    seen = dot(lit, vec4<f32>(bits & vec4<u32>(1u))) / lit_total;
                }
            }
            irradiance += seen * vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, r.x, r.n, terms.r_min);
        }
    }
    return irradiance;
}
