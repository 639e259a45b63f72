//! The light-quadtree paper's harness: `quadray indirect`'s measured run, the tables of
//! `quadray bench indirect` and the pictures of `quadray demo`.

pub mod cut_study;
pub mod demo;
pub mod equal_error;
pub mod run;
pub mod tables;
pub mod temporal;
