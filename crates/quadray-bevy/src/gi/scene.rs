//! The main world's side of the plugin: the components a user adds, and the scene's triangles
//! gathered each frame into [`IndirectLightScene`] for the render world (its lights:
//! `lights.rs`).

use super::cpu_time::CpuTimes;
use super::displaced::{Albedo, ColourMap, Displacement, append_displaced};
use super::posed::Poses;
use super::textures::BaseColours;
use crate::{PyramidMaterial, Pyramids};
use bevy::asset::{AssetEvent, RenderAssetUsages};
use bevy::camera::Hdr;
use bevy::core_pipeline::prepass::{DeferredPrepass, DepthPrepass};
use bevy::math::Affine2;
use bevy::mesh::{Indices, PrimitiveTopology, UvChannel, VertexAttributeValues};
use bevy::pbr::StandardMaterial;
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::*;
use bevy::render::extract_component::ExtractComponent;
use bevy::render::storage::ShaderBuffer;
use quadray_displace::heightmap::HeightMap;
use quadray_indirect::scene::{Light, SceneTextures, Vertex};
use quadray_indirect::{Method, Settings};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

/// On a camera: add one bounce of indirect light from the [`IndirectLightSource`] lights (to the
/// HDR picture, before tone mapping: the camera gets `Hdr` and Bevy's depth and deferred prepasses).
#[derive(Component, Clone, Debug, ExtractComponent)]
#[require(DepthPrepass, DeferredPrepass, Hdr)]
pub struct IndirectLight {
    /// quadray's light-quadtree settings (RSM size, cut levels, validity thresholds, per-tile
    /// cuts, indirect shadows, temporal weight, ...); `size` is ignored: the gather runs at the
    /// camera's size.
    pub settings: Settings,
    /// How the indirect light is gathered: per-tile cuts ([`Method::DEFAULT`]), the quadtree's
    /// one cut, the paper's per-level passes, RSM sampling, or every VPL (the brute force).
    pub method: Method,
    /// Clamp of the VPL kernel's distance (world units): 1/r^4 is taken at no less than this.
    pub r_min: f32,
    /// `false` keeps what is built but gathers and adds no light (to compare).
    pub enabled: bool,
    /// Debug view: the light quadtree's cut over the RSM in the picture's top-left corner, after
    /// tone mapping (the RSM's flux with every cluster outlined in its level's colour: white
    /// single VPLs, then red, yellow, green, blue, violet going up), the picture `quadray
    /// indirect` writes as `*.cut.png`. The per-tile cuts refine this cut tile by tile.
    pub cut_view: bool,
    /// What each light's RSM is drawn from (the first camera's choice holds for every camera).
    pub rsm_source: RsmSource,
    /// Debug output: each frame's indirect radiance (`[f32; 4]` a pixel, row-major, before the
    /// exposure) copied into this buffer, when it has room.
    pub debug_indirect: Option<Handle<ShaderBuffer>>,
}

impl Default for IndirectLight {
    fn default() -> Self {
        Self {
            settings: Settings::DEFAULT,
            method: Method::DEFAULT,
            r_min: quadray_indirect::scene::DEFAULT_R_MIN,
            enabled: true,
            cut_view: false,
            rsm_source: RsmSource::default(),
            debug_indirect: None,
        }
    }
}

/// What the lights' reflective shadow maps are drawn from ([`IndirectLight::rsm_source`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RsmSource {
    /// The scene's triangles made on the CPU ([`IndirectLightScene`]): every visible `Mesh3d`
    /// whose mesh keeps its data in the main world, displaced surfaces displaced, skinned and
    /// morphed meshes posed on the CPU. The RSM is redrawn when the scene or a light changes.
    #[default]
    Triangles,
    /// Bevy's meshes on the GPU, drawn by the plugin's mesh pipeline from Bevy's mesh allocator
    /// (a mesh kept only in the render world, `RenderAssetUsages::RENDER_WORLD`, included),
    /// skinned in the vertex stage by Bevy's skinning: every mesh Bevy extracts (one some
    /// camera or shadow-casting light sees) in its `StandardMaterial`'s base colour times
    /// 1 - metallic, times its base colour texture sampled as Bevy samples it (another material:
    /// grey 0.5). Morph targets are not applied and displaced surfaces are drawn flat. Each
    /// entity's draw is kept across frames; the RSM is redrawn when a light or the draws change
    /// (an entity moved, came or went, its material changed, a skinned mesh's joints moved). Without indirect shadows no triangle is made on the CPU; with them
    /// the occupancy grid is still made of [`IndirectLightScene`]'s triangles.
    Meshes,
}

