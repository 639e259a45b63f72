// Per-tile cuts with indirect shadows: the anchors, the pixels at a tile's corners whose shadow
// rays stand for the others' (a first set, and a second among the pixels on none of the first
// set's surfaces), the rays to each listed node's visibility target, and each pixel's patch of
// anchors and the lone pixels' own sums. Part of the per-tile kernel (kernel.wgsl), whose
// workgroup memory it shares.

// Offers pixel `local` as anchor set `set`'s anchor at each corner (the nearest wins).
fn offer_anchor(local: u32, anchor_set: u32) {
    let p = vec2<i32>(i32(local % TILE), i32(local / TILE));
    for (var c = 0u; c < 4u; c++) {
        let d = p - vec2<i32>(i32(CORNERS[c] % TILE), i32(CORNERS[c] / TILE));
        atomicMin(&anchor_key[4u * anchor_set + c], (u32(dot(d, d)) << 8u) | local);
    }
}

// Phase 1, then, with shadows: the second set of anchors, among the pixels on none of the first
// set's surfaces (each would otherwise walk alone, `lone_sums`), and how many those pixels are.
// Every invocation calls it.
fn second_anchors(local: u32, r: Receiver, shape: PixelPatch) -> u32 {
    if (is_lone(r, shape)) {
        atomicAdd(&off_anchor_count, 1u);
        offer_anchor(local, 1u);
    }
    workgroupBarrier();
    if (local == 0u) {
        off_anchor_total = atomicLoad(&off_anchor_count);
    }
    return workgroupUniformLoad(&off_anchor_total);
}

// Indirect shadows per tile: each target's byte of `verdicts` a set of anchors (`sets`, 1 or 2;
// byte `slot * sets + set`), bit c + 4 set where the target (its mean, mean normal) faces the
// receiver of the set's corner c's anchor (`shadow_anchor`), and then bit c where that receiver
// sees it (`visible`, shadows/march.wgsl), one invocation a target, set and corner; a pixel on an
// anchor's surface weighs each of its tile's nodes by its target's visibility from the anchors
// of its set the target faces, interpolated, so that a tile walks at most four shadow rays a
// target and set instead of one a pixel and node. The fused kernel's walks; the split passes'
// walk their targets a lane each (split.wgsl). (An anchor behind the target's plane
// gets no light from it and no ray: 1-22% fewer fetches on the visibility scenes, the same
// pictures or better. Skipping the anchors whose plane the target is behind too made the door
// scene's shadows blocky, 0.87 -> 1.35; a target behind every anchor's plane walks none:
// BENCHMARKS.md.)
fn corner_visibility(local: u32, tile: u32, targets: u32, sets: u32) {
    let base = tile * shade.tile_capacity;
    for (var k = local; k < 4u * sets * targets; k += TILE_PIXELS) {
        let slot = k / (4u * sets);
        let anchor_set = (k / 4u) % sets;
        let c = k % 4u;
        let seen = anchor_bits(tile, tile_targets[base + slot], anchor_set, c);
        let byte = slot * sets + anchor_set;
        atomicOr(&verdicts[byte / 4u], seen << (8u * (byte % 4u)));
    }
}

// One shadow ray of `corner_visibility`: target `index`'s bits from corner c's anchor of set
// `anchor_set` (bit c + 4: the target faces it; bit c: and the anchor's receiver sees it).
fn anchor_bits(tile: u32, index: u32, anchor_set: u32, c: u32) -> u32 {
    fetches++;
    let node = nodes[index];
    let a = 4u * anchor_set + c;
    let x = anchor_position(tile, a);
    var seen = 0u;
    if (dot(node.normal.xyz, x - node.pos.xyz) > 0.0) {
        seen = 1u << (c + 4u);
        if (!behind_every_anchor(tile, node.pos.xyz, anchor_set) && visible(x, anchor_normal(tile, a), shadow_end(index, node, x), node.normal.xyz)) {
            seen |= 1u << c;
        }
    }
    return seen;
}

