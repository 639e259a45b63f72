//! quadray-displace's integration tests, one module per file, linked as one binary: one test harness to
//! build instead of one per file. One file's tests:
//! `cargo test --release -p quadray-displace --test suite -- height_maps::`.

mod common;
mod gpu_vs_reference;
mod height_maps;
mod layers;
mod non_finite;