/// On a `DirectionalLight`, `PointLight` or `SpotLight`: a light whose first bounce
/// [`IndirectLight`] cameras add.
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct IndirectLightSource;

/// The scene the lights' RSMs and the occupancy grid are made of: the triangles of every
/// visible `Mesh3d` in world space (a `StandardMaterial`'s base colour as their albedo, times its
/// base colour texture at their uv, the textures kept as the layers of one array; a
/// `PyramidMaterial`'s displaced surface, see
/// [`DISPLACED_TRIANGLES_MAX`](super::DISPLACED_TRIANGLES_MAX); a skinned or morphed mesh posed
/// as Bevy poses it), kept per entity, and the marked lights. An entity's triangles are made
/// anew only when its transform, mesh, material or visibility changes (or the mesh, material or
/// texture asset it uses does, a joint of its skin moves or its morph weights change); the
/// render world receives the entities that changed. A resource of the main world, to read.
#[derive(Resource, Default)]
pub struct IndirectLightScene {
    /// Every `Mesh3d` entity, its triangles empty while its mesh is not loaded or it is hidden.
    pub(super) objects: BTreeMap<Entity, SceneObject>,
    /// The update that made [`Self::generation`]: the entities whose triangles changed and
    /// their triangles (`None`: gone or empty), from generation `since`.
    pub(super) changes: Vec<(Entity, Option<Arc<ObjectTriangles>>)>,
    pub(super) since: u64,
    /// Counts the updates that changed triangles.
    pub(super) generation: u64,
    /// Counts the triangles made, all updates together.
    pub(super) triangles_made: u64,
    pub(super) lights: Vec<Light>,
    /// The `StandardMaterial`s' base colour textures the triangles sample.
    pub(super) base_colours: BaseColours,
    /// Entities to make again next frame: their texture was refused while the layers were full,
    /// and layers were dropped since.
    retry: Vec<Entity>,
    /// The bounds (min, max) of the visible meshes' boxes in world space, kept while a camera
    /// draws its RSMs from Bevy's meshes ([`RsmSource::Meshes`]).
    pub(super) mesh_bounds: (Vec3, Vec3),
}

/// One entity's triangles in world space and their bounds, shared with the render world.
#[derive(Debug, PartialEq)]
pub struct ObjectTriangles {
    pub(super) triangles: Vec<[Vertex; 3]>,
    /// Min and max corners.
    pub(super) bounds: (Vec3, Vec3),
}

impl ObjectTriangles {
    fn new(triangles: Vec<[Vertex; 3]>) -> Self {
        let mut bounds = (Vec3::MAX, Vec3::MIN);
        for t in &triangles {
            for v in t {
                let p = Vec3::from(v.position);
                bounds = (bounds.0.min(p), bounds.1.max(p));
            }
        }
        Self { triangles, bounds }
    }

    /// The triangles, in world space, with the normal and albedo the RSM takes.
    pub fn triangles(&self) -> &[[Vertex; 3]] {
        &self.triangles
    }

    /// Their bounds (min and max corners).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }
}

/// An entity of the scene: what its triangles were made from, and them.
pub(super) struct SceneObject {
    mesh: AssetId<Mesh>,
    material: Option<AssetId<StandardMaterial>>,
    displaced: bool,
    /// Its material's base colour texture (read or not), and the packed texture its triangles
    /// sample where read.
    image: Option<AssetId<Image>>,
    texture: Option<u32>,
    pub(super) triangles: Option<Arc<ObjectTriangles>>,
}

impl IndirectLightScene {
    /// The triangles, in world space, with the normal and albedo the RSM takes: each entity's
    /// in turn, by entity.
    pub fn triangles(&self) -> impl Iterator<Item = &[Vertex; 3]> {
        self.objects().flat_map(|(_, o)| o.triangles.iter())
    }

    /// The entities with triangles, by entity, and theirs.
    pub fn objects(&self) -> impl Iterator<Item = (Entity, &ObjectTriangles)> {
        self.objects
            .iter()
            .filter_map(|(e, o)| Some((*e, o.triangles.as_deref()?)))
    }

