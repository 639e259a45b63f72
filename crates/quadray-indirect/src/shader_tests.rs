//! The Rust <-> WGSL contract checked for every shader: each parses and validates with naga, and
//! each shared struct's size and field offsets are those of its Rust declaration
//! (`shader_struct!`, listed in `contract::shared_structs`), from which its WGSL is generated. Here,
//! above every pass, since it reads every pass's shader.

use crate::contract::*;
use crate::gbuffer;
use crate::light::{quadtree, rsm};
use crate::output;

#[test]
fn every_shader_parses_and_its_shared_structs_match_the_rust_side() {
    let shared = shared_structs();
    let mut seen = std::collections::BTreeSet::new();
    for (name, parts) in shaders() {
        let parts: Vec<&str> = parts.iter().map(String::as_str).collect();
        let source = shader_source(&parts);
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        naga::valid::Validator::new(Default::default(), naga::valid::Capabilities::all())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: {e:?}"));
        for (_, ty) in module.types.iter() {
            let naga::TypeInner::Struct { members, span } = &ty.inner else {
                continue;
            };
            let Some(s) = shared.iter().find(|s| ty.name.as_deref() == Some(s.name)) else {
                continue;
            };
            assert_eq!(*span as usize, s.size, "{name}: size of {}", s.name);
            let wgsl: Vec<(&str, usize)> = members
                .iter()
                .map(|m| (m.name.as_deref().unwrap_or(""), m.offset as usize))
                .collect();
            assert_eq!(wgsl, s.offsets, "{name}: fields of {}", s.name);
            seen.insert(s.name);
        }
    }
    for s in &shared {
        assert!(seen.contains(s.name), "no shader declares {}", s.name);
    }
}

/// The limits [`crate::Gather::limit_needs`] declares are the shaders' own: the most storage
/// buffers one shader binds, and the per-tile kernel's workgroup memory.
#[test]
fn the_declared_limit_needs_are_the_shaders() {
    use crate::gathers::gather::{STORAGE_BUFFERS_PER_STAGE, TILE_WORKGROUP_BYTES};
    let mut most_storage = (0, "");
    for (name, parts) in shaders() {
        let parts: Vec<&str> = parts.iter().map(String::as_str).collect();
        let module = naga::front::wgsl::parse_str(&shader_source(&parts)).unwrap();
        let storage = module
            .global_variables
            .iter()
            .filter(|(_, v)| matches!(v.space, naga::AddressSpace::Storage { .. }))
            .count() as u64;
        if storage > most_storage.0 {
            most_storage = (storage, name);
        }
        if name == "gather tiles" {
            let mut layouter = naga::proc::Layouter::default();
            layouter.update(module.to_ctx()).unwrap();
            let workgroup: u64 = module
                .global_variables
                .iter()
                .filter(|(_, v)| v.space == naga::AddressSpace::WorkGroup)
                .map(|(_, v)| u64::from(layouter[v.ty].size))
                .sum();
            assert_eq!(
                workgroup, TILE_WORKGROUP_BYTES,
                "the per-tile kernel's workgroup memory"
            );
        }
    }
    assert_eq!(
        most_storage.0, STORAGE_BUFFERS_PER_STAGE,
        "storage buffers of `{}`, the most of any shader",
        most_storage.1
    );
}

/// The split per-tile passes' workgroup memory (the variables each entry point uses) against
/// the fused kernel's: the walks run beside 64 bytes of counters instead of the kernel's
/// kilobytes, and the sums hold less than half of them (the list stays in storage).
#[test]
fn the_split_tile_passes_hold_less_workgroup_memory() {
    use crate::gathers::resources::shader;
    use crate::tiles::pass::{SPLIT_WGSL, WGSL};
    let bytes = |own: &[&'static str], entry: &str| -> u64 {
        let source = shader_source(&shader(own));
        let module = naga::front::wgsl::parse_str(&source).unwrap();
        let info =
            naga::valid::Validator::new(Default::default(), naga::valid::Capabilities::all())
                .validate(&module)
                .unwrap();
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let index = module
            .entry_points
            .iter()
            .position(|e| e.name == entry)
            .unwrap();
        let used = info.get_entry_point(index);
        module
            .global_variables
            .iter()
            .filter(|(h, v)| v.space == naga::AddressSpace::WorkGroup && !used[*h].is_empty())
            .map(|(_, v)| u64::from(layouter[v.ty].size))
            .sum()
    };
    let fused = bytes(&WGSL, "indirect_tiles");
    let [lists, walks, sums] =
        ["tile_lists", "tile_walks", "tile_sums"].map(|e| bytes(&SPLIT_WGSL, e));
    println!("workgroup bytes: fused {fused}, split lists {lists}, walks {walks}, sums {sums}");
    assert!(
        lists <= fused && sums < fused / 2,
        "{lists}, {sums} of {fused}"
    );
    assert_eq!(walks, 4 * u64::from(crate::tiles::MOST_WALKED_TILES));
}

/// Every shader's parts (before the prelude), by pass.
fn shaders() -> Vec<(&'static str, Vec<String>)> {
    let owned = |parts: &[&str]| parts.iter().map(|p| p.to_string()).collect();
    let mut shaders = vec![
        ("rsm", owned(&rsm::SOURCES)),
        ("gbuffer", owned(&gbuffer::SOURCES)),
        ("quadtree", owned(&quadtree::SOURCES)),
        ("output", output::pass::sources("rgba16float").to_vec()),
        ("shadow map", owned(&rsm::RASTER_WGSL)),
        (
            "direct",
            owned(&crate::gathers::resources::shader(
                &crate::direct::pass::WGSL,
            )),
        ),
    ];
    shaders.extend(
        crate::gathers::gather::shaders()
            .into_iter()
            .map(|(name, parts)| (name, owned(&parts))),
    );
    shaders
}
