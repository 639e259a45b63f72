// The sums over RSM texels: the brute force over every VPL (method reference) and RSM sampling
// (method rsm). Needs node.wgsl, kernel.wgsl, light.wgsl and receiver.wgsl.
// Accessors: `fn load_rsm_normal(t: vec2<i32>) -> vec4<f32>` (xyz: the texel's unit normal, w: 1
// where the light sees geometry), `fn load_rsm_position(t: vec2<i32>) -> vec4<f32>` (xyz: world
// position), `fn load_rsm_flux(t: vec2<i32>) -> vec3<f32>`, and for RSM sampling
// `fn load_rsm_sample(i: u32) -> vec4<f32>`, sample `i` of the pattern (xy: offset in texels, z:
// weight, w: the pattern's radius; `crate::gathers::samples::rsm_samples`).

// Irradiance at `r` from the VPL of RSM texel `t`; an empty texel gives none.
fn texel_irradiance(t: vec2<i32>, r: Receiver, r_min: f32) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    fetches++;
    let n = load_rsm_normal(t);
    if (n.w > 0.5) {
        fetches += 2u;
        let p = load_rsm_position(t);
        let flux = load_rsm_flux(t);
        // (a texel the kernel cannot take is empty, as the quadtree packs it)
        if (kernel_vpl(flux, p, n.xyz)) {
            e = vpl_irradiance(flux, p.xyz, n.xyz, r.x, r.n, r_min);
        }
    }
    return e;
}

// The brute force's sum at `r`: texels `range.x` to `range.y` (excluded) of an RSM of side
// `rsm_size`, row-major.
fn vpl_sum(r: Receiver, rsm_size: u32, r_min: f32, range: vec2<u32>) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    for (var i = range.x; i < range.y; i++) {
        let t = vec2<i32>(i32(i % rsm_size), i32(i / rsm_size));
        e += texel_irradiance(t, r, r_min);
    }
    return e;
}

// RSM sampling's sum at `r` (method rsm): samples `range.x` to `range.y` (excluded) of the
// pattern, every `range.z`-th (interleaved sampling's part), around `r`'s projection into the
// RSM (of side `rsm_size`) of `light`.
fn sampled_sum(r: Receiver, light: Light, rsm_size: u32, r_min: f32, range: vec3<u32>) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    let clip = light.view_proj * vec4<f32>(r.x, 1.0);
    let side = f32(rsm_size);
    // Receivers outside the spot's frustum (the walls beside and above it) project outside
    // the RSM or, behind the light, nowhere: centre their disk on the nearest RSM point, or
    // the middle, so that the disk still reaches the VPLs that light them.
    let ndc = clip.xy / max(clip.w, 1e-6);
    let projected = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * side;
    // (a blend, not `select`: Mesa 22.3's lavapipe crashes compiling a branch here)
    let behind = step(clip.w, 0.0);
    let centre = mix(clamp(projected, vec2<f32>(0.0), vec2<f32>(side)), vec2<f32>(0.5 * side), behind);
    // The pattern reaches sample.w texels; beyond the farthest corner there is nothing to
    // sample, so shrink it to that corner (weights scale with the disk's area).
    let corner = max(centre, vec2<f32>(side) - centre);
    let size = i32(rsm_size);
    for (var s = range.x; s < range.y; s += range.z) {
        let sample = load_rsm_sample(s);
        let scale = min(1.0, length(corner) / sample.w);
        let t = vec2<i32>(floor(centre + sample.xy * scale));
        if (all(t >= vec2<i32>(0)) && all(t < vec2<i32>(size))) {
            e += sample.z * scale * scale * texel_irradiance(t, r, r_min);
        }
    }
    return e;
}
