// The VPL kernel: the irradiance a VPL or cluster gives a receiver, and its vector form.
// Engine-neutral: no bindings, no accessors (needs node.wgsl's counters).

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
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
