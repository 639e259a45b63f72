// quadray's own surfaces (wall, terrain, photo, torus, and the displaced-mesh baseline): every
// method traces the same tangent-space ray and shades the hit the same way; only `trace`
// differs. Composed after the generated constants (METHOD_*) and trace.wgsl, whose conventions it
// follows. The method is a pipeline-overridable constant, so each pipeline compiles to just its
// own search.

override METHOD: u32 = 0u;

// Changes when the map or the surface does.
struct MapParams {
    // The plane of the wall / terrain (mesh baseline): origin, and world vectors per unit of u, v.
    plane_origin: vec4f,
    plane_u: vec4f,
    plane_v: vec4f,
    pyramid: PyramidInfo,
    tile_world: f32,     // world size of one texture repeat
    mesh_grid: u32,      // mesh baseline: quads per side per tile
    tiles: u32,          // texture repeats per side of the surface
    _pad: u32,
}

// Changes every frame.
struct FrameParams {
    view_proj: mat4x4f,
    eye: vec4f,
    light: vec4f,
    depth_scale: f32,    // texture units per unit of depth
    lod: i32,            // finest level the pyramid may reach; -1 = from derivatives
    layers_min: f32,
    layers_max: f32,
    binary_steps: u32,
    shadows: u32,
    show_iterations: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> frame: FrameParams;
@group(1) @binding(0) var<uniform> surface: MapParams;
// Min depths, one mip per level; for METHOD_CONE the cone map (cone.wgsl) instead.
@group(1) @binding(1) var pyramid: texture_2d<f32>;
@group(1) @binding(2) var depth_map: texture_2d<f32>; // the map itself (bilinear reads)
@group(1) @binding(3) var normal_map: texture_2d<f32>;
@group(1) @binding(4) var color_map: texture_2d<f32>;
@group(1) @binding(5) var linear_repeat: sampler;

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
    // Texels the search read (TraceHit.fetches); 1 where the light's ray is blocked, else 0.
    @location(3) search: vec2f,
}

@vertex
fn vs_surface(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4f(v.position, 1.0);
    out.world = v.position;
    out.uv = v.uv;
    out.normal = v.normal;
    out.tangent = v.tangent.xyz;
    out.bitangent = cross(v.normal, v.tangent.xyz) * v.tangent.w;
    out.depth = 0.0;
    return out;
}

// The baseline of figure 20: a grid of 2 * mesh_grid^2 triangles per tile whose vertices sit on
// the bilinear surface, drawn a row of quads at a time as a triangle strip (each vertex shaded
// twice, not six times as a list would: the bilinear reads are most of a vertex's cost), one
// instance a row of a tile. A quad's diagonal runs from its (0, 1) corner to its (1, 0) one.
@vertex
fn vs_mesh(@builtin(vertex_index) vid: u32, @builtin(instance_index) row_of_tile: u32) -> VertexOut {
    let g = surface.mesh_grid;
    let tile = row_of_tile / g;
    let cell = vec2u(vid / 2u, row_of_tile % g + vid % 2u);
    let tile_xy = vec2f(f32(tile % surface.tiles), f32(tile / surface.tiles));
    let uv = tile_xy + vec2f(cell) / f32(g);
    let d = depth_bilinear(depth_map, surface.pyramid, uv);
    let n = normalize(cross(surface.plane_v.xyz, surface.plane_u.xyz));
    let world = surface.plane_origin.xyz + surface.plane_u.xyz * uv.x + surface.plane_v.xyz * uv.y
        - n * d * frame.depth_scale * surface.tile_world;
    var out: VertexOut;
    out.clip = frame.view_proj * vec4f(world, 1.0);
    out.world = world;
    out.uv = uv;
    out.normal = n;
    out.tangent = normalize(surface.plane_u.xyz);
    out.bitangent = normalize(surface.plane_v.xyz);
    out.depth = d;
    return out;
}

