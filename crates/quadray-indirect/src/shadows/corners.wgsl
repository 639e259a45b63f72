// The one cut's indirect shadows from corner receivers (--shadow-corners K): a pass walks from
// the receiver at every K-th pixel across and down (and the last) to each cluster of the cut,
// one workgroup a corner, and keeps a bit a cluster; the gather then weighs a cluster at a pixel
// by the bits of the corners around it that lie on its surface and face the cluster, bilinear,
// instead of walking itself. So a frame walks corners x clusters rays, not pixels x clusters
// (1/K^2 of them), and the walks of one workgroup start at one point. A pixel with no corner on
// its surface (across a depth edge, at a silhouette) walks its own rays, and so does every pixel
// for the clusters past the corners' words. Part of the cut's shader: it reads the bindings of
// gathers/shared.wgsl and `on_surface` of output/upsample.wgsl.

// (SHADOW_CORNER_WORDS, the most words of bits a corner keeps, comes from the prelude)

// Group 3: per corner its receiver (x, w: 1 where covered; n), then its visibility bits, bit
// `rank % 32` of word `rank / 32` for the cluster of that rank in the cut (`cut_rank`).
@group(3) @binding(0) var<storage, read_write> corner_receivers: array<vec4<f32>>;
@group(3) @binding(1) var<storage, read_write> corner_bits: array<u32>;

// The cut's clusters are kept in class segments (light/node.rs): the cluster at `i` of `cut`
// is the one of rank `class_start[class] + i % segment` in the cut taken class by class.
var<private> class_start: array<u32, 17>;

// Fills `class_start` (17 entries: the last is the cut's size) from the class counts.
fn load_class_starts() {
    let segment = arrayLength(&cut) / (CUT_CLASS_SIDE * CUT_CLASS_SIDE);
    var start = 0u;
    for (var c = 0u; c < CUT_CLASS_SIDE * CUT_CLASS_SIDE; c++) {
        class_start[c] = start;
        start += min(cut_count[1u + c], segment);
    }
    class_start[CUT_CLASS_SIDE * CUT_CLASS_SIDE] = start;
}

// The rank of the cluster at `i` of `cut` (after `load_class_starts`).
fn cut_rank(i: u32) -> u32 {
    let segment = arrayLength(&cut) / (CUT_CLASS_SIDE * CUT_CLASS_SIDE);
    return class_start[i / segment] + i % segment;
}

// The index in `cut` of the cluster of rank `rank` (below the cut's size).
fn cut_index(rank: u32) -> u32 {
    let segment = arrayLength(&cut) / (CUT_CLASS_SIDE * CUT_CLASS_SIDE);
    var c = 0u;
    while (c + 1u < CUT_CLASS_SIDE * CUT_CLASS_SIDE && class_start[c + 1u] <= rank) {
        c++;
    }
    return c * segment + rank - class_start[c];
}

// Whether a cluster at `xp` facing `np` and a receiver at `x` facing `n` face each other (both
// of the kernel's cosines positive): a corner's bit for a cluster that does not light it says
// nothing.
fn lights(xp: vec3<f32>, np: vec3<f32>, x: vec3<f32>, n: vec3<f32>) -> bool {
    return dot(np, x - xp) > 0.0 && dot(n, xp - x) > 0.0;
}

// The pixel of corner (x, y).
fn corner_pixel(c: vec2<u32>) -> vec2<u32> {
    return min(c * shade.shadow_corners, vec2<u32>(viewer.width - 1u, viewer.height - 1u));
}

// A workgroup's corners (64 / `shade.corner_lanes` of them, at most CORNERS_A_GROUP), their
// words of bits and their walks' fetches.
const CORNER_GROUP: u32 = 64u;
const CORNERS_A_GROUP: u32 = 8u;
var<workgroup> corner_words: array<atomic<u32>, SHADOW_CORNER_WORDS * CORNERS_A_GROUP>;
var<workgroup> corner_fetches: array<atomic<u32>, CORNERS_A_GROUP>;

// `shade.corner_lanes` threads a corner, 64 / `shade.corner_lanes` corners of a row a
// workgroup: each corner's receiver, and its view of each cluster of the cut (the grid walked,
// or the depth maps marched, as a pixel's own test).
@compute @workgroup_size(CORNER_GROUP)
fn shadow_corners(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let lanes = shade.corner_lanes;
    let slot = local / lanes;
    let lane = local % lanes;
    let across = group.x * (CORNER_GROUP / lanes) + slot;
    // (a row's last workgroup may hold fewer corners than it has room for)
    let in_row = across < shade.corners_x;
    let c = vec2<u32>(min(across, shade.corners_x - 1u), group.y);
    let pixel = corner_pixel(c);
    let corner = c.y * shade.corners_x + c.x;
    let r = receiver(pixel);
    load_class_starts();
    let clusters = min(class_start[CUT_CLASS_SIDE * CUT_CLASS_SIDE], 32u * shade.corner_words);
    let words = slot * SHADOW_CORNER_WORDS;
    for (var w = lane; w < shade.corner_words; w += lanes) {
        atomicStore(&corner_words[words + w], 0u);
    }
    if (lane == 0u) {
        atomicStore(&corner_fetches[slot], 0u);
    }
    workgroupBarrier();
    if (in_row && r.covered) {
        for (var rank = lane; rank < clusters; rank += lanes) {
            fetches++;
            let node = cut[cut_index(rank)];
            if (lights(node.pos.xyz, node.normal.xyz, r.x, r.n) && visible(r.x, r.n, node.pos.xyz, node.normal.xyz)) {
                atomicOr(&corner_words[words + rank / 32u], 1u << (rank % 32u));
            }
        }
    }
    atomicAdd(&corner_fetches[slot], fetches);
    workgroupBarrier();
    if (!in_row) {
        return;
    }
    for (var w = lane; w < shade.corner_words; w += lanes) {
        corner_bits[corner * shade.corner_words + w] = atomicLoad(&corner_words[words + w]);
    }
    if (lane == 0u) {
        corner_receivers[2u * corner] = vec4<f32>(r.x, select(0.0, 1.0, r.covered));
        corner_receivers[2u * corner + 1u] = vec4<f32>(r.n, 0.0);
        // (the corner's walks count at its pixel: the gather adds its own after)
        counts[pixel_index(pixel)] += vec4<u32>(0u, atomicLoad(&corner_fetches[slot]), 0u, 0u);
    }
}

