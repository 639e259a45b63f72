// The fused per-tile kernel (`TilePasses::Fused`): one workgroup a tile builds its cut, walks its
// shadow rays and sums, the list and the anchors' receivers in workgroup memory throughout.

// The accessors of kernel.wgsl and anchors.wgsl: the list as `list_for_gather` left it in the
// frontier, and the anchors' receivers among the tile's.
fn list_node(tile: u32, i: u32) -> u32 {
    return frontier[0][i];
}

fn list_shadow(tile: u32, i: u32) -> u32 {
    return frontier[1][i];
}

fn anchor_position(tile: u32, a: u32) -> vec3<f32> {
    return tile_x[shadow_anchor(a)];
}

fn anchor_normal(tile: u32, a: u32) -> vec3<f32> {
    return tile_n[shadow_anchor(a)];
}

// Phase 4, with shadows: the tile's invocations walk the targets' rays (`corner_visibility`),
// and each listed node's slot in frontier[1] becomes its `list_shadow`. Every invocation calls
// it.
fn see_targets(local: u32, tile: u32, listed: u32, targets: u32, sets: u32) {
    corner_visibility(local, tile, targets, sets);
    workgroupBarrier();
    for (var i = local; i < listed; i += TILE_PIXELS) {
        let slot = frontier[1][i];
        var bytes = verdict_byte(slot * sets);
        if (sets == 2u) {
            bytes |= verdict_byte(2u * slot + 1u) << 8u;
        }
        frontier[1][i] = list_shadow_word(slot, bytes);
    }
}

@compute @workgroup_size(TILE, TILE)
fn indirect_tiles(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) tile_xy: vec3<u32>,
) {
    let inside = id.x < viewer.width && id.y < viewer.height;
    let tile = tile_xy.y * shade.tiles_x + tile_xy.x;
    let r = load_tile(id.xy, inside, local);
    if (tile_is_empty(local, r)) {
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
    let t = open_tile(local, r);
    let shared_nodes = build_list(local, tile, t);
    sum_tile(id.xy, inside, local, tile, t, atomicLoad(&list_len), shared_nodes);
    store_tile_sizes(tile, local);
    store_tile_counts(id.xy, inside, local);
}
