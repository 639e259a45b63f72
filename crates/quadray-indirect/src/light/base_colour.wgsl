// The base colour textures of the scene (`scene/textures.rs`): one array of sRGB layers of one
// size, read texel by texel with `textureLoad` (the format decodes sRGB) and filtered here as
// the vertex's packed glTF sampler says, so that each triangle has its own sampler (one sampler
// binding could not) and the CPU's twin, `SceneTextures::sample`, repeats the arithmetic. No
// mipmaps: nearest reads one texel, linear four.

@group(1) @binding(0) var base_colours: texture_2d_array<f32>;

const UNTEXTURED: u32 = 0xffffffffu;
// the low bits of a packed texture hold the layer; the filter and the wraps lie above
const LAYER_BITS: u32 = 16u;

fn euclid_mod(i: i32, n: i32) -> i32 {
    return ((i % n) + n) % n;
}

// Texel `i` of a row or column of `n` under `wrap` (0 repeat, 1 clamp to edge, 2 mirrored).
fn wrapped(i: i32, n: i32, wrap: u32) -> i32 {
    if (wrap == 1u) {
        return clamp(i, 0, n - 1);
    }
    if (wrap == 2u) {
        let m = euclid_mod(i, 2 * n);
        return select(2 * n - 1 - m, m, m < n);
    }
    return euclid_mod(i, n);
}

fn base_texel(texture: u32, x: i32, y: i32) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(base_colours));
    let wrap_u = (texture >> (LAYER_BITS + 1u)) & 3u;
    let wrap_v = (texture >> (LAYER_BITS + 3u)) & 3u;
    let layer = i32(texture & ((1u << LAYER_BITS) - 1u));
    let at = vec2<i32>(wrapped(x, size.x, wrap_u), wrapped(y, size.y, wrap_v));
    return textureLoad(base_colours, at, layer, 0).rgb;
}

// The linear RGB of packed texture `texture` at `uv` ((0, 0) the top-left corner); one without
// a texture.
fn base_colour(texture: u32, uv: vec2<f32>) -> vec3<f32> {
    if (texture == UNTEXTURED) {
        return vec3<f32>(1.0);
    }
    let at = uv * vec2<f32>(textureDimensions(base_colours));
    if (((texture >> LAYER_BITS) & 1u) == 1u) {
        let i = vec2<i32>(floor(at));
        return base_texel(texture, i.x, i.y);
    }
    let x = at - 0.5;
    let i = floor(x);
    let f = x - i;
    let i0 = vec2<i32>(i);
    let i1 = i0 + vec2<i32>(1);
    let top = mix(base_texel(texture, i0.x, i0.y), base_texel(texture, i1.x, i0.y), f.x);
    let bottom = mix(base_texel(texture, i0.x, i1.y), base_texel(texture, i1.x, i1.y), f.x);
    return mix(top, bottom, f.y);
}

// The fragment's albedo: the vertices' base colour times the texture's.
fn surface_albedo(v: VertexOut) -> vec3<f32> {
    return v.albedo * base_colour(v.texture, v.uv);
}
