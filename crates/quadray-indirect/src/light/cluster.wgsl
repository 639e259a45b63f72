// The light quadtree: pack the RSM into level 0, reduce level by level (summed flux, means),
// mark valid clusters (local or recursive rule), and compact the cut into a list.

// Group 0, per light update: the settings, the RSM (read through light/rsm_read.wgsl), the
// quadtree and the light.
@group(0) @binding(0) var<uniform> params: ClusterParams;
@group(0) @binding(1) var rsm_flux: texture_2d<f32>;
@group(0) @binding(2) var rsm_pos: texture_2d<f32>;
@group(0) @binding(3) var rsm_normal: texture_2d<f32>;
@group(0) @binding(4) var<storage, read_write> nodes: array<Node>;
// the cut's clusters, copied out of the pyramid so that shading reads them in a row, a segment
// of arrayLength / CUT_CLASS_SIDE^2 a class (node.rs); normal.w holds the node's index (bit
// pattern) instead of its validity
@group(0) @binding(5) var<storage, read_write> cut: array<Node>;
// the cut's clusters in all, then in each class
@group(0) @binding(6) var<storage, read_write> cut_count: array<atomic<u32>, CUT_CLASS_SIDE * CUT_CLASS_SIDE + 1u>;
// per node, what bounds its contribution (reduced with the means, read by the per-tile cuts)
@group(0) @binding(7) var<storage, read_write> bounds: array<NodeBounds>;
// the light view the RSM was rendered from (a compact RSM's positions are rebuilt with it)
@group(0) @binding(8) var<uniform> light: Light;
// Group 1, per dispatch: the level (a dynamic offset into slots 0, 1, 2, ...).
@group(1) @binding(0) var<uniform> current: Level;

// The accessor of cut_rule.wgsl.
fn load_node(i: u32) -> Node {
    return nodes[i];
}

@compute @workgroup_size(8, 8)
fn pack(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.rsm_size || id.y >= params.rsm_size) {
        return;
    }
    let t = vec2<i32>(id.xy);
    let flux = load_rsm_flux(t);
    let pos = load_rsm_position(t);
    let n = load_rsm_normal(t);
    // a texel the kernel cannot take (NaN, infinite, a zero normal) packs as a cleared one
    let vpl = n.w > 0.5 && kernel_vpl(flux, pos, n.xyz);
    var node: Node;
    node.flux = select(vec4<f32>(0.0), vec4<f32>(flux, n.w), vpl);
    node.pos = select(vec4<f32>(0.0), pos, vpl);
    node.normal = vec4<f32>(select(vec3<f32>(0.0), n.xyz, vpl), 1.0);
    let index = node_index(params, 0u, id.xy);
    nodes[index] = node;
    // a VPL: a box and a cone of zero size; an empty texel: an empty box
    let lo = select(vec3<f32>(EMPTY_BOX), node.pos.xyz, vpl);
    let hi = select(vec3<f32>(-EMPTY_BOX), node.pos.xyz, vpl);
    bounds[index] = NodeBounds(vec4<f32>(lo, 1.0), vec4<f32>(hi, 0.0));
}

// Index of child `c` (x in bit 0, y in bit 1) of node `xy` of `level`.
fn child_index(level: u32, xy: vec2<u32>, c: u32) -> u32 {
    return node_index(params, level - 1u, xy * 2u + vec2<u32>(c & 1u, c >> 1u));
}

