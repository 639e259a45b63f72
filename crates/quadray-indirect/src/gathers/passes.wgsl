// Indirect light from the light quadtree the paper's way: one pass per level (the sum in
// gather_level.wgsl).

// One level of the paper's traversal: every node of the level, used when the top-down rule says
// so; adds to what the coarser levels' passes left (the buffer is cleared before the first).
@compute @workgroup_size(8, 8)
fn indirect_level(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    let index = pixel_index(id.xy);
    if (!r.covered) {
        store_counts(index);
        return;
    }
    let level = current.level;
    let size = level_size(params, level);
    let e = level_sum(params, level, r, slice_range(size * size, LEVEL_SLICE));
    indirect[index] += vec4<f32>(r.albedo / PI * e, 0.0);
    store_counts(index);
}
