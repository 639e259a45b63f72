// An RSM texel as its readers see it (the quadtree's packing, the gather's sums, direct light and
// the light's depth map in indirect shadows), in either layout (`GBufferLayout`). The including
// shader binds `rsm_flux`, `rsm_pos` (the compact layout: the light view's depth) and
// `rsm_normal` (the compact layout: octahedral), the view's `light` and `params`. Depths are
// reversed (`reversed_depth` in light/view.rs).

// Whether the RSM is compact: a pipeline constant, so that each layout compiles its own reads.
override COMPACT_RSM: bool;

// Texel t's unit normal facing the light; w: 1 where the light sees geometry, else 0.
fn load_rsm_normal(t: vec2<i32>) -> vec4<f32> {
    let texel = textureLoad(rsm_normal, t, 0);
    if (COMPACT_RSM) {
        // where the light sees nothing the (reversed) depth keeps its cleared 0
        let seen = textureLoad(rsm_pos, t, 0).x > 0.0;
        return select(vec4<f32>(0.0), vec4<f32>(octahedral_decode(texel.xy), 1.0), seen);
    }
    return texel;
}

// Texel t's world position; w: its depth along the light's axis (`light_depth`); all 0 where the
// light sees nothing.
fn load_rsm_position(t: vec2<i32>) -> vec4<f32> {
    let texel = textureLoad(rsm_pos, t, 0);
    if (COMPACT_RSM) {
        let size = vec2<f32>(f32(params.rsm_size));
        let x = unproject(light.inv_view_proj, light.position.xyz, t, size, texel.x);
        return select(vec4<f32>(0.0), vec4<f32>(x, light_depth(light, x)), texel.x > 0.0);
    }
    return texel;
}

// Texel t's flux (W; the compact layout stores its share of `rsm_flux_scale`, rsm.wgsl).
fn load_rsm_flux(t: vec2<i32>) -> vec3<f32> {
    let texel = textureLoad(rsm_flux, t, 0).rgb;
    if (COMPACT_RSM) {
        return texel * rsm_flux_scale(light);
    }
    return texel;
}
