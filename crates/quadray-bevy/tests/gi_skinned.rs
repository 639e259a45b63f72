//! A skinned mesh in the indirect-light plugin's light, headless on lavapipe: the bundled red bar
//! skinned to two joints (`scenes/skinned_bar.gltf`, Bevy's glTF loader) in a white room under a
//! spot. At the bind pose the plugin's bounce is quadray's own on the same file; with the joint
//! `bend` turned, the plugin poses the bar as Bevy draws it (its triangles the bar turned about the
//! joint by each vertex's weight), makes it alone anew, and its bounce is quadray's over the posed
//! bar: the red it casts on the wall it bent away from fades as in quadray's. Its morph target's
//! weight set, the bar alone is made anew again, morphed and then bent.

use bevy::mesh::VertexAttributeValues;
use bevy::mesh::morph::MorphWeights;
use bevy::mesh::skinning::SkinnedMesh;
use bevy::prelude::*;
use quadray_bevy::gi::{IndirectLightScene, RsmSource};
use quadray_indirect::reference::compare;
use quadray_indirect::scene::Vertex;
use quadray_indirect::{Method, Renderer, Settings};

use crate::gi::{SIZE, app_of, floats, gathered, in_candela, scene_from};
use crate::gi_meshes::{
    MESHES_RSM_TOLERANCE, assert_still_frames_draw_nothing, bounce_settled,
    meshes_against_triangles, switched,
};

const SKINNED_SCENE: &str = "scenes/skinned_bar.gltf";
/// A camera looking at the room's left wall past the bar, which it never sees (standing or bent
/// right): what the bounce shows there comes from the light, whatever Bevy draws of the bar.
const LEFT_WALL: Option<([f32; 3], [f32; 3])> = Some(([0.2, 0.45, 0.95], [0.0, 0.3, 0.2]));
/// The RSM's side: a small brute force.
const RSM: u32 = 32;
/// The turn of the joint `bend` about its z axis: the bar's top bends towards +x.
const BEND_DEG: f32 = -60.0;

/// The bar's triangles as the bind pose's mesh, its morph target `flare` added `flare` times,
/// turned by `turn` about `pivot`, each vertex by its weight on the joint `bend` (the skin's second
/// joint; the first, `root`, stays still): the positions blended, the normals by the inverse
/// transpose of the blended matrix. With `albedo`.
fn bent_bar(
    mesh: &Mesh,
    flare: f32,
    pivot: Vec3,
    turn: Quat,
    albedo: [f32; 3],
) -> Vec<[Vertex; 3]> {
    let Some(VertexAttributeValues::Float32x3(positions)) =
        mesh.attribute(Mesh::ATTRIBUTE_POSITION)
    else {
        panic!("the bar has positions")
    };
    let Some(VertexAttributeValues::Float32x3(normals)) = mesh.attribute(Mesh::ATTRIBUTE_NORMAL)
    else {
        panic!("the bar has normals")
    };
    let Some(VertexAttributeValues::Float32x4(weights)) =
        mesh.attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT)
    else {
        panic!("the bar has joint weights")
    };
    let targets = mesh
        .get_morph_targets()
        .expect("the bar has a morph target");
    let vertex = |i: usize| {
        let p = Vec3::from(positions[i]) + flare * targets[i].position;
        let w = weights[i][1];
        let turned = pivot + turn * (p - pivot);
        let blend = Mat3::IDENTITY * (1.0 - w) + Mat3::from_quat(turn) * w;
        let n = (blend.inverse().transpose() * Vec3::from(normals[i])).normalize();
        Vertex::untextured(p.lerp(turned, w).to_array(), n.to_array(), albedo)
    };
    let indices: Vec<usize> = mesh.indices().expect("indexed").iter().collect();
    indices
        .chunks_exact(3)
        .map(|t| [vertex(t[0]), vertex(t[1]), vertex(t[2])])
        .collect()
}

/// The largest differences of position and of normal between two lists of triangles of one
/// length.
fn largest_differences(a: &[[Vertex; 3]], b: &[[Vertex; 3]]) -> (f32, f32) {
    assert_eq!(a.len(), b.len());
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .fold((0.0, 0.0), |(position, normal), (u, v)| {
            (
                position.max(Vec3::from(u.position).distance(Vec3::from(v.position))),
                normal.max(Vec3::from(u.normal).distance(Vec3::from(v.normal))),
            )
        })
}

