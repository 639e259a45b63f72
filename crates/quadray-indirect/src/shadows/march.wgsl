// Indirect shadows without an occupancy grid, and the choice between the grid and the march:
// the depth-map march between a receiver and a cluster through the camera's depth (the
// G-buffer) and the light's (the RSM). Part of every gather shader: it reads the bindings of
// gathers/shared.wgsl.

// The texel of a depth map that a point with clip coordinates `c` falls in, or (-1, -1) outside
// the map (`size`: the map's width and height).
fn map_texel(c: vec4<f32>, size: vec2<f32>) -> vec2<i32> {
    let uv = vec2<f32>(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
    if (c.w > 0.0 && all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(1.0))) {
        return vec2<i32>(uv * size);
    }
    return vec2<i32>(-1);
}

// What a depth map says of a marched point: it lies in front of the surface the map sees there
// (or on it), the map tells nothing (the point is outside it, or deep behind a surface it may
// only pass around), the point lies in the thin layer behind the seen surface, or the segment
// passes through the seen surface.
const IN_FRONT = 0u;
const UNSEEN = 1u;
const IN_LAYER = 2u;
const THROUGH = 3u;

// The march's depth bias (world units): a tenth of the layer.
fn march_bias() -> f32 {
    return 0.1 * terms.shadow_thickness;
}

// A marched point `behind` the surface its texel sees (world units): in front, in the layer, or
// past it (UNSEEN, until `crossing_texel` says more).
fn depth_state(behind: f32) -> u32 {
    if (behind <= march_bias()) {
        return IN_FRONT;
    }
    return select(UNSEEN, IN_LAYER, behind < terms.shadow_thickness);
}

// For a point deep behind the surface `seen` (normal `n`) of a depth map: the texel where the
// segment x -> xp (ends `c` in the map's clip space, `size` its texels) crosses that surface's
// plane, or (-1, -1) where it does not. The segment passes through the surface if the map sees
// a point of that plane in this texel (`on_plane`): so a wall thinner than the march's step
// blocks, and a doorway beside it does not, as there the map sees past the wall's plane.
fn crossing_texel(x: vec3<f32>, xp: vec3<f32>, seen: vec3<f32>, n: vec3<f32>, c: array<vec4<f32>, 2>, size: vec2<f32>) -> vec2<i32> {
    let bias = march_bias();
    let a = dot(x - seen, n);
    let b = dot(xp - seen, n);
    if (min(a, b) >= -bias || max(a, b) <= bias) {
        return vec2<i32>(-1);
    }
    return map_texel(mix(c[0], c[1], a / (a - b)), size);
}

fn on_plane(there: vec3<f32>, seen: vec3<f32>, n: vec3<f32>) -> u32 {
    return select(UNSEEN, THROUGH, abs(dot(there - seen, n)) < march_bias());
}

// Marched point t of the segment x -> xp (ends `c` in the camera's clip space) against the
// camera's depth (the G-buffer).
fn camera_state(x: vec3<f32>, xp: vec3<f32>, c: array<vec4<f32>, 2>, t: f32) -> u32 {
    let size = vec2<f32>(f32(viewer.width), f32(viewer.height));
    let texel = map_texel(mix(c[0], c[1], t), size);
    if (texel.x < 0) {
        return UNSEEN;
    }
    fetches++;
    let seen = load_g_position(texel);
    if (seen.w < 0.5) {
        return UNSEEN;
    }
    let state = depth_state(distance(mix(x, xp, t), viewer.eye.xyz) - distance(seen.xyz, viewer.eye.xyz));
    if (state != UNSEEN) {
        return state;
    }
    fetches++;
    let n = load_g_normal(texel);
    let at = crossing_texel(x, xp, seen.xyz, n, c, size);
    if (at.x < 0) {
        return UNSEEN;
    }
    fetches++;
    let there = load_g_position(at);
    return select(UNSEEN, on_plane(there.xyz, seen.xyz, n), there.w > 0.5);
}

// The same against the light's depth (the RSM; ends `l` in the light's clip space).
fn light_state(x: vec3<f32>, xp: vec3<f32>, l: array<vec4<f32>, 2>, t: f32) -> u32 {
    let size = vec2<f32>(f32(params.rsm_size));
    let texel = map_texel(mix(l[0], l[1], t), size);
    if (texel.x < 0) {
        return UNSEEN;
    }
    fetches++;
    let seen = load_rsm_position(texel);
    if (seen.w <= 0.0) {
        return UNSEEN;
    }
    let state = depth_state((light_depth(light, mix(x, xp, t)) - seen.w) / light.position.w);
    if (state != UNSEEN) {
        return state;
    }
    fetches++;
    let n = load_rsm_normal(texel).xyz;
    let at = crossing_texel(x, xp, seen.xyz, n, l, size);
    if (at.x < 0) {
        return UNSEEN;
    }
    fetches++;
    let there = load_rsm_position(at);
    return select(UNSEEN, on_plane(there.xyz, seen.xyz, n), there.w > 0.0);
}

// Approximate visibility between a receiver (normal `n`) and a cluster (mean normal `np`):
// through the scene's occupancy grid where the gather has one (`grid_visibility`), and
// `marched_visible` where it has none or cannot tell.
fn visible(x: vec3<f32>, n: vec3<f32>, xp: vec3<f32>, np: vec3<f32>) -> bool {
    if (occupancy_load(0u) > 0u) {
        let grid = grid_visibility(x, n, xp, np);
        if (grid != GRID_UNKNOWN) {
            return grid == GRID_VISIBLE;
        }
    }
    return marched_visible(x, xp);
}

// No point marched between a receiver and a cluster passes through a surface that the camera's
// or the light's depth sees, or lies in the layer behind one view's surface where the other view
// does not see it in front. Clip coordinates are linear along the segment, so the ends are
// projected once and the points' interpolated.
fn marched_visible(x: vec3<f32>, xp: vec3<f32>) -> bool {
    let camera = array<vec4<f32>, 2>(viewer.view_proj * vec4<f32>(x, 1.0), viewer.view_proj * vec4<f32>(xp, 1.0));
    let lit = array<vec4<f32>, 2>(light.view_proj * vec4<f32>(x, 1.0), light.view_proj * vec4<f32>(xp, 1.0));
    for (var i = 1u; i <= shade.shadow_steps; i++) {
        let t = f32(i) / f32(shade.shadow_steps + 1u);
        let a = camera_state(x, xp, camera, t);
        let b = light_state(x, xp, lit, t);
        if (max(a, b) == THROUGH || (a == IN_LAYER && b != IN_FRONT) || (b == IN_LAYER && a != IN_FRONT)) {
            return false;
        }
    }
    return true;
}
