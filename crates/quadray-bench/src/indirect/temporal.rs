//! Stability under a moving light (`quadray indirect --light-orbit DEG --frames N`): the spot
//! turns DEG a frame about the vertical axis; every frame rebuilds the RSM, the quadtree and the
//! cut. Popping shows as a cut that changes much from frame to frame and as an indirect image
//! that changes more than the brute force's own does under the same motion. A damping that lags
//! the light shows in the error against each frame's brute force.

use quadray_indirect::reference;
use quadray_indirect::{IndirectError, Method, Renderer, Scene};
use serde::Serialize;
use std::collections::HashSet;

/// The sequence's figures (the stats' `temporal`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Temporal {
    /// Degrees the light turns a frame.
    pub degrees_per_frame: f32,
    /// Frames in the sequence.
    pub frames: u32,
    /// Mean over frame pairs of the clusters that enter or leave the cut over the cut's size
    /// (quadtree methods).
    pub cut_changed_fraction: Option<f64>,
    /// Mean frame-to-frame |change| of the method's indirect light over the brute force's.
    pub flicker_ratio: f64,
    /// Mean frame-to-frame |change| of the method's indirect light (per pixel and channel).
    pub flicker: f64,
    /// The same for the brute force over every VPL.
    pub reference_flicker: f64,
    /// Mean over the frames of the indirect light's rel_l1 against that frame's brute force.
    pub mean_rel_l1: f64,
    /// The largest of those.
    pub max_rel_l1: f64,
}

/// One frame of the sequence: our indirect light, the brute force's, and the cut (level, x, y).
type Step = (Vec<[f32; 3]>, Vec<[f32; 3]>, HashSet<(u32, u32, u32)>);

fn mean_change(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let sum: f64 = a
        .iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| f64::from((x - y).abs()))
        .sum();
    sum / (a.len() * 3).max(1) as f64
}

/// Renders `frames` frames of `method` and of the brute force with the light turning
/// `degrees` a frame (the temporal filter's average, if any, starting at the first), and leaves
/// the renderer at `scene`'s own view.
pub fn measure(
    renderer: &mut Renderer,
    scene: &Scene,
    method: Method,
    degrees: f32,
    frames: u32,
) -> Result<Temporal, IndirectError> {
    let mut previous: Option<Step> = None;
    let (mut ours, mut theirs, mut changed) = (0.0, 0.0, 0.0);
    let (mut error_sum, mut error_max) = (0.0, 0.0f64);
    renderer.gather().reset_history();
    for f in 0..frames {
        renderer.set_view(&scene.light_turned(degrees * f as f32));
        let image = renderer.render_frame(method)?.indirect;
        let cut: HashSet<(u32, u32, u32)> = if method.uses_quadtree() {
            // the per-level passes keep no cut: build it without shading
            if method != Method::Quadtree {
                renderer.build_cut()?;
            }
            let cut = renderer.read_cut()?;
            cut.iter().map(|c| (c.level, c.x, c.y)).collect()
        } else {
            HashSet::new()
        };
        let reference = renderer.render_frame(Method::Reference)?.indirect;
        let error = reference::compare(&image, &reference).rel_l1;
        error_sum += error;
        error_max = error_max.max(error);
        if let Some((image0, reference0, cut0)) = &previous {
            ours += mean_change(&image, image0);
            theirs += mean_change(&reference, reference0);
            let moved = cut.symmetric_difference(cut0).count();
            changed += moved as f64 / cut.len().max(1) as f64;
        }
        previous = Some((image, reference, cut));
    }
    renderer.set_view(scene);
    let pairs = f64::from(frames.saturating_sub(1).max(1));
    Ok(Temporal {
        degrees_per_frame: degrees,
        frames,
        cut_changed_fraction: method.uses_quadtree().then_some(changed / pairs),
        flicker_ratio: if theirs > 0.0 { ours / theirs } else { 0.0 },
        flicker: ours / pairs,
        reference_flicker: theirs / pairs,
        mean_rel_l1: error_sum / f64::from(frames.max(1)),
        max_rel_l1: error_max,
    })
}

#[cfg(test)]
mod tests {
    use super::mean_change;

    #[test]
    fn change_is_the_mean_absolute_difference() {
        assert_eq!(mean_change(&[[1.0, 2.0, 3.0]], &[[1.0, 1.0, 1.0]]), 1.0);
    }
}
