// Direct light from one light view through its shadow map; the first view writes, the others
// add. The RSM view's frustum picks the view that lights a point: it is half-open, so a point
// light's faces light each point once.

// `Shadow` is declared in Rust and generated into the prelude (contract.rs).
@group(3) @binding(0) var<uniform> shadow: Shadow;
@group(3) @binding(1) var shadow_map: texture_depth_2d;
@group(3) @binding(2) var shadow_sampler: sampler_comparison;

// Texels the filter reaches either side of a lookup: its taps' bilinear footprints end a texel
// away, and the map's depth is its texel centre's, half a texel more.
const PCF_REACH_TEXELS: f32 = 1.5;

// The share of the view's light that reaches x (normal n; the light travels along w): four
// bilinear comparisons half a texel either way, a 3x3-texel filter weighing 1-2-1 by 1-2-1 (as
// nine plain comparisons would, in four fetches), around x lifted along its normal by the
// filter's reach times the sine of the light's angle to the surface, which keeps every texel the
// filter reads in front of x's own surface however it slopes (a normal offset, no acne), and
// moved half a texel towards the light for the depth's precision.
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
    let h = 0.5 / shadow.texel.z;
    let taps = shadow_tap(uv + vec2<f32>(-h, -h), depth) + shadow_tap(uv + vec2<f32>(h, -h), depth)
        + shadow_tap(uv + vec2<f32>(-h, h), depth) + shadow_tap(uv + vec2<f32>(h, h), depth);
    return 0.25 * taps;
}

// One bilinear comparison: the share of the four texels around uv that lie at or behind depth
// (depths reversed, as the raster passes draw: nearer is greater).
fn shadow_tap(uv: vec2<f32>, depth: f32) -> f32 {
    return textureSampleCompareLevel(shadow_map, shadow_sampler, uv, depth);
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
