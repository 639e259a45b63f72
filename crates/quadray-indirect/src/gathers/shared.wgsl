// What every gather pass sees (the quadtree's, the baselines' and the reference's): the settings,
// light, camera and per-dispatch uniforms, the RSM, quadtree and G-buffer, the outputs, and the
// helpers every pass shares.

// Whether the gather tests indirect shadows (shade.shadow_steps > 0): a pipeline constant, so
// that a gather without them compiles no visibility test at all. A walk inlined in a summing
// loop, even one that never runs, made that loop 4-11 times slower on lavapipe.
override SHADOWS: bool;

// Whether the G-buffer is compact (`GBufferLayout`): a pipeline constant, so that each layout
// compiles its own reads (the RSM's: light/rsm_read.wgsl).
override COMPACT_GBUFFER: bool;

// The structs bound here (`Shade`, `LightTerms`, `Camera`, `Level`, `ClusterParams`, `Light`,
// `Node`, `NodeBounds`) are declared in Rust and generated into the prelude (contract.rs; the
// gather's settings, `Shade`, in settings.rs).

// Group 0, per light update: the quadtree's settings, the light, the RSM, the quadtree and cut.
@group(0) @binding(0) var<uniform> params: ClusterParams;
@group(0) @binding(1) var<uniform> light: Light;
// (the light's terms and the camera are read-only storage: lavapipe, Mesa 22.3, crashes running
// the shadow march with them as uniforms beside `shade`)
@group(0) @binding(2) var<storage, read> terms: LightTerms;
@group(0) @binding(3) var rsm_flux: texture_2d<f32>;
@group(0) @binding(4) var rsm_pos: texture_2d<f32>;
@group(0) @binding(5) var rsm_normal: texture_2d<f32>;
@group(0) @binding(6) var<storage, read> nodes: array<Node>;
@group(0) @binding(7) var<storage, read> cut: array<Node>;
// the cut's clusters in all, then in each class's segment of `cut` (light/node.rs)
@group(0) @binding(8) var<storage, read> cut_count: array<u32, CUT_CLASS_SIDE * CUT_CLASS_SIDE + 1u>;
@group(0) @binding(9) var<storage, read> bounds: array<NodeBounds>;
// Group 1, per frame (its targets): the settings, the camera, the G-buffer, the outputs and the
// RSM samples.
@group(1) @binding(0) var<uniform> shade: Shade;
@group(1) @binding(1) var<storage, read> viewer: Camera;
// (the compact layout: the camera's depth in g_pos, g_normal octahedral)
@group(1) @binding(2) var g_pos: texture_2d<f32>;
@group(1) @binding(3) var g_normal: texture_2d<f32>;
@group(1) @binding(4) var g_albedo: texture_2d<f32>;
// rgb: indirect radiance (or irradiance for the low-resolution pass), w: 1 when recomputed
@group(1) @binding(5) var<storage, read_write> indirect: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read_write> direct: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read_write> low: array<vec4<f32>>;
// xy: offset in RSM texels, z: weight, w: the pattern's radius
@group(1) @binding(8) var<storage, read> samples: array<vec4<f32>>;
// per pixel: VPL evaluations, fetches, bound evaluations and refused splits of the indirect
// passes (cleared before them)
@group(1) @binding(9) var<storage, read_write> counts: array<vec4<u32>>;
// the running average of the indirect light over the last frames (rgb)
@group(1) @binding(10) var<storage, read_write> history: array<vec4<f32>>;
// the scene's occupancy grid's words (shadows/occupancy.rs, `gpu_words`), OCCUPANCY_ROW a row:
// zero dimensions where the gather has none, and indirect shadows march the depth maps instead
@group(1) @binding(11) var occupancy: texture_2d<u32>;
// Group 2, per dispatch: the level of a per-level pass, and which slice of a long per-pixel sum
// this dispatch adds (see SLICE); dynamic offsets into slots 0, 1, 2, ...
@group(2) @binding(0) var<uniform> current: Level;
@group(2) @binding(1) var<uniform> slice: Level;

// A G-buffer pixel's world position (w: 1 where geometry is seen, else 0) and unit normal, in
// either layout (`GBufferLayout`; the compact one's g_pos holds the camera's reversed depth, 0
// where nothing is seen, its g_normal octahedral coordinates).
fn load_g_position(t: vec2<i32>) -> vec4<f32> {
    let texel = textureLoad(g_pos, t, 0);
    if (COMPACT_GBUFFER) {
        let size = vec2<f32>(f32(viewer.width), f32(viewer.height));
        let x = unproject(viewer.inv_view_proj, viewer.eye.xyz, t, size, texel.x);
        return vec4<f32>(x, select(0.0, 1.0, texel.x > 0.0));
    }
    return texel;
}

