// Indirect light from the light quadtree's compacted cut: every pixel sums the cut's clusters
// (the sum in gather_cut.wgsl).

// A part of this dispatch's slice of the cut.
fn cut_irradiance(r: Receiver, part: vec2<u32>) -> vec3<f32> {
    return cut_sum(r, part_range(slice_range(min(cut_count, arrayLength(&cut)), SLICE), part));
}

// The accessor gather_cut.wgsl reads the cut with.
fn load_cut_node(i: u32) -> Node {
    return cut[i];
}

@compute @workgroup_size(8, 8)
fn indirect_cut(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        e = cut_irradiance(r, WHOLE_SUM);
    }
    add_indirect(pixel_index(id.xy), vec4<f32>(r.albedo / PI * e, 0.0));
    store_counts(pixel_index(id.xy));
}

// What the sub-sampled and interleaved passes (upsample.wgsl) gather: a part of this dispatch's
// slice of the cut.
fn gathered_irradiance(r: Receiver, part: vec2<u32>) -> vec3<f32> {
    return cut_irradiance(r, part);
}
