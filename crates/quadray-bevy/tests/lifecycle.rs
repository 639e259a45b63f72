//! What a Bevy app does to a camera with the indirect-light plugin while it runs (its target
//! replaced or resized in place, `Hdr` and MSAA toggled, `IndirectLight` removed and put back,
//! the camera respawned, the glTF scene replaced, a camera without the plugin beside it): after
//! each change the next frames' bounce equals a fresh app's with the new state from the start
//! (where the state returns to the first one, the app's own first gather, which a fresh app's
//! is), and each test checks that the change matters (a stale bounce would differ). The apps are
//! `gi.rs`'s: the bundled Cornell box, 64x64, 64^2 RSM.

use bevy::asset::RenderAssetUsages;
use bevy::camera::{Hdr, RenderTarget};
use bevy::core_pipeline::prepass::{DeferredPrepass, DepthPrepass};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::gltf::GltfAssetLabel;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{Extent3d, TextureFormat, TextureUsages};
use bevy::render::storage::ShaderBuffer;
use bevy::world_serialization::WorldAssetRoot;
use quadray_bevy::gi::{IndirectLight, RsmSource};
use quadray_indirect::reference::{ImageError, compare};
use quadray_indirect::{Method, Settings};
use std::sync::{Arc, Mutex};

use crate::gi::{
    Case, Probe, Probes, RSM, SCENE, SIZE, TEXTURED_SCENE, app, app_with, app_without_plugin,
    cameras_with_passes, check_textured_floor, compiling, floats, gathered,
};
use crate::gi_meshes::{
    MESHES_RSM_TOLERANCE, assert_still_frames_draw_nothing, bounce_settled,
    meshes_against_triangles, switched,
};

/// A picture read back every frame, the latest kept.
type Read = Arc<Mutex<Option<Vec<u8>>>>;

/// One camera with the default method.
const GI: [Case; 1] = [(Method::DEFAULT, true, false)];
/// The bounce equals the fresh app's below this.
const SAME: f64 = 1e-5;
/// Frames a change may take to show.
const MAX_FRAMES: u32 = 300;

/// The bounce a fresh app with [`GI`]'s camera gathers on `scene` at `width` x `height`.
fn fresh(scene: &'static str, width: u32, height: u32) -> Vec<[f32; 3]> {
    let mut app = app_with(scene, &GI, Settings::sized(width, height, RSM));
    let (_, mut bounce) = gathered(&mut app);
    bounce.swap_remove(0)
}

/// Zeroes `probe`'s copy of the bounce: a read that is not zero is a gather made after now.
fn zero_bounce(app: &mut App, probe: &Probe) {
    let mut buffers = app.world_mut().resource_mut::<Assets<ShaderBuffer>>();
    let mut buffer = buffers.get_mut(&probe.indirect).unwrap();
    buffer.data = Some(vec![0; buffer.buffer_description.size as usize]);
}

/// What a probe's gathers and pictures were after a change, each frame's read back.
struct AfterChange {
    /// Frames until a gather equalled the fresh app's.
    frames: u32,
    /// Gathers that differed from it before that, and after.
    before: usize,
    after: usize,
    /// Frames whose picture differs from the last frame's (a frame without the bounce).
    pictures_differing: usize,
    /// The last read (the whole buffer: as many pixels as the probe's first size).
    last: Vec<[f32; 3]>,
    /// The last read's first pixels against the fresh app's.
    error: ImageError,
}

