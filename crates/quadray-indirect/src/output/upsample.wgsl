// A sub-sampled method: its sum gathered at one sample per `subsample`^2 pixels, then brought to
// full resolution with geometry-aware upsampling. The including shader defines what is summed:
// `fn gathered_irradiance(r: Receiver) -> vec3<f32>`, this dispatch's slice of it.

// The full-resolution pixel a low-resolution sample stands for.
fn low_pixel(low_xy: vec2<u32>) -> vec2<u32> {
    let p = low_xy * shade.subsample + vec2<u32>(shade.subsample / 2u);
    return min(p, vec2<u32>(viewer.width - 1u, viewer.height - 1u));
}

// One low-resolution sample's irradiance (w: 1 where it sees geometry).
fn low_sample(low_xy: vec2<u32>) {
    if (low_xy.x >= shade.low_width || low_xy.y >= shade.low_height) {
        return;
    }
    let r = receiver(low_pixel(low_xy));
    var e = vec3<f32>(0.0);
    if (r.covered) {
        e = gathered_irradiance(r);
    }
    let index = terms.low_offset + low_xy.y * shade.low_width + low_xy.x;
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
    low_sample(id.xy);
}

// Bilinear over the four nearest low-resolution samples that lie on the same surface (normals
// and planes agree); where none does, the pixel is recomputed at full resolution, one slice per
// dispatch like the low-resolution pass.
fn upsample_pixel(pixel: vec2<u32>) {
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
            e += w * low[terms.low_offset + u32(s.y) * shade.low_width + u32(s.x)].rgb;
            weight += w;
        }
    }
    if (weight > 1e-3) {
        if (slice.level == 0u) {
            add_indirect(index, vec4<f32>(r.albedo / PI * e / weight, 0.0));
        }
    } else {
        add_indirect(index, vec4<f32>(r.albedo / PI * gathered_irradiance(r), 1.0));
    }
    store_counts(index);
}

@compute @workgroup_size(8, 8)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    upsample_pixel(id.xy);
}
