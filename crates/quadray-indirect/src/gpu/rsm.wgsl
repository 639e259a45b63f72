// The reflective shadow map from the spot light: flux, position + depth, normal. Cleared texels
// read as empty (normal.w = 0).

@group(0) @binding(1) var<uniform> light: Light;

struct RsmOut {
    @location(0) flux: vec4<f32>,
    @location(1) pos: vec4<f32>,
    @location(2) normal: vec4<f32>,
}

// Each texel is a VPL: flux = I(w) * solid angle * albedo.
@fragment
fn rsm(v: VertexOut) -> RsmOut {
    let to_point = v.world - light.position.xyz;
    let w = normalize(to_point);
    let cos_axis = dot(w, light.direction.xyz);
    let solid_angle = raster.texel.x * cos_axis * cos_axis * cos_axis;
    var out: RsmOut;
    out.flux = vec4<f32>(spot_intensity(light, w) * solid_angle * v.albedo, 1.0);
    out.pos = vec4<f32>(v.world, light_depth(light, v.world));
    out.normal = vec4<f32>(facing(v.normal, -to_point), 1.0);
    return out;
}
