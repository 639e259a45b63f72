// The split per-tile passes (`TilePasses::Split`, with indirect shadows only): the fused kernel's
// phases in three dispatches, so that the shadow walks run in a pass that holds almost no
// workgroup memory, with many waves resident to hide their fetches' latency, instead of between
// the kernel's barriers beside its kilobytes of workgroup memory.
// - `tile_lists`: the kernel up to the list, each listed node's target slot and shared mark
//   written back into `tile_cuts`, and the tile's shadow record (`tile_shadows`), no walk.
// - `tile_walks`: `tile_walk_lanes` threads a tile, each walking a target's rays from every
//   anchor (`anchor_bits`, the fused kernel's rays) and writing its visibility word.
// - `tile_sums`: each pixel's sum of the list from storage (every invocation reads the same
//   words), the receivers, anchors and patches recomputed as the first pass found them, the lone
//   pixels' walks as the fused kernel's.

// Group 3, binding 3: per tile a record of TILE_SHADOW_HEADER words (how many targets, the
// anchor sets, how many nodes are shared, then each anchor's receiver: position and normal, as
// f32 bits), then a word a target slot: its visibility bytes, the second set's in bits 8-15.
@group(3) @binding(3) var<storage, read_write> tile_shadows: array<u32>;

fn shadow_record(tile: u32) -> u32 {
    return tile * (TILE_SHADOW_HEADER + shade.tile_capacity);
}

// Anchor a's receiver in the record: position, then normal.
fn record_anchor(tile: u32, a: u32, normal: bool) -> vec3<f32> {
    let at = shadow_record(tile) + 3u + 6u * a + select(0u, 3u, normal);
    return bitcast<vec3<f32>>(vec3<u32>(tile_shadows[at], tile_shadows[at + 1u], tile_shadows[at + 2u]));
}

// The accessors of kernel.wgsl and anchors.wgsl: the list as `see_targets` wrote it back (the
// sum pass), and the anchors' receivers in the record (the walk pass).
fn list_node(tile: u32, i: u32) -> u32 {
    return tile_cuts[tile * shade.tile_capacity + i] & (ENTRY_INDEX | SHARED);
}

fn list_shadow(tile: u32, i: u32) -> u32 {
    let slot = (tile_cuts[tile * shade.tile_capacity + i] & ~SHARED) >> TILE_ENTRY_INDEX_BITS;
    return list_shadow_word(slot, tile_shadows[shadow_record(tile) + TILE_SHADOW_HEADER + slot]);
}

fn anchor_position(tile: u32, a: u32) -> vec3<f32> {
    return record_anchor(tile, a, false);
}

fn anchor_normal(tile: u32, a: u32) -> vec3<f32> {
    return record_anchor(tile, a, true);
}

// Phase 4, with shadows: what the walk and sum passes read of the tile, the targets' count, the
// anchor sets and the anchors' receivers, and each listed node's entry with its target's slot
// and its shared mark (SHARED in the flag's bit: every entry has a slot now). Every invocation
// calls it.
fn see_targets(local: u32, tile: u32, listed: u32, targets: u32, sets: u32) {
    let record = shadow_record(tile);
    if (local == 0u) {
        tile_shadows[record] = targets;
        tile_shadows[record + 1u] = sets;
    }
    if (local < 4u * sets) {
        let a = shadow_anchor(local);
        let words = array<vec3<u32>, 2>(bitcast<vec3<u32>>(tile_x[a]), bitcast<vec3<u32>>(tile_n[a]));
        for (var w = 0u; w < 6u; w++) {
            tile_shadows[record + 3u + 6u * local + w] = words[w / 3u][w % 3u];
        }
    }
    let base = tile * shade.tile_capacity;
    for (var i = local; i < listed; i += TILE_PIXELS) {
        tile_cuts[base + i] = frontier[0][i] | (frontier[1][i] << TILE_ENTRY_INDEX_BITS);
    }
}

