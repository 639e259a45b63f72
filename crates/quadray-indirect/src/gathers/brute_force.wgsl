// The GPU reference: every VPL of the RSM, no clustering (the sum in gather_vpls.wgsl).

@compute @workgroup_size(8, 8)
fn brute_force(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        let size = params.rsm_size;
        e = vpl_sum(r, size, terms.r_min, slice_range(size * size, SLICE));
    }
    add_indirect(pixel_index(id.xy), vec4<f32>(r.albedo / PI * e, 0.0));
    store_counts(pixel_index(id.xy));
}
