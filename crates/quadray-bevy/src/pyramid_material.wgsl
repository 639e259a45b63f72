// quadray-bevy's fragment stage: Bevy's StandardMaterial with its parallax replaced by the
// pyramid trace of quadray_displace (imported as `quadray::trace`, the engine-neutral module).
// One entry point serves every pass Bevy draws the material in: the forward main pass (lit
// colour), and, compiled with PREPASS_PIPELINE, the depth, normal and motion-vector prepasses,
// the deferred G-buffer and the shadow maps. Each traces the same ray from its own view and
// writes the traced depth, so every pass sees the displaced surface where it really is. The
// traced uv feeds Bevy's own PBR input, so lighting, shadows and textures stay Bevy's.

#import bevy_pbr::{
    pbr_fragment::pbr_input_from_standard_material,
    pbr_functions::{alpha_discard, calculate_tbn_mikktspace, calculate_view},
    pbr_types::PbrInput,
    mesh_view_bindings::view,
}
#ifdef PREPASS_PIPELINE
#import bevy_pbr::prepass_io::VertexOutput
#ifdef DEFERRED_PREPASS
#import bevy_pbr::pbr_deferred_functions::deferred_gbuffer_from_pbr_input
#endif
#ifdef MOTION_VECTOR_PREPASS
#import bevy_pbr::pbr_prepass_functions::calculate_motion_vector
#endif
#else
#import bevy_pbr::{
    forward_io::VertexOutput,
    pbr_functions::{apply_pbr_lighting, main_pass_post_lighting_processing},
}
#endif
#import quadray::trace::{PyramidInfo, ray_slope, pyramid_trace, pyramid_lod, pyramid_lit, depth_bilinear}

// Mirrors `PyramidUniform` in lib.rs.
struct PyramidParams {
    levels: i32,
    clamp_to_map: u32,
    iteration_cap: u32,
    refine_cap: u32,
    // The depth map's width and height in texels (the pyramid pads them to powers of two).
    map_size: vec2<u32>,
    // 0 until the pyramid is built.
    depth_scale: f32,
    flags: u32,
    debug_width: u32,
    // How much of the lit colour a self-shadowed pixel loses (0: no self-shadowing).
    shadow_strength: f32,
    // The self-shadowing light: world direction towards it (w = 0) or its position (w = 1).
    light: vec4<f32>,
}

const FLAG_LOD: u32 = 1u;