@compute @workgroup_size(TILE, TILE)
fn tile_lists(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) tile_xy: vec3<u32>,
) {
    let inside = id.x < viewer.width && id.y < viewer.height;
    let tile = tile_xy.y * shade.tiles_x + tile_xy.x;
    let r = load_tile(id.xy, inside, local);
    if (tile_is_empty(local, r)) {
        if (local == 0u) {
            tile_sizes[tile] = vec4<u32>(0u);
            // (no target to walk to; no anchor set, the sum pass's sign of an empty tile)
            tile_shadows[shadow_record(tile)] = 0u;
            tile_shadows[shadow_record(tile) + 1u] = 0u;
        }
        store_tile_counts(id.xy, inside, local);
        return;
    }
    let t = open_tile(local, r);
    let shared_nodes = build_list(local, tile, t);
    if (local == 0u) {
        tile_shadows[shadow_record(tile) + 2u] = shared_nodes;
    }
    store_tile_sizes(tile, local);
    store_tile_counts(id.xy, inside, local);
}

// The walks' fetches of each of the workgroup's tiles, counted with the tile's first pixel.
var<workgroup> walk_fetches: array<atomic<u32>, MOST_WALKED_TILES>;

// 64 / `tile_walk_lanes` tiles of a row a workgroup, `tile_walk_lanes` threads a tile: each
// thread walks every `tile_walk_lanes`-th of its tile's targets, from each anchor of each set,
// and writes the target's visibility word.
@compute @workgroup_size(64)
fn tile_walks(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let lanes = shade.tile_walk_lanes;
    let held = local / lanes;
    let lane = local % lanes;
    let across = group.x * (64u / lanes) + held;
    // (a row's last workgroup may hold fewer tiles than it has room for)
    let in_row = across < shade.tiles_x;
    let tile = group.y * shade.tiles_x + min(across, shade.tiles_x - 1u);
    if (lane == 0u) {
        atomicStore(&walk_fetches[held], 0u);
    }
    workgroupBarrier();
    if (in_row) {
        let record = shadow_record(tile);
        let targets = min(tile_shadows[record], shade.tile_capacity);
        let sets = min(tile_shadows[record + 1u], 2u);
        let base = tile * shade.tile_capacity;
        for (var slot = lane; slot < targets; slot += lanes) {
            let index = tile_targets[base + slot];
            var bytes = 0u;
            for (var anchor_set = 0u; anchor_set < sets; anchor_set++) {
                for (var c = 0u; c < 4u; c++) {
                    bytes |= anchor_bits(tile, index, anchor_set, c) << (8u * anchor_set);
                }
            }
            tile_shadows[record + TILE_SHADOW_HEADER + slot] = bytes;
        }
    }
    atomicAdd(&walk_fetches[held], fetches);
    workgroupBarrier();
    if (in_row && lane == 0u) {
        let first = vec2<u32>(across, group.y) * TILE;
        counts[pixel_index(first)] += vec4<u32>(0u, atomicLoad(&walk_fetches[held]), 0u, 0u);
    }
}

// The sum pass's phase 1: each covered pixel offered as its corners' anchor (as
// `tile_is_empty` does), and whether the list's pass found the tile empty (it left no anchor
// set): read from the record, not reduced again over the tile (2 barriers, not 8). Every
// invocation calls it.
fn listed_tile_is_empty(local: u32, tile: u32, r: Receiver) -> bool {
    if (local == 0u) {
        anchor_sets = tile_shadows[shadow_record(tile) + 1u];
    }
    // (also publishes load_tile's stores before the atomics below)
    workgroupBarrier();
    if (r.covered) {
        offer_anchor(local, 0u);
    }
    return workgroupUniformLoad(&anchor_sets) == 0u;
}

@compute @workgroup_size(TILE, TILE)
fn tile_sums(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) tile_xy: vec3<u32>,
) {
    let inside = id.x < viewer.width && id.y < viewer.height;
    let tile = tile_xy.y * shade.tiles_x + tile_xy.x;
    let r = load_tile(id.xy, inside, local);
    if (listed_tile_is_empty(local, tile, r)) {
        if (inside) {
            add_indirect(pixel_index(id.xy), vec4<f32>(0.0));
        }
        store_tile_counts(id.xy, inside, local);
        return;
    }
    let t = open_tile(local, r);
    // what the list's pass found of the tile, for `sum_tile` and `lone_sums`
    if (local == 0u) {
        let record = shadow_record(tile);
        atomicStore(&target_count, tile_shadows[record]);
        anchor_sets = tile_shadows[record + 1u];
        shared_total = tile_shadows[record + 2u];
    }
    let shared_nodes = workgroupUniformLoad(&shared_total);
    sum_tile(id.xy, inside, local, tile, t, tile_sizes[tile].x, shared_nodes);
    store_tile_counts(id.xy, inside, local);
}
