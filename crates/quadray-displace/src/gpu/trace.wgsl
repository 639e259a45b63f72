// quadray-displace's tracing module: pyramid inverse displacement mapping (Oh & Ki 2007) as plain
// WGSL functions, for any renderer's fragment or compute shader. It declares no bindings, no
// entry points, no overrides and uses nothing else of quadray: concatenate it ahead of your own
// code (`quadray_displace::TRACE_WGSL` holds this text). Names it declares: PyramidInfo, TraceHit,
// pyramid_*, depth_bilinear, bilinear_*, ray_slope, shadow_lit, outside_map.
//
// What a caller provides
// - Texture space: uv in [0, 1)^2 per copy of a W x H map (any size); texel (i, j) covers
//   [i, i + 1) / W x [j, j + 1) / H, row j = 0 at v = 0. The functions work in texel units,
//   x = uv * (W, H).
// - Depth, not height: 0 is the polygon's plane, 1 the deepest point of the map.
// - The pyramid: a texture_2d<f32> (wgpu R32Float, unfilterable) whose mip 0 is the map padded to
//   Pw x Ph, the next powers of two of W and H, with depth 1 (the deepest), and a full mip chain
//   of n + 1 mips (mip k is max(Pw >> k, 1) x max(Ph >> k, 1), mip n is 1x1); mip k holds at each
//   texel the minimum depth of the 2^k x 2^k texels of mip 0 below it.
//   `quadray_displace::HeightPyramid` builds it: the point variant (mip 0 is the map itself) or
//   the conservative one for the bilinear surface (mip 0 the minimum over each texel's 3x3
//   neighbourhood). The bilinear functions also read the map: mip 0 of the point pyramid. Nodes
//   are clipped to the map: tracing never visits padding.
// - The ray: P(z) = p0 + e * z, its parameter z the depth in [0, 1]. p0 is the uv where the view
//   ray meets the polygon (wrapped into [0, 1) on a tiling map); e = ray_slope(V, depth_scale)
//   = -V.xy / V.z * depth_scale, with V the unit tangent-space direction towards the eye (x along
//   +u, y along +v, z along the surface normal, V.z > 0) and depth_scale the texture units per
//   unit of depth. The hit's uv is p0 + e * z.
// - A PyramidInfo (below), e.g. uploaded as a uniform (`quadray_displace::PyramidInfo`).
// Every function reads mips with textureLoad only, so it works in any shader stage; only the
// caller's derivatives for pyramid_lod need a fragment shader.

struct PyramidInfo {
    levels: i32,        // n: the root (mip n) is 1x1
    clamp_to_map: u32,  // 1: rays that leave [0, 1)^2 miss (terrain); 0: the map tiles
    iteration_cap: u32, // hard cap on the steps of any one trace (the per-ray bound is far lower)
    refine_cap: u32,    // hard cap on bilinear_trace's refinement rounds
    size: vec2u,        // W, H: the map's texels, which uv [0, 1) spans (without the padding)
    _pad: vec2u,
}

// What a trace found: the depth z where it stopped, the steps it took, the texels it read
// (fetches: every textureLoad), whether the ray left a clamped map (missed) and whether a cap
// stopped it (capped: a bound was too low).
struct TraceHit {
    z: f32,
    iterations: u32,
    fetches: u32,
    missed: bool,
    capped: bool,
}

// e of the ray towards `towards` (a unit tangent-space direction with towards.z > 0).
fn ray_slope(towards: vec3f, depth_scale: f32) -> vec2f {
    return -towards.xy / towards.z * depth_scale;
}

// Texel t of the map, wrapped or clamped to the map's own W x H (never into the padding).
fn pyramid_address(info: PyramidInfo, t: vec2i) -> vec2i {
    let size = vec2i(info.size);
    if info.clamp_to_map == 1u {
        return clamp(t, vec2i(0), size - 1);
    }
    return ((t % size) + size) % size;
}

// The map's size in texels, as floats: uv * pyramid_texels(info) is in level-0 texel units.
fn pyramid_texels(info: PyramidInfo) -> vec2f {
    return vec2f(info.size);
}

// True when p is off a clamped map (a ray there has missed).
fn outside_map(info: PyramidInfo, p: vec2f) -> bool {
    return info.clamp_to_map == 1u && (any(p < vec2f(0.0)) || any(p >= vec2f(1.0)));
}

