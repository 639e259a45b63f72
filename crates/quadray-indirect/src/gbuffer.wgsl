// quadray's own G-buffer from the camera, in either layout (`GBufferLayout`): the wide one
// writes position (w = 1 where geometry is seen), normal (towards the viewer) and albedo; the
// compact one the normal octahedral and the albedo, the position left to the depth buffer.
// Cleared texels read as empty.

struct WideOut {
    @location(0) pos: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
}

struct CompactOut {
    @location(0) normal: vec2<f32>,
    @location(1) albedo: vec4<f32>,
}

fn viewed_normal(v: VertexOut) -> vec3<f32> {
    return facing(v.normal, raster.eye.xyz - v.world);
}

@fragment
fn gbuffer_wide(v: VertexOut) -> WideOut {
    var out: WideOut;
    out.pos = vec4<f32>(v.world, 1.0);
    out.normal = vec4<f32>(viewed_normal(v), 1.0);
    out.albedo = vec4<f32>(surface_albedo(v), 1.0);
    return out;
}

@fragment
fn gbuffer_compact(v: VertexOut) -> CompactOut {
    var out: CompactOut;
    out.normal = octahedral_encode(viewed_normal(v));
    out.albedo = vec4<f32>(surface_albedo(v), 1.0);
    return out;
}
