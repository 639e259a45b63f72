// The RSM's vertex stage over Bevy's meshes (`RsmSource::Meshes`): each vertex of Bevy's mesh
// allocator's slabs to world space by the instance's mesh uniform, or by Bevy's own skinning
// (`bevy_pbr::skinning`, the joints of the entity's skin), then quadray's RSM fragment stage
// (`RsmPass::fragment_source`, before this file) over the albedo below: the material's base
// colour (times 1 - metallic) times its base colour texture, sampled with the image's sampler
// (an sRGB image's view decodes sRGB). Group 0: the RSM's raster and light uniforms; group 1:
// the material; group 2: Bevy's mesh bind group.

struct RsmMaterial {
    // rgb: the base colour times 1 - metallic
    albedo: vec4<f32>,
    // the uv transform's matrix (x axis, y axis) and translation (xy)
    uv_matrix: vec4<f32>,
    uv_translation: vec4<f32>,
}

@group(1) @binding(0) var<uniform> material: RsmMaterial;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var base_color_sampler: sampler;

struct MeshVertex {
    @builtin(instance_index) instance_index: u32,
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
#ifdef VERTEX_UVS
    @location(2) uv: vec2<f32>,
#endif
#ifdef SKINNED
    @location(3) joint_indices: vec4<u32>,
    @location(4) joint_weights: vec4<f32>,
#endif
}

@vertex
fn mesh_vertex(in: MeshVertex) -> VertexOut {
#ifdef SKINNED
    let world_from_local = skinning::skin_model(in.joint_indices, in.joint_weights, in.instance_index);
    let normal = skinning::skin_normals(world_from_local, in.normal);
#else
    let instance = mesh[in.instance_index];
    let world_from_local = affine3_to_square(instance.world_from_local);
    let normal = mat2x4_f32_to_mat3x3_unpack(
        instance.local_from_world_transpose_a,
        instance.local_from_world_transpose_b,
    ) * in.normal;
#endif
    let world = (world_from_local * vec4<f32>(in.position, 1.0)).xyz;
    var out: VertexOut;
    out.clip = raster.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.normal = normal;
    out.albedo = material.albedo.rgb;
#ifdef VERTEX_UVS
    let uv_matrix = mat2x2<f32>(material.uv_matrix.xy, material.uv_matrix.zw);
    out.uv = uv_matrix * in.uv + material.uv_translation.xy;
#else
    out.uv = vec2<f32>(0.0);
#endif
    out.texture = 0u;
    return out;
}

fn surface_albedo(v: VertexOut) -> vec3<f32> {
#ifdef VERTEX_UVS
    return v.albedo * textureSample(base_color_texture, base_color_sampler, v.uv).rgb;
#else
    return v.albedo;
#endif
}
