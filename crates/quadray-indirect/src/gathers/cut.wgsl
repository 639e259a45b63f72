// Indirect light from the light quadtree's compacted cut: every pixel sums the cut's clusters
// (the sum in gather_cut.wgsl), with indirect shadows tested by the pixel itself or taken from
// the corner receivers around it (shadows/corners.wgsl).

// A part of this dispatch's slice of the cut: the segments of the part's classes, in turn, as
// one list (the whole cut: every class). Part `part.x` of `part.y` = N^2 (an offset in an NxN
// block) holds the classes whose offsets in the CUT_CLASS_SIDE^2 block are the same modulo N.
fn cut_irradiance(r: Receiver, part: vec2<u32>) -> vec3<f32> {
    from_corners = false;
    if (SHADOWS && shade.shadow_corners > 0u && !recomputing) {
        load_class_starts();
        from_corners = corner_patch(r);
    }
    let n = u32(round(sqrt(f32(part.y))));
    let offset = vec2<u32>(part.x % n, part.x / n);
    let per_side = CUT_CLASS_SIDE / n;
    let segment = arrayLength(&cut) / (CUT_CLASS_SIDE * CUT_CLASS_SIDE);
    let range = slice_range(arrayLength(&cut), SLICE);
    var e = vec3<f32>(0.0);
    var before = 0u;
    for (var j = 0u; j < per_side * per_side; j++) {
        let c = offset + n * vec2<u32>(j % per_side, j / per_side);
        let cut_class = c.x + CUT_CLASS_SIDE * c.y;
        let count = min(cut_count[1u + cut_class], segment);
        let first = max(range.x, before);
        let end = min(range.y, before + count);
        if (first < end) {
            e += cut_sum(r, vec2<u32>(first, end) - before + cut_class * segment);
        }
        before += count;
    }
    return e;
}

// Whether the receiver being summed takes its clusters' visibility from its corners' patch.
var<private> from_corners: bool;

// The accessor of gather_cut.wgsl: cluster `i` of the cut at `r`, its visibility the corners'
// where the receiver takes theirs.
fn cut_node_irradiance(i: u32, r: Receiver) -> vec3<f32> {
    let node = cut[i];
    if (!from_corners) {
        return node_irradiance(node, r);
    }
    let e = vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, r.x, r.n, terms.r_min);
    if (any(e != vec3<f32>(0.0))) {
        return e * corner_visibility(i, node, r);
    }
    return e;
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