// A receiver's corners (`corner_patch`): the four around its pixel, their weights (bilinear,
// zero for a corner off the receiver's surface) and the words of bits last read.
struct CornerPatch {
    corners: vec4<u32>,
    w: vec4<f32>,
    x: array<vec3<f32>, 4>,
    n: array<vec3<f32>, 4>,
    // the word of bits held (its index + 1; 0 before the first) and each corner's
    word: u32,
    bits: vec4<u32>,
}

var<private> corner_set: CornerPatch;

// Finds receiver `r`'s corners (its pixel from the camera's projection, as the pass may gather
// a receiver for another pixel's sum), after `load_class_starts`; whether any lies on its
// surface.
fn corner_patch(r: Receiver) -> bool {
    let c = viewer.view_proj * vec4<f32>(r.x, 1.0);
    let size = vec2<f32>(f32(viewer.width), f32(viewer.height));
    let uv = vec2<f32>(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
    let pixel = vec2<u32>(clamp(uv * size, vec2<f32>(0.0), size - 1.0));
    let last = vec2<u32>(shade.corners_x, shade.corners_y) - 1u;
    let lo = min(pixel / shade.shadow_corners, last);
    let hi = min(lo + 1u, last);
    let p0 = vec2<f32>(corner_pixel(lo));
    let span = max(vec2<f32>(corner_pixel(hi)) - p0, vec2<f32>(1.0));
    let t = clamp((vec2<f32>(pixel) - p0) / span, vec2<f32>(0.0), vec2<f32>(1.0));
    let bilinear = vec4<f32>((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
    corner_set.corners = vec4<u32>(lo.y, lo.y, hi.y, hi.y) * shade.corners_x + vec4<u32>(lo.x, hi.x, lo.x, hi.x);
    corner_set.word = 0u;
    var any_on = false;
    for (var i = 0u; i < 4u; i++) {
        fetches += 2u;
        let x = corner_receivers[2u * corner_set.corners[i]];
        var q: Receiver;
        q.x = x.xyz;
        q.n = corner_receivers[2u * corner_set.corners[i] + 1u].xyz;
        q.covered = x.w > 0.5;
        corner_set.x[i] = q.x;
        corner_set.n[i] = q.n;
        corner_set.w[i] = select(0.0, max(bilinear[i], 1e-3), on_surface(q, r));
        any_on = any_on || corner_set.w[i] > 0.0;
    }
    return any_on;
}

// The visibility of the cut's cluster at `i` (`node`) from receiver `r` on its corners' patch
// (`corner_patch`): the bits of the corners it lights, weighted; where it lights none (it lies
// nearly in the surface's plane), its little light there counts as seen, as the per-tile cuts
// take it; past the corners' words the receiver walks.
fn corner_visibility(i: u32, node: Node, r: Receiver) -> f32 {
    let rank = cut_rank(i);
    if (rank >= 32u * shade.corner_words) {
        return select(0.0, 1.0, visible(r.x, r.n, node.pos.xyz, node.normal.xyz));
    }
    if (corner_set.word != rank / 32u + 1u) {
        fetches += 4u;
        corner_set.word = rank / 32u + 1u;
        corner_set.bits = vec4<u32>(
            corner_bits[corner_set.corners.x * shade.corner_words + rank / 32u],
            corner_bits[corner_set.corners.y * shade.corner_words + rank / 32u],
            corner_bits[corner_set.corners.z * shade.corner_words + rank / 32u],
            corner_bits[corner_set.corners.w * shade.corner_words + rank / 32u],
        );
    }
    var lit = 0.0;
    var seen = 0.0;
    for (var c = 0u; c < 4u; c++) {
        if (corner_set.w[c] > 0.0 && lights(node.pos.xyz, node.normal.xyz, corner_set.x[c], corner_set.n[c])) {
            lit += corner_set.w[c];
            seen += corner_set.w[c] * f32((corner_set.bits[c] >> (rank % 32u)) & 1u);
        }
    }
    return select(1.0, seen / lit, lit > 0.0);
}