/// The red the bar casts on the white room in `image`: how much more red than green each pixel
/// has, summed.
fn red_on_room(image: &[[f32; 3]]) -> f32 {
    image.iter().map(|p| (p[0] - p[1]).max(0.0)).sum()
}

#[test]
fn a_skinned_mesh_s_bounce_moves_with_its_joints() {
    let settings = Settings::sized(SIZE, SIZE, RSM);
    let cases = [(Method::Reference, true, false)];
    let mut app = app_of(SKINNED_SCENE, &cases, settings.clone(), true, LEFT_WALL);
    let (probes, bind) = gathered(&mut app);
    let read = || floats(probes[0].read_indirect.lock().unwrap().as_ref().unwrap());

    // the bind pose: the bar where the mesh places it, as quadray's reader (which ignores skins)
    // reads the file
    let gpu = quadray_gpu::Gpu::new().expect("an adapter (scripts/setup.sh installs lavapipe)");
    let file = scene_from(SKINNED_SCENE, LEFT_WALL);
    let quadray = |scene: &quadray_indirect::Scene| {
        let mut renderer = Renderer::new(&gpu, scene, settings.clone()).unwrap();
        in_candela(renderer.render_frame(Method::Reference).unwrap().indirect)
    };
    let quadray_bind = quadray(&file);
    let at_bind = compare(&bind[0], &quadray_bind);
    println!("bind pose: plugin's bounce against quadray's: {at_bind:?}");
    assert!(at_bind.rel_l1 <= 0.05, "{at_bind:?}");

    let world = app.world_mut();
    let (bar, mesh) = world
        .query_filtered::<(Entity, &Mesh3d), With<SkinnedMesh>>()
        .single(world)
        .map(|(e, m)| (e, m.0.clone()))
        .unwrap();
    let (bend, pivot) = world
        .query::<(Entity, &Name, &GlobalTransform)>()
        .iter(world)
        .find(|(_, name, _)| name.as_str() == "bend")
        .map(|(e, _, t)| (e, t.translation()))
        .unwrap();
    let mesh = world.resource::<Assets<Mesh>>().get(&mesh).unwrap().clone();
    let held = |app: &App| {
        let scene = app.world().resource::<IndirectLightScene>();
        let (_, triangles) = scene.objects().find(|(e, _)| *e == bar).unwrap();
        triangles.triangles().to_vec()
    };
    let bind_triangles = held(&app);
    let red = bind_triangles[0][0].albedo;
    let unbent = bent_bar(&mesh, 0.0, pivot, Quat::IDENTITY, red);
    let (position, normal) = largest_differences(&bind_triangles, &unbent);
    assert!(position < 1e-5 && normal < 1e-5, "{position} {normal}");

    // the joint turned: the bar alone made anew, once, bent as Bevy bends it
    let scene = app.world().resource::<IndirectLightScene>();
    let (generation, made) = (scene.generation(), scene.triangles_made());
    let turn = Quat::from_rotation_z(BEND_DEG.to_radians());
    app.world_mut().get_mut::<Transform>(bend).unwrap().rotation = turn;
    let (mut last, mut still) = (bind[0].clone(), 0);
    for _ in 0..30 {
        app.update();
        let now = read();
        still = if now == last && now != bind[0] {
            still + 1
        } else {
            0
        };
        last = now;
        if still == 2 {
            break;
        }
    }
    assert_eq!(still, 2, "the bounce never settled after the joint turned");
    let scene = app.world().resource::<IndirectLightScene>();
    assert_eq!(scene.generation(), generation + 1, "one update");
    assert_eq!(
        scene.triangles_made(),
        made + bind_triangles.len() as u64,
        "the bar alone made anew"
    );
    let bent = bent_bar(&mesh, 0.0, pivot, turn, red);
    let posed = held(&app);
    let (moved, _) = largest_differences(&posed, &bind_triangles);
    let (position, normal) = largest_differences(&posed, &bent);
    println!(
        "the bar's triangles: moved up to {moved:.3}, off the bent reference by {position:.2e} \
         (positions) and {normal:.2e} (normals)"
    );
    assert!(moved > 0.2 && position < 1e-5 && normal < 1e-5);

    // the bounce: quadray's over the room and the bent bar (the file's bar taken out)
    let mut bent_file = file.clone();
    bent_file.triangles.retain(|t| t[0].albedo != red);
    assert_eq!(file.triangles.len() - bent_file.triangles.len(), bent.len());
    bent_file.triangles.extend(bent);
    let quadray_bent = quadray(&bent_file);
    let at_pose = compare(&last, &quadray_bent);
    let moved_bounce = compare(&quadray_bent, &quadray_bind).rel_l1;
    let (before, after) = (red_on_room(&bind[0]), red_on_room(&last));
    let (quadray_before, quadray_after) = (red_on_room(&quadray_bind), red_on_room(&quadray_bent));
    println!(
        "bent: plugin's bounce against quadray's over the bent bar: {at_pose:?}; quadray's bent \
         against its bind pose: rel_l1 {moved_bounce:.4}; red on the left of the room: plugin \
         {before:.1} to {after:.1}, quadray {quadray_before:.1} to {quadray_after:.1}"
    );
    assert!(at_pose.rel_l1 <= 0.05 && at_pose.rel_l1 <= 0.25 * moved_bounce);
    // the bar bent away from the left wall: less of its red there, as much less as quadray's
    let (fades, quadray_fades) = (after / before, quadray_after / quadray_before);
    assert!(
        fades < 0.9 && (fades - quadray_fades).abs() < 0.02,
        "{fades} {quadray_fades}"
    );

    // the RSM drawn from Bevy's meshes, the bar skinned by Bevy's vertex stage: the bent bar's
    // bounce as from the triangles posed on the CPU; then from the triangles again, made anew
    let meshes = switched(&mut app, &probes, RsmSource::Meshes);
    let error = meshes_against_triangles("the bent bar", &meshes[0], &last);
    assert!(error.rel_l1 <= MESHES_RSM_TOLERANCE, "{error:?}");
    // with nothing moving the RSM is not drawn again; the joint turned back and bent again, it
    // is, each pose's bounce as the triangles' was
    assert_still_frames_draw_nothing(&mut app, "the bent bar");
    for (rotation, pose, expected) in [
        (Quat::IDENTITY, "the bind pose", &bind[0]),
        (turn, "bent again", &last),
    ] {
        app.world_mut().get_mut::<Transform>(bend).unwrap().rotation = rotation;
        let posed = bounce_settled(&mut app, &probes, 100);
        let error = meshes_against_triangles(pose, &posed[0], expected);
        assert!(error.rel_l1 <= MESHES_RSM_TOLERANCE, "{pose}: {error:?}");
    }
    let triangles = switched(&mut app, &probes, RsmSource::Triangles);
    assert_eq!(triangles[0], last);

    // the morph target `flare` weighed in (on the glTF node the mesh refers to): the bar alone
    // made anew, morphed, then bent
    let world = app.world_mut();
    let scene = world.resource::<IndirectLightScene>();
    let (generation, made) = (scene.generation(), scene.triangles_made());
    let mut weights = world.query::<(&Name, &mut MorphWeights)>();
    let (_, mut node) = weights
        .iter_mut(world)
        .find(|(name, _)| name.as_str() == "bar")
        .unwrap();
    node.weights_mut()[0] = 1.0;
    app.update();
    let scene = app.world().resource::<IndirectLightScene>();
    assert_eq!(scene.generation(), generation + 1, "one update");
    assert_eq!(scene.triangles_made(), made + posed.len() as u64);
    let flared = held(&app);
    let (moved, _) = largest_differences(&flared, &posed);
    let (position, normal) = largest_differences(&flared, &bent_bar(&mesh, 1.0, pivot, turn, red));
    println!(
        "flared: moved up to {moved:.3}, off the reference by {position:.2e} (positions) and \
         {normal:.2e} (normals)"
    );
    assert!(moved > 0.05 && position < 1e-5 && normal < 1e-5);
}
