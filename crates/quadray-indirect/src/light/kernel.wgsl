// The VPL kernel: the irradiance a VPL or cluster gives a receiver, and its vector form.
// Engine-neutral: no bindings, no accessors (needs node.wgsl's counters).

// (the prelude's LUMINANCE: the Rec. 709 weights, declared in reference.rs)
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, LUMINANCE);
}

// Whether every component of v is a finite number, read from the exponent bits: WGSL lets a
// compiler assume that floats are never NaN or infinite and fold a float test (v != v) away.
fn all_finite(v: vec4<f32>) -> bool {
    return all((bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u)) != vec4<u32>(0x7f800000u));
}

// Whether a surface point x with normal n can enter the kernel (a receiver, a VPL): x finite, n
// finite and not zero (a degenerate triangle's). Callers take any other texel as empty: its NaN
// would reach every sum, cluster and tile it joins.
fn kernel_point(x: vec3<f32>, n: vec3<f32>) -> bool {
    let n2 = dot(n, n);
    return all_finite(vec4<f32>(x, n2)) && n2 > 0.0;
}

// Whether an RSM texel (flux, position and depth, normal) can enter the kernel as a VPL.
fn kernel_vpl(flux: vec3<f32>, pos: vec4<f32>, n: vec3<f32>) -> bool {
    return kernel_point(pos.xyz, n) && all_finite(vec4<f32>(flux, pos.w));
}

// Irradiance at x (normal n) from a VPL or cluster of flux `flux` at xp (normal np), with the
// 1/r^4 clamped at r_min (the spec's kernel; the reference uses the same). A diffuse VPL radiates
// flux / pi * cos: the 1/pi the spec's formula (after the RSM paper) leaves out is put back so
// that indirect and direct light are on the same scale; errors are ratios and do not change.
fn vpl_irradiance(flux: vec3<f32>, xp: vec3<f32>, np: vec3<f32>, x: vec3<f32>, n: vec3<f32>, r_min: f32) -> vec3<f32> {
    evaluations++;
    let d = x - xp;
    let d2 = max(dot(d, d), r_min * r_min);
    return flux * (max(0.0, dot(np, d)) * max(0.0, dot(n, -d)) / (PI * d2 * d2));
}

// The vector irradiance at x from a VPL or cluster: `vpl_irradiance` without the receiver's
// cosine, one column a colour channel, so that transpose(V) * n is `vpl_irradiance` for every
// receiver normal n that faces the VPL (per-tile cuts gather far clusters this way once per
// tile corner and interpolate).
fn vpl_vector(flux: vec3<f32>, xp: vec3<f32>, np: vec3<f32>, x: vec3<f32>, r_min: f32) -> mat3x3<f32> {
    evaluations++;
    let d = x - xp;
    let d2 = max(dot(d, d), r_min * r_min);
    let v = -d * (max(0.0, dot(np, d)) / (PI * d2 * d2));
    return mat3x3<f32>(v * flux.r, v * flux.g, v * flux.b);
}
