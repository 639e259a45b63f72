// A sub-sampled or interleaved method: its sum gathered at one sample per `subsample`^2 pixels,
// or at every pixel one of `interleave`^2 parts of it, then brought to the full sum at full
// resolution from the samples on each pixel's surface. The including shader defines what is
// summed: `fn gathered_irradiance(r: Receiver, part: vec2<u32>) -> vec3<f32>`, a part
// (`interleaved_part`, or `WHOLE_SUM`) of this dispatch's slice of it.

// The full-resolution pixel a low-resolution sample stands for (itself when interleaved: the
// subsample is 1).
fn low_pixel(low_xy: vec2<u32>) -> vec2<u32> {
    let p = low_xy * shade.subsample + vec2<u32>(shade.subsample / 2u);
    return min(p, vec2<u32>(viewer.width - 1u, viewer.height - 1u));
}

// One low-resolution sample's irradiance (w: 1 where it sees geometry); interleaved, its part
// scaled to stand for the whole sum.
fn low_sample(low_xy: vec2<u32>) {
    if (low_xy.x >= shade.low_width || low_xy.y >= shade.low_height) {
        return;
    }
    let full = low_pixel(low_xy);
    let r = receiver(full);
    var e = vec3<f32>(0.0);
    if (r.covered) {
        let part = interleaved_part(full);
        e = f32(part.y) * gathered_irradiance(r, part);
    }
    let index = terms.low_offset + low_xy.y * shade.low_width + low_xy.x;
    if (slice.level == 0u) {
        low[index] = vec4<f32>(e, select(0.0, 1.0, r.covered));
    } else {
        low[index] += vec4<f32>(e, 0.0);
    }
    store_counts(full.y * viewer.width + full.x);
}

@compute @workgroup_size(8, 8)
fn indirect_low(@builtin(global_invocation_id) id: vec3<u32>) {
    low_sample(id.xy);
}

// Whether a sample's receiver `q` lies on `r`'s surface: normals and planes agree.
fn on_surface(q: Receiver, r: Receiver) -> bool {
    return q.covered && dot(q.n, r.n) > shade.normal_agreement
        && abs(dot(q.x - r.x, r.n)) < terms.plane_agreement;
}

// The low-resolution sample at `s` (clamped to the samples).
fn low_at(s: vec2<i32>) -> vec3<f32> {
    fetches++;
    let c = vec2<u32>(clamp(s, vec2<i32>(0), vec2<i32>(i32(shade.low_width) - 1, i32(shade.low_height) - 1)));
    return low[terms.low_offset + c.y * shade.low_width + c.x].rgb;
}

// Sub-sampled: bilinear over the four nearest samples on the pixel's surface (rgb: the weighted
// sum, w: the weights' sum).
fn bilinear(pixel: vec2<u32>, r: Receiver) -> vec4<f32> {
    let k = f32(shade.subsample);
    let f = (vec2<f32>(pixel) + 0.5 - vec2<f32>(f32(shade.subsample / 2u) + 0.5)) / k;
    let base = vec2<i32>(floor(f));
    let t = f - vec2<f32>(base);
    var e = vec4<f32>(0.0);
    for (var c = 0u; c < 4u; c++) {
        let o = vec2<i32>(i32(c & 1u), i32(c >> 1u));
        let s = clamp(base + o, vec2<i32>(0), vec2<i32>(i32(shade.low_width) - 1, i32(shade.low_height) - 1));
        let w = select(1.0 - t.x, t.x, o.x == 1) * select(1.0 - t.y, t.y, o.y == 1);
        if (w > 0.0 && on_surface(receiver(low_pixel(vec2<u32>(s))), r)) {
            e += vec4<f32>(w * low_at(s), w);
        }
    }
    return e;
}