    /// How many triangles the scene has.
    pub fn triangle_count(&self) -> usize {
        self.objects().map(|(_, o)| o.triangles.len()).sum()
    }

    /// Counts the updates that changed the triangles.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Counts the triangles made (transformed to world space), every update together: an update
    /// adds the triangles of the entities that changed, not the scene's.
    pub fn triangles_made(&self) -> u64 {
        self.triangles_made
    }

    /// The base colour textures the triangles' [`Vertex::texture`] sample.
    pub fn textures(&self) -> &SceneTextures {
        &self.base_colours.textures
    }
}

impl RsmSource {
    /// Every source, by its name (the default first).
    pub const ALL: [Self; 2] = [Self::Triangles, Self::Meshes];

    /// Its name, as a command line writes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Triangles => "triangles",
            Self::Meshes => "meshes",
        }
    }
}

impl std::str::FromStr for RsmSource {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        quadray_core::parse_named(s, &Self::ALL, Self::name, "RSM source")
    }
}

impl std::fmt::Display for RsmSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The entities whose triangles make the RSM.
type Objects<'w, 's> = Query<
    'w,
    's,
    (
        &'static GlobalTransform,
        &'static Mesh3d,
        Option<&'static MeshMaterial3d<StandardMaterial>>,
        Option<&'static MeshMaterial3d<PyramidMaterial>>,
        &'static InheritedVisibility,
    ),
>;

/// The entities whose transform, mesh, material or visibility changed.
type Changed3d<'w, 's> = Query<
    'w,
    's,
    Entity,
    (
        With<Mesh3d>,
        Or<(
            Changed<GlobalTransform>,
            Changed<Mesh3d>,
            Changed<MeshMaterial3d<StandardMaterial>>,
            Changed<MeshMaterial3d<PyramidMaterial>>,
            Changed<InheritedVisibility>,
        )>,
    ),
>;

/// The entities that lost their mesh or a material (or were despawned).
#[derive(bevy::ecs::system::SystemParam)]
pub(super) struct Removed<'w, 's> {
    meshes: RemovedComponents<'w, 's, Mesh3d>,
    materials: RemovedComponents<'w, 's, MeshMaterial3d<StandardMaterial>>,
    displaced: RemovedComponents<'w, 's, MeshMaterial3d<PyramidMaterial>>,
}

/// What the scene's triangles are made from besides the meshes: the materials, the displaced
/// surfaces' height fields (the displacement plugin's, absent without it) and the colour
/// textures read on the CPU.
#[derive(bevy::ecs::system::SystemParam)]
pub(super) struct Sources<'w, 's> {
    meshes: Res<'w, Assets<Mesh>>,
    materials: Res<'w, Assets<StandardMaterial>>,
    displaced: Option<Res<'w, Assets<PyramidMaterial>>>,
    pyramids: Option<Res<'w, Pyramids>>,
    images: Res<'w, Assets<Image>>,
    assets: Res<'w, AssetServer>,
    mesh_events: MessageReader<'w, 's, AssetEvent<Mesh>>,
    material_events: MessageReader<'w, 's, AssetEvent<StandardMaterial>>,
    /// (absent without the displacement plugin)
    displaced_events: Option<MessageReader<'w, 's, AssetEvent<PyramidMaterial>>>,
    image_events: MessageReader<'w, 's, AssetEvent<Image>>,
    /// Each colour texture as the RSM reads it (`None`: not readable on the CPU, warned once).
    colours: Local<'s, HashMap<AssetId<Image>, Option<Arc<ColourMap>>>>,
    /// The meshes kept only in the render world, warned once.
    gpu_only: Local<'s, HashSet<AssetId<Mesh>>>,
}

/// Whether the scene's triangles are made: unless every [`IndirectLight`] camera draws its RSMs
/// from Bevy's meshes without indirect shadows (whose occupancy grid needs them).
fn triangles_needed(cameras: &Query<&IndirectLight>) -> bool {
    cameras.is_empty()
        || cameras
            .iter()
            .any(|c| c.rsm_source == RsmSource::Triangles || c.settings.indirect_shadows)
}