// The bilinear surface's depth at p, between texel centres at (i + 0.5) / (W, H), by hand:
// hardware filtering has only a few bits of sub-texel precision and differs between GPUs (and
// would blend in the padding).
fn depth_bilinear(depth_map: texture_2d<f32>, info: PyramidInfo, p: vec2f) -> f32 {
    let x = p * pyramid_texels(info) - 0.5;
    let i = vec2i(floor(x));
    let f = x - floor(x);
    let d00 = textureLoad(depth_map, pyramid_address(info, i), 0).r;
    let d10 = textureLoad(depth_map, pyramid_address(info, i + vec2i(1, 0)), 0).r;
    let d01 = textureLoad(depth_map, pyramid_address(info, i + vec2i(0, 1)), 0).r;
    let d11 = textureLoad(depth_map, pyramid_address(info, i + vec2i(1, 1)), 0).r;
    return mix(mix(d00, d10, f.x), mix(d01, d11, f.x), f.y);
}

// Sections 3.2 and 4 (figure 13): the first intersection of the ray with the point-sampled height
// field (flat-topped texel columns), from depth z_start on pyramid level start_level (info.levels
// for a whole ray; the trace starts no coarser than the ray's footprint needs), reading at the
// ray's current point. `finest` is the level whose nodes act as
// leaves (0, or pyramid_lod's choice). `ascend`: after a node crossing go one level up (maximum
// mipmaps / QDM) instead of staying on the level (the paper).
fn pyramid_trace(pyramid: texture_2d<f32>, info: PyramidInfo, p0: vec2f, e: vec2f, z_start: f32, start_level: i32, finest: i32, ascend: bool) -> TraceHit {
    // Level-0 texel units of the map: x(z) = x0 + ex * z.
    let size = pyramid_texels(info);
    let x0 = p0 * size;
    let ex = e * size;
    let footprint = length(ex);
    // Node crossing steps 0.1% of a texel past the boundary. The step can clip the corner of a
    // texel the ray only grazes (the paper's 1% missed such corners visibly on real maps); 0.1%
    // is still above float spacing for coordinates up to 4096 texels, and the next-float guard
    // below keeps the ray moving where it is not.
    let delta = 0.001;
    var t: TraceHit;
    t.z = z_start;
    // A ray that is not a number (NaN or infinite p0 or e: a degenerate tangent frame) meets
    // nothing, at once rather than after up to the whole iteration cap. Tested on the exponent
    // bits: WGSL lets a compiler assume that floats are never NaN and fold a float test away.
    if any((bitcast<vec4u>(vec4f(p0, e)) & vec4u(0x7f800000u)) == vec4u(0x7f800000u)) {
        t.missed = true;
        return t;
    }
    // Start no coarser than the ray needs: on levels whose nodes exceed the ray's footprint a read
    // can barely move it, so each such level costs a read for little. The trace is exact from any
    // level (every node bounds all the texels below it); nodes of about half the footprint
    // measured fewest reads on the bundled maps (BENCHMARKS.md, "Where the trace starts").
    let needed = i32(ceil(log2(max(footprint, 1.0)))) - 1;
    var level = min(start_level, max(needed, finest));
    // A bound on any ray: at most two steps per node its footprint crosses on each level, plus
    // the descents; the global cap keeps even absurd inputs finite.
    let cap = min(info.iteration_cap, u32(8.0 * (footprint + 2.0)) + 16u * u32(info.levels + 1));
    loop {
        if level < finest {
            break;
        }
        if t.iterations >= cap {
            t.capped = true;
            break;
        }
        t.iterations += 1u;
        if outside_map(info, p0 + e * t.z) {
            t.missed = true;
            break;
        }
        let x = x0 + ex * t.z;
        // The copy of the map x lies in (x / size can round up to the next one; a clamped map
        // has only copy 0), and the node of this level within it.
        var copy = floor(x / size);
        copy -= select(vec2f(0.0), vec2f(1.0), x < copy * size);
        copy *= f32(1u - info.clamp_to_map);
        let origin = copy * size;
        let scale = f32(1 << u32(level)); // level-0 texels per node side
        let node = clamp(floor((x - origin) / scale), vec2f(0.0), ceil(size / scale) - 1.0);
        let d = textureLoad(pyramid, vec2i(node), level).r;
        t.fetches += 1u;
        // The node's extent, clipped to the map: a ray leaving the last (partial) node goes on in
        // the next copy's first node (wrap) or off the map (clamp), never into the padding.
        let lo = origin + node * scale;
        let hi = origin + min(node * scale + scale, size);
        if t.z < d {
            let advanced = x0 + ex * d;
            if all((advanced >= lo) & (advanced < hi)) {
                t.z = d;
                level -= 1;
            } else {
                // Node crossing: move to the nearer boundary along the ray, just past it.
                let boundary = select(lo, hi, ex > vec2f(0.0));
                let to_boundary = select(vec2f(1.0e30), (boundary - x0) / ex, ex != vec2f(0.0));
                let x_first = to_boundary.x < to_boundary.y;
                let crossing = select(to_boundary.y, to_boundary.x, x_first);
                // Step `delta` along the footprint, not along the crossing axis: when that axis
                // is nearly parallel to the ray, a step of delta along it could skip texels on the
                // other. If rounding keeps the ray in its node, the next crossing steps on again.
                t.z = max(max(t.z, crossing) + delta / footprint, bitcast<f32>(bitcast<u32>(t.z) + 1u));
                if ascend {
                    level = min(level + 1, info.levels);
                }
            }
        } else {
            level -= 1;
        }
    }
    return t;
}

