// Bevy's deferred G-buffer and prepass depth as the G-buffer quadray's gather reads: world
// position (w = 1 where lit geometry is seen), the normal turned towards the camera, and the
// diffuse albedo, each Rgba32Float. Bevy's own unpacking functions read its packed texels.

#import bevy_pbr::pbr_deferred_types::{
    unpack_unorm4x8_, unpack_24bit_normal, unpack_flags, DEFERRED_FLAGS_UNLIT_BIT
}
#import bevy_pbr::utils::octahedral_decode

struct View {
    world_from_clip: mat4x4<f32>,
    eye: vec4<f32>,
    size: vec2<u32>,
}

@group(0) @binding(0) var deferred: texture_2d<u32>;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var<uniform> view: View;
@group(0) @binding(3) var position_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var normal_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var albedo_out: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn translate(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= view.size)) {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let z = textureLoad(depth, pixel, 0);
    let texel = textureLoad(deferred, pixel, 0);
    // Bevy's depth is reversed (0 at infinity: nothing drawn); unlit materials reflect nothing
    if (z <= 0.0 || (unpack_flags(texel.a) & DEFERRED_FLAGS_UNLIT_BIT) != 0u) {
        textureStore(position_out, pixel, vec4<f32>(0.0));
        textureStore(normal_out, pixel, vec4<f32>(0.0));
        textureStore(albedo_out, pixel, vec4<f32>(0.0));
        return;
    }
    let ndc = (vec2<f32>(id.xy) + 0.5) / vec2<f32>(view.size) * vec2<f32>(2.0, -2.0)
        + vec2<f32>(-1.0, 1.0);
    let world = view.world_from_clip * vec4<f32>(ndc, z, 1.0);
    let position = world.xyz / world.w;
    var normal = octahedral_decode(unpack_24bit_normal(texel.a));
    normal = select(-normal, normal, dot(normal, view.eye.xyz - position) >= 0.0);
    // as Bevy stores them: sRGB-ish base colour (gamma 2.2), metallic in the properties' green
    let base = pow(unpack_unorm4x8_(texel.r).rgb, vec3<f32>(2.2));
    let metallic = unpack_unorm4x8_(texel.b).g;
    textureStore(position_out, pixel, vec4<f32>(position, 1.0));
    textureStore(normal_out, pixel, vec4<f32>(normal, 1.0));
    textureStore(albedo_out, pixel, vec4<f32>(base * (1.0 - metallic), 1.0));
}