fn load_g_normal(t: vec2<i32>) -> vec3<f32> {
    let texel = textureLoad(g_normal, t, 0);
    if (COMPACT_GBUFFER) {
        return octahedral_decode(texel.xy);
    }
    return texel.xyz;
}

// The accessors of the engine-neutral modules (src/wgsl.rs): node `i` of the pyramid, and a pixel's
// receiver from the G-buffer.
fn load_node(i: u32) -> Node {
    return nodes[i];
}

fn receiver(pixel: vec2<u32>) -> Receiver {
    let t = vec2<i32>(pixel);
    fetches += 3u;
    let p = load_g_position(t);
    var r: Receiver;
    r.x = p.xyz;
    r.n = load_g_normal(t);
    r.albedo = textureLoad(g_albedo, t, 0).rgb;
    // a texel the kernel cannot take sees no geometry: its NaN would spread through its tile's
    // cut and the neighbours that upsample or reproject from it
    r.covered = p.w > 0.5 && kernel_point(r.x, r.n);
    return r;
}

// The accessors of shadows/occupancy.wgsl: the header's words, then the bits.
fn occupancy_load(i: u32) -> u32 {
    return textureLoad(occupancy, vec2<u32>(i % OCCUPANCY_ROW, i / OCCUPANCY_ROW), 0).x;
}

fn occupancy_dims() -> vec3<u32> {
    return vec3<u32>(occupancy_load(0u), occupancy_load(1u), occupancy_load(2u));
}

fn occupancy_levels() -> u32 {
    return occupancy_load(3u);
}

fn occupancy_origin() -> vec3<f32> {
    return bitcast<vec3<f32>>(vec3<u32>(occupancy_load(4u), occupancy_load(5u), occupancy_load(6u)));
}

fn occupancy_cell() -> f32 {
    return bitcast<f32>(occupancy_load(7u));
}

fn occupancy_word(i: u32) -> u32 {
    return occupancy_load(OCCUPANCY_HEADER + i);
}

// The kernel with indirect shadows (the accessor of gather_cut.wgsl and gather_level.wgsl).
fn node_irradiance(node: Node, r: Receiver) -> vec3<f32> {
    let e = vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, r.x, r.n, terms.r_min);
    // (branches, not `||`: the visibility test's loops must not run without shadows, as
    // lavapipe counts their iterations towards the summing loop's cap)
    if (SHADOWS && any(e != vec3<f32>(0.0))) {
        if (!visible(r.x, r.n, node.pos.xyz, node.normal.xyz)) {
            return vec3<f32>(0.0);
        }
    }
    return e;
}

// Splits of a per-tile cut refused because the tile's list was full (counted once a tile).
var<private> refused_splits: u32;

// Adds this invocation's work to pixel `index`'s counts.
fn store_counts(index: u32) {
    counts[index] += vec4<u32>(evaluations, fetches, bound_evaluations, refused_splits);
}

fn pixel_index(pixel: vec2<u32>) -> u32 {
    return pixel.y * viewer.width + pixel.x;
}

// This dispatch's items of a sum over `count` items, `per_slice` at a time: [x, y).
fn slice_range(count: u32, per_slice: u32) -> vec2<u32> {
    let first = slice.level * per_slice;
    return vec2<u32>(first, min(first + per_slice, count));
}

// The whole of a sum, as a part of it (`interleaved_part`'s form: part 0 of 1).
const WHOLE_SUM: vec2<u32> = vec2<u32>(0u, 1u);

// Interleaved sampling: the part of a sum pixel `pixel` takes, its offset in its
// `interleave` x `interleave` block (x) of the block's parts (y).
fn interleaved_part(pixel: vec2<u32>) -> vec2<u32> {
    let n = shade.interleave;
    return vec2<u32>(pixel.x % n + n * (pixel.y % n), n * n);
}

// A part's items of a slice [x, y) of a sum: every `part.y`-th from the first of its offset
// (first, end, stride).
fn part_range(range: vec2<u32>, part: vec2<u32>) -> vec3<u32> {
    return vec3<u32>(range.x + (part.x + part.y - range.x % part.y) % part.y, range.y, part.y);
}

// Whether this is a frame's first light view, which writes the radiance the others add to.
fn first_view() -> bool {
    return terms.low_offset == 0u;
}

// Stores one slice's share of a pixel's indirect light: the first slice of the first light view
// writes, the others add.
fn add_indirect(index: u32, value: vec4<f32>) {
    if (slice.level == 0u && first_view()) {
        indirect[index] = value;
    } else {
        indirect[index] += value;
    }
}

// The accessors of gather_vpls.wgsl: an RSM texel's (light/rsm_read.wgsl) and RSM sampling's
// pattern.
fn load_rsm_sample(i: u32) -> vec4<f32> {
    return samples[i];
}
