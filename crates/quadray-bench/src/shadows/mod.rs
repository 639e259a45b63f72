//! Hybrid shadow testing: `quadray bench shadows` (the paper's tables 1-4 and figure 6, the SAH
//! BVH and Embree as today's baselines) and the ray-traced pictures of `quadray demo`.

pub mod demo;
pub mod measure;
pub mod tables;

pub use demo::render_demo;
pub use measure::{BenchResults, bench_shadows};