// The point a shadow ray from receiver `x` walks to: the target's mean; with the occupancy grid,
// for a target of several surfaces facing one way (its normal cone within PARALLEL_TARGET_COS,
// from the prelude) and a receiver beyond its box's farthest face along its normal, a point on
// that face: the mean lies between the surfaces (inside a box whose top and the floor around it
// make the cluster), where the grid finds the top in the way while every VPL of the cluster is
// in view. (The depth maps marched alone judge the mean better: the face took the OBJ box's
// FLIP with them 0.0243 -> 0.0287.)
fn shadow_end(index: u32, node: Node, x: vec3<f32>) -> vec3<f32> {
    let n = node.normal.xyz;
    if (node.normal.w > 0.5 || dot(n, n) < 0.01 || occupancy_load(0u) == 0u) {
        return node.pos.xyz;
    }
    fetches++;
    let b = bounds[index];
    if (b.lo.w < PARALLEL_TARGET_COS) {
        return node.pos.xyz;
    }
    let u = normalize(n);
    let reach = max(u * (b.hi.xyz - node.pos.xyz), u * (b.lo.xyz - node.pos.xyz));
    let face = node.pos.xyz + u * max(reach.x + reach.y + reach.z, 0.0);
    return select(node.pos.xyz, face, dot(u, x - face) > 0.0);
}

// Whether `p` lies behind the plane of every corner's anchor by more than the plane agreement:
// the receivers on the anchors' surfaces get no light from it, and a ray from an anchor would
// pass through the anchor's own surface, so it counts as hidden without one.
// (of set `anchor_set`)
fn behind_every_anchor(tile: u32, p: vec3<f32>, anchor_set: u32) -> bool {
    for (var c = 0u; c < 4u; c++) {
        let a = 4u * anchor_set + c;
        if (dot(anchor_normal(tile, a), p - anchor_position(tile, a)) >= -terms.plane_agreement) {
            return false;
        }
    }
    return true;
}

// The pixel that stands for corner c % 4 in the shadow rays of anchor set c / 4: the covered
// pixel nearest the corner (phase 1 found it), so that a tile at the picture's silhouette or
// with a hole at a corner still tests from four receivers instead of every pixel walking alone.
// (With them the shadowed gather takes 0.55-0.62x the time of the corners alone on the leak,
// storeys and gap scenes, though only 4-6% of the pixels walked alone: BENCHMARKS.md.)
fn shadow_anchor(c: u32) -> u32 {
    return atomicLoad(&anchor_key[c]) & 255u;
}

// Phase 1 (with shadows, before `second_anchors`) and phase 5: where a covered pixel takes the
// shared nodes from the corners' bilinear patch (`on_patch`; else, across a depth edge, it
// evaluates them too), and with shadows the weights of the first set's anchors on its own
// surface, normalised (all zero: none is); then, where none is and the tile walks from two sets,
// the second set's (`second_patch`; all zero again: the pixel is lone). Every pixel's own.
struct PixelPatch {
    on_patch: bool,
    w: vec4<f32>,
    seen_weights: vec4<f32>,
    // the anchor set the weights are of
    anchor_set: u32,
}