// A pixel from the samples on its surface (`e`: their weighted sum, w: the weights' sum) where
// they are `enough`; elsewhere recomputed from the whole sum, one slice per dispatch like the
// low-resolution pass (w: 1 there). It follows every light view's low-resolution pass, so
// `recomputing` tells the including shader that what it kept of one view for that pass may be
// another's by now (the cut's corner visibility).
var<private> recomputing: bool;

fn reconstruct_pixel(pixel: vec2<u32>, r: Receiver, e: vec4<f32>, enough: bool) {
    let index = pixel_index(pixel);
    if (!r.covered) {
        add_indirect(index, vec4<f32>(0.0));
    } else if (enough) {
        if (slice.level == 0u) {
            add_indirect(index, vec4<f32>(r.albedo / PI * e.rgb / e.w, 0.0));
        }
    } else {
        recomputing = true;
        add_indirect(index, vec4<f32>(r.albedo / PI * gathered_irradiance(r, WHOLE_SUM), 1.0));
    }
    store_counts(index);
}

// Sub-sampled: each pixel bilinear from the samples on its surface.
@compute @workgroup_size(8, 8)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec4<f32>(0.0);
    if (r.covered) {
        e = bilinear(id.xy, r);
    }
    reconstruct_pixel(id.xy, r, e, e.w > 1e-3);
}

// Interleaved: the parts rejoined by a tent filter 2N - 1 pixels wide (N = `interleave`) over the
// pixels on the pixel's surface. Its weights give each of the N^2 parts the same total, so that
// where every neighbour is on the surface the parts add up to the whole sum, and unlike an NxN box
// it leaves no ripple of period N (the box's response is zero there). The workgroup's pixels and
// an apron of N - 1 are read once into workgroup memory, not once a tap. A pixel whose neighbours
// on its surface carry a quarter of the weights or less (a thin strip, a corner) is recomputed.
const REJOIN_SIDE: u32 = 8u + 2u * (MAX_INTERLEAVE - 1u);
var<workgroup> rejoin_x: array<vec4<f32>, REJOIN_SIDE * REJOIN_SIDE>;
var<workgroup> rejoin_n: array<vec3<f32>, REJOIN_SIDE * REJOIN_SIDE>;
var<workgroup> rejoin_e: array<vec3<f32>, REJOIN_SIDE * REJOIN_SIDE>;

@compute @workgroup_size(8, 8)
fn rejoin(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let n = i32(shade.interleave);
    let side = 8 + 2 * (n - 1);
    let origin = vec2<i32>(group.xy * 8u) - vec2<i32>(n - 1);
    let size = vec2<i32>(i32(viewer.width), i32(viewer.height));
    for (var i = i32(local); i < side * side; i += 64) {
        let s = origin + vec2<i32>(i % side, i / side);
        var q: Receiver;
        var e = vec3<f32>(0.0);
        if (all(s >= vec2<i32>(0)) && all(s < size)) {
            q = receiver(vec2<u32>(s));
            if (q.covered) {
                e = low_at(s);
            }
        }
        rejoin_x[i] = vec4<f32>(q.x, select(0.0, 1.0, q.covered));
        rejoin_n[i] = q.n;
        rejoin_e[i] = e;
    }
    workgroupBarrier();
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var e = vec4<f32>(0.0);
    if (r.covered) {
        let centre = vec2<i32>(id.xy) - origin;
        for (var dy = 1 - n; dy < n; dy++) {
            for (var dx = 1 - n; dx < n; dx++) {
                let i = (centre.y + dy) * side + centre.x + dx;
                var q: Receiver;
                q.x = rejoin_x[i].xyz;
                q.n = rejoin_n[i];
                q.covered = rejoin_x[i].w > 0.5;
                if (on_surface(q, r)) {
                    let w = f32((n - abs(dx)) * (n - abs(dy)));
                    e += vec4<f32>(w * rejoin_e[i], w);
                }
            }
        }
    }
    // (the weights sum to N^4 where every neighbour is on the surface)
    let all_weights = f32(n * n * n * n);
    reconstruct_pixel(id.xy, r, e, e.w > 0.25 * all_weights);
}
