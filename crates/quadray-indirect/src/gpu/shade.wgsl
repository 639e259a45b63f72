// Indirect light from the light quadtree: from the compacted cut, or the paper's way with one
// pass per level; optionally at low resolution with geometry-aware upsampling. Direct light from
// the spot with the RSM depth as shadow map.

// This dispatch's slice of the cut.
fn cut_irradiance(r: Receiver) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    let range = slice_range(min(cut_count, arrayLength(&cut)), SLICE);
    for (var i = range.x; i < range.y; i++) {
        e += node_irradiance(cut[i], r);
    }
    fetches += range.y - min(range.x, range.y);
    return e;
}

@compute @workgroup_size(8, 8)
fn indirect_cut(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        e = cut_irradiance(r);
    }
    add_indirect(pixel_index(id.xy), vec4<f32>(r.albedo / PI * e, 0.0));
    store_counts(pixel_index(id.xy));
}

// One level of the paper's traversal: every node of the level, used when the top-down rule says
// so; adds to what the coarser levels' passes left (the buffer is cleared before the first).
@compute @workgroup_size(8, 8)
fn indirect_level(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    let index = pixel_index(id.xy);
    if (!r.covered) {
        store_counts(index);
        return;
    }
    let level = current.level;
    let size = level_size(params, level);
    var e = vec3<f32>(0.0);
    let range = slice_range(size * size, LEVEL_SLICE);
    for (var i = range.x; i < range.y; i++) {
        let xy = vec2<u32>(i % size, i / size);
        if (in_cut(params, level, xy)) {
            fetches++;
            e += node_irradiance(nodes[level_offset(params, level) + i], r);
        }
    }
    indirect[index] += vec4<f32>(r.albedo / PI * e, 0.0);
    store_counts(index);
}

// The full-resolution pixel a low-resolution sample stands for.
fn low_pixel(low_xy: vec2<u32>) -> vec2<u32> {
    let p = low_xy * shade.subsample + vec2<u32>(shade.subsample / 2u);
    return min(p, vec2<u32>(viewer.width - 1u, viewer.height - 1u));
}

// This dispatch's slice of the sum a sub-sampled method gathers: the cut's clusters, or RSM
// sampling's samples (`sampled`).
fn gathered_irradiance(r: Receiver, sampled: bool) -> vec3<f32> {
    if (sampled) {
        return sampled_irradiance(r);
    }
    return cut_irradiance(r);
}

// One low-resolution sample's irradiance (w: 1 where it sees geometry).
fn low_sample(low_xy: vec2<u32>, sampled: bool) {
    if (low_xy.x >= shade.low_width || low_xy.y >= shade.low_height) {
        return;
    }
    let r = receiver(low_pixel(low_xy));
    var e = vec3<f32>(0.0);
    if (r.covered) {
        e = gathered_irradiance(r, sampled);
    }
    let index = low_xy.y * shade.low_width + low_xy.x;
    if (slice.level == 0u) {
        low[index] = vec4<f32>(e, select(0.0, 1.0, r.covered));
    } else {
        low[index] += vec4<f32>(e, 0.0);
    }
    let full = low_pixel(low_xy);
    store_counts(full.y * viewer.width + full.x);
}

@compute @workgroup_size(8, 8)
fn indirect_low(@builtin(global_invocation_id) id: vec3<u32>) {
    low_sample(id.xy, false);
}

@compute @workgroup_size(8, 8)
fn sampled_low(@builtin(global_invocation_id) id: vec3<u32>) {
    low_sample(id.xy, true);
}

// Bilinear over the four nearest low-resolution samples that lie on the same surface (normals
// and planes agree); where none does, the pixel is recomputed at full resolution, one slice per
// dispatch like the low-resolution pass.
fn upsample_pixel(pixel: vec2<u32>, sampled: bool) {
    if (pixel.x >= viewer.width || pixel.y >= viewer.height) {
        return;
    }
    let r = receiver(pixel);
    let index = pixel_index(pixel);
    if (!r.covered) {
        add_indirect(index, vec4<f32>(0.0));
        store_counts(index);
        return;
    }
    let k = f32(shade.subsample);
    let f = (vec2<f32>(pixel) + 0.5 - vec2<f32>(f32(shade.subsample / 2u) + 0.5)) / k;
    let base = vec2<i32>(floor(f));
    let t = f - vec2<f32>(base);
    var e = vec3<f32>(0.0);
    var weight = 0.0;
    for (var c = 0u; c < 4u; c++) {
        let o = vec2<i32>(i32(c & 1u), i32(c >> 1u));
        let s = clamp(base + o, vec2<i32>(0), vec2<i32>(i32(shade.low_width) - 1, i32(shade.low_height) - 1));
        let q = receiver(low_pixel(vec2<u32>(s)));
        let agree = q.covered && dot(q.n, r.n) > shade.normal_agreement
            && abs(dot(q.x - r.x, r.n)) < terms.plane_agreement;
        let w = select(1.0 - t.x, t.x, o.x == 1) * select(1.0 - t.y, t.y, o.y == 1);
        if (agree && w > 0.0) {
            fetches++;
            e += w * low[u32(s.y) * shade.low_width + u32(s.x)].rgb;
            weight += w;
        }
    }
    if (weight > 1e-3) {
        if (slice.level == 0u) {
            indirect[index] = vec4<f32>(r.albedo / PI * e / weight, 0.0);
        }
    } else {
        add_indirect(index, vec4<f32>(r.albedo / PI * gathered_irradiance(r, sampled), 1.0));
    }
    store_counts(index);
}

@compute @workgroup_size(8, 8)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    upsample_pixel(id.xy, false);
}

@compute @workgroup_size(8, 8)
fn sampled_upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    upsample_pixel(id.xy, true);
}

// Direct light from the spot, shadowed by the RSM depth.
@compute @workgroup_size(8, 8)
fn direct_light(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var l = vec3<f32>(0.0);
    if (r.covered) {
        let clip = light.view_proj * vec4<f32>(r.x, 1.0);
        let ndc = clip.xyz / clip.w;
        let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        let size = i32(params.rsm_size);
        let texel = clamp(vec2<i32>(floor(uv * f32(size))), vec2<i32>(0), vec2<i32>(size - 1));
        let occluder = textureLoad(rsm_pos, texel, 0);
        let inside = all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0)) && clip.w > 0.0;
        let lit = textureLoad(rsm_normal, texel, 0).w < 0.5
            || light_depth(light, r.x) <= occluder.w + terms.depth_bias;
        if (inside && lit) {
            let to_light = light.position.xyz - r.x;
            let d2 = dot(to_light, to_light);
            let w = to_light / sqrt(d2);
            l = r.albedo / PI * spot_intensity(light, -w) * max(0.0, dot(r.n, w)) / d2;
        }
    }
    direct[pixel_index(id.xy)] = vec4<f32>(l, select(0.0, 1.0, r.covered));
}

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
