//! Engine-neutral WGSL: the light quadtree's node layout and pyramid addressing, the VPL kernel,
//! the spot light, the top-down cut rule, the bound of a node's contribution, the per-tile cut's
//! rules, the per-method sums of the gather and the occupancy grid's walk, each kept in the
//! feature folder it belongs to (`light/`, `tiles/`, `gathers/`, `shadows/`). No module declares
//! a binding: where one needs data it calls accessor functions that the including shader defines
//! from its own bindings (quadray's bindings files are next to the pass that declares them:
//! `light/cluster.wgsl`, `gathers/shared.wgsl`). Another engine includes the same modules with its
//! own bindings file.
//!
//! A shader is [`prelude`], then the modules it uses in the order of the constants here (each
//! needs the ones listed with it), then the including shader's bindings, accessors and entry
//! points. WGSL declarations may come in any order, so the accessors may follow the modules.

/// The constants every module uses (`SLICE`, `LEVEL_SLICE`, `MAX_LEVELS`, `TILE`,
/// `TILE_FRONTIER`, `PI`, ...) and the structs shared with Rust (`Node`, `NodeBounds`,
/// `ClusterParams`, `Light`, ...), generated from the Rust declarations: put it first.
pub fn prelude() -> String {
    crate::contract::prelude()
}

/// The light quadtree's pyramid addressing over the prelude's `Node` and `ClusterParams`
/// (`level_size`, `level_offset`, `node_index`: levels finest first) and the work counters every
/// module adds to (`evaluations`, `fetches`, `bound_evaluations`). Accessors: none.
pub const NODE: &str = include_str!("light/node.wgsl");

/// The VPL kernel: `vpl_irradiance` (a VPL or cluster's irradiance at a receiver, 1/r^4 clamped
/// at `r_min`), `vpl_vector` (its vector irradiance), `luminance`, and what it may be given:
/// `kernel_point` (a receiver: finite, a non-zero normal), `kernel_vpl` (an RSM texel) and
/// `all_finite`. Needs [`NODE`]. Accessors: none.
pub const KERNEL: &str = include_str!("light/kernel.wgsl");

/// The spot light over the prelude's `Light` uniform: `spot_edge`, `spot_intensity`,
/// `light_depth` (the RSM's depth) and `rsm_flux_scale` (what an RSM texel's flux is a share of).
/// Accessors: none.
pub const LIGHT: &str = include_str!("light/light.wgsl");

/// The compact G-buffer and RSM layout's encodings ([`crate::GBufferLayout::Compact`]):
/// `octahedral_encode` and `octahedral_decode` (a unit normal in two coordinates) and `unproject`
/// (a depth texel's world position through the inverse of its view's projection relative to its
/// eye). Accessors: none.
pub const COMPACT: &str = include_str!("light/compact.wgsl");

/// `Receiver`, what a G-buffer texel holds (position, normal, albedo, covered); the including
/// shader reads its G-buffer into it. Accessors: none.
pub const RECEIVER: &str = include_str!("gathers/receiver.wgsl");

/// The top-down cut rule, `in_cut`: a node is used when it is valid (or at the limit level) and
/// none of its ancestors up to the start level is. Needs [`NODE`]. Accessor:
/// `fn load_node(i: u32) -> Node`, node `i` of the pyramid.
pub const CUT_RULE: &str = include_str!("light/cut_rule.wgsl");

/// `node_bound`, an upper bound of the irradiance a node gives any receiver of a box whose
/// normals lie in a cone (Lightcuts' bound with normal cones). Needs [`NODE`], [`KERNEL`].
/// Accessors: none.
pub const BOUND: &str = include_str!("light/bound.wgsl");

