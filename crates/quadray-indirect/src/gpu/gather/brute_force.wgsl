// The GPU reference: every VPL of the RSM, no clustering.

@compute @workgroup_size(8, 8)
fn brute_force(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        let size = params.rsm_size;
        let range = slice_range(size * size, SLICE);
        for (var i = range.x; i < range.y; i++) {
            let t = vec2<i32>(i32(i % size), i32(i / size));
            e += texel_irradiance(t, r);
        }
    }
    add_indirect(pixel_index(id.xy), vec4<f32>(r.albedo / PI * e, 0.0));
    store_counts(pixel_index(id.xy));
}
