// The compacted cut's sum at a receiver (method quadtree): the irradiance from clusters
// `range.x` to `range.y` (excluded) of the cut. Needs node.wgsl and receiver.wgsl.
// Accessors: `fn load_cut_node(i: u32) -> Node`, cluster `i` of the cut;
// `fn node_irradiance(node: Node, r: Receiver) -> vec3<f32>`, the kernel with the including
// shader's visibility.
fn cut_sum(r: Receiver, range: vec2<u32>) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    for (var i = range.x; i < range.y; i++) {
        e += node_irradiance(load_cut_node(i), r);
    }
    fetches += range.y - min(range.x, range.y);
    return e;
}
