// Relaxed cone step mapping (Policarpo & Oliveira, GPU Gems 3 ch. 18) on the point-sampled
// height field, after trace.wgsl (PyramidInfo, TraceHit, its addressing) and in its conventions.
// The cone map (quadray_displace::cone::ConeMap): a texture_2d<f32> (Rg32Float, one mip) of the
// map's size (PyramidInfo.size), r the texel's depth, g its relaxed cone ratio (uv units per unit
// of depth), read by textureLoad (point sampling) and addressed as the map is.

// The cone map texel under uv p: (depth, cone ratio).
fn cone_load(cone_map: texture_2d<f32>, info: PyramidInfo, p: vec2f) -> vec2f {
    let texel = vec2i(floor(p * pyramid_texels(info)));
    return textureLoad(cone_map, pyramid_address(info, texel), 0).rg;
}

// At most `cone_steps` steps, each to the edge of the cone of the texel under the ray, until the
// ray is at or below the surface; then `binary_steps` halvings of the step that got it there. A
// relaxed cone holds no place where a ray leaves the solid, so that step holds exactly one
// crossing: the first intersection. A ray still above the surface after its steps stops where
// it is (the method's error).
fn cone_trace(cone_map: texture_2d<f32>, info: PyramidInfo, p0: vec2f, e: vec2f, cone_steps: u32, binary_steps: u32) -> TraceHit {
    var t: TraceHit;
    let slope = length(e);
    var above = 0.0;
    var inside = false;
    for (var i = 0u; i < cone_steps; i++) {
        let p = p0 + e * t.z;
        if outside_map(info, p) {
            t.missed = true;
            return t;
        }
        let texel = cone_load(cone_map, info, p);
        t.iterations += 1u;
        t.fetches += 1u;
        let height = texel.x - t.z;
        if height <= 0.0 {
            inside = true;
            break;
        }
        above = t.z;
        // To the cone's edge: slope * step = ratio * (height - step). A vertical ray meets the
        // top of its column.
        t.z += select(height * texel.y / (slope + texel.y), height, slope == 0.0);
    }
    if !inside {
        return t;
    }
    var below = t.z;
    for (var i = 0u; i < binary_steps; i++) {
        let mid = 0.5 * (above + below);
        t.iterations += 1u;
        t.fetches += 1u;
        if mid < cone_load(cone_map, info, p0 + e * mid).x {
            above = mid;
        } else {
            below = mid;
        }
    }
    t.z = below;
    return t;
}
