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
// * albedo; from a point that area is the texel's solid angle (raster.texel.x on the axis,
// shrinking as cos^3 off it) times d^2, so flux = I(w) * solid angle * albedo.
fn texel_flux(v: VertexOut) -> vec3<f32> {
    let w = light_towards(light, v.world);
    var measure = raster.texel.x;
    var flux = light.intensity.rgb;
    if (!is_parallel(light)) {
        let cos_axis = dot(w, light.direction.xyz);
        measure *= cos_axis * cos_axis * cos_axis;
        flux = spot_intensity(light, w);
    }
    return flux * measure * v.albedo;
}

fn lit_normal(v: VertexOut) -> vec3<f32> {
    return facing(v.normal, -light_towards(light, v.world));
}

@fragment
fn rsm_wide(v: VertexOut) -> WideOut {
    var out: WideOut;
    out.flux = vec4<f32>(texel_flux(v), 1.0);
    out.pos = vec4<f32>(v.world, light_depth(light, v.world));
    out.normal = vec4<f32>(lit_normal(v), 1.0);
    return out;
}

@fragment
fn rsm_compact(v: VertexOut) -> CompactOut {
    var out: CompactOut;
    out.flux = vec4<f32>(texel_flux(v), 1.0);
    out.normal = octahedral_encode(lit_normal(v));
    return out;
}
