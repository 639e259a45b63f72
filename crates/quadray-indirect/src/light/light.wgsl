// One RSM view of a light (a spot, a point light's cube face, the sun): its uniform's layout,
// its light towards a point and the RSM's depth. Engine-neutral: no bindings, no accessors.

// `Light`, one RSM view's uniform, is declared in Rust and generated into the prelude
// (contract.rs).

fn is_parallel(light: Light) -> bool {
    return light.parallel.x > 0.5;
}

// The share of the light's intensity sent towards unit direction w (a spot's cone and falloff;
// 1 from a point light).
fn spot_edge(light: Light, w: vec3<f32>) -> f32 {
    let c = dot(w, light.direction.xyz);
    let outer = light.direction.w;
    let inner = light.intensity.w;
    return select(select(0.0, 1.0, c >= outer), smoothstep(outer, inner, c), inner > outer);
}

// Radiant intensity towards unit direction w from the light (a point or spot light).
fn spot_intensity(light: Light, w: vec3<f32>) -> vec3<f32> {
    return light.intensity.rgb * spot_edge(light, w);
}

// What an RSM texel's flux is a share of: the intensity (the sun: irradiance) times a texel's
// measure on the axis (rsm.wgsl).
fn rsm_flux_scale(light: Light) -> vec3<f32> {
    return light.intensity.rgb * light.parallel.y;
}

// Unit direction the light travels in to reach x.
fn light_towards(light: Light, x: vec3<f32>) -> vec3<f32> {
    if (is_parallel(light)) {
        return light.direction.xyz;
    }
    return normalize(x - light.position.xyz);
}

// Irradiance at x on a surface facing the light (W/m^2 per channel): I(w) / d^2, or the sun's.
fn light_irradiance(light: Light, x: vec3<f32>) -> vec3<f32> {
    if (is_parallel(light)) {
        return light.intensity.rgb;
    }
    let to_point = x - light.position.xyz;
    return spot_intensity(light, normalize(to_point)) / max(dot(to_point, to_point), 1e-30);
}

// Depth as the RSM stores it: distance along the light axis in units of the scene extent.
fn light_depth(light: Light, x: vec3<f32>) -> f32 {
    return dot(x - light.position.xyz, light.direction.xyz) * light.position.w;
}
