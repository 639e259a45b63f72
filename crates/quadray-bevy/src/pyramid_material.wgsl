// quadray-bevy's fragment stage: Bevy's StandardMaterial with its parallax replaced by the
// pyramid trace of quadray_displace (imported as `quadray::trace`, the engine-neutral module).
// One entry point serves every pass Bevy draws the material in: the forward main pass (lit
// colour), and, compiled with PREPASS_PIPELINE, the depth, normal and motion-vector prepasses,
// the deferred G-buffer and the shadow maps. Each traces the same ray from its own view and
// writes the traced depth, so every pass sees the displaced surface where it really is. The
// traced uv feeds Bevy's own PBR input, so lighting, shadows and textures stay Bevy's; the main
// pass then takes out of Bevy's lit colour each light the height field hides from the hit.

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
    pbr_functions::{apply_pbr_lighting, main_pass_post_lighting_processing, calculate_diffuse_color, calculate_F0_dielectric},
    clustered_forward as clustering,
    lighting,
    lighting::{LAYER_BASE, LAYER_CLEARCOAT},
    mesh_types::MESH_FLAGS_SHADOW_RECEIVER_BIT,
    mesh_view_bindings as view_bindings,
    mesh_view_types,
    shadows,
}
#ifdef CONTACT_SHADOWS
#ifdef DEPTH_PREPASS
#import bevy_pbr::pbr_functions::calculate_contact_shadow
#endif
#endif
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
    // The share of a light's contribution a pixel loses where the height field hides that light
    // (0: no self-shadowing).
    shadow_strength: f32,
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
    // Where the rays towards the lights start (none where nothing was traced): the hit in the
    // pyramid's texture space and its depth, the tangent frame and the finest level traced.
    traced: bool,
    texture_hit: vec2<f32>,
    z: f32,
    tbn: mat3x3<f32>,
    finest: i32,
}

fn pyramid_info() -> PyramidInfo {
    return PyramidInfo(params.levels, params.clamp_to_map, params.iteration_cap, params.refine_cap, params.map_size, vec2(0u));
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
    s.traced = false;
#ifdef VERTEX_TANGENTS
    let V = calculate_view(in.world_position, view.clip_from_view[3].w == 1.0);
    let tbn = calculate_tbn_mikktspace(in.world_normal, in.world_tangent);
    // Bevy's bitangent points along -v; quadray's tangent space has y along +v.
    let towards = vec3(dot(V, tbn[0]), -dot(V, tbn[1]), dot(V, tbn[2]));
    // No branch on the uniform around the trace (a material whose pyramid is not built yet
    // traces flat, depth scale 0): lavapipe (Mesa 22.3) crashes drawing a G-buffer whose
    // shader reads memory under such a branch.
    if towards.z > 1.0e-4 {
        let info = pyramid_info();
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
        s.traced = true;
        s.texture_hit = p0 + e * hit.z;
        s.z = hit.z;
        s.tbn = tbn;
        s.finest = finest;
    }
#endif
    return s;
}

#ifndef PREPASS_PIPELINE
// The most lights per pixel whose rays the height field may stop (`SELF_SHADOWED_LIGHTS` in lib.rs).
const SELF_SHADOWED_LIGHTS: u32 = #{SELF_SHADOWED_LIGHTS}u;

// Whether the height field lets the light in world direction L reach the traced hit.
fn reaches_hit(s: Surface, L: vec3<f32>) -> bool {
    let to_light = vec3(dot(L, s.tbn[0]), -dot(L, s.tbn[1]), dot(L, s.tbn[2]));
    return pyramid_lit(pyramid, pyramid_info(), s.texture_hit, s.z, to_light, params.depth_scale, s.finest);
}

// Bevy's contact shadow towards L where the view and the light have them on.
fn contact_shadow(in: PbrInput, L: vec3<f32>, light_has_them: bool) -> f32 {
#ifdef CONTACT_SHADOWS
#ifdef DEPTH_PREPASS
    let steps = view_bindings::contact_shadows_settings.linear_steps;
    if steps > 0u && light_has_them {
        return calculate_contact_shadow(in.world_position.xyz, in.frag_coord.xy, L, steps);
    }
#endif
#endif
    return 1.0;
}

