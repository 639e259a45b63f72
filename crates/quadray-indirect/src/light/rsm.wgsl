// The reflective shadow map of one light view, in either layout (`GBufferLayout`): the wide one
// writes flux, position + depth and normal (w = 1 where the light sees geometry); the compact
// one the flux and the normal octahedral, the position and coverage left to the depth buffer.
// Cleared texels read as empty.

@group(0) @binding(1) var<uniform> light: Light;

struct WideOut {
    @location(0) flux: vec4<f32>,
    @location(1) pos: vec4<f32>,
    @location(2) normal: vec4<f32>,
}

struct CompactOut {
    @location(0) flux: vec4<f32>,
    @location(1) normal: vec2<f32>,
}

// Each texel is a VPL: flux = irradiance facing the light * the texel's area across the light
// * albedo; from a point that area is the texel's solid angle (the view's measure on the axis,
// shrinking as cos^3 off it) times d^2, so flux = I(w) * solid angle * albedo. That is the view's
// `rsm_flux_scale` (intensity * measure on the axis) times the texel's share of it, in [0, 1]:
// the spot's falloff, cos^3 and the albedo. The compact layout stores the share: a 512^2 map's
// flux lies below a half float's normal range (6.1e-5), where it keeps only a few bits.
fn texel_share(v: VertexOut) -> vec3<f32> {
    let albedo = surface_albedo(v);
    if (is_parallel(light)) {
        return albedo;
    }
    let w = light_towards(light, v.world);
    let cos_axis = dot(w, light.direction.xyz);
    return spot_edge(light, w) * cos_axis * cos_axis * cos_axis * albedo;
}

fn lit_normal(v: VertexOut) -> vec3<f32> {
    return facing(v.normal, -light_towards(light, v.world));
}

@fragment
fn rsm_wide(v: VertexOut) -> WideOut {
    var out: WideOut;
    out.flux = vec4<f32>(rsm_flux_scale(light) * texel_share(v), 1.0);
    out.pos = vec4<f32>(v.world, light_depth(light, v.world));
    out.normal = vec4<f32>(lit_normal(v), 1.0);
    return out;
}

@fragment
fn rsm_compact(v: VertexOut) -> CompactOut {
    var out: CompactOut;
    out.flux = vec4<f32>(texel_share(v), 1.0);
    out.normal = octahedral_encode(lit_normal(v));
    return out;
}
