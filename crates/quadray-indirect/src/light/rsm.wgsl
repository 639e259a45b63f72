// The reflective shadow map of one light view: flux, position + depth, normal. Cleared texels
// read as empty (normal.w = 0).

@group(0) @binding(1) var<uniform> light: Light;

struct RsmOut {
    @location(0) flux: vec4<f32>,
    @location(1) pos: vec4<f32>,
    @location(2) normal: vec4<f32>,
}

// Each texel is a VPL: flux = irradiance facing the light * the texel's area across the light
// * albedo; from a point that area is the texel's solid angle (raster.texel.x on the axis,
// shrinking as cos^3 off it) times d^2, so flux = I(w) * solid angle * albedo.
@fragment
fn rsm(v: VertexOut) -> RsmOut {
    let w = light_towards(light, v.world);
    var measure = raster.texel.x;
    var flux = light.intensity.rgb;
    if (!is_parallel(light)) {
        let cos_axis = dot(w, light.direction.xyz);
        measure *= cos_axis * cos_axis * cos_axis;
        flux = spot_intensity(light, w);
    }
    var out: RsmOut;
    out.flux = vec4<f32>(flux * measure * v.albedo, 1.0);
    out.pos = vec4<f32>(v.world, light_depth(light, v.world));
    out.normal = vec4<f32>(facing(v.normal, -w), 1.0);
    return out;
}
