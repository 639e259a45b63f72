//! quadray-gpu's integration tests, one module per file, linked as one binary: one test harness
//! to build instead of one per file. One file's tests:
//! `cargo test --release -p quadray-gpu --test suite -- bounded_wait::`.

mod bounded_wait;
mod harness;
mod layers;
