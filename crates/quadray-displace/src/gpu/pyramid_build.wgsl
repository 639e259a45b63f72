// Builds the min-depth (max-height) pyramid of section 3.1 one level per dispatch, from level 0:
// the map, or for the bilinear surface the minimum over each texel's 3x3 neighbourhood, padded to
// powers of two with depth 1 (the deepest, so padding never lowers a node's minimum).
// min() on f32 is exact, so this matches the CPU builder bit for bit.

// 1: wrap texel reads (tiled surface), 0: clamp (terrain).
override WRAP: u32 = 1u;
// Level 0 takes the minimum over (2 RADIUS + 1)^2 texels: 0 for the map itself, 1 conservative.
override RADIUS: i32 = 0;

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var dst: texture_storage_2d<r32float, write>;

// Texel t of a map of `size` texels (per axis) under this pipeline's addressing.
fn address(t: vec2i, size: vec2i) -> vec2i {
    if WRAP == 1u {
        return ((t % size) + size) % size;
    }
    return clamp(t, vec2i(0), size - 1);
}

@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    // A side already down to one texel has one child per parent on that axis.
    let last = vec2i(textureDimensions(src)) - 1;
    let c = vec2i(id.xy) * 2;
    let c1 = min(c + 1, last);
    let m = min(
        min(textureLoad(src, c, 0).r, textureLoad(src, vec2i(c1.x, c.y), 0).r),
        min(textureLoad(src, vec2i(c.x, c1.y), 0).r, textureLoad(src, c1, 0).r),
    );
    textureStore(dst, vec2i(id.xy), vec4f(m, 0.0, 0.0, 0.0));
}

// src: the map (any size); dst: level 0, padded to powers of two.
@compute @workgroup_size(8, 8)
fn level0(@builtin(global_invocation_id) id: vec3u) {
    let padded = textureDimensions(dst);
    if id.x >= padded.x || id.y >= padded.y {
        return;
    }
    let size = vec2i(textureDimensions(src));
    var m = 1.0;
    if all(vec2i(id.xy) < size) {
        m = 1.0e30;
        for (var dy = -RADIUS; dy <= RADIUS; dy++) {
            for (var dx = -RADIUS; dx <= RADIUS; dx++) {
                m = min(m, textureLoad(src, address(vec2i(id.xy) + vec2i(dx, dy), size), 0).r);
            }
        }
    }
    textureStore(dst, vec2i(id.xy), vec4f(m, 0.0, 0.0, 0.0));
}
