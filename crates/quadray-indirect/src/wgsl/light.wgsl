// The spot light: its uniform's layout, its intensity by direction and the RSM's depth.
// Engine-neutral: no bindings, no accessors.

struct Light {
    view_proj: mat4x4<f32>,
    // xyz: position, w: 1 / scene extent (RSM depth unit)
    position: vec4<f32>,
    // xyz: unit axis, w: cos(cone)
    direction: vec4<f32>,
    // rgb: intensity on the axis, w: cos(cone - falloff)
    intensity: vec4<f32>,
}

// Radiant intensity towards unit direction w from the light.
fn spot_intensity(light: Light, w: vec3<f32>) -> vec3<f32> {
    let c = dot(w, light.direction.xyz);
    let outer = light.direction.w;
    let inner = light.intensity.w;
    let edge = select(select(0.0, 1.0, c >= outer), smoothstep(outer, inner, c), inner > outer);
    return light.intensity.rgb * edge;
}

// Depth as the RSM stores it: distance along the light axis in units of the scene extent.
fn light_depth(light: Light, x: vec3<f32>) -> f32 {
    return dot(x - light.position.xyz, light.direction.xyz) * light.position.w;
}
