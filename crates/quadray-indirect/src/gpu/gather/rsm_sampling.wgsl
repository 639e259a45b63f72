// RSM sampling (Dachsbacher & Stamminger 2005): N samples around the pixel's projection into the
// RSM, weights compensating the density.

// This dispatch's slice of the Poisson-disk samples around `r`'s projection into the RSM.
fn sampled_irradiance(r: Receiver) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    let clip = light.view_proj * vec4<f32>(r.x, 1.0);
    let side = f32(params.rsm_size);
    // Receivers outside the spot's frustum (the walls beside and above it) project outside
    // the RSM or, behind the light, nowhere: centre their disk on the nearest RSM point, or
    // the middle, so that the disk still reaches the VPLs that light them.
    let ndc = clip.xy / max(clip.w, 1e-6);
    let projected = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * side;
    // (a blend, not `select`: Mesa 22.3's lavapipe crashes compiling a branch here)
    let behind = step(clip.w, 0.0);
    let centre = mix(clamp(projected, vec2<f32>(0.0), vec2<f32>(side)), vec2<f32>(0.5 * side), behind);
    // The pattern reaches sample.w texels; beyond the farthest corner there is nothing to
    // sample, so shrink it to that corner (weights scale with the disk's area).
    let corner = max(centre, vec2<f32>(side) - centre);
    let size = i32(params.rsm_size);
    let range = slice_range(min(shade.sample_count, arrayLength(&samples)), SLICE);
    for (var s = range.x; s < range.y; s++) {
        let sample = samples[s];
        let scale = min(1.0, length(corner) / sample.w);
        let t = vec2<i32>(floor(centre + sample.xy * scale));
        if (all(t >= vec2<i32>(0)) && all(t < vec2<i32>(size))) {
            e += sample.z * scale * scale * texel_irradiance(t, r);
        }
    }
    return e;
}

@compute @workgroup_size(8, 8)
fn rsm_sampling(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        e = sampled_irradiance(r);
    }
    add_indirect(pixel_index(id.xy), vec4<f32>(r.albedo / PI * e, 0.0));
    store_counts(pixel_index(id.xy));
}

// What the sub-sampled passes (upsample.wgsl) gather: this dispatch's slice of the samples.
fn gathered_irradiance(r: Receiver) -> vec3<f32> {
    return sampled_irradiance(r);
}
