// The vertex stage both raster passes share (the RSM from the spot, the camera's G-buffer):
// world position, normal, albedo and the base colour texture's coordinate and layer per vertex
// (`base_colour.wgsl` samples it, in the passes that need the albedo).

// `Raster` is declared in Rust and generated into the prelude (contract.rs).

@group(0) @binding(0) var<uniform> raster: Raster;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) @interpolate(flat) texture: u32,
}

@vertex
fn vertex(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) texture: u32,
) -> VertexOut {
    var out: VertexOut;
    out.clip = raster.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    out.albedo = albedo;
    out.uv = uv;
    out.texture = texture;
    return out;
}

fn facing(n: vec3<f32>, towards: vec3<f32>) -> vec3<f32> {
    let u = normalize(n);
    return select(-u, u, dot(u, towards) >= 0.0);
}
