// The gather's work counts of a frame as means per shaded pixel, for Bevy's diagnostics (which
// read one value at a time): what `quadray indirect`'s stats report, reduced on the GPU instead
// of read back. One workgroup; totals over every pixel, divided by the pixels with geometry.

@group(0) @binding(0) var<storage, read> counts: array<vec4<u32>>;
@group(0) @binding(1) var position: texture_2d<f32>;
// VPL evaluations and texel fetches per shaded pixel, the shaded pixels, 0
@group(0) @binding(2) var<storage, read_write> means: vec4<f32>;

const THREADS: u32 = 256u;
var<workgroup> sums: array<vec3<f32>, THREADS>;

@compute @workgroup_size(256)
fn mean_counts(@builtin(local_invocation_index) thread: u32) {
    let size = textureDimensions(position);
    var sum = vec3<f32>(0.0);
    for (var i = thread; i < size.x * size.y; i += THREADS) {
        let shaded = textureLoad(position, vec2<u32>(i % size.x, i / size.x), 0).w > 0.5;
        sum += vec3<f32>(select(0.0, 1.0, shaded), f32(counts[i].x), f32(counts[i].y));
    }
    sums[thread] = sum;
    workgroupBarrier();
    for (var stride = THREADS / 2u; stride > 0u; stride /= 2u) {
        if (thread < stride) {
            sums[thread] += sums[thread + stride];
        }
        workgroupBarrier();
    }
    if (thread == 0u) {
        let total = sums[0];
        means = vec4<f32>(total.yz / max(total.x, 1.0), total.x, 0.0);
    }
}
