//! The Rust <-> WGSL contract checked for every shader: each parses and validates with naga, and
//! each shared struct's size and field offsets are those of its Rust twin in `contract.rs`. Here,
//! above every pass, since it reads every pass's shader.

use crate::contract::*;
use crate::gbuffer;
use crate::light::{quadtree, rsm};
use crate::output;
use std::mem::offset_of;

/// A shared struct: its WGSL name, Rust size and Rust field offsets by name.
struct Shared {
    wgsl: &'static str,
    size: usize,
    fields: Vec<(&'static str, usize)>,
}

macro_rules! shared {
    ($wgsl:literal, $rust:ty, [$($field:ident),*]) => {
        Shared {
            wgsl: $wgsl,
            size: size_of::<$rust>(),
            fields: vec![$((stringify!($field), offset_of!($rust, $field))),*],
        }
    };
}

#[test]
fn every_shader_parses_and_its_shared_structs_match_the_rust_side() {
    let shared = [
        shared!(
            "Light",
            LightUniform,
            [view_proj, position, direction, intensity, parallel]
        ),
        shared!("Raster", RasterUniform, [view_proj, eye, texel]),
        shared!(
            "ClusterParams",
            ClusterUniform,
            [
                rsm_size,
                levels,
                start_level,
                limit_level,
                recursive,
                flux_weighted,
                depth_threshold,
                normal_threshold
            ]
        ),
        shared!(
            "Shade",
            ShadeUniform,
            [
                sample_count,
                subsample,
                low_width,
                low_height,
                normal_agreement,
                shadow_steps,
                temporal_weight,
                tile_error,
                tile_capacity,
                tile_start,
                tiles_x,
                tile_estimate,
                tile_share,
                tile_deblock,
                tile_shadow_angle
            ]
        ),
        shared!(
            "LightTerms",
            LightTermsUniform,
            [
                r_min,
                depth_bias,
                plane_agreement,
                shadow_thickness,
                low_offset
            ]
        ),
        shared!("Camera", CameraUniform, [view_proj, eye, width, height]),
        shared!("Level", LevelSlot, [level]),
        shared!("Node", GpuNode, [flux, pos, normal]),
        shared!("NodeBounds", GpuNodeBounds, [lo, hi]),
    ];
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
            let Some(s) = shared.iter().find(|s| ty.name.as_deref() == Some(s.wgsl)) else {
                continue;
            };
            assert_eq!(*span as usize, s.size, "{name}: size of {}", s.wgsl);
            let wgsl: Vec<(&str, usize)> = members
                .iter()
                .map(|m| (m.name.as_deref().unwrap_or(""), m.offset as usize))
                .collect();
            assert_eq!(wgsl, s.fields, "{name}: fields of {}", s.wgsl);
            seen.insert(s.wgsl);
        }
    }
    for s in &shared {
        assert!(seen.contains(s.wgsl), "no shader declares {}", s.wgsl);
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

/// Every shader's parts (before the prelude), by pass.
fn shaders() -> Vec<(&'static str, Vec<String>)> {
    let owned = |parts: &[&str]| parts.iter().map(|p| p.to_string()).collect();
    let mut shaders = vec![
        ("rsm", owned(&rsm::SOURCES)),
        ("gbuffer", owned(&gbuffer::SOURCES)),
        ("quadtree", owned(&quadtree::SOURCES)),
        ("output", output::pass::sources("rgba16float").to_vec()),
    ];
    shaders.extend(
        crate::gathers::gather::shaders()
            .into_iter()
            .map(|(name, parts)| (name, owned(&parts))),
    );
    shaders
}