/// Zeroes `probe`'s copy of the bounce and updates `app` until a gather (its first pixels, as
/// many as `expected` has) equals `expected`, then three frames more; each frame's gather and
/// `picture` are read and compared.
fn after_change(
    app: &mut App,
    probe: &Probe,
    picture: &Handle<Image>,
    expected: &[[f32; 3]],
) -> AfterChange {
    zero_bounce(app, probe);
    let every_read = |app: &mut App, readback: Readback| {
        let reads = Arc::new(Mutex::new(Vec::new()));
        let sink = reads.clone();
        let recorder = app
            .world_mut()
            .spawn(readback)
            .observe(move |e: On<ReadbackComplete>| sink.lock().unwrap().push(e.data.clone()))
            .id();
        (recorder, reads)
    };
    let (gathers, reads) = every_read(app, Readback::buffer(probe.indirect.clone()));
    let (pictures, picture_reads) = every_read(app, Readback::texture(picture.clone()));
    let (mut frames, mut more, mut equal_at) = (0, 3, None);
    let (mut before, mut after, mut last) = (0, 0, Vec::new());
    while more > 0 {
        app.update();
        frames += 1;
        for read in reads.lock().unwrap().drain(..).map(|b| floats(&b)) {
            if read.iter().all(|v| *v == [0.0; 3]) {
                continue;
            }
            let equal = compare(&read[..expected.len()], expected).rel_l1 < SAME;
            match (equal_at, equal) {
                (None, true) => equal_at = Some(frames),
                (None, false) => before += 1,
                (Some(_), false) => after += 1,
                (Some(_), true) => {}
            }
            last = read;
        }
        if equal_at.is_some() || frames >= MAX_FRAMES {
            more -= 1;
        }
    }
    app.world_mut().despawn(gathers);
    app.world_mut().despawn(pictures);
    assert!(
        !last.is_empty(),
        "no gather in {frames} frames after the change"
    );
    let pictures = picture_reads.lock().unwrap();
    let final_picture = pictures.last().expect("a picture");
    AfterChange {
        frames: equal_at.unwrap_or(frames),
        before,
        after,
        pictures_differing: pictures.iter().filter(|p| *p != final_picture).count(),
        error: compare(&last[..expected.len()], expected),
        last,
    }
}

/// The camera with `IndirectLight` (the one `gi.rs`'s `configure` spawned).
fn gi_camera(app: &mut App) -> Entity {
    let world = app.world_mut();
    world
        .query_filtered::<Entity, With<IndirectLight>>()
        .single(world)
        .unwrap()
}

/// A render target for a camera, readable.
fn target(app: &mut App, width: u32, height: u32) -> Handle<Image> {
    let mut image = Image::new_target_texture(width, height, TextureFormat::Rgba8UnormSrgb, None);
    image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    app.world_mut().resource_mut::<Assets<Image>>().add(image)
}

/// Reads `picture` back every frame; the latest read.
fn read_picture(app: &mut App, picture: &Handle<Image>) -> Read {
    let read = Arc::new(Mutex::new(None));
    let sink = read.clone();
    app.world_mut()
        .spawn(Readback::texture(picture.clone()))
        .observe(move |e: On<ReadbackComplete>| *sink.lock().unwrap() = Some(e.data.clone()));
    read
}

/// A camera beside the GI camera that sees what it sees (its projection and transform) without
/// `IndirectLight`: with its prepasses, and with `Hdr` where `hdr`.
fn plain_camera(app: &mut App, picture: &Handle<Image>, hdr: bool) -> Entity {
    let gi = gi_camera(app);
    let world = app.world_mut();
    let projection = world.get::<Projection>(gi).unwrap().clone();
    let transform = *world.get::<Transform>(gi).unwrap();
    let mut camera = world.spawn((
        Camera3d::default(),
        projection,
        transform,
        RenderTarget::Image(picture.clone().into()),
        Tonemapping::None,
        Msaa::Off,
        DepthPrepass,
        DeferredPrepass,
    ));
    if hdr {
        camera.insert(Hdr);
    }
    camera.id()
}

/// Updates `app` until each picture read shows the scene lit (the red wall), Bevy compiles no
/// pipeline and the pictures have not changed for five frames; the pictures.
fn settled(app: &mut App, reads: &[&Read]) -> Vec<Vec<u8>> {
    let latest =
        || -> Vec<Option<Vec<u8>>> { reads.iter().map(|r| r.lock().unwrap().clone()).collect() };
    let (mut last, mut still) = (latest(), 0);
    for _ in 0..MAX_FRAMES {
        app.update();
        let now = latest();
        let lit = now.iter().all(|p| {
            p.as_ref()
                .is_some_and(|p| p.chunks_exact(4).any(|c| c[0] > 100))
        });
        still = if lit && now == last && !compiling(app) {
            still + 1
        } else {
            0
        };
        last = now;
        if still == 5 {
            return last.into_iter().map(Option::unwrap).collect();
        }
    }
    panic!("the pictures did not settle in {MAX_FRAMES} frames");
}

/// Pixels that differ between two RGBA8 pictures.
fn differing(a: &[u8], b: &[u8]) -> usize {
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(x, y)| x != y)
        .count()
}

