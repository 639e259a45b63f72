// Inverse displacement mapping: every method traces the same tangent-space ray and shades the
// hit the same way; only `trace` differs. The method is a pipeline-overridable constant, so each
// pipeline compiles to just its own search.
//
// Ray convention (spec): P(z) = p0 + e * z, z is the depth in [0,1] (0 = the polygon's plane),
// e = -V.xy / V.z * depth_scale with V the tangent-space direction towards the eye.

const PYRAMID: u32 = 0u;          // the paper: top-down, node crossing stays on its level
const PYRAMID_ASCEND: u32 = 1u;   // after a crossing go one level up (maximum mipmaps / QDM)
const PYRAMID_BILINEAR: u32 = 2u; // section 3.3 on the conservative pyramid
const BUMP: u32 = 3u;
const PARALLAX: u32 = 4u;         // with offset limiting
const POM: u32 = 5u;              // linear search, secant between the last two samples
const RELIEF: u32 = 6u;           // linear search, then binary search
const MESH: u32 = 7u;             // real displaced geometry (vs_mesh)

override METHOD: u32 = 0u;

struct Params {
    view_proj: mat4x4f,
    eye: vec4f,
    light: vec4f,
    // The plane of the wall / terrain (mesh baseline): origin, and world vectors per unit of u, v.
    plane_origin: vec4f,
    plane_u: vec4f,
    plane_v: vec4f,
    tile_world: f32,     // world size of one texture repeat
    depth_scale: f32,    // texture units per unit of depth
    levels: i32,         // n: level 0 is 2^n x 2^n, the root is level n
    lod: i32,            // finest level the pyramid may reach; -1 = from derivatives
    layers_min: f32,
    layers_max: f32,
    binary_steps: u32,
    iteration_cap: u32,
    clamp_to_map: u32,   // 1: terrain, rays that leave [0,1]^2 miss
    shadows: u32,
    mesh_grid: u32,      // mesh baseline: quads per side per tile
    tiles: u32,          // texture repeats per side of the surface
    bilinear_cap: u32,   // refinement rounds of section 3.3
    show_iterations: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var pyramid: texture_2d<f32>;   // min depths, one mip per level
@group(0) @binding(2) var depth_map: texture_2d<f32>; // the map itself (bilinear reads)
@group(0) @binding(3) var normal_map: texture_2d<f32>;
@group(0) @binding(4) var color_map: texture_2d<f32>;
@group(0) @binding(5) var linear_repeat: sampler;

struct VertexIn {
    @location(0) position: vec3f,
    @location(1) normal: vec3f,
    @location(2) tangent: vec4f,   // xyz: world direction of +u; w: sign of +v relative to N x T
    @location(3) uv: vec2f,
}

struct VertexOut {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
    @location(1) uv: vec2f,
    @location(2) normal: vec3f,
    @location(3) tangent: vec3f,
    @location(4) bitangent: vec3f,
    @location(5) depth: f32,       // mesh baseline: the vertex's depth
}

struct FragmentOut {
    @location(0) color: vec4f,
    // Hit uv, hit depth (-1: the ray left the map), iterations spent.
    @location(1) hit: vec4f,
    // The ray itself, so the CPU ground truth traces exactly the same one.
    @location(2) ray: vec4f,
}

@vertex
fn vs_surface(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = params.view_proj * vec4f(v.position, 1.0);
    out.world = v.position;
    out.uv = v.uv;
    out.normal = v.normal;
    out.tangent = v.tangent.xyz;
    out.bitangent = cross(v.normal, v.tangent.xyz) * v.tangent.w;
    out.depth = 0.0;
    return out;
}

// The baseline of figure 20: a grid of 2 * mesh_grid^2 triangles per tile whose vertices sit on
// the bilinear surface, instanced over the tiles.
@vertex
fn vs_mesh(@builtin(vertex_index) vid: u32, @builtin(instance_index) tile: u32) -> VertexOut {
    let quad = vid / 6u;
    let corner = array<vec2u, 6>(vec2u(0u, 0u), vec2u(1u, 0u), vec2u(0u, 1u), vec2u(0u, 1u), vec2u(1u, 0u), vec2u(1u, 1u))[vid % 6u];
    let g = params.mesh_grid;
    let cell = vec2u(quad % g, quad / g) + corner;
    let tile_xy = vec2f(f32(tile % params.tiles), f32(tile / params.tiles));
    let uv = tile_xy + vec2f(cell) / f32(g);
    let d = bilinear_depth(uv);
    let n = normalize(cross(params.plane_v.xyz, params.plane_u.xyz));
    let world = params.plane_origin.xyz + params.plane_u.xyz * uv.x + params.plane_v.xyz * uv.y
        - n * d * params.depth_scale * params.tile_world;
    var out: VertexOut;
    out.clip = params.view_proj * vec4f(world, 1.0);
    out.world = world;
    out.uv = uv;
    out.normal = n;
    out.tangent = normalize(params.plane_u.xyz);
    out.bitangent = normalize(params.plane_v.xyz);
    out.depth = d;
    return out;
}

fn address(t: vec2i, size: i32) -> vec2i {
    if params.clamp_to_map == 1u {
        return clamp(t, vec2i(0), vec2i(size - 1));
    }
    return ((t % size) + size) % size;
}

fn load_level(level: i32, node: vec2f) -> f32 {
    let size = 1 << u32(params.levels - level);
    return textureLoad(pyramid, address(vec2i(node), size), level).r;
}

fn point_depth(p: vec2f) -> f32 {
    let size = i32(textureDimensions(depth_map).x);
    return textureLoad(depth_map, address(vec2i(floor(p * f32(size))), size), 0).r;
}

// Bilinear between texel centres at (i + 0.5) / 2^n, by hand: hardware filtering has only a few
// bits of sub-texel precision and differs between GPUs.
fn bilinear_depth(p: vec2f) -> f32 {
    let size = i32(textureDimensions(depth_map).x);
    let x = p * f32(size) - 0.5;
    let i = vec2i(floor(x));
    let f = x - floor(x);
    let d00 = textureLoad(depth_map, address(i, size), 0).r;
    let d10 = textureLoad(depth_map, address(i + vec2i(1, 0), size), 0).r;
    let d01 = textureLoad(depth_map, address(i + vec2i(0, 1), size), 0).r;
    let d11 = textureLoad(depth_map, address(i + vec2i(1, 1), size), 0).r;
    return mix(mix(d00, d10, f.x), mix(d01, d11, f.x), f.y);
}

fn outside_map(p: vec2f) -> bool {
    return params.clamp_to_map == 1u && (any(p < vec2f(0.0)) || any(p >= vec2f(1.0)));
}

struct Trace {
    z: f32,
    iterations: u32,
    missed: bool,   // left a clamped map
    capped: bool,   // stopped by the iteration cap (must never happen: tests count it)
}

// Sections 3.2 and 4 (figure 13), reading at the ray's current point (the spec's fix of the
// figure's P/P' mix-up). `finest` is the LOD level whose nodes act as leaves.
fn trace_pyramid(p0: vec2f, e: vec2f, z_start: f32, start_level: i32, finest: i32, ascend: bool) -> Trace {
    let res0 = f32(1 << u32(params.levels));
    // Node crossing steps 0.1% of a finest texel past the boundary. The step can clip the corner
    // of a texel the ray only grazes (the paper's 1% missed such corners visibly on real maps);
    // 0.1% is still above float spacing for coordinates in [0, 1) up to 4096^2 maps, and the
    // next-float guard below keeps the ray moving where it is not.
    let delta = 0.001 / res0;
    var t: Trace;
    t.z = z_start;
    var level = start_level;
    // A bound on any ray: at most two steps per node its footprint crosses on each level, plus
    // the descents; the global cap keeps even absurd inputs finite.
    let cap = min(params.iteration_cap, u32(8.0 * (length(e) * res0 + 2.0)) + 16u * u32(params.levels + 1));
    loop {
        if level < finest {
            break;
        }
        if t.iterations >= cap {
            t.capped = true;
            break;
        }
        t.iterations += 1u;
        let res = f32(1 << u32(params.levels - level));
        let p = p0 + e * t.z;
        if outside_map(p) {
            t.missed = true;
            break;
        }
        let node = floor(p * res);
        let d = load_level(level, node);
        if t.z < d {
            let advanced = p0 + e * d;
            if all(floor(advanced * res) == node) {
                t.z = d;
                level -= 1;
            } else {
                // Node crossing: move to the nearer boundary along the ray, just past it.
                let boundary = (node + select(vec2f(0.0), vec2f(1.0), e > vec2f(0.0))) / res;
                let to_boundary = select(vec2f(1.0e30), (boundary - p0) / e, e != vec2f(0.0));
                let x_first = to_boundary.x < to_boundary.y;
                let crossing = select(to_boundary.y, to_boundary.x, x_first);
                // Step `delta` along the footprint, not along the crossing axis: when that axis
                // is nearly parallel to the ray, a step of delta along it could skip texels on the
                // other. If rounding keeps the ray in its node, the next crossing steps on again.
                t.z = max(max(t.z, crossing) + delta / length(e), bitcast<f32>(bitcast<u32>(t.z) + 1u));
                if ascend {
                    level = min(level + 1, params.levels);
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
fn bilinear_cells(p0: vec2f, e: vec2f, z_start: f32, max_cells: u32) -> vec3f {
    let res0 = f32(1 << u32(params.levels));
    let size = i32(res0);
    let q = (p0 + e * z_start) * res0 - 0.5;
    var cell = floor(q);
    let dir = select(vec2f(-1.0), vec2f(1.0), e >= vec2f(0.0));
    let boundary = cell + select(vec2f(0.0), vec2f(1.0), e > vec2f(0.0));
    // Depth at which the ray crosses the next cell boundary on each axis, and per cell after.
    var next = select(vec2f(1.0e30), z_start + (boundary - q) / (e * res0), e != vec2f(0.0));
    let step = select(vec2f(1.0e30), abs(1.0 / (e * res0)), e != vec2f(0.0));
    var z_in = z_start;
    for (var k = 0u; k < max_cells; k++) {
        let z_out = min(min(next.x, next.y), 1.0);
        let c = vec2i(cell);
        let s00 = textureLoad(depth_map, address(c, size), 0).r;
        let s10 = textureLoad(depth_map, address(c + vec2i(1, 0), size), 0).r;
        let s01 = textureLoad(depth_map, address(c + vec2i(0, 1), size), 0).r;
        let s11 = textureLoad(depth_map, address(c + vec2i(1, 1), size), 0).r;
        // Cell coordinates f(z) = a + b z; surface s = s00 + A fx + B fy + C fx fy; the ray is
        // above the surface while g(z) = s - z > 0, a quadratic in z.
        let a = p0 * res0 - 0.5 - cell;
        let b = e * res0;
        let ca = s10 - s00;
        let cb = s01 - s00;
        let cc = s00 - s10 - s01 + s11;
        let c0 = s00 + ca * a.x + cb * a.y + cc * a.x * a.y;
        let c1 = ca * b.x + cb * b.y + cc * (a.x * b.y + a.y * b.x) - 1.0;
        let c2 = cc * b.x * b.y;
        let g_in = c0 + c1 * z_in + c2 * z_in * z_in;
        if g_in <= 0.0 {
            return vec3f(z_in, z_in, f32(k + 1u));
        }
        var root = 2.0;
        if abs(c2) < 1.0e-7 * max(abs(c1), 1.0) {
            root = -c0 / c1;
        } else {
            let disc = c1 * c1 - 4.0 * c2 * c0;
            if disc >= 0.0 {
                let h = -0.5 * (c1 + select(-1.0, 1.0, c1 >= 0.0) * sqrt(disc));
                let r1 = h / c2;
                let r2 = c0 / h;
                if r1 >= z_in && r1 <= z_out { root = r1; }
                if r2 >= z_in && r2 <= z_out { root = min(root, r2); }
            }
        }
        let g_out = c0 + c1 * z_out + c2 * z_out * z_out;
        if root >= z_in && root <= z_out {
            return vec3f(root, root, f32(k + 1u));
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

// Section 3.3, magnification: the point-sampled search on the conservative pyramid brings the ray
// to just above the bilinear surface; there the intersection is refined. The paper interpolates
// between half a texel back and half a texel forward and, when the ray is still above the surface,
// jumps on to the surface depth there (d_i). Both lose intersections on steep maps (the jump by
// up to whole features at grazing angles), so the refinement here solves the ray/bilinear-patch
// quadratic exactly over the next few cells, then resumes the conservative search (climbing
// from level 0, as maximum mipmaps do) when the ray passed them untouched.
fn trace_bilinear(p0: vec2f, e: vec2f, finest: i32) -> Trace {
    let res0 = f32(1 << u32(params.levels));
    var t = trace_pyramid(p0, e, 0.0, params.levels, finest, false);
    // Refinement rounds can at most walk the ray's whole footprint.
    let round_cap = min(params.bilinear_cap, u32(length(e) * res0 + 4.0));
    var round = 0u;
    loop {
        if t.missed || t.capped {
            break;
        }
        if round >= round_cap {
            t.capped = true;
            break;
        }
        round += 1u;
        let cells = bilinear_cells(p0, e, t.z, 4u);
        t.iterations += u32(cells.z);
        if cells.x >= 0.0 {
            t.z = cells.x;
            t.missed = outside_map(p0 + e * t.z);
            break;
        }
        let resumed = trace_pyramid(p0, e, cells.y, 0, finest, true);
        t.z = resumed.z;
        t.missed = resumed.missed;
        t.capped = resumed.capped;
        t.iterations += resumed.iterations;
    }
    return t;
}

// Linear search shared by POM and relief mapping: the first layer at or below the surface and
// the layer before it. Layer count between min and max by view angle, as the engines do.
struct Bracket {
    z_above: f32,
    z_below: f32,
    gap_above: f32,   // surface depth - ray depth at z_above (> 0)
    gap_below: f32,   // ray depth - surface depth at z_below (>= 0)
    steps: u32,
}

fn linear_search(p0: vec2f, e: vec2f, view_z: f32) -> Bracket {
    let layers = max(round(mix(params.layers_max, params.layers_min, abs(view_z))), 1.0);
    let dz = 1.0 / layers;
    var b: Bracket;
    var d = bilinear_depth(p0);
    b.gap_above = d;
    // The ray is at or below every surface point by z = 1, so this ends after `layers` steps.
    while b.z_below < d && f32(b.steps) < layers + 2.0 {
        b.z_above = b.z_below;
        b.gap_above = d - b.z_above;
        b.z_below += dz;
        d = bilinear_depth(p0 + e * b.z_below);
        b.steps += 1u;
    }
    b.gap_below = b.z_below - d;
    return b;
}

fn trace(p0: vec2f, e: vec2f, view_z: f32, finest: i32) -> Trace {
    var t: Trace;
    switch METHOD {
        case PYRAMID: {
            t = trace_pyramid(p0, e, 0.0, params.levels, finest, false);
        }
        case PYRAMID_ASCEND: {
            t = trace_pyramid(p0, e, 0.0, params.levels, finest, true);
        }
        case PYRAMID_BILINEAR: {
            t = trace_bilinear(p0, e, finest);
        }
        case PARALLAX: {
            // Offset limiting: the offset is not divided by V.z, so it never runs away.
            t.z = bilinear_depth(p0);
            t.iterations = 1u;
        }
        case POM: {
            let b = linear_search(p0, e, view_z);
            let w = select(0.0, b.gap_above / (b.gap_above + b.gap_below), b.steps > 0u);
            t.z = mix(b.z_above, b.z_below, w);
            t.iterations = b.steps;
        }
        case RELIEF: {
            let b = linear_search(p0, e, view_z);
            var lo = b.z_above;
            var hi = b.z_below;
            for (var i = 0u; i < params.binary_steps; i++) {
                let mid = 0.5 * (lo + hi);
                if mid < bilinear_depth(p0 + e * mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            t.z = 0.5 * (lo + hi);
            t.iterations = b.steps + params.binary_steps;
        }
        default: {
            // BUMP: no search, the surface stays flat.
            t.z = 0.0;
        }
    }
    return t;
}

fn finest_level(uv: vec2f) -> i32 {
    if params.lod >= 0 {
        return min(params.lod, params.levels);
    }
    let res0 = f32(1 << u32(params.levels));
    let footprint = max(length(dpdx(uv)), length(dpdy(uv))) * res0;
    return clamp(i32(floor(log2(max(footprint, 1.0)))), 0, params.levels);
}

fn shade(uv: vec2f, world: vec3f, tangent: vec3f, bitangent: vec3f, normal: vec3f, lit: bool) -> vec3f {
    let albedo = textureSampleLevel(color_map, linear_repeat, uv, 0.0).rgb;
    let gradient = textureSampleLevel(normal_map, linear_repeat, uv, 0.0).xy;
    let nt = vec3f(gradient * params.depth_scale, 1.0);
    let n = normalize(tangent * nt.x + bitangent * nt.y + normal * nt.z);
    let l = normalize(params.light.xyz - world);
    let v = normalize(params.eye.xyz - world);
    let h = normalize(l + v);
    let ambient = 0.12 * albedo;
    if !lit {
        return ambient;
    }
    let diffuse = max(dot(n, l), 0.0) * albedo;
    let specular = 0.25 * pow(max(dot(n, h), 0.0), 48.0);
    return ambient + diffuse + vec3f(specular);
}

const SKY: vec4f = vec4f(0.16, 0.18, 0.22, 1.0);

@fragment
fn fs_surface(in: VertexOut) -> FragmentOut {
    // Derivatives first, in uniform control flow.
    let finest = finest_level(in.uv);
    let t_axis = normalize(in.tangent);
    let b_axis = normalize(in.bitangent);
    let n_axis = normalize(in.normal);
    let to_eye = normalize(params.eye.xyz - in.world);
    let v = vec3f(dot(to_eye, t_axis), dot(to_eye, b_axis), dot(to_eye, n_axis));
    var out: FragmentOut;
    if v.z <= 1.0e-4 {
        discard;
    }
    let e = -v.xy / v.z * params.depth_scale;
    // Trace within the tile the ray starts in: float spacing stays that of [0, 1).
    let p0 = in.uv - floor(in.uv) * f32(1u - params.clamp_to_map);
    out.ray = vec4f(p0, e);
    var t: Trace;
    if METHOD != BUMP {
        t = trace(p0, e, v.z, finest);
    }
    var hit_uv = p0 + e * t.z;
    if METHOD == PARALLAX {
        hit_uv = p0 - v.xy * params.depth_scale * t.z;
    }
    t.missed = t.missed || outside_map(hit_uv);
    // Iterations, negated when the cap stopped the search.
    out.hit = vec4f(hit_uv, select(t.z, -1.0, t.missed), select(f32(t.iterations), -f32(t.iterations), t.capped));
    if t.missed {
        out.color = SKY;
        return out;
    }
    // World position of the hit: along the surface by the uv offset, into it by the depth.
    let world = in.world + (t_axis * (hit_uv.x - p0.x) + b_axis * (hit_uv.y - p0.y)) * params.tile_world
        - n_axis * t.z * params.depth_scale * params.tile_world;
    var lit = true;
    if params.shadows == 1u && METHOD != BUMP && METHOD != PARALLAX {
        lit = light_reaches(hit_uv, t.z, world, t_axis, b_axis, n_axis, finest);
    }
    out.color = vec4f(shade(hit_uv, world, t_axis, b_axis, n_axis, lit), 1.0);
    if params.show_iterations == 1u {
        // Black through red and yellow to white at 64 iterations, as the CPU heat maps.
        let k = clamp(f32(t.iterations) / 64.0, 0.0, 1.0) * 3.0;
        out.color = vec4f(clamp(vec3f(k, k - 1.0, k - 2.0), vec3f(0.0), vec3f(1.0)), 1.0);
    }
    return out;
}

// Self-shadowing (section 4): trace from where the light ray enters the height field towards
// the hit; the point is lit when that trace ends at the hit.
fn light_reaches(hit: vec2f, z: f32, world: vec3f, t_axis: vec3f, b_axis: vec3f, n_axis: vec3f, finest: i32) -> bool {
    let to_light = normalize(params.light.xyz - world);
    let l = vec3f(dot(to_light, t_axis), dot(to_light, b_axis), dot(to_light, n_axis));
    if l.z <= 1.0e-4 {
        return false;
    }
    let el = -l.xy / l.z * params.depth_scale;
    let entry = hit - el * z;
    let from_light = trace(entry, el, l.z, finest);
    // A light ray that enters a terrain patch through its side is not blocked before it.
    if from_light.missed {
        return true;
    }
    // Lit when the light's ray gets to the hit: within 1.5 texels along the surface, or within a
    // small depth when the light is nearly overhead.
    let short_by = z - from_light.z;
    let res0 = f32(1 << u32(params.levels));
    return short_by * length(el) <= 1.5 / res0 || short_by <= 2.0e-3;
}

@fragment
fn fs_mesh(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    out.ray = vec4f(in.uv, 0.0, 0.0);
    out.hit = vec4f(in.uv, in.depth, 0.0);
    out.color = vec4f(shade(in.uv, in.world, normalize(in.tangent), normalize(in.bitangent), normalize(in.normal), true), 1.0);
    return out;
}
