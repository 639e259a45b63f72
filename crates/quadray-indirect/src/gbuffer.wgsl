// quadray's own G-buffer from the camera: position, normal (towards the viewer), albedo; w = 1
// where geometry is seen, cleared texels read as empty.

struct GBufferOut {
    @location(0) pos: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
}

@fragment
fn gbuffer(v: VertexOut) -> GBufferOut {
    var out: GBufferOut;
    out.pos = vec4<f32>(v.world, 1.0);
    out.normal = vec4<f32>(facing(v.normal, raster.eye.xyz - v.world), 1.0);
    out.albedo = vec4<f32>(v.albedo, 1.0);
    return out;
}