/// After a change that leaves `probe`'s camera as it was: updates `app` until a gather equals
/// `expected` (see [`after_change`]) and the picture `read` settles; prints what it found after
/// `what` and asserts that no gather differed, that no more than `first_frames` frames' pictures
/// differed from the last, and that the settled picture is `before`.
fn settles_as_before(
    app: &mut App,
    probe: &Probe,
    (read, before): (&Read, &[u8]),
    expected: &[[f32; 3]],
    what: &str,
    first_frames: usize,
) {
    let change = after_change(app, probe, &probe.picture, expected);
    let [now] = settled(app, &[read]).try_into().unwrap();
    let changed = differing(&now, before);
    println!(
        "{what}: equal to a fresh app's after {} frames ({} gathers differed before, {} after; \
         last {:?}; {} frames' pictures differ from the last); {changed} pixels differ from the \
         picture before",
        change.frames, change.before, change.after, change.error, change.pictures_differing
    );
    assert_eq!(change.before + change.after, 0, "{what}: a gather differed");
    assert!(
        change.pictures_differing <= first_frames,
        "{what}: a frame's picture differed"
    );
    assert_eq!(changed, 0, "{what}: the picture is not the one before");
}

/// After the camera's target became `picture` at another size (`how`): updates `app` until
/// `probe`'s gather equals `expected` (that size's, see [`after_change`]); asserts that every
/// gather from the first frame Bevy renders at that size is `expected`, written over its pixels
/// only, and that no frame's picture differed.
fn gathers_at_the_new_size(
    app: &mut App,
    probe: &Probe,
    picture: &Handle<Image>,
    expected: &[[f32; 3]],
    how: &str,
) {
    // Bevy's camera takes the new size a frame later (when it reads the image's asset event)
    // and renders this frame at the old one, the bounce with it
    app.update();
    let resized = after_change(app, probe, picture, expected);
    let past = resized.last[expected.len()..]
        .iter()
        .filter(|v| **v != [0.0; 3])
        .count();
    println!(
        "{how}: equal to a fresh app's after {} frames ({} gathers differed before, {} after; \
         last {:?}); {} frames' pictures differ from the last; {past} pixels written past the \
         new size",
        resized.frames, resized.before, resized.after, resized.error, resized.pictures_differing
    );
    assert_eq!(past, 0, "{how}: the gather is not the new size's");
    assert_eq!(
        resized.before + resized.after,
        0,
        "{how}: a gather differed"
    );
    assert_eq!(
        resized.pictures_differing, 0,
        "{how}: a frame's picture differed"
    );
}

/// The camera's target image resized in place (the same handle, as a window's or a
/// render-to-texture app's image is), then replaced by an image of the first size: from the
/// first frame Bevy renders at a new size every gather is a fresh app's at that size.
#[test]
fn a_resized_target_gathers_as_a_fresh_app_at_its_new_size() {
    let (width, height) = (48, 40);
    let expected = fresh(SCENE, width, height);
    let mut app = app(SCENE, &GI);
    let (probes, first) = gathered(&mut app);
    // the first size's gather read as the new size's pixels
    let stale = compare(&first[0][..expected.len()], &expected);
    println!("the first size's bounce against the new size's: {stale:?}");
    assert!(stale.rel_l1 > 0.1, "the sizes gather alike: {stale:?}");
    let image = probes[0].picture.clone();
    let new_size = Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    };
    let mut images = app.world_mut().resource_mut::<Assets<Image>>();
    images.get_mut(&image).unwrap().resize(new_size);
    let how = format!("resized in place to {width}x{height}");
    gathers_at_the_new_size(&mut app, &probes[0], &image, &expected, &how);
    let camera = gi_camera(&mut app);
    let replaced = target(&mut app, SIZE, SIZE);
    app.world_mut()
        .entity_mut(camera)
        .insert(RenderTarget::Image(replaced.clone().into()));
    let how = format!("replaced by a {SIZE}x{SIZE} image");
    gathers_at_the_new_size(&mut app, &probes[0], &replaced, &first[0], &how);
}