// Exact intersection with the bilinear patches (cells between texel centres) the ray crosses
// from depth z_start, at most `max_cells` of them. x: the hit depth, or -1 when none; y: the depth
// where the walk stopped; z: cells visited.
fn bilinear_cells(depth_map: texture_2d<f32>, info: PyramidInfo, p0: vec2f, e: vec2f, z_start: f32, max_cells: u32) -> vec3f {
    let size = pyramid_texels(info);
    let q = (p0 + e * z_start) * size - 0.5;
    var cell = floor(q);
    let dir = select(vec2f(-1.0), vec2f(1.0), e >= vec2f(0.0));
    let boundary = cell + select(vec2f(0.0), vec2f(1.0), e > vec2f(0.0));
    // Depth at which the ray crosses the next cell boundary on each axis, and per cell after.
    var next = select(vec2f(1.0e30), z_start + (boundary - q) / (e * size), e != vec2f(0.0));
    let step = select(vec2f(1.0e30), abs(1.0 / (e * size)), e != vec2f(0.0));
    var z_in = z_start;
    for (var k = 0u; k < max_cells; k++) {
        let z_out = min(min(next.x, next.y), 1.0);
        let c = vec2i(cell);
        let s00 = textureLoad(depth_map, pyramid_address(info, c), 0).r;
        let s10 = textureLoad(depth_map, pyramid_address(info, c + vec2i(1, 0)), 0).r;
        let s01 = textureLoad(depth_map, pyramid_address(info, c + vec2i(0, 1)), 0).r;
        let s11 = textureLoad(depth_map, pyramid_address(info, c + vec2i(1, 1)), 0).r;
        // Cell coordinates f(t) = a + b t, t = z - z_in the depth past the cell's entry; surface
        // s = s00 + A fx + B fy + C fx fy; the ray is above the surface while g(t) = s - z > 0, a
        // quadratic in t. Centred on the cell, its coefficients stay of cell size: centred on
        // p0, a far cell's cancel to a few bits, which loses grazing hits.
        let b = e * size;
        let a = (p0 * size - 0.5 - cell) + b * z_in;
        let ca = s10 - s00;
        let cb = s01 - s00;
        let cc = s00 - s10 - s01 + s11;
        let c0 = s00 + ca * a.x + cb * a.y + cc * a.x * a.y - z_in;
        let c1 = ca * b.x + cb * b.y + cc * (a.x * b.y + a.y * b.x) - 1.0;
        let c2 = cc * b.x * b.y;
        if c0 <= 0.0 {
            return vec3f(z_in, z_in, f32(k + 1u));
        }
        let span = z_out - z_in;
        var root = 2.0;
        if abs(c2) < 1.0e-7 * max(abs(c1), 1.0) {
            root = -c0 / c1;
        } else {
            let disc = c1 * c1 - 4.0 * c2 * c0;
            if disc >= 0.0 {
                let h = -0.5 * (c1 + select(-1.0, 1.0, c1 >= 0.0) * sqrt(disc));
                let r1 = h / c2;
                let r2 = c0 / h;
                if r1 >= 0.0 && r1 <= span { root = r1; }
                if r2 >= 0.0 && r2 <= span { root = min(root, r2); }
            }
        }
        let g_out = c0 + c1 * span + c2 * span * span;
        if root >= 0.0 && root <= span {
            return vec3f(z_in + root, z_in + root, f32(k + 1u));
        }
        // The sign changed but rounding put the root just outside the cell; or the ray reached
        // depth 1, at or below every surface point (rounding can leave g a hair above 0 there).
        if g_out <= 0.0 || z_out >= 1.0 {
            return vec3f(z_out, z_out, f32(k + 1u));
        }
        if next.x < next.y {
            cell.x += dir.x;
            z_in = next.x;
            next.x += step.x;
        } else {
            cell.y += dir.y;
            z_in = next.y;
            next.y += step.y;
        }
    }
    return vec3f(-1.0, z_in, f32(max_cells));
}

