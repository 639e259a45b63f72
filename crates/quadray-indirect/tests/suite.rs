//! quadray-indirect's integration tests, one module per file, linked as one binary: one test harness to
//! build instead of one per file. One file's tests:
//! `cargo test --release -p quadray-indirect --test suite -- counts::`.

mod counts;
mod gltf_export;
mod gpu;
mod layers;
mod lights;
mod non_finite;
mod output;
mod textures;
mod tile_cut;
mod visibility;
