// The two raster passes: the reflective shadow map from the spot light (flux, position + depth,
// normal) and the camera's G-buffer (position, normal, albedo). Cleared texels read as empty.

struct Raster {
    view_proj: mat4x4<f32>,
    // camera position for the G-buffer (normals are turned towards the viewer)
    eye: vec4<f32>,
    // x: solid angle of an RSM texel on the axis (it shrinks as cos^3 off axis)
    texel: vec4<f32>,
}

@group(0) @binding(0) var<uniform> light: Light;
@group(0) @binding(1) var<uniform> raster: Raster;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
}

@vertex
fn vertex(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) albedo: vec3<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = raster.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    out.albedo = albedo;
    return out;
}

fn facing(n: vec3<f32>, towards: vec3<f32>) -> vec3<f32> {
    let u = normalize(n);
    return select(-u, u, dot(u, towards) >= 0.0);
}

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
