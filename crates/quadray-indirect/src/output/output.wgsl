// Copies the gather's radiance into the caller's texture (same size as the gather's settings):
// the indirect term, the direct term or both, as the override TERM says.

override TERM: u32;

@group(0) @binding(0) var<storage, read> indirect: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> direct: array<vec4<f32>>;
@group(0) @binding(2) var output: texture_storage_2d<OUTPUT_FORMAT, write>;

@compute @workgroup_size(8, 8)
fn write_output(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(output);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let i = id.y * size.x + id.x;
    var rgb = vec3<f32>(0.0);
    if (TERM != OUTPUT_INDIRECT) {
        rgb = direct[i].rgb;
    }
    if (TERM != OUTPUT_DIRECT) {
        rgb += indirect[i].rgb;
    }
    textureStore(output, vec2<i32>(id.xy), vec4<f32>(rgb, 1.0));
}
