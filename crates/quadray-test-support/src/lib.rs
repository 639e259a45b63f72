//! What the tests of several quadray crates share, as a dev-dependency of each: the layering check
//! of a crate's modules, the workspace's example programs built and run as a user runs them, and
//! the round trip of a settings type through a command's flags, and small glTF files.

pub mod examples;
pub mod flags;
pub mod gltf;
pub mod layering;
