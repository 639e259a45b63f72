// RSM sampling (Dachsbacher & Stamminger 2005): N samples around the pixel's projection into the
// RSM, weights compensating the density (the sum in gather_vpls.wgsl).

// A part of this dispatch's slice of the Poisson-disk samples around `r`'s projection into the
// RSM.
fn sampled_irradiance(r: Receiver, part: vec2<u32>) -> vec3<f32> {
    let range = slice_range(min(shade.sample_count, arrayLength(&samples)), SLICE);
    return sampled_sum(r, light, params.rsm_size, terms.r_min, part_range(range, part));
}

@compute @workgroup_size(8, 8)
fn rsm_sampling(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        e = sampled_irradiance(r, WHOLE_SUM);
    }
    add_indirect(pixel_index(id.xy), vec4<f32>(r.albedo / PI * e, 0.0));
    store_counts(pixel_index(id.xy));
}

// What the sub-sampled and interleaved passes (upsample.wgsl) gather: a part of this
// dispatch's slice of the samples.
fn gathered_irradiance(r: Receiver, part: vec2<u32>) -> vec3<f32> {
    return sampled_irradiance(r, part);
}
