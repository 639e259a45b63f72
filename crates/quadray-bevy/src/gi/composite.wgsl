// Adds the gather's indirect radiance, scaled by the camera's exposure as Bevy scales its own
// light, to the lit picture (the pipeline blends One + One; alpha is kept).

struct Composite {
    width: u32,
    exposure: f32,
}

@group(0) @binding(0) var<storage, read> indirect: array<vec4<f32>>;
@group(0) @binding(1) var<uniform> composite: Composite;

@vertex
fn fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn add_indirect(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let radiance = indirect[u32(pixel.y) * composite.width + u32(pixel.x)].rgb;
    return vec4<f32>(radiance * composite.exposure, 0.0);
}
