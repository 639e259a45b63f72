// Deblocking of the per-tile cuts' light. Neighbouring tiles' cuts differ, so their light steps
// at the boundary between them where the truth is smooth. On each line of pixels across a
// boundary, the step between the two pixels beside it that the slopes on either side do not
// explain is spread as a ramp over `tile_deblock` pixels each side, where those pixels and one
// more each side lie on one surface: a video codec's deblocking filter, with the G-buffer for
// its edges. It works on the irradiance (the radiance over the albedo), so that textures keep
// their detail. Boundaries' windows do not overlap (`Settings::TILE_DEBLOCK`), so that each
// invocation filters its own in place. The CPU's twin is `deblock.rs`.

// DEBLOCK_LIMIT (an unexplained step larger than this times the light beside it is the light's
// own edge: kept), DEBLOCK_PLANE (the sine by which a step between two neighbours on one surface
// may leave their plane) and DEBLOCK_ALBEDO (below it a channel's light is left as it is) come
// from the prelude, the twin's constants.

fn one_surface(a: Receiver, b: Receiver) -> bool {
    let d = b.x - a.x;
    return a.covered && b.covered && dot(a.n, b.n) > shade.normal_agreement
        && abs(dot(d, a.n)) <= DEBLOCK_PLANE * length(d);
}

// Filters tile boundary `boundary` (its second tile starts at pixel `boundary` * TILE) on
// `line`, across columns (`axis` 0: the line is a row) or across rows (1).
fn deblock(axis: u32, boundary: u32, line: u32) {
    let radius = min(shade.tile_deblock, TILE / 2u - 1u);
    let along = select(viewer.width, viewer.height, axis == 1u);
    let lines = select(viewer.height, viewer.width, axis == 1u);
    let start = boundary * TILE;
    if (line >= lines || start + radius >= along) {
        return;
    }
    // the window: `radius` + 1 pixels each side, the boundary's first pixel at `radius` + 1
    var pixel: array<vec2<u32>, TILE>;
    var irradiance: array<vec3<f32>, TILE>;
    var albedo: array<vec3<f32>, TILE>;
    var flat = true;
    var previous: Receiver;
    for (var i = 0u; i < 2u * radius + 2u; i++) {
        let at = start - radius - 1u + i;
        pixel[i] = select(vec2<u32>(at, line), vec2<u32>(line, at), axis == 1u);
        let r = receiver(pixel[i]);
        flat = flat && r.covered && (i == 0u || one_surface(previous, r));
        previous = r;
        fetches++;
        albedo[i] = r.albedo;
        let lit = albedo[i] > vec3<f32>(DEBLOCK_ALBEDO);
        irradiance[i] = select(vec3<f32>(0.0), indirect[pixel_index(pixel[i])].rgb / albedo[i], lit);
    }
    if (flat) {
        let k = radius + 1u;
        let step = irradiance[k] - irradiance[k - 1u];
        let slope = 0.5 * (irradiance[k - 1u] - irradiance[k - 2u] + irradiance[k + 1u] - irradiance[k]);
        let excess = step - slope;
        let level = 0.5 * (abs(irradiance[k]) + abs(irradiance[k - 1u]));
        let spread = select(vec3<f32>(0.0), excess, abs(excess) <= DEBLOCK_LIMIT * level);
        for (var j = 0u; j < radius; j++) {
            let w = f32(radius - j) / f32(2u * radius);
            irradiance[k - 1u - j] += w * spread;
            irradiance[k + j] -= w * spread;
        }
        for (var i = 1u; i < 2u * radius + 1u; i++) {
            let index = pixel_index(pixel[i]);
            let lit = albedo[i] > vec3<f32>(DEBLOCK_ALBEDO);
            let e = indirect[index];
            indirect[index] = vec4<f32>(select(e.rgb, irradiance[i] * albedo[i], lit), e.w);
        }
    }
    store_counts(pixel_index(pixel[radius + 1u]));
}

@compute @workgroup_size(8, 8)
fn deblock_columns(@builtin(global_invocation_id) id: vec3<u32>) {
    deblock(0u, id.x + 1u, id.y);
}

@compute @workgroup_size(8, 8)
fn deblock_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    deblock(1u, id.x + 1u, id.y);
}
