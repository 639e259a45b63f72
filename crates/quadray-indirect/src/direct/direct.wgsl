// Direct light from one light view through its shadow map; the first view writes, the others
// add. The RSM view's frustum picks the view that lights a point: it is half-open, so a point
// light's faces light each point once.

// `Shadow` is declared in Rust and generated into the prelude (contract.rs).
@group(3) @binding(0) var<uniform> shadow: Shadow;
@group(3) @binding(1) var shadow_map: texture_depth_2d;
@group(3) @binding(2) var shadow_sampler: sampler_comparison;

// Texels the filter reaches either side of a lookup: 3x3 bilinear comparisons a texel apart
// (1.5), and half a texel for the map's depth being its texel centre's.
const PCF_REACH_TEXELS: f32 = 2.5;

// The share of the view's light that reaches x (normal n; the light travels along w): 3x3
// bilinear comparisons of the shadow map around x lifted along its normal by the filter's reach
// times the sine of the light's angle to the surface, which keeps every tap in front of x's own
// surface however it slopes (a normal offset, no acne), and moved half a texel towards the light
// for the depth's precision.
fn shadow_visibility(x: vec3<f32>, n: vec3<f32>, w: vec3<f32>) -> f32 {
    var side = shadow.texel.x;
    if (shadow.texel.y < 0.5) {
        side *= max(dot(x - light.position.xyz, light.direction.xyz), 0.0);
    }
    let cos_light = clamp(-dot(n, w), 0.0, 1.0);
    let sin_light = sqrt(1.0 - cos_light * cos_light);
    let p = x + n * (PCF_REACH_TEXELS * side * sin_light) - w * (0.5 * side);
    let c = shadow.view_proj * vec4<f32>(p, 1.0);
    let uv = vec2<f32>(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
    let depth = c.z / c.w;
    let texel = 1.0 / shadow.texel.z;
    var lit = 0.0;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let at = uv + vec2<f32>(f32(i), f32(j)) * texel;
            lit += textureSampleCompareLevel(shadow_map, shadow_sampler, at, depth);
        }
    }
    return lit / 9.0;
}

@compute @workgroup_size(8, 8)
fn direct_light(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= viewer.width || id.y >= viewer.height) {
        return;
    }
    let r = receiver(id.xy);
    var l = vec3<f32>(0.0);
    if (r.covered && map_texel(light.view_proj * vec4<f32>(r.x, 1.0), vec2<f32>(1.0)).x >= 0) {
        let w = light_towards(light, r.x);
        let cos_light = -dot(r.n, w);
        if (cos_light > 0.0) {
            let e = light_irradiance(light, r.x) * cos_light;
            l = r.albedo / PI * e * shadow_visibility(r.x, r.n, w);
        }
    }
    let index = pixel_index(id.xy);
    let value = vec4<f32>(l, select(0.0, 1.0, r.covered));
    if (first_view()) {
        direct[index] = value;
    } else {
        direct[index] += vec4<f32>(l, 0.0);
    }
}
