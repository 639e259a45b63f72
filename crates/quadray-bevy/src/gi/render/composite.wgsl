// Into the view: `add_indirect` adds the gather's indirect radiance, scaled by the camera's
// exposure as Bevy scales its own light, to the lit picture (the pipeline blends One + One;
// alpha is kept). `draw_cut_view` draws the light quadtree's cut over the RSM (quadray's
// cut_view.wgsl, after node.wgsl, kernel.wgsl and cut_rule.wgsl) into the tone-mapped picture's
// top-left corner, within the pass's scissor rectangle.

struct Composite {
    width: u32,
    exposure: f32,
}

struct CutViewPlacement {
    zoom: u32,
}

@group(0) @binding(0) var<storage, read> indirect: array<vec4<f32>>;
@group(0) @binding(1) var<uniform> composite: Composite;
@group(0) @binding(2) var<uniform> params: ClusterParams;
@group(0) @binding(3) var<storage, read> nodes: array<Node>;
@group(0) @binding(4) var<uniform> placement: CutViewPlacement;

// The accessor of quadray's cut_rule.wgsl and cut_view.wgsl.
fn load_node(i: u32) -> Node {
    return nodes[i];
}

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

@fragment
fn draw_cut_view(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let colour = cut_view_pixel(params, placement.zoom, vec2<u32>(pixel.xy), cut_view_exposure(params));
    return vec4<f32>(colour, 1.0);
}
