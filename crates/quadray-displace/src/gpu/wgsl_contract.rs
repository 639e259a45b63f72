//! The Rust <-> WGSL contract, checked by reflection with naga: every shader parses and
//! validates (the tracing module on its own, as a user's shader includes it), each struct both
//! sides share has the Rust side's size and field offsets, and the method ids are Rust's.

use super::TRACE_WGSL;
use super::height_pyramid::PyramidInfo;
use super::surface_pass::{FrameParams, MapParams, shader_source};
use crate::method::Method;

fn validated(source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    module
}

/// A Rust struct's size and (field, offset) list, in declaration order.
macro_rules! rust_layout {
    ($t:ty: $($field:ident),+) => {
        (
            std::mem::size_of::<$t>(),
            vec![$((stringify!($field), std::mem::offset_of!($t, $field))),+],
        )
    };
}

fn assert_layout(module: &naga::Module, name: &str, rust: (usize, Vec<(&str, usize)>)) {
    let ty = module
        .types
        .iter()
        .find_map(|(_, t)| (t.name.as_deref() == Some(name)).then_some(&t.inner))
        .unwrap_or_else(|| panic!("the shader declares no struct {name}"));
    let naga::TypeInner::Struct { members, span } = ty else {
        panic!("{name} is not a struct");
    };
    let wgsl: Vec<(&str, usize)> = members
        .iter()
        .map(|m| (m.name.as_deref().unwrap_or("?"), m.offset as usize))
        .collect();
    assert_eq!(
        (*span as usize, wgsl),
        rust,
        "{name}: WGSL (size, fields) vs Rust"
    );
}

fn pyramid_info() -> (usize, Vec<(&'static str, usize)>) {
    rust_layout!(PyramidInfo: levels, clamp_to_map, iteration_cap, refine_cap, size, _pad)
}

#[test]
fn the_tracing_module_stands_alone_and_matches_pyramid_info() {
    assert_layout(&validated(TRACE_WGSL), "PyramidInfo", pyramid_info());
}

#[test]
fn the_surface_shader_matches_its_uniforms() {
    let module = validated(&shader_source());
    assert_layout(&module, "PyramidInfo", pyramid_info());
    assert_layout(
        &module,
        "MapParams",
        rust_layout!(MapParams: plane_origin, plane_u, plane_v, pyramid, tile_world, mesh_grid, tiles, _pad),
    );
    assert_layout(
        &module,
        "FrameParams",
        rust_layout!(FrameParams: view_proj, eye, light, depth_scale, lod, layers_min, layers_max,
            binary_steps, shadows, show_iterations, _pad),
    );
}

#[test]
fn the_surface_shader_names_every_method_by_its_rust_id() {
    let module = validated(&shader_source());
    for method in Method::ALL {
        let name = format!("METHOD_{}", method.name().to_uppercase().replace('-', "_"));
        let (_, constant) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name.as_str()))
            .unwrap_or_else(|| panic!("no {name}"));
        let value = &module.global_expressions[constant.init];
        let id = naga::Expression::Literal(naga::Literal::U32(method.shader_id()));
        assert_eq!(format!("{value:?}"), format!("{id:?}"), "{name}");
    }
}

#[test]
fn the_pyramid_build_shader_validates() {
    validated(include_str!("pyramid_build.wgsl"));
}
