//! quadray-bevy's tests in a real Bevy app, headless on lavapipe, one module per file, linked as
//! one binary (each test binary links Bevy). One file's tests:
//! `cargo test --release -p quadray-bevy --test suite -- gi::`.

mod common;
mod gi;
mod gi_displaced;
mod gi_meshes;
mod gi_scene;
mod gi_skinned;
mod hits;
mod layers;
mod lifecycle;
mod pass_cost;
mod prepass;
mod self_shadow;
mod shadows;
mod validation;