/// The per-tile cut's rules (method `quadtree-tiles`): the receivers' groups (`receiver_group`,
/// `group_axis`, `group_cone`), the coarse estimate and threshold (`coarse_light`,
/// `tile_threshold`), the bound a node is held to (`tile_bound`), when the estimate decides
/// (`near_field`, `estimate_decides`, `estimated_error`), the split bins (`split_bin`) and the
/// nodes shared at the tile's corners (`all_corners_covered`, `shareable`); the CPU's twin is
/// [`crate::tiles::twin`]. Needs [`NODE`], [`KERNEL`], [`BOUND`]. Accessors: `load_node` (as
/// [`CUT_RULE`]), `fn tile_position(p: u32) -> vec3<f32>`, `fn tile_normal(p: u32) -> vec3<f32>`
/// (the tile's receiver `p`, row-major, an uncovered one at `EMPTY_BOX`) and
/// `fn tile_sample(q: u32) -> u32` (quadrant `q`'s sample pixel, `TILE_PIXELS` where none).
pub const TILE_RULE: &str = include_str!("tiles/rule.wgsl");

/// The compacted cut's sum at a receiver, `cut_sum(r, range)` (method `quadtree`). Needs
/// [`NODE`], [`RECEIVER`]. Accessor: `fn cut_node_irradiance(i: u32, r: Receiver) -> vec3<f32>`,
/// cluster `i` of the cut's irradiance at `r`: [`KERNEL`]'s `vpl_irradiance` with the including
/// shader's visibility.
pub const GATHER_CUT: &str = include_str!("gathers/gather_cut.wgsl");

/// One level of the paper's traversal at a receiver, `level_sum(params, level, r, range)`
/// (method `quadtree-passes`). Needs [`NODE`], [`RECEIVER`], [`CUT_RULE`]. Accessors:
/// `load_node` (as [`CUT_RULE`]) and `fn node_irradiance(node: Node, r: Receiver) -> vec3<f32>`,
/// [`KERNEL`]'s `vpl_irradiance` with the including shader's visibility.
pub const GATHER_LEVEL: &str = include_str!("gathers/gather_level.wgsl");

/// The sums over RSM texels at a receiver: `vpl_sum` (every VPL, method `reference`) and
/// `sampled_sum` (RSM sampling, method `rsm`; every `range.z`-th sample). Needs [`NODE`], [`KERNEL`], [`LIGHT`],
/// [`RECEIVER`]. Accessors: `fn load_rsm_normal(t: vec2<i32>) -> vec4<f32>` (w: 1 where the light
/// sees geometry), `fn load_rsm_position(t: vec2<i32>) -> vec4<f32>`,
/// `fn load_rsm_flux(t: vec2<i32>) -> vec3<f32>`, and for `sampled_sum`
/// `fn load_rsm_sample(i: u32) -> vec4<f32>` (the pattern of [`crate::gathers::samples::rsm_samples`]).
pub const GATHER_VPLS: &str = include_str!("gathers/gather_vpls.wgsl");

/// The cut over the RSM as a picture (a debug view): `cut_view_exposure(params)` and
/// `cut_view_pixel(params, zoom, pixel, exposure)`, the linear colour whose sRGB encoding is
/// [`crate::picture::cut_view`]'s pixel (the Bevy plugin draws it in a corner of the picture).
/// Needs [`NODE`], [`KERNEL`], [`CUT_RULE`]. Accessor: `load_node` (as [`CUT_RULE`]).
pub const CUT_VIEW: &str = include_str!("light/cut_view.wgsl");

/// Visibility through the scene's occupancy grid, `grid_visibility(x, n, xp, np)` (indirect
/// shadows): a 3D DDA from a receiver to a cluster, each end moved two cells off its surface;
/// the CPU's twin is [`crate::shadows::occupancy::OccupancyGrid::visible`]. Needs [`NODE`] (the fetch
/// counter). Accessors: `fn occupancy_dims() -> vec3<u32>`, `fn occupancy_levels() -> u32`,
/// `fn occupancy_origin() -> vec3<f32>`, `fn occupancy_cell() -> f32`,
/// `fn occupancy_word(i: u32) -> u32`.
pub const OCCUPANCY: &str = include_str!("shadows/occupancy.wgsl");

#[cfg(test)]
mod tests {
    use super::*;

    /// Accessors that return nothing, as an engine's bindings file would define them.
    const NODE_ACCESSORS: &str = "
fn load_node(i: u32) -> Node { return Node(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0)); }
";
    const CUT_ACCESSORS: &str = "