/// What the plugin says in the log while [`hdr_off_shows_bevy_s_picture_and_back_gathers_as_a_fresh_app`]
/// and [`a_camera_without_the_plugin_for_a_while_or_respawned_gathers_as_a_fresh_app`] run (in
/// a child process, whose log is read): once, that the camera without `Hdr` gets no bounce and
/// how to fix it; nothing else (a camera that lost `IndirectLight` or was despawned leaves
/// nothing behind that warns).
#[test]
fn hdr_off_and_a_camera_without_the_plugin_for_a_while_log_only_the_hdr_warning() {
    let log = crate::common::child_log(&[
        "lifecycle::hdr_off_shows_bevy_s_picture_and_back_gathers_as_a_fresh_app",
        "lifecycle::a_camera_without_the_plugin_for_a_while_or_respawned_gathers_as_a_fresh_app",
    ]);
    let told = ["Hdr ", "IndirectLight ", "respawned camera:"];
    for line in log.lines() {
        if told.iter().any(|t| line.starts_with(t)) {
            println!("{line}");
        }
    }
    let warnings: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("quadray indirect light"))
        .collect();
    println!("the plugin's warnings: {warnings:#?}");
    assert_eq!(warnings.len(), 1, "{warnings:#?}");
    assert!(
        warnings[0].contains(
            "renders without Hdr, so Bevy tone-maps in its lighting shaders and the bounce would \
             be added after: keep the Hdr component IndirectLight brings; no indirect light is added"
        ),
        "{warnings:#?}"
    );
}

/// `Hdr` taken off the camera: the plugin refuses it (a warning names the fix), frees the
/// camera's passes and the picture is Bevy's own, the same as a camera without `IndirectLight`
/// beside it, with no gather; `Hdr` put back: every gather is a fresh app's and the picture is
/// the one before.
#[test]
#[ignore = "run by hdr_off_and_a_camera_without_the_plugin_for_a_while_log_only_the_hdr_warning in a child process, which reads its log"]
fn hdr_off_shows_bevy_s_picture_and_back_gathers_as_a_fresh_app() {
    let mut app = app(SCENE, &GI);
    let (probes, first) = gathered(&mut app);
    let picture = read_picture(&mut app, &probes[0].picture);
    let [with_bounce] = settled(&mut app, &[&picture]).try_into().unwrap();
    let camera = gi_camera(&mut app);
    let plain = target(&mut app, SIZE, SIZE);
    plain_camera(&mut app, &plain, false);
    let plain_picture = read_picture(&mut app, &plain);
    app.world_mut().entity_mut(camera).remove::<Hdr>();
    zero_bounce(&mut app, &probes[0]);
    let [off, bevy_s] = settled(&mut app, &[&picture, &plain_picture])
        .try_into()
        .unwrap();
    let gathered_while_off = floats(probes[0].read_indirect.lock().unwrap().as_ref().unwrap())
        .iter()
        .any(|v| *v != [0.0; 3]);
    let passes_while_off = cameras_with_passes(&app);
    let (off_from_bevy_s, bounce_shows) = (differing(&off, &bevy_s), differing(&with_bounce, &off));
    println!(
        "Hdr off: {off_from_bevy_s} pixels differ from a camera without IndirectLight, \
         gathered {gathered_while_off}, {passes_while_off} cameras hold the plugin's passes; \
         the bounce shows on {bounce_shows} pixels"
    );
    assert!(bounce_shows * 4 > (SIZE * SIZE) as usize, "{bounce_shows}");
    assert_eq!(
        off_from_bevy_s, 0,
        "with Hdr off the picture is not Bevy's own"
    );
    assert!(
        !gathered_while_off,
        "the plugin gathered for a camera it refuses"
    );
    assert_eq!(passes_while_off, 0);
    app.world_mut().entity_mut(camera).insert(Hdr);
    settles_as_before(
        &mut app,
        &probes[0],
        (&picture, &with_bounce),
        &first[0],
        "Hdr back",
        0,
    );
}

/// MSAA switched on and off again on the camera: Bevy turns it off on a deferred camera itself
/// (with its own warning), so every gather stays a fresh app's and the picture the same.
#[test]
fn msaa_toggled_leaves_the_bounce_as_a_fresh_app_s() {
    let mut app = app(SCENE, &GI);
    let (probes, first) = gathered(&mut app);
    let picture = read_picture(&mut app, &probes[0].picture);
    let [before] = settled(&mut app, &[&picture]).try_into().unwrap();
    let camera = gi_camera(&mut app);
    for msaa in [Msaa::Sample4, Msaa::Off] {
        app.world_mut().entity_mut(camera).insert(msaa);
        let what = format!("{msaa:?} inserted");
        settles_as_before(
            &mut app,
            &probes[0],
            (&picture, &before),
            &first[0],
            &what,
            0,
        );
        let kept = *app.world().get::<Msaa>(camera).unwrap();
        assert_eq!(kept, Msaa::Off, "Bevy kept MSAA on a deferred camera");
    }
}

