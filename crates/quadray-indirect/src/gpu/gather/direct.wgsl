// Direct light from the spot, shadowed by the RSM depth.
@compute @workgroup_size(8, 8)
fn direct_light(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var l = vec3<f32>(0.0);
    if (r.covered) {
        let clip = light.view_proj * vec4<f32>(r.x, 1.0);
        let ndc = clip.xyz / clip.w;
        let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        let size = i32(params.rsm_size);
        let texel = clamp(vec2<i32>(floor(uv * f32(size))), vec2<i32>(0), vec2<i32>(size - 1));
        let occluder = textureLoad(rsm_pos, texel, 0);
        let inside = all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0)) && clip.w > 0.0;
        let lit = textureLoad(rsm_normal, texel, 0).w < 0.5
            || light_depth(light, r.x) <= occluder.w + terms.depth_bias;
        if (inside && lit) {
            let to_light = light.position.xyz - r.x;
            let d2 = dot(to_light, to_light);
            let w = to_light / sqrt(d2);
            l = r.albedo / PI * spot_intensity(light, -w) * max(0.0, dot(r.n, w)) / d2;
        }
    }
    direct[pixel_index(id.xy)] = vec4<f32>(l, select(0.0, 1.0, r.covered));
}
