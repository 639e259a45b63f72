// The top-down cut rule, shared by the compacted cut's selection and the per-level passes: a node
// is used when it is accepted (valid, or at the limit level) and none of its ancestors up to the
// start level was. This is the paper's "revisit" of ancestors. Needs node.wgsl.
// Accessor: `fn load_node(i: u32) -> Node`, node `i` of the pyramid (node.wgsl's order).
fn accepted(p: ClusterParams, level: u32, xy: vec2<u32>) -> bool {
    if (level == p.limit_level) {
        return true;
    }
    fetches++;
    return load_node(node_index(p, level, xy)).normal.w > 0.5;
}

fn in_cut(p: ClusterParams, level: u32, xy: vec2<u32>) -> bool {
    if (level < p.limit_level || level > p.start_level) {
        return false;
    }
    fetches++;
    if (load_node(node_index(p, level, xy)).flux.w < 0.5 || !accepted(p, level, xy)) {
        return false;
    }
    for (var a = level + 1u; a <= min(p.start_level, MAX_LEVELS); a++) {
        if (accepted(p, a, xy >> vec2<u32>(a - level))) {
            return false;
        }
    }
    return true;
}