/// `IndirectLight` taken off the camera (its `Hdr` and prepasses stay): the plugin frees the
/// camera's passes and gathers nothing for it, and its picture is a camera's without the plugin
/// beside it; put back: every gather is a fresh app's and the picture the one before. Then the
/// camera despawned (its passes go with it), frames without it, and a camera like it spawned:
/// every gather of the new camera is a fresh app's, and its pictures are the first camera's.
#[test]
#[ignore = "run by hdr_off_and_a_camera_without_the_plugin_for_a_while_log_only_the_hdr_warning in a child process, which reads its log"]
fn a_camera_without_the_plugin_for_a_while_or_respawned_gathers_as_a_fresh_app() {
    let mut app = app(SCENE, &GI);
    let (probes, first) = gathered(&mut app);
    let picture = read_picture(&mut app, &probes[0].picture);
    let [before] = settled(&mut app, &[&picture]).try_into().unwrap();
    let camera = gi_camera(&mut app);
    let passes_before = cameras_with_passes(&app);
    let plain = target(&mut app, SIZE, SIZE);
    let plain_camera = plain_camera(&mut app, &plain, true);
    let plain_picture = read_picture(&mut app, &plain);
    let gi = app.world_mut().entity_mut(camera).take::<IndirectLight>();
    zero_bounce(&mut app, &probes[0]);
    let [without, bevy_s] = settled(&mut app, &[&picture, &plain_picture])
        .try_into()
        .unwrap();
    let gathered_without = floats(probes[0].read_indirect.lock().unwrap().as_ref().unwrap())
        .iter()
        .any(|v| *v != [0.0; 3]);
    let passes_without = cameras_with_passes(&app);
    let (from_bevy_s, bounce_shows) = (differing(&without, &bevy_s), differing(&before, &without));
    println!(
        "IndirectLight removed: {from_bevy_s} pixels differ from a camera without it, gathered \
         {gathered_without}; cameras holding the plugin's passes {passes_before} -> \
         {passes_without}; the bounce shows on {bounce_shows} pixels"
    );
    assert!(bounce_shows * 4 > (SIZE * SIZE) as usize, "{bounce_shows}");
    assert_eq!(from_bevy_s, 0, "the picture is not Bevy's own");
    assert!(
        !gathered_without,
        "the plugin gathered for a camera without it"
    );
    assert_eq!(
        (passes_before, passes_without),
        (1, 0),
        "the camera's passes were kept"
    );
    app.world_mut().despawn(plain_camera);
    app.world_mut().entity_mut(camera).insert(gi.unwrap());
    settles_as_before(
        &mut app,
        &probes[0],
        (&picture, &before),
        &first[0],
        "IndirectLight put back",
        0,
    );
    assert_eq!(cameras_with_passes(&app), 1);

    let world = app.world_mut();
    let respawned = (
        Camera3d::default(),
        world.get::<Projection>(camera).unwrap().clone(),
        *world.get::<Transform>(camera).unwrap(),
        world.get::<RenderTarget>(camera).unwrap().clone(),
        Tonemapping::None,
        Msaa::Off,
        world.get::<IndirectLight>(camera).unwrap().clone(),
    );
    world.despawn(camera);
    for _ in 0..5 {
        app.update();
    }
    let passes_despawned = cameras_with_passes(&app);
    println!(
        "respawned camera: {passes_despawned} cameras hold the plugin's passes while it is away"
    );
    assert_eq!(passes_despawned, 0);
    app.world_mut().spawn(respawned);
    // Bevy draws a new camera's first frame darker, with the bounce or without it (942 pixels
    // differ with it off): that one frame may differ
    settles_as_before(
        &mut app,
        &probes[0],
        (&picture, &before),
        &first[0],
        "respawned camera",
        1,
    );
}