// Linear search shared by POM and relief mapping: the first layer at or below the surface and
// the layer before it. Layer count between min and max by view angle, as the engines do.
struct Bracket {
    z_above: f32,
    z_below: f32,
    gap_above: f32,   // surface depth - ray depth at z_above (> 0)
    gap_below: f32,   // ray depth - surface depth at z_below (>= 0)
    steps: u32,
    fetches: u32,
}

// The textureLoads of one depth_bilinear.
const BILINEAR_FETCHES: u32 = 4u;

fn linear_search(p0: vec2f, e: vec2f, view_z: f32) -> Bracket {
    let layers = max(round(mix(frame.layers_max, frame.layers_min, abs(view_z))), 1.0);
    let dz = 1.0 / layers;
    var b: Bracket;
    var d = depth_bilinear(depth_map, surface.pyramid, p0);
    b.fetches = BILINEAR_FETCHES;
    b.gap_above = d;
    // The ray is at or below every surface point by z = 1, so this ends after `layers` steps;
    // the integer bound holds where a NaN view direction makes `layers` NaN.
    let max_steps = u32(frame.layers_max) + 1u;
    while b.z_below < d && f32(b.steps) < layers + 2.0 && b.steps <= max_steps {
        b.z_above = b.z_below;
        b.gap_above = d - b.z_above;
        b.z_below += dz;
        d = depth_bilinear(depth_map, surface.pyramid, p0 + e * b.z_below);
        b.steps += 1u;
        b.fetches += BILINEAR_FETCHES;
    }
    b.gap_below = b.z_below - d;
    return b;
}

