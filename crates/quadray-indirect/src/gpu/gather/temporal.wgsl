// The temporal filter: the running average moves `temporal_weight` of the way to this frame's
// indirect light, and the frame shows the average (the recomputed flag stays this frame's).
@compute @workgroup_size(8, 8)
fn temporal_blend(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let index = pixel_index(id.xy);
    let now = indirect[index];
    let average = mix(history[index].rgb, now.rgb, shade.temporal_weight);
    history[index] = vec4<f32>(average, 0.0);
    indirect[index] = vec4<f32>(average, now.w);
}