/// The glTF scene's root despawned and another bundled glTF spawned (the room whose floor is red
/// and green by its texture alone; `configure` marks its light and gives the cameras its
/// projection): once the new scene has loaded, the bounce is a fresh app's on it, far from the
/// first scene's; the fresh app's is quadray's, the floor's texture in it
/// ([`check_textured_floor`]). Then the RSM drawn from Bevy's meshes on it: as the triangles'
/// RSM, with a box whose mesh only the render world keeps, after the floor's texture is edited
/// in place and after the box moves; not drawn again while nothing moves.
#[test]
fn a_replaced_scene_gathers_as_a_fresh_app_on_the_new_one() {
    let expected = fresh(TEXTURED_SCENE, SIZE, SIZE);
    check_textured_floor(&expected);
    let mut app = app(SCENE, &GI);
    let (probes, first) = gathered(&mut app);
    let world = app.world_mut();
    let root = world
        .query_filtered::<Entity, With<WorldAssetRoot>>()
        .single(world)
        .unwrap();
    world.despawn(root);
    let second = world
        .resource::<AssetServer>()
        .load(GltfAssetLabel::Scene(0).from_asset(TEXTURED_SCENE));
    world.spawn(WorldAssetRoot(second));
    let changed = compare(&first[0], &expected);
    assert!(changed.rel_l1 > 0.1, "the scenes bounce alike: {changed:?}");
    let replaced = after_change(&mut app, &probes[0], &probes[0].picture, &expected);
    println!(
        "scene replaced: equal to a fresh app's on the new one after {} frames ({} gathers \
         before it, while the scene loads; {} differed after); the first scene's {changed:?}",
        replaced.frames, replaced.before, replaced.after
    );
    assert!(replaced.error.rel_l1 < SAME, "{:?}", replaced.error);
    assert_eq!(replaced.after, 0, "a gather differed once the scene was in");

    // the RSM drawn from Bevy's meshes: the floor's texture as the triangles' RSM samples it
    let pixels = (SIZE * SIZE) as usize;
    let meshes = switched(&mut app, &probes, RsmSource::Meshes);
    let error = meshes_against_triangles("textured floor", &meshes[0], &replaced.last[..pixels]);
    assert!(error.rel_l1 <= MESHES_RSM_TOLERANCE, "{error:?}");

    // a red box on the floor whose mesh only the render world keeps: the RSM from Bevy's meshes
    // draws it as the triangles' RSM draws the same box readable on the CPU; the triangles'
    // misses it
    let world = app.world_mut();
    let mut mesh = Cuboid::new(0.2, 0.3, 0.2).mesh().build();
    mesh.asset_usage = RenderAssetUsages::RENDER_WORLD;
    let render_world_only = world.resource_mut::<Assets<Mesh>>().add(mesh);
    let readable = world
        .resource_mut::<Assets<Mesh>>()
        .add(Cuboid::new(0.2, 0.3, 0.2));
    let red = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(Color::srgb(0.9, 0.1, 0.1));
    let place = Transform::from_xyz(0.5, 0.15, 0.5);
    let red_box = world
        .spawn((Mesh3d(render_world_only), MeshMaterial3d(red), place))
        .id();
    let drawn = switched(&mut app, &probes, RsmSource::Meshes);
    let missed = switched(&mut app, &probes, RsmSource::Triangles);
    app.world_mut().entity_mut(red_box).insert(Mesh3d(readable));
    let readable = switched(&mut app, &probes, RsmSource::Triangles);
    let error = meshes_against_triangles("a render-world mesh", &drawn[0], &readable[0]);
    let missing = compare(&missed[0], &readable[0]);
    let added = compare(&meshes[0], &readable[0]);
    println!(
        "the box missed by the triangles' RSM: {missing:?}; the box's bounce (its light and its \
         shade) against the floor's alone: {added:?}"
    );
    assert!(error.rel_l1 <= MESHES_RSM_TOLERANCE, "{error:?}");
    assert!(missing.rel_l1 > 0.01, "{missing:?}");

    // the floor's texture edited in place, mirrored and twice as wide (Bevy makes a new texture
    // for the new size): both RSMs sample the new one
    mirror_floor_texture(&mut app);
    let edited = switched(&mut app, &probes, RsmSource::Meshes);
    let edited_triangles = switched(&mut app, &probes, RsmSource::Triangles);
    sources_agree_on_a_change(
        "an edited texture",
        (&edited[0], &edited_triangles[0]),
        &readable[0],
        0.05,
    );

    // the box moved while the RSM is drawn from Bevy's meshes: its kept draw takes the new
    // transform; then, with nothing moving, the RSM is not drawn again
    switched(&mut app, &probes, RsmSource::Meshes);
    let moved_place = Transform::from_xyz(-0.4, 0.15, 0.3);
    app.world_mut().entity_mut(red_box).insert(moved_place);
    let moved = bounce_settled(&mut app, &probes, 100);
    assert_still_frames_draw_nothing(&mut app, "the moved box");
    let moved_triangles = switched(&mut app, &probes, RsmSource::Triangles);
    sources_agree_on_a_change(
        "a moved box",
        (&moved[0], &moved_triangles[0]),
        &edited_triangles[0],
        0.01,
    );
}

