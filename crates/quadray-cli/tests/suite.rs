//! quadray-cli's integration tests, one module per file, linked as one binary: one test harness to
//! build instead of one per file. One file's tests:
//! `cargo test --release -p quadray-cli --test suite -- displace_cli::`.

mod common;
mod deploy_files;
mod displace_cli;
mod examples;
mod fuzz_loaders;
mod gpu_tables;
mod headless_cli;
mod indirect_cli;
mod inputs;
mod layers;
mod provenance;
mod raytrace_cli;
mod readme_snippets;
mod scene_cli;
mod slurm;
mod tiles_cli;
mod validation;