// One level from the one below: sums of flux and texel counts, weighted means of position, depth
// and normal over the non-empty children (weights: flux luminance, or texel counts).
@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) id: vec3<u32>) {
    let level = current.level;
    let size = level_size(params, level);
    if (id.x >= size || id.y >= size) {
        return;
    }
    var flux = vec4<f32>(0.0);
    var pos = vec4<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var weight = 0.0;
    var count_pos = vec4<f32>(0.0);
    var count_normal = vec3<f32>(0.0);
    for (var c = 0u; c < 4u; c++) {
        let child = nodes[child_index(level, id.xy, c)];
        flux += child.flux;
        let w = select(child.flux.w, luminance(child.flux.rgb), params.flux_weighted != 0u);
        pos += w * child.pos;
        normal += w * child.normal.xyz;
        weight += w;
        count_pos += child.flux.w * child.pos;
        count_normal += child.flux.w * child.normal.xyz;
    }
    // Black surfaces carry no flux: fall back to texel counts so their means stay defined.
    if (weight <= 0.0) {
        pos = count_pos;
        normal = count_normal;
        weight = flux.w;
    }
    var node: Node;
    node.flux = flux;
    node.pos = select(vec4<f32>(0.0), pos / weight, weight > 0.0);
    let len = length(normal);
    node.normal = vec4<f32>(select(vec3<f32>(0.0), normal / len, len > 0.0), 0.0);
    let index = node_index(params, level, id.xy);
    nodes[index] = node;
    // the children's boxes joined; the cone around the mean normal that holds the children's
    // cones: its half-angle is the widest child's angle from the axis plus the child's own
    var lo = vec3<f32>(EMPTY_BOX);
    var hi = vec3<f32>(-EMPTY_BOX);
    var angle = 0.0;
    for (var c = 0u; c < 4u; c++) {
        let at = child_index(level, id.xy, c);
        if (nodes[at].flux.w > 0.5) {
            let child = bounds[at];
            lo = min(lo, child.lo.xyz);
            hi = max(hi, child.hi.xyz);
            let axis = nodes[at].normal.xyz;
            let apart = acos(clamp(dot(axis, node.normal.xyz), -1.0, 1.0));
            angle = max(angle, apart + acos(clamp(child.lo.w, -1.0, 1.0)));
        }
    }
    // (no mean direction: the cone is the whole sphere)
    let cone = select(cos(min(angle + CONE_SLACK, PI)), -1.0, len <= 0.0);
    bounds[index] = NodeBounds(vec4<f32>(lo, cone), vec4<f32>(hi, 0.0));
}

// Valid when every non-empty child is close to the mean in depth and direction (the paper's local
// rule); the recursive rule also wants every child valid. Empty nodes are valid (they add nothing).
@compute @workgroup_size(8, 8)
fn validity(@builtin(global_invocation_id) id: vec3<u32>) {
    let level = current.level;
    let size = level_size(params, level);
    if (id.x >= size || id.y >= size) {
        return;
    }
    let index = node_index(params, level, id.xy);
    let mean = nodes[index];
    var valid = true;
    for (var c = 0u; c < 4u; c++) {
        let child = nodes[child_index(level, id.xy, c)];
        if (child.flux.w > 0.5) {
            let close = abs(child.pos.w - mean.pos.w) < params.depth_threshold
                && dot(child.normal.xyz, mean.normal.xyz) > params.normal_threshold;
            let child_ok = params.recursive == 0u || child.normal.w > 0.5;
            valid = valid && close && child_ok;
        }
    }
    nodes[index].normal.w = select(0.0, 1.0, valid);
}

// One thread per node of the levels limit..start (stored contiguously); appends the cut's nodes.
@compute @workgroup_size(256)
fn select_cut(@builtin(global_invocation_id) id: vec3<u32>) {
    let first = level_offset(params, params.limit_level);
    let end = level_offset(params, params.start_level + 1u);
    let index = first + id.x;
    if (index >= end) {
        return;
    }
    var level = params.limit_level;
    while (level < params.start_level && index >= level_offset(params, level + 1u)) {
        level++;
    }
    let local = index - level_offset(params, level);
    let size = level_size(params, level);
    let xy = vec2<u32>(local % size, local / size);
    if (in_cut(params, level, xy)) {
        var node = nodes[index];
        node.normal.w = bitcast<f32>(index);
        let c = xy % CUT_CLASS_SIDE;
        let cut_class = c.x + CUT_CLASS_SIDE * c.y;
        let segment = arrayLength(&cut) / (CUT_CLASS_SIDE * CUT_CLASS_SIDE);
        atomicAdd(&cut_count[0], 1u);
        cut[cut_class * segment + atomicAdd(&cut_count[1u + cut_class], 1u)] = node;
    }
}
