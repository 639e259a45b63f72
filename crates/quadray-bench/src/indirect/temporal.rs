//! Stability under motion (`quadray indirect --light-orbit DEG [--camera-orbit DEG] --frames
//! N`): the spot turns DEG a frame about the vertical axis, the camera orbits its target; every
//! frame rebuilds the RSM, the quadtree and the cut. Popping shows as a cut that changes much
//! from frame to frame and as an indirect image that changes more than the brute force's own does
//! under the same motion. A damping that lags shows in the error against each frame's brute
//! force, and a temporal filter that drags old light onto newly seen surfaces (ghosting) in the
//! error on the pixels the last frame did not see.

use quadray_gpu::Gpu;
use quadray_indirect::{IndirectError, Method, Receiver, Renderer, Scene, Settings, reference};
use serde::Serialize;
use std::collections::HashSet;

/// The motion per frame.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Orbit {
    /// Degrees the spot turns a frame about the vertical axis.
    pub light_degrees: f32,
    /// Degrees the camera moves a frame along its orbit about the target's vertical axis.
    pub camera_degrees: f32,
}

/// The sequence's figures (the stats' `temporal`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Temporal {
    /// Degrees the light turns a frame.
    pub degrees_per_frame: f32,
    /// Degrees the camera orbits a frame.
    pub camera_degrees_per_frame: f32,
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
    /// Mean frame-to-frame |change| of the error image (the method's light minus the brute
    /// force's): popping that a moving camera's own change of the picture does not hide.
    pub error_flicker: f64,
    /// Mean over the frames of the indirect light's rel_l1 against that frame's brute force.
    pub mean_rel_l1: f64,
    /// The largest of those.
    pub max_rel_l1: f64,
    /// With the camera moving: the mean fraction of a frame's shaded pixels whose surface point
    /// the last frame did not see (disoccluded or new in the view).
    pub disoccluded_fraction: Option<f64>,
    /// The mean over frames of the rel_l1 against the brute force on those pixels alone (a
    /// filter that drags old light onto them shows here).
    pub disoccluded_rel_l1: Option<f64>,
}

/// A cut as the set of its clusters (level, x, y).
type Cut = HashSet<(u32, u32, u32)>;

/// A frame of a method: its indirect light, its error image against the brute force, its cut.
struct Step {
    image: Vec<[f32; 3]>,
    error: Vec<[f32; 3]>,
    cut: Cut,
}

/// A method's figures summed over the frames so far, and its last frame.
#[derive(Default)]
struct Sums {
    previous: Option<Step>,
    flicker: f64,
    cut_changed: f64,
    error_flicker: f64,
    error: f64,
    error_max: f64,
    disoccluded_error: f64,
}

impl Sums {
    /// Adds a frame: the method's light, its cut, that frame's brute force, and the pixels that
    /// show what the last frame did not see (with the camera moving).
    fn add(
        &mut self,
        image: Vec<[f32; 3]>,
        cut: Cut,
        reference: &[[f32; 3]],
        new: Option<&[bool]>,
    ) {
        let error = reference::compare(&image, reference).rel_l1;
        self.error += error;
        self.error_max = self.error_max.max(error);
        if let Some(new) = new.filter(|new| new.contains(&true)) {
            let pick = |image: &[[f32; 3]]| -> Vec<[f32; 3]> {
                image
                    .iter()
                    .zip(new)
                    .filter(|(_, n)| **n)
                    .map(|(p, _)| *p)
                    .collect()
            };
            self.disoccluded_error += reference::compare(&pick(&image), &pick(reference)).rel_l1;
        }
        let step = Step {
            error: difference(&image, reference),
            image,
            cut,
        };
        if let Some(last) = &self.previous {
            self.flicker += mean_change(&step.image, &last.image);
            self.error_flicker += mean_change(&step.error, &last.error);
            let moved = step.cut.symmetric_difference(&last.cut).count();
            self.cut_changed += moved as f64 / step.cut.len().max(1) as f64;
        }
        self.previous = Some(step);
    }
}

/// What the frames have in common whatever the method: the brute force's change and the
/// pixels newly seen.
#[derive(Default)]
struct Shared {
    reference_flicker: f64,
    disoccluded_fraction: f64,
    /// Frames with newly seen pixels.
    disoccluded_frames: u32,
}

fn mean_change(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let sum: f64 = a
        .iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| f64::from((x - y).abs()))
        .sum();
    sum / (a.len() * 3).max(1) as f64
}

/// Per pixel and channel, `a - b`.
fn difference(a: &[[f32; 3]], b: &[[f32; 3]]) -> Vec<[f32; 3]> {
    a.iter()
        .zip(b)
        .map(|(a, b)| std::array::from_fn(|c| a[c] - b[c]))
        .collect()
}

/// How far (relative to the distance from the last frame's eye) the point the last frame saw at
/// a pixel may lie from this frame's point and still be the same.
const SAME_POINT: f32 = 0.02;

/// What a frame saw, for the next one's disocclusion: each pixel's point, the view and the eye.
struct Seen {
    receivers: Vec<Option<Receiver>>,
    view_proj: glam::Mat4,
    eye: glam::Vec3,
}

