// Direct light from one light view, shadowed by its RSM depth; the first view writes, the others
// add. A texel's frustum is half-open, so a point light's faces light each point once.
@compute @workgroup_size(8, 8)
fn direct_light(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var l = vec3<f32>(0.0);
    if (r.covered) {
        let clip = light.view_proj * vec4<f32>(r.x, 1.0);
        let size = f32(params.rsm_size);
        let texel = map_texel(clip, vec2<f32>(size));
        if (texel.x >= 0) {
            let occluder = load_rsm_position(texel);
            let lit = load_rsm_normal(texel).w < 0.5
                || light_depth(light, r.x) <= occluder.w + terms.depth_bias;
            if (lit) {
                let w = light_towards(light, r.x);
                l = r.albedo / PI * light_irradiance(light, r.x) * max(0.0, -dot(r.n, w));
            }
        }
    }
    let index = pixel_index(id.xy);
    let value = vec4<f32>(l, select(0.0, 1.0, r.covered));
    if (first_view()) {
        direct[index] = value;
    } else {
        direct[index] += vec4<f32>(l, 0.0);
    }
}