/// While a camera draws its RSMs from Bevy's meshes: every visible mesh marked seen (so that Bevy
/// extracts it to the render world, where the RSM draws it, though no camera or shadow-casting
/// light sees it), and the bounds of their boxes in world space, which the lights' views frame
/// without the triangles. In Bevy's visibility check, after the boxes are computed.
pub(super) fn collect_meshes(
    mut meshes: Query<
        (
            &bevy::camera::primitives::Aabb,
            &GlobalTransform,
            &InheritedVisibility,
            &mut ViewVisibility,
        ),
        With<Mesh3d>,
    >,
    cameras: Query<&IndirectLight>,
    mut scene: ResMut<IndirectLightScene>,
    times: Res<CpuTimes>,
) {
    use bevy::camera::visibility::SetViewVisibility;
    let _span = times.main();
    if !cameras.iter().any(|c| c.rsm_source == RsmSource::Meshes) {
        return;
    }
    let mut bounds = (Vec3::MAX, Vec3::MIN);
    for (aabb, transform, visible, mut seen) in &mut meshes {
        if !visible.get() {
            continue;
        }
        seen.set_visible();
        let affine = transform.affine();
        let centre = affine.transform_point3a(aabb.center);
        let half = affine.matrix3.abs() * aabb.half_extents;
        bounds = (
            bounds.0.min((centre - half).into()),
            bounds.1.max((centre + half).into()),
        );
    }
    if scene.mesh_bounds != bounds {
        scene.mesh_bounds = bounds;
    }
}

/// Whether the triangles are made ([`triangles_needed`]), and every mesh entity, all made anew
/// when they are made again.
#[derive(bevy::ecs::system::SystemParam)]
pub(super) struct Pause<'w, 's> {
    cameras: Query<'w, 's, &'static IndirectLight>,
    mesh_entities: Query<'w, 's, Entity, With<Mesh3d>>,
    /// None was made last frame.
    paused: Local<'s, bool>,
}

