//! quadray-core's integration tests, one module per file, linked as one binary: one test harness to
//! build instead of one per file. One file's tests:
//! `cargo test --release -p quadray-core --test suite -- mesh::`.

mod common;
mod gltf_export;
mod layers;
mod mesh;
mod scene;
