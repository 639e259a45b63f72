// Builds the min-depth (max-height) pyramid of section 3.1 one level per dispatch, and the
// conservative level 0 for the bilinear surface (min over each texel's 3x3 neighbourhood).
// min() on f32 is exact, so this matches the CPU builder bit for bit.

// 1: wrap texel reads (tiled surface), 0: clamp (terrain).
override WRAP: u32 = 1u;

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var dst: texture_storage_2d<r32float, write>;

fn address(t: vec2i, size: i32) -> vec2i {
    if WRAP == 1u {
        return ((t % size) + size) % size;
    }
    return clamp(t, vec2i(0), vec2i(size - 1));
}

@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let c = vec2i(id.xy) * 2;
    let m = min(
        min(textureLoad(src, c, 0).r, textureLoad(src, c + vec2i(1, 0), 0).r),
        min(textureLoad(src, c + vec2i(0, 1), 0).r, textureLoad(src, c + vec2i(1, 1), 0).r),
    );
    textureStore(dst, vec2i(id.xy), vec4f(m, 0.0, 0.0, 0.0));
}

@compute @workgroup_size(8, 8)
fn dilate(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(dst);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    var m = 1.0e30;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let t = address(vec2i(id.xy) + vec2i(dx, dy), i32(size.x));
            m = min(m, textureLoad(src, t, 0).r);
        }
    }
    textureStore(dst, vec2i(id.xy), vec4f(m, 0.0, 0.0, 0.0));
}