/// After a change, the bounce over the RSM drawn from Bevy's meshes is the triangles' (within
/// [`MESHES_RSM_TOLERANCE`]), which the change moved more than `least` rel. L1 from `before`.
fn sources_agree_on_a_change(
    what: &str,
    (meshes, triangles): (&[[f32; 3]], &[[f32; 3]]),
    before: &[[f32; 3]],
    least: f64,
) {
    let error = meshes_against_triangles(what, meshes, triangles);
    let changed = compare(triangles, before);
    println!("{what}: {changed:?} from the bounce before");
    assert!(error.rel_l1 <= MESHES_RSM_TOLERANCE, "{what}: {error:?}");
    assert!(changed.rel_l1 > least, "{what}: {changed:?}");
}

/// Mirrors the one base colour texture of the app's materials left to right in place, each
/// texel twice as wide.
fn mirror_floor_texture(app: &mut App) {
    let world = app.world_mut();
    let textures: Vec<AssetId<Image>> = world
        .resource::<Assets<StandardMaterial>>()
        .iter()
        .filter_map(|(_, m)| m.base_color_texture.as_ref().map(Handle::id))
        .collect();
    assert_eq!(textures.len(), 1, "the textured room has one texture");
    let mut images = world.resource_mut::<Assets<Image>>();
    let mut image = images.get_mut(textures[0]).unwrap();
    let (width, height) = (image.width() as usize, image.height() as usize);
    let old = image.data.clone().expect("the texture on the CPU");
    assert_eq!(old.len(), width * height * 4, "four bytes a texel");
    let texel = |x: usize, y: usize| &old[(y * width + x) * 4..][..4];
    let data = (0..height)
        .flat_map(|y| (0..2 * width).flat_map(move |x| texel(width - 1 - x / 2, y).to_vec()))
        .collect();
    image.resize(Extent3d {
        width: 2 * width as u32,
        height: height as u32,
        depth_or_array_layers: 1,
    });
    image.data = Some(data);
}

/// A camera without `IndirectLight` beside one with it: its picture is an app's without the
/// plugin, byte for byte, and every gather of the other is a fresh app's with one GI camera.
#[test]
fn a_camera_without_the_plugin_beside_one_with_it_keeps_bevy_s_picture() {
    let mut bevy_only = app_without_plugin(SCENE, &[(Method::DEFAULT, false, false)]);
    bevy_only.update();
    let probe = bevy_only.world().resource::<Probes>().0[0].clone();
    let read = read_picture(&mut bevy_only, &probe.picture);
    let [bevy_s] = settled(&mut bevy_only, &[&read]).try_into().unwrap();
    drop(bevy_only);

    let mut app = app(SCENE, &GI);
    let (probes, first) = gathered(&mut app);
    let plain = target(&mut app, SIZE, SIZE);
    plain_camera(&mut app, &plain, true);
    let plain_picture = read_picture(&mut app, &plain);
    let gi_picture = read_picture(&mut app, &probes[0].picture);
    let beside = after_change(&mut app, &probes[0], &probes[0].picture, &first[0]);
    let [without, with] = settled(&mut app, &[&plain_picture, &gi_picture])
        .try_into()
        .unwrap();
    let (from_bevy_s, bounce_shows) = (differing(&without, &bevy_s), differing(&with, &bevy_s));
    println!(
        "two cameras: the one without IndirectLight differs from an app without the plugin on \
         {from_bevy_s} pixels, the one with it on {bounce_shows}; its gathers equal to a fresh \
         app's after {} frames ({} differed before, {} after; {} frames' pictures differ from \
         the last)",
        beside.frames, beside.before, beside.after, beside.pictures_differing
    );
    assert!(bounce_shows * 4 > (SIZE * SIZE) as usize, "{bounce_shows}");
    assert_eq!(from_bevy_s, 0);
    assert_eq!(beside.before + beside.after, 0, "a gather differed");
    assert_eq!(beside.pictures_differing, 0, "a frame's picture differed");
}