/// Makes anew the triangles of the entities that changed (their transform, mesh, material or
/// visibility, their skin's joints or morph weights, or the assets they use) and hands them to
/// the render world; in a frame where nothing changed it does nothing more than find that out.
pub(super) fn collect_triangles(
    (objects, changed): (Objects, Changed3d),
    sources: Sources,
    mut poses: Poses,
    mut removed: Removed,
    mut scene: ResMut<IndirectLightScene>,
    mut pause: Pause,
    times: Res<CpuTimes>,
) {
    let _span = times.main();
    let Pause {
        cameras,
        mesh_entities,
        paused,
    } = &mut pause;
    if !triangles_needed(cameras) {
        if !**paused {
            // none made while paused: the render world drops the scene's
            **paused = true;
            let changes: Vec<_> = scene.objects().map(|(e, _)| (e, None)).collect();
            scene.objects.clear();
            if !changes.is_empty() {
                scene.since = scene.generation;
                scene.generation += 1;
                scene.changes = changes;
            }
        }
        return;
    }
    let resumed = std::mem::take(&mut **paused);
    let Sources {
        meshes,
        materials,
        displaced,
        pyramids,
        images,
        assets,
        mut mesh_events,
        mut material_events,
        mut displaced_events,
        mut image_events,
        mut colours,
        mut gpu_only,
    } = sources;
    let displaced = displaced.as_deref();
    if resumed {
        // the images' events while paused were not read: every image read again
        colours.clear();
        scene.base_colours.forget_all();
    }
    let mut dirty: BTreeSet<Entity> = if resumed {
        mesh_entities.iter().collect()
    } else {
        changed.iter().collect()
    };
    dirty.extend(std::mem::take(&mut scene.retry));
    dirty.extend(removed.meshes.read());
    dirty.extend(removed.materials.read());
    dirty.extend(removed.displaced.read());
    let changed_bindposes = changed_assets(&mut poses.bindpose_events);
    dirty.extend(poses.changed(&changed_bindposes));
    let changed_meshes = changed_assets(&mut mesh_events);
    let changed_materials = changed_assets(&mut material_events);
    let mut every_displaced = displaced_events
        .as_mut()
        .is_some_and(|e| e.read().count() > 0);
    let changed_images: HashSet<AssetId<Image>> =
        image_events.read().filter_map(changed_asset).collect();
    for &id in &changed_images {
        // a colour texture read, or one a displaced material waits for
        every_displaced |= colours.remove(&id).is_some() || uses_image(displaced, id);
        scene.base_colours.forget(id);
    }
    if !changed_meshes.is_empty()
        || !changed_materials.is_empty()
        || every_displaced
        || !changed_images.is_empty()
    {
        dirty.extend(scene.objects.iter().filter_map(|(e, o)| {
            let uses = changed_meshes.contains(&o.mesh)
                || o.material.is_some_and(|m| changed_materials.contains(&m))
                || (o.displaced && every_displaced)
                || o.image.is_some_and(|i| changed_images.contains(&i));
            uses.then_some(*e)
        }));
    }
    if dirty.is_empty() {
        return;
    }
    let mut changes = Vec::new();
    let mut made = 0;
    // a texture no longer sampled by an entity, whose layer may be unused
    let mut released = false;
    for entity in dirty {
        let Ok((transform, mesh, material, pyramid, visible)) = objects.get(entity) else {
            if let Some(before) = scene.objects.remove(&entity) {
                released |= before.texture.is_some();
                if before.triangles.is_some() {
                    changes.push((entity, None));
                }
            }
            continue;
        };
        let mut triangles = Vec::new();
        let standard = material.and_then(|m| materials.get(&m.0));
        let image = standard.and_then(|m| m.base_color_texture.as_ref());
        let mut texture = None;
        let readable = meshes.get(&mesh.0).filter(|m| {
            let kept = m.asset_usage.contains(RenderAssetUsages::MAIN_WORLD);
            if !kept && gpu_only.insert(mesh.id()) {
                warn!(
                    "quadray indirect light: a mesh ({:?}) is kept only in the render world \
                     (RenderAssetUsages::RENDER_WORLD): the RSM from the scene's triangles \
                     leaves it out; RsmSource::Meshes draws it",
                    mesh.id()
                );
            }
            kept
        });
        if let Some(mesh) = readable.filter(|_| visible.get()) {
            let posed = poses.posed(entity, mesh);
            let (mesh, transform) = match &posed {
                Some(posed) if posed.in_world => (&posed.mesh, &GlobalTransform::IDENTITY),
                Some(posed) => (&posed.mesh, transform),
                None => (mesh, transform),
            };
            if let Some(material) = pyramid.and_then(|m| displaced?.get(&m.0)) {
                let colour = material
                    .base
                    .base_color_texture
                    .as_ref()
                    .and_then(|texture| {
                        colours
                            .entry(texture.id())
                            .or_insert_with(|| read_colours(&images, &assets, texture))
                            .clone()
                    });
                let map = pyramids
                    .as_ref()
                    .and_then(|p| p.0.get(&material.extension.depth_map.id()))
                    .and_then(|built| built.as_ref())
                    .filter(|_| material.extension.pyramid.is_some())
                    .map(|(_, _, map)| map.as_ref());
                append_displaced_mesh(
                    mesh,
                    transform,
                    material,
                    map,
                    colour.as_deref(),
                    &mut triangles,
                );
            } else {
                let albedo = standard.map_or(Vec3::splat(0.5), base_albedo);
                // (no layer for a texture that a mesh without uvs would not sample)
                let uvs = standard.and_then(|m| {
                    let (image, uvs) = (image?, uvs_of(mesh, m)?);
                    Some((scene.base_colours.packed(&images, &assets, image)?, uvs))
                });
                texture = uvs.as_ref().map(|(packed, _)| *packed);
                append_triangles(mesh, transform, albedo.to_array(), uvs, &mut triangles);
            }
        }
        made += triangles.len() as u64;
        let triangles = (!triangles.is_empty()).then(|| Arc::new(ObjectTriangles::new(triangles)));
        // (a layer is used by the triangles that sample it)
        let texture = texture.filter(|_| triangles.is_some());
        let object = SceneObject {
            mesh: mesh.id(),
            material: material.map(|m| m.id()),
            displaced: pyramid.is_some(),
            image: image.map(Handle::id),
            texture,
            triangles: triangles.clone(),
        };
        let before = scene.objects.insert(entity, object);
        released |= before
            .as_ref()
            .is_some_and(|o| o.texture.is_some_and(|t| texture != Some(t)));
        if before.and_then(|o| o.triangles).is_some() || triangles.is_some() {
            changes.push((entity, triangles));
        }
    }
    if released {
        relayer_unused(&mut scene, &mut changes);
    }
    scene.base_colours.publish();
    scene.triangles_made += made;
    if !changes.is_empty() {
        scene.since = scene.generation;
        scene.generation += 1;
        scene.changes = changes;
    }
}

