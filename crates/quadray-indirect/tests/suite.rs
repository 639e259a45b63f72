//! quadray-indirect's integration tests, one module per file, linked as one binary: one test harness to
//! build instead of one per file. One file's tests:
//! `cargo test --release -p quadray-indirect --test suite -- counts::`.

mod counts;
// Not `example`: the file declares its own `mod example` (the example's source).
#[path = "example.rs"]
mod gi_gbuffer_example;
mod gpu;
mod layers;
mod output;
mod visibility;
