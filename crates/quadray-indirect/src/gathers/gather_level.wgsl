// One level of the paper's traversal at a receiver (method quadtree-passes): the irradiance from
// the nodes `range.x` to `range.y` (excluded) of `level`, row-major, that the top-down cut rule
// takes. Needs node.wgsl, receiver.wgsl and cut_rule.wgsl.
// Accessors: `fn load_node(i: u32) -> Node` (as cut_rule.wgsl);
// `fn node_irradiance(node: Node, r: Receiver) -> vec3<f32>`, the kernel with the including
// shader's visibility.
fn level_sum(p: ClusterParams, level: u32, r: Receiver, range: vec2<u32>) -> vec3<f32> {
    let size = level_size(p, level);
    var e = vec3<f32>(0.0);
    for (var i = range.x; i < range.y; i++) {
        let xy = vec2<u32>(i % size, i / size);
        if (in_cut(p, level, xy)) {
            fetches++;
            e += node_irradiance(load_node(level_offset(p, level) + i), r);
        }
    }
    return e;
}