/// Drops the texture layers no entity samples any more: the entities that sample a layer after
/// them take its new place (their triangles' textures renumbered, not made anew).
fn relayer_unused(
    scene: &mut IndirectLightScene,
    changes: &mut Vec<(Entity, Option<Arc<ObjectTriangles>>)>,
) {
    let used: Vec<u32> = scene.objects.values().filter_map(|o| o.texture).collect();
    let Some((moved, refused)) = scene.base_colours.drop_unused(used) else {
        return;
    };
    // the entities whose texture was refused while the layers were full: made again next frame
    scene.retry.extend(
        scene
            .objects
            .iter()
            .filter(|(_, o)| o.texture.is_none() && o.image.is_some_and(|i| refused.contains(&i)))
            .map(|(e, _)| *e),
    );
    for (entity, object) in &mut scene.objects {
        let Some(before) = object.texture else {
            continue;
        };
        let now = moved.packed(before);
        if now == before {
            continue;
        }
        object.texture = Some(now);
        let triangles = object.triangles.as_ref().map(|o| {
            let renumbered = o
                .triangles
                .iter()
                .map(|t| t.map(|v| Vertex { texture: now, ..v }))
                .collect();
            Arc::new(ObjectTriangles::new(renumbered))
        });
        object.triangles.clone_from(&triangles);
        match changes.iter_mut().find(|(e, _)| e == entity) {
            Some(change) => change.1 = triangles,
            None => changes.push((*entity, triangles)),
        }
    }
}

/// The assets the events say were added, changed or removed.
fn changed_assets<A: Asset>(events: &mut MessageReader<AssetEvent<A>>) -> HashSet<AssetId<A>> {
    events.read().filter_map(changed_asset).collect()
}

/// The asset an event says was added, changed or removed.
fn changed_asset<A: Asset>(event: &AssetEvent<A>) -> Option<AssetId<A>> {
    match event {
        AssetEvent::Added { id }
        | AssetEvent::Modified { id }
        | AssetEvent::Removed { id }
        | AssetEvent::LoadedWithDependencies { id } => Some(*id),
        AssetEvent::Unused { .. } => None,
    }
}

/// Whether a displaced material uses image `id` as its depth map or colour texture.
fn uses_image(materials: Option<&Assets<PyramidMaterial>>, id: AssetId<Image>) -> bool {
    materials.is_some_and(|materials| {
        materials.iter().any(|(_, m)| {
            m.extension.depth_map.id() == id
                || m.base
                    .base_color_texture
                    .as_ref()
                    .is_some_and(|t| t.id() == id)
        })
    })
}

/// A colour texture as the RSM reads it, once loaded; `None` (with a warning naming it) where
/// it cannot be read on the CPU.
fn read_colours(
    images: &Assets<Image>,
    assets: &AssetServer,
    texture: &Handle<Image>,
) -> Option<Arc<ColourMap>> {
    let image = images.get(texture)?;
    let read = ColourMap::of_image(image).map(Arc::new);
    if read.is_none() {
        let name = assets
            .get_path(texture.id())
            .map_or_else(|| format!("{:?}", texture.id()), |p| p.to_string());
        warn!(
            "quadray indirect light: the colour texture {name} cannot be read on the CPU (no \
             CPU-side data, or a format Image::get_color_at does not read): the RSM takes the \
             displaced surface's base colour alone"
        );
    }
    read
}

/// A standard material's diffuse albedo: its base colour times 1 - metallic.
pub(super) fn base_albedo(m: &StandardMaterial) -> Vec3 {
    let c = LinearRgba::from(m.base_color);
    Vec3::new(c.red, c.green, c.blue) * (1.0 - m.metallic)
}

/// Appends a mesh with a [`PyramidMaterial`]: its displaced surface once the material traces
/// its depth `map`, before that its polygon (as the material draws it: flat), in the material's
/// base colour times its colour texture where that was read on the CPU.
fn append_displaced_mesh(
    mesh: &Mesh,
    transform: &GlobalTransform,
    material: &PyramidMaterial,
    map: Option<&HeightMap>,
    colour: Option<&ColourMap>,
    out: &mut Vec<[Vertex; 3]>,
) {
    let albedo = Albedo {
        base: base_albedo(&material.base),
        texture: colour,
        uv_transform: material.base.uv_transform,
    };
    let flat = HeightMap {
        width: 1,
        height: 1,
        depth: vec![0.0],
    };
    let displacement = Displacement {
        map: map.unwrap_or(&flat),
        depth_scale: material.extension.depth_scale,
        addressing: material.extension.addressing(),
    };
    if !append_displaced(mesh, transform, &displacement, &albedo, out) {
        append_triangles(mesh, transform, albedo.base.to_array(), None, out);
    }
}

