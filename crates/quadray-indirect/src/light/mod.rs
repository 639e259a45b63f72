//! The light: its views ([`view`]: a spot's or the sun's one reflective shadow map, a point
//! light's six), the RSM pass that renders them ([`rsm`]), and the light quadtree over each
//! ([`quadtree`]: the pyramid of clusters, their validity, the compacted cut), with the
//! engine-neutral WGSL every pass reads them through: the node layout and pyramid addressing
//! (`node.wgsl`, its Rust side [`node`]), the VPL kernel (`kernel.wgsl`), the light
//! (`light.wgsl`), the top-down cut rule (`cut_rule.wgsl`), a node's bound (`bound.wgsl`) and
//! the cut drawn over the RSM (`cut_view.wgsl`).

#[cfg(test)]
mod bound_tests;
pub(crate) mod node;
pub(crate) mod quadtree;
pub(crate) mod rsm;
pub(crate) mod view;
