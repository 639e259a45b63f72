// The compact G-buffer and RSM layout's encodings (`GBufferLayout::Compact`): a unit normal in
// two octahedral coordinates, and a position rebuilt from the depth buffer.

// The octahedral coordinates of unit normal `n` (in [-1, 1]^2): the axes map to exact values.
fn octahedral_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z >= 0.0) {
        return p;
    }
    return (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
}

// The unit normal of octahedral coordinates `e`.
fn octahedral_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    // the lower half folded back over the diagonals
    let fold = max(-n.z, 0.0);
    n.x -= select(fold, -fold, n.x < 0.0);
    n.y -= select(fold, -fold, n.y < 0.0);
    return normalize(n);
}

// The world position whose depth texel `t` of a `size` map holds, through `inverse` (clip ->
// world relative to `origin`, the view's eye; the depth reversed, as quadray's raster passes draw
// it): the texel's centre at that depth, as the rasteriser interpolated it. Relative to the eye,
// f32 rounding moves it along its ray only.
fn unproject(inverse: mat4x4<f32>, origin: vec3<f32>, t: vec2<i32>, size: vec2<f32>, depth: f32) -> vec3<f32> {
    let uv = (vec2<f32>(t) + 0.5) / size;
    let clip = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, depth, 1.0);
    let relative = inverse * clip;
    return origin + relative.xyz / relative.w;
}