/// The uv a `StandardMaterial` reads its base colour texture at, per vertex of `mesh`: the
/// channel it names through its `uv_transform` (`None` where the mesh has no such channel, or
/// not one a position).
fn uvs_of(mesh: &Mesh, material: &StandardMaterial) -> Option<Vec<[f32; 2]>> {
    let channel = match material.base_color_channel {
        UvChannel::Uv0 => Mesh::ATTRIBUTE_UV_0,
        UvChannel::Uv1 => Mesh::ATTRIBUTE_UV_1,
    };
    let Some(VertexAttributeValues::Float32x2(uvs)) = mesh.attribute(channel) else {
        return None;
    };
    if mesh.attribute(Mesh::ATTRIBUTE_POSITION).map(|p| p.len()) != Some(uvs.len()) {
        return None;
    }
    let transform: Affine2 = material.uv_transform;
    Some(
        uvs.iter()
            .map(|uv| transform.transform_point2(Vec2::from(*uv)).to_array())
            .collect(),
    )
}

/// Appends `mesh`'s triangles in world space (a triangle list with positions; face normals where
/// it has none); other topologies add nothing. With `texture` (a packed texture and a uv per
/// position of the mesh, [`uvs_of`]), the triangles sample it.
fn append_triangles(
    mesh: &Mesh,
    transform: &GlobalTransform,
    albedo: [f32; 3],
    texture: Option<(u32, Vec<[f32; 2]>)>,
    out: &mut Vec<[Vertex; 3]>,
) {
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return;
    }
    let Some(VertexAttributeValues::Float32x3(positions)) =
        mesh.attribute(Mesh::ATTRIBUTE_POSITION)
    else {
        return;
    };
    let normals = match mesh.attribute(Mesh::ATTRIBUTE_NORMAL) {
        Some(VertexAttributeValues::Float32x3(n)) if n.len() == positions.len() => Some(n),
        _ => None,
    };
    // each vertex to world space once (an indexed mesh's is shared by several triangles)
    let affine = transform.affine();
    let positions: Vec<Vec3> = positions
        .iter()
        .map(|p| affine.transform_point3(Vec3::from(*p)))
        .collect();
    let normal_matrix = Mat3::from(affine.matrix3).inverse().transpose();
    let normals: Option<Vec<Vec3>> = normals.map(|n| {
        n.iter()
            .map(|n| (normal_matrix * Vec3::from(*n)).normalize_or_zero())
            .collect()
    });
    // (over the slices: Bevy's index iterator is a call an index)
    let corners: Vec<usize> = match mesh.indices() {
        Some(Indices::U16(indices)) => indices.iter().map(|&i| usize::from(i)).collect(),
        Some(Indices::U32(indices)) => indices.iter().map(|&i| i as usize).collect(),
        None => (0..positions.len()).collect(),
    };
    out.reserve(corners.len() / 3);
    // plain code, not array maps: this crate is built at opt-level 1
    let vertex = |i: usize, p: Vec3, n: Vec3| {
        let plain = Vertex::untextured(p.to_array(), n.to_array(), albedo);
        match &texture {
            Some((packed, uvs)) => Vertex {
                uv: uvs[i],
                texture: *packed,
                ..plain
            },
            None => plain,
        }
    };
    for t in corners.chunks_exact(3) {
        let (a, b, c) = (t[0], t[1], t[2]);
        if a >= positions.len() || b >= positions.len() || c >= positions.len() {
            continue;
        }
        let (pa, pb, pc) = (positions[a], positions[b], positions[c]);
        let (na, nb, nc) = match &normals {
            Some(n) => (n[a], n[b], n[c]),
            // the face's normal where the mesh has none
            None => {
                let face = (pb - pa).cross(pc - pa).normalize_or_zero();
                (face, face, face)
            }
        };
        out.push([vertex(a, pa, na), vertex(b, pb, nb), vertex(c, pc, nc)]);
    }
}
