// The compacted cut's sum at a receiver (method quadtree): the irradiance from clusters
// `range.x` to `range.y` (excluded) of the cut. Needs node.wgsl and receiver.wgsl.
// Accessor: `fn cut_node_irradiance(i: u32, r: Receiver) -> vec3<f32>`, cluster `i` of the
// cut's irradiance at `r` (the kernel with the including shader's visibility).
fn cut_sum(r: Receiver, range: vec2<u32>) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    for (var i = range.x; i < range.y; i++) {
        e += cut_node_irradiance(i, r);
    }
    fetches += range.y - min(range.x, range.y);
    return e;
}
