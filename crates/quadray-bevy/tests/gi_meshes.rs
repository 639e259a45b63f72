//! What the tests of the lights' RSMs drawn from Bevy's meshes ([`RsmSource::Meshes`]) share:
//! each camera's source switched in a running app and the bounce read once it settles, to hold
//! against the bounce over the CPU's triangles in the same app (`gi.rs`: the Cornell box,
//! `lifecycle.rs`: the textured floor and a mesh only the render world keeps, `gi_skinned.rs`:
//! the bent skinned bar).

use bevy::prelude::*;
use quadray_bevy::gi::{IndirectLight, RsmSource};
use quadray_indirect::reference::{ImageError, compare};

use crate::gi::{Probe, floats, meshes_drawn};

/// The largest rel. L1 difference between a bounce over the RSM drawn from Bevy's meshes and
/// one over the CPU's triangles of the same scene: the two rasterise the same world triangles
/// (transformed on the GPU or on the CPU), 1.5e-8 apart on the Cornell box, 0 on the textured
/// floor and the bent skinned bar, on lavapipe.
pub(crate) const MESHES_RSM_TOLERANCE: f64 = 1e-4;

/// Frames the switched source may take to show.
const MAX_FRAMES: u32 = 100;

/// Every camera's RSM source set to `source`; then frames until the render world draws the RSMs
/// from it (its count of meshes drawn grows from Bevy's meshes, holds from the triangles), and
/// until every probe's bounce holds still for three frames: each probe's last bounce.
pub(crate) fn switched(app: &mut App, probes: &[Probe], source: RsmSource) -> Vec<Vec<[f32; 3]>> {
    let world = app.world_mut();
    for mut gi in world.query::<&mut IndirectLight>().iter_mut(world) {
        gi.rsm_source = source;
    }
    let mut drawn = meshes_drawn(app);
    let mut frames = 0;
    loop {
        assert!(frames < MAX_FRAMES, "the RSMs never drew from {source:?}");
        app.update();
        frames += 1;
        let now = meshes_drawn(app);
        let grows = now > drawn;
        drawn = now;
        if grows == (source == RsmSource::Meshes) {
            break;
        }
    }
    bounce_settled(app, probes, MAX_FRAMES - frames)
}

/// Frames (at most `frames`) until every probe's bounce holds still for three frames: each
/// probe's last bounce.
pub(crate) fn bounce_settled(app: &mut App, probes: &[Probe], frames: u32) -> Vec<Vec<[f32; 3]>> {
    let read = |p: &Probe| floats(p.read_indirect.lock().unwrap().as_ref().unwrap());
    let mut last: Vec<_> = probes.iter().map(read).collect();
    // the readbacks of the frames before the change arrive after it
    let mut still = -3;
    for _ in 0..frames {
        app.update();
        let now: Vec<_> = probes.iter().map(read).collect();
        still = if now == last { still + 1 } else { still.min(0) };
        last = now;
        if still == 3 {
            return last;
        }
    }
    panic!("the bounce never settled in {frames} frames");
}

/// Three frames with nothing moving draw no mesh into the RSMs.
pub(crate) fn assert_still_frames_draw_nothing(app: &mut App, what: &str) {
    let drawn = meshes_drawn(app);
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(
        meshes_drawn(app),
        drawn,
        "{what}: the RSM drawn again, nothing moving"
    );
}

/// The bounce of `meshes` (drawn from Bevy's meshes) against `triangles` (from the CPU's
/// triangles), printed.
pub(crate) fn meshes_against_triangles(
    what: &str,
    meshes: &[[f32; 3]],
    triangles: &[[f32; 3]],
) -> ImageError {
    let error = compare(meshes, triangles);
    println!("{what}: the RSM from Bevy's meshes against the triangles': {error:?}");
    error
}