fn cut_node_irradiance(i: u32, r: Receiver) -> vec3<f32> { return node_irradiance(load_node(i), r); }
fn node_irradiance(node: Node, r: Receiver) -> vec3<f32> {
    return vpl_irradiance(node.flux.rgb, node.pos.xyz, node.normal.xyz, r.x, r.n, 0.1);
}
";
    const RSM_ACCESSORS: &str = "
fn load_rsm_normal(t: vec2<i32>) -> vec4<f32> { return vec4<f32>(0.0); }
fn load_rsm_position(t: vec2<i32>) -> vec4<f32> { return vec4<f32>(0.0); }
fn load_rsm_flux(t: vec2<i32>) -> vec3<f32> { return vec3<f32>(0.0); }
fn load_rsm_sample(i: u32) -> vec4<f32> { return vec4<f32>(0.0); }
";
    const TILE_ACCESSORS: &str = "
fn tile_position(p: u32) -> vec3<f32> { return vec3<f32>(0.0); }
fn tile_normal(p: u32) -> vec3<f32> { return vec3<f32>(0.0); }
fn tile_sample(q: u32) -> u32 { return 0u; }
";
    const OCCUPANCY_ACCESSORS: &str = "
fn occupancy_dims() -> vec3<u32> { return vec3<u32>(0u); }
fn occupancy_levels() -> u32 { return 1u; }
fn occupancy_origin() -> vec3<f32> { return vec3<f32>(0.0); }
fn occupancy_cell() -> f32 { return 1.0; }
fn occupancy_word(i: u32) -> u32 { return 0u; }
";

    /// Each module after the modules it needs, then the stub accessors it calls.
    fn modules() -> [(&'static str, Vec<&'static str>); 13] {
        [
            ("node", vec![NODE]),
            ("kernel", vec![NODE, KERNEL]),
            ("light", vec![LIGHT]),
            ("compact", vec![COMPACT]),
            ("receiver", vec![RECEIVER]),
            ("cut rule", vec![NODE, CUT_RULE, NODE_ACCESSORS]),
            ("bound", vec![NODE, KERNEL, BOUND]),
            (
                "tile rule",
                vec![
                    NODE,
                    KERNEL,
                    BOUND,
                    TILE_RULE,
                    NODE_ACCESSORS,
                    TILE_ACCESSORS,
                ],
            ),
            (
                "cut view",
                vec![NODE, KERNEL, CUT_RULE, CUT_VIEW, NODE_ACCESSORS],
            ),
            (
                "gather cut",
                vec![
                    NODE,
                    KERNEL,
                    RECEIVER,
                    GATHER_CUT,
                    NODE_ACCESSORS,
                    CUT_ACCESSORS,
                ],
            ),
            (
                "gather level",
                vec![
                    NODE,
                    KERNEL,
                    RECEIVER,
                    CUT_RULE,
                    GATHER_LEVEL,
                    NODE_ACCESSORS,
                    CUT_ACCESSORS,
                ],
            ),
            (
                "gather vpls",
                vec![NODE, KERNEL, LIGHT, RECEIVER, GATHER_VPLS, RSM_ACCESSORS],
            ),
            ("occupancy", vec![NODE, OCCUPANCY, OCCUPANCY_ACCESSORS]),
        ]
    }

    #[test]
    fn every_module_declares_no_binding_and_parses_with_stub_accessors() {
        let all = [
            NODE,
            KERNEL,
            LIGHT,
            COMPACT,
            RECEIVER,
            CUT_RULE,
            BOUND,
            TILE_RULE,
            GATHER_CUT,
            GATHER_LEVEL,
            GATHER_VPLS,
            CUT_VIEW,
            OCCUPANCY,
        ];
        for module in all {
            assert!(
                !module.contains("@group") && !module.contains("@binding"),
                "a module declares a binding: {}",
                module.lines().next().unwrap_or_default()
            );
        }
        for (name, parts) in modules() {
            let source: String = std::iter::once(prelude().as_str()).chain(parts).collect();
            let parsed = naga::front::wgsl::parse_str(&source)
                .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
            naga::valid::Validator::new(Default::default(), naga::valid::Capabilities::all())
                .validate(&parsed)
                .unwrap_or_else(|e| panic!("{name}: {e:?}"));
        }
    }
}