fn pixel_patch(local: u32, r: Receiver, corners_covered: bool) -> PixelPatch {
    let t = vec2<f32>(f32(local % TILE), f32(local / TILE)) / f32(TILE - 1u);
    let w = vec4<f32>((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
    var on_patch = false;
    var seen_weights = vec4<f32>(0.0);
    if (r.covered && corners_covered) {
        var x = vec3<f32>(0.0);
        for (var c = 0u; c < 4u; c++) {
            x += w[c] * tile_x[CORNERS[c]];
        }
        on_patch = distance(x, r.x) <= terms.plane_agreement;
    }
    if (SHADOWS && r.covered) {
        seen_weights = select(anchor_weights(r, w, 0u), w, on_patch);
    }
    return PixelPatch(on_patch, w, seen_weights, 0u);
}

// The weights of anchor set `set`'s anchors on the receiver's surface (bilinear weights `w`),
// normalised (all zero: none is).
fn anchor_weights(r: Receiver, w: vec4<f32>, anchor_set: u32) -> vec4<f32> {
    var weights = vec4<f32>(0.0);
    for (var c = 0u; c < 4u; c++) {
        let a = shadow_anchor(4u * anchor_set + c);
        let same_surface = dot(tile_n[a], r.n) > shade.normal_agreement
            && abs(dot(r.x - tile_x[a], tile_n[a])) < terms.plane_agreement;
        weights[c] = select(0.0, max(w[c], 1e-3), same_surface);
    }
    return weights / max(weights.x + weights.y + weights.z + weights.w, 1e-6);
}

// A pixel on none of the first set's surfaces in a tile that walks from two sets: the second
// set's weights, by the inverse square of the distance to each anchor in pixels (the second
// set's anchors lie anywhere in the tile, where the first set's stand at the corners; on the
// leak scene the bilinear weights took the FLIP with shadows 0.00685 -> 0.00700, inverse
// distances to 0.00693, their squares to 0.00689).
fn second_patch(local: u32, r: Receiver, shape: PixelPatch) -> PixelPatch {
    let p = vec2<f32>(f32(local % TILE), f32(local / TILE));
    var near = vec4<f32>(0.0);
    for (var c = 0u; c < 4u; c++) {
        let a = shadow_anchor(4u + c);
        let d = p - vec2<f32>(f32(a % TILE), f32(a / TILE));
        let q = 0.25 + dot(d, d);
        near[c] = 1.0 / (q * q);
    }
    return PixelPatch(shape.on_patch, shape.w, anchor_weights(r, near, 1u), 1u);
}

// Whether a covered pixel is lone: with shadows, no anchor lies on its surface.
fn is_lone(r: Receiver, shape: PixelPatch) -> bool {
    return SHADOWS && r.covered && all(shape.seen_weights == vec4<f32>(0.0));
}

// Phase 5, with shadows: the lone pixels' sums. A lone pixel (off the corners' patch: it sums
// every listed node; on no anchor's surface of either set) walks once to the target of each
// node that lights it, and the tile's invocations share those walks: a bit a lone pixel and target in `verdicts` (free once
// `list_for_gather` copied the corners' bits), as many lone pixels a batch as the bits hold.
// (Each lone pixel walking to its targets in turn kept the other invocations of its SIMD group
// waiting: the gather took 0.81-0.86x the time with the lone pixels' walks left out on the leak,
// storeys and courtyard scenes.) Every invocation calls it; a lone pixel's sum, else zero.
fn lone_sums(local: u32, tile: u32, r: Receiver, listed: u32, lone: bool) -> vec3<f32> {
    if (local == 0u) {
        atomicStore(&lone_count, 0u);
    }
    if (local < TILE_PIXELS / 4u) {
        atomicStore(&lone_pixels[local], 0u);
    }
    workgroupBarrier();
    var row = 0u;
    if (lone) {
        row = atomicAdd(&lone_count, 1u);
        atomicOr(&lone_pixels[row / 4u], local << (8u * (row % 4u)));
    }
    workgroupBarrier();
    let targets = max(atomicLoad(&target_count), 1u);
    let rows = atomicLoad(&lone_count);
    let batch_rows = min(TILE_PIXELS, 32u * (TILE_FRONTIER / 4u) / targets);
    if (local == 0u) {
        lone_batches = (rows + batch_rows - 1u) / batch_rows;
    }
    let batches = workgroupUniformLoad(&lone_batches);
    let base = tile * shade.tile_capacity;
    var irradiance = vec3<f32>(0.0);
    for (var b = 0u; b < batches; b++) {
        let first = b * batch_rows;
        let bits = min(rows - first, batch_rows) * targets;
        let mine = lone && row >= first && row < first + batch_rows;
        for (var i = local; i < (bits + 31u) / 32u; i += TILE_PIXELS) {
            atomicStore(&verdicts[i], 0u);
        }
        workgroupBarrier();
        // the targets of the nodes that light the pixel (those facing it, and it them)
        if (mine) {
            for (var i = 0u; i < listed; i++) {
                fetches++;
                let node = nodes[list_node(tile, i) & ~SHARED];
                let d = r.x - node.pos.xyz;
                if (dot(node.normal.xyz, d) > 0.0 && dot(r.n, d) < 0.0) {
                    let bit = (row - first) * targets + (list_shadow(tile, i) >> 16u);
                    atomicOr(&verdicts[bit / 32u], 1u << (bit % 32u));
                }
            }
        }
        workgroupBarrier();
        // the walks, one invocation a lone pixel and target; a bit stays set where it sees it
        for (var k = local; k < bits; k += TILE_PIXELS) {
            if (((atomicLoad(&verdicts[k / 32u]) >> (k % 32u)) & 1u) == 1u) {
                let lone_row = first + k / targets;
                let p = (atomicLoad(&lone_pixels[lone_row / 4u]) >> (8u * (lone_row % 4u))) & 255u;
                fetches++;
                let index = tile_targets[base + k % targets];
                let t = nodes[index];
                if (!visible(tile_x[p], tile_n[p], shadow_end(index, t, tile_x[p]), t.normal.xyz)) {
                    atomicAnd(&verdicts[k / 32u], ~(1u << (k % 32u)));
                }
            }
        }
        workgroupBarrier();
        if (mine) {
            for (var i = 0u; i < listed; i++) {
                fetches++;
                let node = nodes[list_node(tile, i) & ~SHARED];
                let bit = (row - first) * targets + (list_shadow(tile, i) >> 16u);
                let seen = f32((atomicLoad(&verdicts[bit / 32u]) >> (bit % 32u)) & 1u);
                irradiance += seen * vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, r.x, r.n, terms.r_min);
            }
        }
        workgroupBarrier();
    }
    return irradiance;
}