/// Per pixel of `now`: whether it shows a point `then` did not see.
fn disoccluded(now: &[Option<Receiver>], then: &Seen, (width, height): (u32, u32)) -> Vec<bool> {
    now.iter()
        .map(|r| {
            let Some(r) = r else { return false };
            let p = glam::Vec3::from(r.position);
            let clip = then.view_proj * p.extend(1.0);
            if clip.w <= 0.0 {
                return true;
            }
            let x = (clip.x / clip.w * 0.5 + 0.5) * width as f32;
            let y = (0.5 - clip.y / clip.w * 0.5) * height as f32;
            if !(0.0..width as f32).contains(&x) || !(0.0..height as f32).contains(&y) {
                return true;
            }
            match &then.receivers[y as usize * width as usize + x as usize] {
                Some(seen) => {
                    let tolerance = SAME_POINT * p.distance(then.eye);
                    glam::Vec3::from(seen.position).distance(p) > tolerance
                }
                None => true,
            }
        })
        .collect()
}

/// The sequence's figures with the temporal filter `renderer`'s settings give and, where it
/// filters, without it (the filter's damping and its cost in one run, against the same
/// brute-force frames).
pub struct Measured {
    pub filtered: Temporal,
    pub unfiltered: Option<Temporal>,
}

/// `method`'s frame on `renderer` and its cut (empty for methods without a quadtree).
fn frame_and_cut(
    renderer: &mut Renderer,
    method: Method,
) -> Result<(Vec<[f32; 3]>, Cut), IndirectError> {
    let image = renderer.render_frame(method)?.indirect;
    if !method.uses_quadtree() {
        return Ok((image, HashSet::new()));
    }
    // the per-level passes keep no cut: build it without shading
    if method != Method::Quadtree {
        renderer.build_cut()?;
    }
    let cut = renderer.read_cut()?;
    Ok((image, cut.iter().map(|c| (c.level, c.x, c.y)).collect()))
}

/// Renders `frames` frames of `method` and of the brute force under `orbit` (the temporal
/// filter's average, if any, starting at the first; the same frames without it on a second
/// renderer), and leaves the renderer at `scene`'s own view.
pub fn measure(
    gpu: &Gpu,
    renderer: &mut Renderer,
    scene: &Scene,
    method: Method,
    orbit: Orbit,
    frames: u32,
) -> Result<Measured, IndirectError> {
    let settings = renderer.settings().clone();
    let filters = settings.temporal_weight < 1.0 && method != Method::Reference;
    let mut plain = if filters {
        let unfiltered = Settings {
            temporal_weight: 1.0,
            ..settings.clone()
        };
        Some(Renderer::new(gpu, scene, unfiltered)?)
    } else {
        None
    };
    let (width, height) = (settings.size.width, settings.size.height);
    let camera_moves = orbit.camera_degrees != 0.0;
    let mut shared = Shared::default();
    let (mut sums, mut plain_sums) = (Sums::default(), Sums::default());
    let mut previous_reference: Option<Vec<[f32; 3]>> = None;
    let mut seen: Option<Seen> = None;
    renderer.gather().reset_history();
    for f in 0..frames {
        let view = scene
            .light_turned(orbit.light_degrees * f as f32)
            .camera_orbited(orbit.camera_degrees * f as f32);
        renderer.set_view(&view)?;
        let (image, cut) = frame_and_cut(renderer, method)?;
        let reference = renderer.render_frame(Method::Reference)?.indirect;
        let mut new = None;
        if camera_moves {
            let receivers = renderer.read_receivers()?;
            if let Some(then) = &seen {
                let mask = disoccluded(&receivers, then, (width, height));
                let shaded = receivers.iter().filter(|r| r.is_some()).count().max(1);
                let count = mask.iter().filter(|n| **n).count();
                shared.disoccluded_fraction += count as f64 / shaded as f64;
                shared.disoccluded_frames += u32::from(count > 0);
                new = Some(mask);
            }
            seen = Some(Seen {
                receivers,
                view_proj: view.camera_view_proj(width as f32 / height as f32),
                eye: view.camera.position,
            });
        }
        sums.add(image, cut, &reference, new.as_deref());
        if let Some(plain) = plain.as_mut() {
            plain.set_view(&view)?;
            let (image, cut) = frame_and_cut(plain, method)?;
            plain_sums.add(image, cut, &reference, new.as_deref());
        }
        if let Some(reference0) = &previous_reference {
            shared.reference_flicker += mean_change(&reference, reference0);
        }
        previous_reference = Some(reference);
    }
    renderer.set_view(scene)?;
    let pairs = f64::from(frames.saturating_sub(1).max(1));
    let figures = |sums: &Sums| Temporal {
        degrees_per_frame: orbit.light_degrees,
        camera_degrees_per_frame: orbit.camera_degrees,
        frames,
        cut_changed_fraction: method.uses_quadtree().then_some(sums.cut_changed / pairs),
        flicker_ratio: if shared.reference_flicker > 0.0 {
            sums.flicker / shared.reference_flicker
        } else {
            0.0
        },
        flicker: sums.flicker / pairs,
        reference_flicker: shared.reference_flicker / pairs,
        error_flicker: sums.error_flicker / pairs,
        mean_rel_l1: sums.error / f64::from(frames.max(1)),
        max_rel_l1: sums.error_max,
        disoccluded_fraction: camera_moves.then_some(shared.disoccluded_fraction / pairs),
        disoccluded_rel_l1: (camera_moves && shared.disoccluded_frames > 0)
            .then(|| sums.disoccluded_error / f64::from(shared.disoccluded_frames)),
    };
    Ok(Measured {
        filtered: figures(&sums),
        unfiltered: plain.is_some().then(|| figures(&plain_sums)),
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
