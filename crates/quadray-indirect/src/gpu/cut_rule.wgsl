// The top-down rule, shared by the compacted cut (cluster.wgsl) and the per-level passes
// (gather/passes.wgsl): a node is used when it is accepted (valid, or at the limit level) and
// none of its ancestors up to the start level was. This is the paper's "revisit" of ancestors.
fn accepted(p: ClusterParams, level: u32, xy: vec2<u32>) -> bool {
    if (level == p.limit_level) {
        return true;
    }
    fetches++;
    return nodes[node_index(p, level, xy)].normal.w > 0.5;
}

fn in_cut(p: ClusterParams, level: u32, xy: vec2<u32>) -> bool {
    if (level < p.limit_level || level > p.start_level) {
        return false;
    }
    fetches++;
    if (nodes[node_index(p, level, xy)].flux.w < 0.5 || !accepted(p, level, xy)) {
        return false;
    }
    for (var a = level + 1u; a <= min(p.start_level, MAX_LEVELS); a++) {
        if (accepted(p, a, xy >> vec2<u32>(a - level))) {
            return false;
        }
    }
    return true;
}
