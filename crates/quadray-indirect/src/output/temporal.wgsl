// The temporal filter: a running average of the indirect light, reprojected through the camera's
// motion. Each pixel's surface point is projected with the view of the frame the average holds;
// the average is read there (bilinear over the four nearest pixels that saw the same surface:
// their depth within SAME_SURFACE of the point's, their normal agreeing as the upsampler's must),
// moved `temporal_weight` of the way to this frame's light and stored with this frame's depth
// and normal. A point that frame did not see (disoccluded, across a crease, or outside its view)
// starts from this frame's light.

// The average as the last filtered frame left it (rgb, w: that pixel's depth, 0 where nothing
// was seen), that frame's world -> clip and its normals; this frame's normals.
@group(3) @binding(0) var<storage, read> previous: array<vec4<f32>>;
@group(3) @binding(1) var<storage, read> previous_view_proj: mat4x4<f32>;
@group(3) @binding(2) var<storage, read> previous_normal: array<vec4<f32>>;
@group(3) @binding(3) var<storage, read_write> history_normal: array<vec4<f32>>;

// relative depth difference under which a pixel of the last frame saw the same surface
const SAME_SURFACE: f32 = 0.01;

@compute @workgroup_size(8, 8)
fn temporal_blend(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let index = pixel_index(id.xy);
    let now = indirect[index];
    let r = receiver(id.xy);
    if (!r.covered) {
        history[index] = vec4<f32>(now.rgb, 0.0);
        history_normal[index] = vec4<f32>(0.0);
        return;
    }
    let then = previous_view_proj * vec4<f32>(r.x, 1.0);
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    if (then.w > 0.0) {
        let size = vec2<f32>(f32(viewer.width), f32(viewer.height));
        let uv = vec2<f32>(then.x / then.w * 0.5 + 0.5, 0.5 - then.y / then.w * 0.5);
        let xy = uv * size - 0.5;
        let corner = floor(xy);
        let f = xy - corner;
        for (var k = 0u; k < 4u; k++) {
            let offset = vec2<f32>(f32(k & 1u), f32(k >> 1u));
            let q = corner + offset;
            if (all(q >= vec2<f32>(0.0)) && all(q < size)) {
                let i = u32(q.y) * viewer.width + u32(q.x);
                let h = previous[i];
                let w = mix(1.0 - f, f, offset);
                let same_depth = h.w > 0.0 && abs(h.w - then.w) <= SAME_SURFACE * then.w;
                if (same_depth && dot(previous_normal[i].xyz, r.n) >= shade.normal_agreement) {
                    sum += w.x * w.y * h.rgb;
                    weight += w.x * w.y;
                }
            }
        }
    }
    var average = now.rgb;
    if (weight > 0.01) {
        average = mix(sum / weight, now.rgb, shade.temporal_weight);
    }
    let depth = (viewer.view_proj * vec4<f32>(r.x, 1.0)).w;
    history[index] = vec4<f32>(average, depth);
    history_normal[index] = vec4<f32>(r.n, 0.0);
    indirect[index] = vec4<f32>(average, now.w);
}
