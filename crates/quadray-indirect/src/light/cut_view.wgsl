// The cut over the RSM as a picture, for a debug view: the RSM's flux, exposed by the mean over
// the texels that see geometry and tone-mapped as `picture::tone_map` does, magnified `zoom`
// times, with every cluster of the cut outlined (top and left edges) in its level's colour. The
// colour is linear: written to an sRGB target (or sRGB-encoded) it is `picture::cut_view`'s
// pixel. Needs node.wgsl, kernel.wgsl (`luminance`), cut_rule.wgsl. Accessor: `load_node`.

// The outlines' sRGB colours by level (0 = single VPLs), as `picture::LEVEL_COLOURS`.
const CUT_LEVEL_COLOURS = array<vec3<f32>, 6>(
    vec3<f32>(255.0, 255.0, 255.0),
    vec3<f32>(255.0, 64.0, 64.0),
    vec3<f32>(255.0, 200.0, 0.0),
    vec3<f32>(64.0, 220.0, 64.0),
    vec3<f32>(64.0, 160.0, 255.0),
    vec3<f32>(230.0, 90.0, 255.0),
);

// The view's exposure: texels that see geometry over their summed flux luminance (the root's).
fn cut_view_exposure(p: ClusterParams) -> f32 {
    let root = load_node(node_index(p, p.levels - 1u, vec2<u32>(0u)));
    let sum = luminance(root.flux.rgb);
    return select(1.0, root.flux.w / sum, sum > 0.0);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

// Pixel `pixel` of the view (`rsm_size * zoom` a side).
fn cut_view_pixel(p: ClusterParams, zoom: u32, pixel: vec2<u32>, exposure: f32) -> vec3<f32> {
    let texel = pixel / zoom;
    for (var level = p.limit_level; level <= min(p.start_level, MAX_LEVELS); level++) {
        if (in_cut(p, level, texel >> vec2<u32>(level))) {
            let side = (1u << level) * zoom;
            if (pixel.x % side == 0u || pixel.y % side == 0u) {
                return srgb_to_linear(CUT_LEVEL_COLOURS[level % 6u] / 255.0);
            }
            break;
        }
    }
    let flux = load_node(node_index(p, 0u, texel)).flux.rgb;
    return 1.0 - exp(-max(flux, vec3<f32>(0.0)) * exposure);
}
