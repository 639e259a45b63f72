// quadray-bevy's fragment stage: Bevy's StandardMaterial with its parallax replaced by the
// pyramid trace of quadray_displace (imported as `quadray::trace`, the engine-neutral module).
// The traced uv feeds Bevy's own PBR input, so lighting, shadows and textures stay Bevy's; the
// traced depth is written so displaced surfaces meet other geometry where they really are.

#import bevy_pbr::{
    pbr_fragment::pbr_input_from_standard_material,
    pbr_functions::{alpha_discard, apply_pbr_lighting, calculate_tbn_mikktspace, calculate_view, main_pass_post_lighting_processing},
    forward_io::VertexOutput,
    mesh_view_bindings::view,
}
#import quadray::trace::{PyramidInfo, ray_slope, pyramid_trace, pyramid_lod, pyramid_lit}

// Mirrors `PyramidUniform` in lib.rs.
struct PyramidParams {
    levels: i32,
    clamp_to_map: u32,
    iteration_cap: u32,
    refine_cap: u32,
    // The depth map's width and height in texels (the pyramid pads them to powers of two).
    map_size: vec2<u32>,
    depth_scale: f32,
    flags: u32,
    debug_width: u32,
    // How much of the lit colour a self-shadowed pixel loses (0: no self-shadowing).
    shadow_strength: f32,
    // The self-shadowing light: world direction towards it (w = 0) or its position (w = 1).
    light: vec4<f32>,
}

const FLAG_READY: u32 = 1u;
const FLAG_LOD: u32 = 2u;

@group(#{MATERIAL_BIND_GROUP}) @binding(100) var<uniform> params: PyramidParams;
@group(#{MATERIAL_BIND_GROUP}) @binding(101) var pyramid: texture_2d<f32>;
// Debug output, two entries per pixel: the ray (p0, e) and the hit (u, v, z or -1 when the ray
// left a clamped map, iterations), the layout of quadray_displace's `Frame`.
@group(#{MATERIAL_BIND_GROUP}) @binding(102) var<storage, read_write> debug_hits: array<vec4<f32>>;

struct PyramidOutput {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fragment(in: VertexOutput, @builtin(front_facing) is_front: bool) -> PyramidOutput {
    // Derivatives first, in uniform control flow.
    let uv_dx = dpdx(in.uv);
    let uv_dy = dpdy(in.uv);
    let world_dx = dpdx(in.world_position.xyz);
    let world_dy = dpdy(in.world_position.xyz);

    var displaced = in;
    var depth = in.position.z;
    var shadowed = false;
#ifdef VERTEX_TANGENTS
    let V = calculate_view(in.world_position, view.clip_from_view[3].w == 1.0);
    let tbn = calculate_tbn_mikktspace(in.world_normal, in.world_tangent);
    // Bevy's bitangent points along -v; quadray's tangent space has y along +v.
    let towards = vec3(dot(V, tbn[0]), -dot(V, tbn[1]), dot(V, tbn[2]));
    if (params.flags & FLAG_READY) != 0u && towards.z > 1.0e-4 {
        let info = PyramidInfo(params.levels, params.clamp_to_map, params.iteration_cap, params.refine_cap, params.map_size, vec2(0u));
        var finest = 0;
        if (params.flags & FLAG_LOD) != 0u {
            finest = pyramid_lod(info, uv_dx, uv_dy);
        }
        let e = ray_slope(towards, params.depth_scale);
        var p0 = in.uv;
        if info.clamp_to_map == 0u {
            p0 = fract(in.uv);
        }
        let hit = pyramid_trace(pyramid, info, p0, e, 0.0, info.levels, finest, false);
        if params.debug_width != 0u {
            let pixel = 2u * (u32(in.position.y) * params.debug_width + u32(in.position.x));
            let iterations = select(f32(hit.iterations), -f32(hit.iterations), hit.capped);
            debug_hits[pixel] = vec4(p0, e);
            debug_hits[pixel + 1u] = vec4(p0 + e * hit.z, select(hit.z, -1.0, hit.missed), iterations);
        }
        if hit.missed {
            discard;
        }
        displaced.uv = in.uv + e * hit.z;
        // The hit lies hit.z * depth_scale uv units below the polygon; uv units to world units
        // from the screen-space derivatives.
        let world_per_uv = (length(world_dx) + length(world_dy)) / max(length(uv_dx) + length(uv_dy), 1.0e-12);
        let along_view = world_per_uv * hit.z * params.depth_scale / towards.z;
        let clip = view.clip_from_world * vec4(in.world_position.xyz - V * along_view, 1.0);
        depth = clip.z / clip.w;
        if params.shadow_strength > 0.0 {
            let L = normalize(params.light.xyz - in.world_position.xyz * params.light.w);
            let to_light = vec3(dot(L, tbn[0]), -dot(L, tbn[1]), dot(L, tbn[2]));
            shadowed = !pyramid_lit(pyramid, info, p0 + e * hit.z, hit.z, to_light, params.depth_scale, finest);
        }
    }
#endif

    var pbr_input = pbr_input_from_standard_material(displaced, is_front);
    pbr_input.material.base_color = alpha_discard(pbr_input.material, pbr_input.material.base_color);
    var out: PyramidOutput;
    out.color = apply_pbr_lighting(pbr_input);
    if shadowed {
        out.color = vec4(out.color.rgb * (1.0 - params.shadow_strength), out.color.a);
    }
    out.color = main_pass_post_lighting_processing(pbr_input, out.color);
    out.depth = depth;
    return out;
}
