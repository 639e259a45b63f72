// The reference (every VPL of the RSM, no clustering) and RSM sampling (Dachsbacher & Stamminger
// 2005: N samples around the pixel's projection into the RSM, weights compensating the density).

@compute @workgroup_size(8, 8)
fn brute_force(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= shade.width || id.y >= shade.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        let size = params.rsm_size;
        for (var i = 0u; i < min(size * size, LOOP_CAP); i++) {
            let t = vec2<i32>(i32(i % size), i32(i / size));
            let n = textureLoad(rsm_normal, t, 0);
            if (n.w > 0.5) {
                let p = textureLoad(rsm_pos, t, 0);
                let flux = textureLoad(rsm_flux, t, 0).rgb;
                e += vpl_irradiance(flux, p.xyz, n.xyz, r.x, r.n, shade.r_min);
            }
        }
    }
    indirect[pixel_index(id.xy)] = vec4<f32>(r.albedo / PI * e, 0.0);
}

@compute @workgroup_size(8, 8)
fn rsm_sampling(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= shade.width || id.y >= shade.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        let clip = light.view_proj * vec4<f32>(r.x, 1.0);
        let ndc = clip.xy / clip.w;
        let centre = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * f32(params.rsm_size);
        let size = i32(params.rsm_size);
        for (var s = 0u; s < min(shade.sample_count, arrayLength(&samples)); s++) {
            let sample = samples[s];
            let t = vec2<i32>(floor(centre + sample.xy));
            if (all(t >= vec2<i32>(0)) && all(t < vec2<i32>(size))) {
                let n = textureLoad(rsm_normal, t, 0);
                if (n.w > 0.5) {
                    let p = textureLoad(rsm_pos, t, 0);
                    let flux = textureLoad(rsm_flux, t, 0).rgb;
                    e += sample.z * vpl_irradiance(flux, p.xyz, n.xyz, r.x, r.n, shade.r_min);
                }
            }
        }
    }
    indirect[pixel_index(id.xy)] = vec4<f32>(r.albedo / PI * e, 0.0);
}