// Section 3.3, magnification: the first intersection with the bilinear surface. `pyramid` is the
// conservative pyramid, `depth_map` the map (mip 0 of the point pyramid). The point-sampled
// search on the conservative pyramid brings the ray to just above the bilinear surface; there the
// intersection is refined. The paper interpolates between half a texel back and half a texel
// forward and, when the ray is still above the surface, jumps on to the surface depth there
// (d_i). Both lose intersections on steep maps (the jump by up to whole features at grazing
// angles), so the refinement here solves the ray/bilinear-patch quadratic exactly over the next
// few cells, then resumes the conservative search (climbing from level 0, as maximum mipmaps do)
// when the ray passed them untouched.
fn bilinear_trace(pyramid: texture_2d<f32>, depth_map: texture_2d<f32>, info: PyramidInfo, p0: vec2f, e: vec2f, finest: i32) -> TraceHit {
    var t = pyramid_trace(pyramid, info, p0, e, 0.0, info.levels, finest, false);
    // Refinement rounds can at most walk the ray's whole footprint.
    let round_cap = min(info.refine_cap, u32(length(e * pyramid_texels(info)) + 4.0));
    var round = 0u;
    loop {
        if t.missed || t.capped {
            break;
        }
        // The iteration cap bounds the whole trace, not each search in it.
        if round >= round_cap || t.iterations >= info.iteration_cap {
            t.capped = true;
            break;
        }
        round += 1u;
        let cells = bilinear_cells(depth_map, info, p0, e, t.z, 4u);
        t.iterations += u32(cells.z);
        t.fetches += 4u * u32(cells.z);
        if cells.x >= 0.0 {
            t.z = cells.x;
            t.missed = outside_map(info, p0 + e * t.z);
            break;
        }
        let resumed = pyramid_trace(pyramid, info, p0, e, cells.y, 0, finest, true);
        t.z = resumed.z;
        t.missed = resumed.missed;
        t.capped = resumed.capped;
        t.iterations += resumed.iterations;
        t.fetches += resumed.fetches;
    }
    return t;
}

// Section 3.4: the finest level worth reaching for a pixel whose uv changes by uv_dx, uv_dy to
// its neighbours (in a fragment shader: dpdx(uv), dpdy(uv), taken in uniform control flow), as
// mip selection does: the pixel's footprint in texels of the map.
fn pyramid_lod(info: PyramidInfo, uv_dx: vec2f, uv_dy: vec2f) -> i32 {
    let size = pyramid_texels(info);
    let footprint = max(length(uv_dx * size), length(uv_dy * size));
    return clamp(i32(floor(log2(max(footprint, 1.0)))), 0, info.levels);
}

// Self-shadowing (section 4). The light's ray through a hit at uv `hit` and depth z enters the
// height field at hit - el * z (depth 0), with el = ray_slope(L, depth_scale) and L the unit
// tangent-space direction towards the light. Trace that ray from its entry (with the same search
// as the view ray); the hit is lit when the trace, `from_light`, gets to it: within 1.5 texels
// along the surface, or within a small depth when the light is nearly overhead. A light ray that
// enters a clamped map through its side is not blocked before it.
fn shadow_lit(info: PyramidInfo, z: f32, from_light: TraceHit, el: vec2f) -> bool {
    if from_light.missed {
        return true;
    }
    let short_by = z - from_light.z;
    return short_by * length(el * pyramid_texels(info)) <= 1.5 || short_by <= 2.0e-3;
}

// shadow_lit with the point-sampled trace: is the hit (uv, depth z) lit by a light in unit
// tangent-space direction to_light?
fn pyramid_lit(pyramid: texture_2d<f32>, info: PyramidInfo, hit: vec2f, z: f32, to_light: vec3f, depth_scale: f32, finest: i32) -> bool {
    if to_light.z <= 1.0e-4 {
        return false;
    }
    let el = ray_slope(to_light, depth_scale);
    let from_light = pyramid_trace(pyramid, info, hit - el * z, el, 0.0, info.levels, finest, false);
    return shadow_lit(info, z, from_light, el);
}
