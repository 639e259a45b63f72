// What the gather reads of the G-buffer and of a light view's RSM, in either layout, written out
// whole (three vec4 a pixel or texel, row-major) for the CPU reference: the CPU then sums the
// very receivers and VPLs the passes sum.

@group(3) @binding(0) var<storage, read_write> decoded: array<vec4<f32>>;

// Position (w: 1 where geometry is seen), normal, albedo.
@compute @workgroup_size(8, 8)
fn decode_gbuffer(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let t = vec2<i32>(id.xy);
    let i = 3u * pixel_index(id.xy);
    decoded[i] = load_g_position(t);
    decoded[i + 1u] = vec4<f32>(load_g_normal(t), 0.0);
    decoded[i + 2u] = vec4<f32>(textureLoad(g_albedo, t, 0).rgb, 0.0);
}

// Flux, position (w: depth along the light's axis), normal (w: 1 where the light sees geometry).
@compute @workgroup_size(8, 8)
fn decode_rsm(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.rsm_size || id.y >= params.rsm_size) {
        return;
    }
    let t = vec2<i32>(id.xy);
    let i = 3u * (id.y * params.rsm_size + id.x);
    decoded[i] = vec4<f32>(load_rsm_flux(t), 0.0);
    decoded[i + 1u] = load_rsm_position(t);
    decoded[i + 2u] = load_rsm_normal(t);
}