// The direct light of the lights the height field hides from the hit, each light's term exactly
// as Bevy's apply_pbr_lighting adds it (times its shadow map and contact shadow), for the caller
// to take out of Bevy's lit colour. Bevy 0.19 has no per-light hook, so this repeats the least of
// its light loop (pbr_functions.wgsl): its LightingInput and each light's term; rect lights,
// ambient, environment, emissive and transmitted light stay Bevy's. The rays of at most
// SELF_SHADOWED_LIGHTS lights that light the hit are traced, in this order: directional lights,
// then the cluster's point and spot lights; later lights are not self-shadowed.
fn hidden_direct_light(in: PbrInput, s: Surface) -> vec3<f32> {
    var hidden = vec3(0.0);
    if !s.traced || params.shadow_strength <= 0.0 {
        return hidden;
    }
    let NdotV = max(dot(in.N, in.V), 0.0001);
    var input: lighting::LightingInput;
    input.layers[LAYER_BASE].NdotV = NdotV;
    input.layers[LAYER_BASE].N = in.N;
    input.layers[LAYER_BASE].R = reflect(-in.V, in.N);
    input.layers[LAYER_BASE].perceptual_roughness = in.material.perceptual_roughness;
    input.layers[LAYER_BASE].roughness = lighting::perceptualRoughnessToRoughness(in.material.perceptual_roughness);
    input.P = in.world_position.xyz;
    input.V = in.V;
    input.diffuse_color = calculate_diffuse_color(in.material.base_color.rgb, in.material.metallic, in.material.specular_transmission, in.material.diffuse_transmission);
    input.metallic = in.material.metallic;
    input.F0_dielectric = calculate_F0_dielectric(in.material.reflectance);
    input.F0_metallic = in.material.base_color.rgb;
    input.F_ab = lighting::F_AB(in.material.perceptual_roughness, NdotV);
#ifdef STANDARD_MATERIAL_CLEARCOAT
    input.layers[LAYER_CLEARCOAT].NdotV = max(dot(in.clearcoat_N, in.V), 0.0001);
    input.layers[LAYER_CLEARCOAT].N = in.clearcoat_N;
    input.layers[LAYER_CLEARCOAT].R = reflect(-in.V, in.clearcoat_N);
    input.layers[LAYER_CLEARCOAT].perceptual_roughness = in.material.clearcoat_perceptual_roughness;
    input.layers[LAYER_CLEARCOAT].roughness = lighting::perceptualRoughnessToRoughness(in.material.clearcoat_perceptual_roughness);
    input.clearcoat_strength = in.material.clearcoat;
#endif
#ifdef STANDARD_MATERIAL_ANISOTROPY
    input.anisotropy = in.anisotropy_strength;
    input.Ta = in.anisotropy_T;
    input.Ba = in.anisotropy_B;
#endif
    let receives_shadows = (in.flags & MESH_FLAGS_SHADOW_RECEIVER_BIT) != 0u;
    let view_z = dot(vec4(view.view_from_world[0].z, view.view_from_world[1].z, view.view_from_world[2].z, view.view_from_world[3].z), in.world_position);
    var traced = 0u;

    for (var i = 0u; i < view_bindings::lights.n_directional_lights && traced < SELF_SHADOWED_LIGHTS; i++) {
        let light = &view_bindings::lights.directional_lights[i];
#ifdef LIGHTMAP
        let enable_diffuse = ((*light).flags & mesh_view_types::DIRECTIONAL_LIGHT_FLAGS_AFFECTS_LIGHTMAPPED_MESH_DIFFUSE_BIT) != 0u;
#else
        let enable_diffuse = true;
#endif
        let term = lighting::directional_light(i, &input, enable_diffuse);
        if all(term == vec3(0.0)) {
            continue;
        }
        traced += 1u;
        let L = (*light).direction_to_light;
        if reaches_hit(s, L) {
            continue;
        }
        var shadow = 1.0;
        if receives_shadows && ((*light).flags & mesh_view_types::DIRECTIONAL_LIGHT_FLAGS_SHADOWS_ENABLED_BIT) != 0u {
            shadow = shadows::fetch_directional_shadow(i, in.world_position, in.world_normal, view_z, in.frag_coord.xy);
        }
        shadow *= contact_shadow(in, L, receives_shadows && ((*light).flags & mesh_view_types::DIRECTIONAL_LIGHT_FLAGS_CONTACT_SHADOWS_ENABLED_BIT) != 0u);
        hidden += term * shadow;
    }

    let cluster_index = clustering::view_fragment_cluster_index(in.frag_coord.xy, view_z, in.is_orthographic);
    let ranges = clustering::unpack_clusterable_object_index_ranges(cluster_index);
    // The cluster lists its point lights, then its spot lights.
    for (var i = ranges.first_point_light_index_offset; i < ranges.first_reflection_probe_index_offset && traced < SELF_SHADOWED_LIGHTS; i++) {
        let light_id = clustering::get_clusterable_object_id(i);
        let light = &view_bindings::clustered_lights.data[light_id];
        let spot = i >= ranges.first_spot_light_index_offset;
#ifdef LIGHTMAP
        let enable_diffuse = ((*light).flags & mesh_view_types::POINT_LIGHT_FLAGS_AFFECTS_LIGHTMAPPED_MESH_DIFFUSE_BIT) != 0u;
#else
        let enable_diffuse = true;
#endif
        var term: vec3<f32>;
        if spot {
            term = lighting::spot_light(light_id, &input, enable_diffuse);
        } else {
            term = lighting::point_light(light_id, &input, enable_diffuse, true);
        }
        if all(term == vec3(0.0)) {
            continue;
        }
        traced += 1u;
        let L = normalize((*light).position_radius.xyz - in.world_position.xyz);
        if reaches_hit(s, L) {
            continue;
        }
        var shadow = 1.0;
        if receives_shadows && ((*light).flags & mesh_view_types::POINT_LIGHT_FLAGS_SHADOWS_ENABLED_BIT) != 0u {
            if spot {
                shadow = shadows::fetch_spot_shadow(light_id, in.world_position, in.world_normal, (*light).shadow_map_near_z, in.frag_coord.xy);
            } else {
                shadow = shadows::fetch_point_shadow(light_id, in.world_position, in.world_normal, in.frag_coord.xy);
            }
        }
        shadow *= contact_shadow(in, L, receives_shadows && ((*light).flags & mesh_view_types::POINT_LIGHT_FLAGS_CONTACT_SHADOWS_ENABLED_BIT) != 0u);
        hidden += term * shadow;
    }
    return hidden;
}
#endif

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
    // Bevy's sum scales direct light by the exposure.
    let hidden = view.exposure * params.shadow_strength * hidden_direct_light(pbr_input, s);
    out.color = vec4(max(out.color.rgb - hidden, vec3(0.0)), out.color.a);
    out.color = main_pass_post_lighting_processing(pbr_input, out.color);
#endif
    out.depth = s.depth;
    return out;
}
