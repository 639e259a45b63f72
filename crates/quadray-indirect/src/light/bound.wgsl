// An upper bound on what a light-quadtree node gives any receiver of a box (per-tile cuts): the
// kernel of `vpl_irradiance`, flux cos_p cos |d|^2 / (pi max(|d|^2, r_min^2)^2), is at most
// flux cos_p cos / (pi max(|d|^2, r_min^2)), which falls with the distance, so the boxes' nearest
// distance and bounds of the two cosines over the boxes and normal cones bound it (Walter et al.
// 2005, Lightcuts, section 4.1, with cones as Conty & Kulla 2018). Engine-neutral: no bindings,
// no accessors (needs node.wgsl and kernel.wgsl).

// A bound of max(0, dot(n, normalize(d))) over unit n within `half_cos` of `axis` and d in the
// box [lo, hi]: the box turned into a frame whose z is the axis (the box of the turned box), the
// least angle of its directions from z bounded from its z_max and its least |x|, |y| (Lightcuts;
// behind the axis's plane its largest), less the cone's half-angle.
fn cone_box_cos_bound(axis: vec3<f32>, half_cos: f32, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    if (half_cos <= 0.0) {
        return 1.0;
    }
    let centre = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    // any two unit vectors perpendicular to the axis and to each other
    let helper = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(axis.x) > 0.7);
    let tx = normalize(cross(axis, helper));
    let ty = cross(axis, tx);
    let z_max = dot(axis, centre) + dot(abs(axis), half);
    let lateral = abs(vec2<f32>(dot(tx, centre), dot(ty, centre)));
    let spread = vec2<f32>(dot(abs(tx), half), dot(abs(ty), half));
    // z / |d| is highest at the box's highest z and, in front of the axis's plane, its least
    // lateral reach; behind it (every direction at least 90 degrees from the axis) its widest
    let reach = select(max(vec2<f32>(0.0), lateral - spread), lateral + spread, z_max <= 0.0);
    let least_cos = z_max / max(length(vec3<f32>(reach, z_max)), 1e-30);
    if (least_cos >= half_cos) {
        return 1.0;
    }
    // cos(least angle - half-angle)
    let half_sin = sqrt(max(0.0, 1.0 - half_cos * half_cos));
    return max(0.0, least_cos * half_cos + sqrt(max(0.0, 1.0 - least_cos * least_cos)) * half_sin);
}

// A bound of the luminance of the irradiance a node of flux `flux` (`node`: its box and normal
// cone around `axis`) gives any receiver in the box [lo, hi] whose normal lies within
// `receiver_cos` of `receiver_axis`, with the kernel's clamp `r_min`.
fn node_bound(flux: vec3<f32>, node: NodeBounds, axis: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>, receiver_axis: vec3<f32>, receiver_cos: f32, r_min: f32) -> f32 {
    bound_evaluations++;
    // the box of d = receiver - VPL
    let d_lo = lo - node.hi.xyz;
    let d_hi = hi - node.lo.xyz;
    let nearest = max(vec3<f32>(0.0), max(d_lo, -d_hi));
    let d2 = max(dot(nearest, nearest), r_min * r_min);
    let cos_vpl = cone_box_cos_bound(axis, node.lo.w, d_lo, d_hi);
    let cos_receiver = cone_box_cos_bound(receiver_axis, receiver_cos, -d_hi, -d_lo);
    return luminance(flux) * cos_vpl * cos_receiver / (PI * d2);
}