fn trace(p0: vec2f, e: vec2f, view_z: f32, finest: i32) -> TraceHit {
    let info = surface.pyramid;
    var t: TraceHit;
    switch METHOD {
        case METHOD_PYRAMID: {
            t = pyramid_trace(pyramid, info, p0, e, 0.0, info.levels, finest, false);
        }
        case METHOD_PYRAMID_ASCEND: {
            t = pyramid_trace(pyramid, info, p0, e, 0.0, info.levels, finest, true);
        }
        case METHOD_PYRAMID_BILINEAR: {
            t = bilinear_trace(pyramid, depth_map, info, p0, e, finest);
        }
        case METHOD_PARALLAX: {
            // Offset limiting: the offset is not divided by V.z, so it never runs away.
            t.z = depth_bilinear(depth_map, info, p0);
            t.iterations = 1u;
            t.fetches = BILINEAR_FETCHES;
        }
        case METHOD_POM: {
            let b = linear_search(p0, e, view_z);
            let w = select(0.0, b.gap_above / (b.gap_above + b.gap_below), b.steps > 0u);
            t.z = mix(b.z_above, b.z_below, w);
            t.iterations = b.steps;
            t.fetches = b.fetches;
        }
        case METHOD_RELIEF: {
            let b = linear_search(p0, e, view_z);
            var lo = b.z_above;
            var hi = b.z_below;
            t.fetches = b.fetches;
            for (var i = 0u; i < frame.binary_steps; i++) {
                let mid = 0.5 * (lo + hi);
                t.fetches += BILINEAR_FETCHES;
                if mid < depth_bilinear(depth_map, info, p0 + e * mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            t.z = 0.5 * (lo + hi);
            t.iterations = b.steps + frame.binary_steps;
        }
        case METHOD_CONE: {
            // The cone map is bound in the pyramid's place; the largest layer count is the
            // number of cone steps.
            t = cone_trace(pyramid, info, p0, e, u32(frame.layers_max), frame.binary_steps);
        }
        default: {
            // METHOD_BUMP: no search, the surface stays flat.
            t.z = 0.0;
        }
    }
    return t;
}

fn finest_level(uv: vec2f) -> i32 {
    let levels = surface.pyramid.levels;
    if frame.lod >= 0 {
        return min(frame.lod, levels);
    }
    return pyramid_lod(surface.pyramid, dpdx(uv), dpdy(uv));
}

fn shade(uv: vec2f, world: vec3f, tangent: vec3f, bitangent: vec3f, normal: vec3f, lit: bool) -> vec3f {
    let albedo = textureSampleLevel(color_map, linear_repeat, uv, 0.0).rgb;
    let gradient = textureSampleLevel(normal_map, linear_repeat, uv, 0.0).xy;
    let nt = vec3f(gradient * frame.depth_scale, 1.0);
    let n = normalize(tangent * nt.x + bitangent * nt.y + normal * nt.z);
    let l = normalize(frame.light.xyz - world);
    let v = normalize(frame.eye.xyz - world);
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
    let info = surface.pyramid;
    let t_axis = normalize(in.tangent);
    let b_axis = normalize(in.bitangent);
    let n_axis = normalize(in.normal);
    let to_eye = normalize(frame.eye.xyz - in.world);
    let v = vec3f(dot(to_eye, t_axis), dot(to_eye, b_axis), dot(to_eye, n_axis));
    var out: FragmentOut;
    if v.z <= 1.0e-4 {
        discard;
    }
    let e = ray_slope(v, frame.depth_scale);
    // Trace within the tile the ray starts in: float spacing stays that of [0, 1).
    let p0 = in.uv - floor(in.uv) * f32(1u - info.clamp_to_map);
    out.ray = vec4f(p0, e);
    var t: TraceHit;
    if METHOD != METHOD_BUMP {
        t = trace(p0, e, v.z, finest);
    }
    var hit_uv = p0 + e * t.z;
    if METHOD == METHOD_PARALLAX {
        hit_uv = p0 - v.xy * frame.depth_scale * t.z;
    }
    t.missed = t.missed || outside_map(info, hit_uv);
    // Iterations, negated when the cap stopped the search.
    out.hit = vec4f(hit_uv, select(t.z, -1.0, t.missed), select(f32(t.iterations), -f32(t.iterations), t.capped));
    out.search.x = f32(t.fetches);
    if t.missed {
        out.color = SKY;
        return out;
    }
    // World position of the hit: along the surface by the uv offset, into it by the depth.
    let world = in.world + (t_axis * (hit_uv.x - p0.x) + b_axis * (hit_uv.y - p0.y)) * surface.tile_world
        - n_axis * t.z * frame.depth_scale * surface.tile_world;
    var lit = true;
    if frame.shadows == 1u && METHOD != METHOD_BUMP && METHOD != METHOD_PARALLAX {
        lit = light_reaches(hit_uv, t.z, world, t_axis, b_axis, n_axis, finest);
    }
    out.search.y = select(1.0, 0.0, lit);
    out.color = vec4f(shade(hit_uv, world, t_axis, b_axis, n_axis, lit), 1.0);
    if frame.show_iterations == 1u {
        // Black through red and yellow to white at 64 iterations, as the CPU heat maps.
        let k = clamp(f32(t.iterations) / 64.0, 0.0, 1.0) * 3.0;
        out.color = vec4f(clamp(vec3f(k, k - 1.0, k - 2.0), vec3f(0.0), vec3f(1.0)), 1.0);
    }
    return out;
}

// Self-shadowing with this pipeline's own search (trace.wgsl's shadow_lit).
fn light_reaches(hit: vec2f, z: f32, world: vec3f, t_axis: vec3f, b_axis: vec3f, n_axis: vec3f, finest: i32) -> bool {
    let to_light = normalize(frame.light.xyz - world);
    let l = vec3f(dot(to_light, t_axis), dot(to_light, b_axis), dot(to_light, n_axis));
    if l.z <= 1.0e-4 {
        return false;
    }
    let el = ray_slope(l, frame.depth_scale);
    return shadow_lit(surface.pyramid, z, trace(hit - el * z, el, l.z, finest), el);
}

@fragment
fn fs_mesh(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    out.ray = vec4f(in.uv, 0.0, 0.0);
    out.hit = vec4f(in.uv, in.depth, 0.0);
    out.color = vec4f(shade(in.uv, in.world, normalize(in.tangent), normalize(in.bitangent), normalize(in.normal), true), 1.0);
    return out;
}
