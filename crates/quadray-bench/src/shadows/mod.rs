//! Hybrid shadow testing: `quadray bench shadows` (the paper's tables 1-4 and figure 6, the SAH
//! BVH and Embree as today's baselines) and the ray-traced pictures of `quadray demo`.

pub mod demo;
pub mod measure;
pub mod tables;

pub use demo::render_demo;
pub use measure::BenchResults;

use quadray_core::FileError;
use std::path::Path;

/// Runs the whole benchmark and writes `results.json`, `shadows.md` and one figure-6 SVG per scene
/// into `out`.
pub fn bench_shadows(
    quick: bool,
    out: &Path,
    progress: &dyn Fn(&str),
) -> Result<BenchResults, FileError> {
    let results = measure::measure(quick, progress)?;
    tables::write(out, &results)?;
    Ok(results)
}