@group(#{MATERIAL_BIND_GROUP}) @binding(100) var<uniform> params: PyramidParams;
@group(#{MATERIAL_BIND_GROUP}) @binding(101) var pyramid: texture_2d<f32>;
// Debug output, two entries per pixel: the ray (p0, e) and the hit (u, v, z or -1 when the ray
// left a clamped map, iterations), the layout of quadray_displace's `Frame`.
@group(#{MATERIAL_BIND_GROUP}) @binding(102) var<storage, read_write> debug_hits: array<vec4<f32>>;

// Bevy's prepass outputs at Bevy's locations (prepass_io's FragmentOutput), plus the traced
// depth, which Bevy's struct carries only for its own depth-clamp emulation.
#ifdef PREPASS_PIPELINE
struct PyramidOutput {
#ifdef NORMAL_PREPASS
    @location(0) normal: vec4<f32>,
#endif
#ifdef MOTION_VECTOR_PREPASS
    @location(1) motion_vector: vec2<f32>,
#endif
#ifdef DEFERRED_PREPASS
    @location(2) deferred: vec4<u32>,
    @location(3) deferred_lighting_pass_id: u32,
#endif
    @builtin(frag_depth) depth: f32,
}
#else
struct PyramidOutput {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}
#endif

// The displaced surface under a fragment of the polygon.
struct Surface {
    // The hit's uv (not wrapped: textures tile as the polygon's uv does).
    uv: vec2<f32>,
    world_position: vec3<f32>,
    // The hit's depth in the view's depth buffer.
    depth: f32,
    // The height field's normal at the hit, in world space.
    normal: vec3<f32>,
    // The hit is hidden from `params.light` by the height field.
    shadowed: bool,
}

// The height field's normal at uv `p` in quadray's tangent space (x along +u, y along +v):
// central differences of the bilinear surface one texel apart, so the normal varies smoothly
// with the hit and a hit a fraction of a texel off turns it only a little.
fn height_field_normal(info: PyramidInfo, p: vec2<f32>) -> vec3<f32> {
    let texel = 1.0 / vec2<f32>(info.size);
    let du = depth_bilinear(pyramid, info, p + vec2(texel.x, 0.0)) - depth_bilinear(pyramid, info, p - vec2(texel.x, 0.0));
    let dv = depth_bilinear(pyramid, info, p + vec2(0.0, texel.y)) - depth_bilinear(pyramid, info, p - vec2(0.0, texel.y));
    // The surface is z = -depth_scale * d(u, v) in uv units.
    return normalize(vec3(params.depth_scale * du / (2.0 * texel.x), params.depth_scale * dv / (2.0 * texel.y), 1.0));
}

// Traces the fragment's ray from the current view (the camera's, or a light's in a shadow pass)
// and discards it when the ray leaves a clamped map. Derivatives come from the caller, taken in
// uniform control flow.
fn traced_surface(in: VertexOutput, uv_dx: vec2<f32>, uv_dy: vec2<f32>, world_dx: vec3<f32>, world_dy: vec3<f32>) -> Surface {
    var s: Surface;
    s.uv = in.uv;
    s.world_position = in.world_position.xyz;
    s.depth = in.position.z;
#ifdef UNCLIPPED_DEPTH_ORTHO_EMULATION
    s.depth = in.unclipped_depth;
#endif
    s.normal = normalize(in.world_normal);
    s.shadowed = false;
#ifdef VERTEX_TANGENTS
    let V = calculate_view(in.world_position, view.clip_from_view[3].w == 1.0);
    let tbn = calculate_tbn_mikktspace(in.world_normal, in.world_tangent);
    // Bevy's bitangent points along -v; quadray's tangent space has y along +v.
    let towards = vec3(dot(V, tbn[0]), -dot(V, tbn[1]), dot(V, tbn[2]));
    // No branch on the uniform around the trace (a material whose pyramid is not built yet
    // traces flat, depth scale 0): lavapipe (Mesa 22.3) crashes drawing a G-buffer whose
    // shader reads memory under such a branch.
    if towards.z > 1.0e-4 {
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
#ifndef PREPASS_PIPELINE
        // Nothing recorded until the pyramid is built.
        if params.debug_width != 0u && params.depth_scale > 0.0 {
            let pixel = 2u * (u32(in.position.y) * params.debug_width + u32(in.position.x));
            let iterations = select(f32(hit.iterations), -f32(hit.iterations), hit.capped);
            debug_hits[pixel] = vec4(p0, e);
            debug_hits[pixel + 1u] = vec4(p0 + e * hit.z, select(hit.z, -1.0, hit.missed), iterations);
        }
#endif
        if hit.missed {
            discard;
        }
        s.uv = in.uv + e * hit.z;
        // The hit lies hit.z * depth_scale uv units below the polygon; uv units to world units
        // from the screen-space derivatives.
        let world_per_uv = (length(world_dx) + length(world_dy)) / max(length(uv_dx) + length(uv_dy), 1.0e-12);
        let along_view = world_per_uv * hit.z * params.depth_scale / towards.z;
        s.world_position = in.world_position.xyz - V * along_view;
        let clip = view.clip_from_world * vec4(s.world_position, 1.0);
        s.depth = clip.z / clip.w;
        let n = height_field_normal(info, p0 + e * hit.z);
        s.normal = normalize(n.x * tbn[0] - n.y * tbn[1] + n.z * tbn[2]);
#ifndef PREPASS_PIPELINE
        if params.shadow_strength > 0.0 {
            let L = normalize(params.light.xyz - in.world_position.xyz * params.light.w);
            let to_light = vec3(dot(L, tbn[0]), -dot(L, tbn[1]), dot(L, tbn[2]));
            s.shadowed = !pyramid_lit(pyramid, info, p0 + e * hit.z, hit.z, to_light, params.depth_scale, finest);
        }
#endif
    }
#endif
    return s;
}

// Bevy's PBR input of the standard material at the hit: its textures at the hit's uv, its
// position, and the height field's normal unless the material brings a normal map of its own.
fn pbr_input_at(in: VertexOutput, is_front: bool, s: Surface) -> PbrInput {
    var displaced = in;
    displaced.uv = s.uv;
    var pbr_input = pbr_input_from_standard_material(displaced, is_front);
    pbr_input.material.base_color = alpha_discard(pbr_input.material, pbr_input.material.base_color);
    pbr_input.world_position = vec4(s.world_position, 1.0);
    pbr_input.frag_coord.z = s.depth;
#ifndef STANDARD_MATERIAL_NORMAL_MAP
    pbr_input.N = s.normal;
    pbr_input.clearcoat_N = s.normal;
#endif
    return pbr_input;
}

@fragment
fn fragment(in: VertexOutput, @builtin(front_facing) is_front: bool) -> PyramidOutput {
    // Derivatives first, in uniform control flow.
    let uv_dx = dpdx(in.uv);
    let uv_dy = dpdy(in.uv);
    let world_dx = dpdx(in.world_position.xyz);
    let world_dy = dpdy(in.world_position.xyz);

    var out: PyramidOutput;
#ifdef PREPASS_PIPELINE
    let s = traced_surface(in, uv_dx, uv_dy, world_dx, world_dy);
#ifdef MOTION_VECTOR_PREPASS
    // The hit's offset from the polygon carried to the previous frame unchanged: exact for
    // meshes that stand still or move without turning.
    let offset = vec4(s.world_position - in.world_position.xyz, 0.0);
    out.motion_vector = calculate_motion_vector(in.world_position + offset, in.previous_world_position + offset);
#endif
    // The material's textures only where a prepass stores more than depth.
#ifdef DEFERRED_PREPASS
    let pbr_input = pbr_input_at(in, is_front, s);
    out.deferred = deferred_gbuffer_from_pbr_input(pbr_input);
    out.deferred_lighting_pass_id = pbr_input.material.deferred_lighting_pass_id;
#ifdef NORMAL_PREPASS
    out.normal = vec4(pbr_input.N * 0.5 + vec3(0.5), 1.0);
#endif
#else ifdef NORMAL_PREPASS
    out.normal = vec4(pbr_input_at(in, is_front, s).N * 0.5 + vec3(0.5), 1.0);
#endif
#else
    let s = traced_surface(in, uv_dx, uv_dy, world_dx, world_dy);
    let pbr_input = pbr_input_at(in, is_front, s);
    out.color = apply_pbr_lighting(pbr_input);
    if s.shadowed {
        out.color = vec4(out.color.rgb * (1.0 - params.shadow_strength), out.color.a);
    }
    out.color = main_pass_post_lighting_processing(pbr_input, out.color);
#endif
    out.depth = s.depth;
    return out;
}
