//! Extract and prepare, the scene's triangles in the render world: each entity's as the main
//! world's updates hand them over ([`SceneMirror`]), one vertex buffer of a range an entity
//! ([`SceneBuffer`]) and the occupancy grid, both updated by the entities that changed.

use crate::gi::cpu_time::CpuTimes;
use crate::gi::scene::{IndirectLightScene, ObjectTriangles, RsmSource};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::Extract;
use quadray_indirect::scene::{Light, SceneTextures, Vertex};
use quadray_indirect::shadows::occupancy::{Footprint, OccupancyGrid};
use std::ops::Range;
use std::sync::Arc;

/// The main world's scene as the render world keeps it: each entity's triangles, the entities
/// changed since the lights' side last took them, and the marked lights.
#[derive(Resource, Default)]
pub(super) struct SceneMirror {
    /// The main world's [`IndirectLightScene::generation`] last extracted.
    generation: u64,
    pub(super) objects: HashMap<Entity, Arc<ObjectTriangles>>,
    /// The entities changed since [`Self::take_changes`], with their triangles before.
    changed: HashMap<Entity, Option<Arc<ObjectTriangles>>>,
    /// Every entity is to be taken anew (an update was missed).
    replaced: bool,
    pub(super) lights: Vec<Light>,
    /// The bounds of the visible meshes' boxes in world space ([`IndirectLightScene`]'s).
    mesh_bounds: (Vec3, Vec3),
    /// The base colour textures, the main world's count of their changes last extracted, and
    /// whether they changed since the lights' side last took them.
    pub(super) textures: Arc<SceneTextures>,
    textures_generation: u64,
    pub(super) textures_changed: bool,
}

/// What changed in the scene since the last take.
pub(super) enum SceneChanges {
    None,
    /// These entities, with their triangles before.
    Some(HashMap<Entity, Option<Arc<ObjectTriangles>>>),
    /// Everything: take the whole scene anew.
    All,
}

impl SceneMirror {
    /// What changed since the last call.
    pub(super) fn take_changes(&mut self) -> SceneChanges {
        let changed = std::mem::take(&mut self.changed);
        if std::mem::take(&mut self.replaced) {
            SceneChanges::All
        } else if changed.is_empty() {
            SceneChanges::None
        } else {
            SceneChanges::Some(changed)
        }
    }

    /// The bounds the lights' views frame with `source`: the triangles' ([`Self::bounds`]) or
    /// the meshes' boxes'.
    pub(super) fn bounds_of(&self, source: RsmSource) -> (Vec3, Vec3) {
        match source {
            RsmSource::Triangles => self.bounds(),
            RsmSource::Meshes => self.mesh_bounds,
        }
    }

    /// The scene's bounds, from its entities' (min above max without triangles).
    pub(super) fn bounds(&self) -> (Vec3, Vec3) {
        self.objects
            .values()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), o| {
                (lo.min(o.bounds().0), hi.max(o.bounds().1))
            })
    }
}

/// Takes the main world's last update: the entities it changed, or (where one was missed, which
/// Bevy's extraction every frame does not do) every entity. A frame without a change costs a
/// comparison.
pub(super) fn extract_scene(
    scene: Extract<Option<Res<IndirectLightScene>>>,
    mut mirror: ResMut<SceneMirror>,
    times: Res<CpuTimes>,
) {
    let _span = times.render();
    let Some(scene) = scene.as_ref() else { return };
    if scene.lights != mirror.lights {
        mirror.lights.clone_from(&scene.lights);
    }
    mirror.mesh_bounds = scene.mesh_bounds;
    let textures = &scene.base_colours;
    if textures.generation != mirror.textures_generation {
        mirror.textures = textures.textures.clone();
        mirror.textures_generation = textures.generation;
        mirror.textures_changed = true;
    }
    if scene.generation == mirror.generation {
        return;
    }
    if scene.since == mirror.generation {
        for (entity, triangles) in &scene.changes {
            let before = match triangles {
                Some(t) => mirror.objects.insert(*entity, t.clone()),
                None => mirror.objects.remove(entity),
            };
            mirror.changed.entry(*entity).or_insert(before);
        }
    } else {
        mirror.objects = scene
            .objects
            .iter()
            .filter_map(|(entity, o)| Some((*entity, o.triangles.clone()?)))
            .collect();
        mirror.changed.clear();
        mirror.replaced = true;
    }
    mirror.generation = scene.generation;
}

/// Triangles the vertex buffer holds at least when made.
const MIN_CAPACITY: u32 = 1024;

/// Bytes of a triangle in the vertex buffer.
const TRIANGLE_BYTES: u64 = std::mem::size_of::<[Vertex; 3]>() as u64;

/// The scene's triangles on the GPU: one vertex buffer, a range of it an entity, written where
/// an entity changed; a removed entity's range is zeroed (degenerate triangles draw nothing)
/// and taken again by the next entity that fits. Made anew, packed with room to spare, when an
/// entity fits nowhere.
pub(super) struct SceneBuffer {
    buffer: wgpu::Buffer,
    /// Triangles the buffer holds.
    capacity: u32,
    /// The end of the last range in use: the triangles drawn.
    end: u32,
    ranges: HashMap<Entity, Range<u32>>,
    /// The free ranges below `end`, by start, none adjacent to another.
    free: Vec<Range<u32>>,
}

/// Counts of the render world's work on the scene, every frame together: what a frame in which
/// nothing moved adds nothing to (but [`SceneWork::meshes_drawn`]). A resource of the render
/// world.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneWork {
    /// Triangles written to the vertex buffer.
    pub triangles_written: u64,
    /// Times the vertex buffer was made anew (the first time, and when it was full).
    pub buffers_made: u64,
    /// Triangles added to or removed from the occupancy grid.
    pub grid_triangles: u64,
    /// Times the occupancy grid was made anew from every triangle (the first time, new grid
    /// settings, or the scene grown out of the grid's bounds).
    pub grids_made: u64,
    /// Times the base colour textures were uploaded (the first time, and when the set of
    /// textures changed).
    pub textures_uploaded: u64,
    /// Meshes drawn into the lights' RSMs from Bevy's meshes ([`RsmSource::Meshes`]: every
    /// frame, each mesh once a light view).
    pub meshes_drawn: u64,
}

impl SceneBuffer {
    /// The buffer of `mirror`'s triangles, packed, with room for a quarter more (and at least
    /// [`MIN_CAPACITY`] more).
    pub(super) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mirror: &SceneMirror,
        work: &mut SceneWork,
    ) -> Self {
        let total: usize = mirror.objects.values().map(|o| o.triangles().len()).sum();
        let capacity = total as u32 + (total as u32 / 4).max(MIN_CAPACITY);
        // (zeroed by wgpu)
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("quadray gi triangles"),
            size: u64::from(capacity) * TRIANGLE_BYTES,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut ranges = HashMap::default();
        let mut entities: Vec<_> = mirror.objects.iter().collect();
        entities.sort_by_key(|(e, _)| **e);
        let mut packed: Vec<[Vertex; 3]> = Vec::with_capacity(total);
        for (entity, o) in entities {
            let start = packed.len() as u32;
            packed.extend_from_slice(o.triangles());
            ranges.insert(*entity, start..packed.len() as u32);
        }
        if !packed.is_empty() {
            queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&packed));
        }
        work.buffers_made += 1;
        work.triangles_written += total as u64;
        Self {
            buffer,
            capacity,
            end: total as u32,
            ranges,
            free: Vec::new(),
        }
    }

    /// The vertex buffer and the vertices to draw (none without triangles).
    pub(super) fn vertices(&self) -> Option<(&wgpu::Buffer, u32)> {
        (self.end > 0).then_some((&self.buffer, self.end * 3))
    }

    /// Writes the changed entities' triangles (`changed`'s keys, their triangles now in
    /// `mirror`); `false` where one fits nowhere (the buffer is to be made anew).
    pub(super) fn update(
        &mut self,
        queue: &wgpu::Queue,
        mirror: &SceneMirror,
        changed: &HashMap<Entity, Option<Arc<ObjectTriangles>>>,
        work: &mut SceneWork,
    ) -> bool {
        for entity in changed.keys() {
            let now = mirror.objects.get(entity).map(|o| o.triangles());
            let len = now.map_or(0, |t| t.len() as u32);
            let range = match self.ranges.get(entity) {
                // the same number of triangles: in place
                Some(range) if range.len() as u32 == len => range.clone(),
                before => {
                    if let Some(range) = before.cloned() {
                        self.ranges.remove(entity);
                        queue.write_buffer(
                            &self.buffer,
                            u64::from(range.start) * TRIANGLE_BYTES,
                            &vec![0; range.len() * TRIANGLE_BYTES as usize],
                        );
                        self.release(range);
                    }
                    if len == 0 {
                        continue;
                    }
                    let Some(range) = self.allocate(len) else {
                        return false;
                    };
                    self.ranges.insert(*entity, range.clone());
                    range
                }
            };
            if let Some(triangles) = now.filter(|t| !t.is_empty()) {
                queue.write_buffer(
                    &self.buffer,
                    u64::from(range.start) * TRIANGLE_BYTES,
                    bytemuck::cast_slice(triangles),
                );
                work.triangles_written += triangles.len() as u64;
            }
        }
        true
    }

    /// The first free range that holds `len` triangles, or room past the end.
    fn allocate(&mut self, len: u32) -> Option<Range<u32>> {
        if let Some(i) = self.free.iter().position(|r| r.len() as u32 >= len) {
            let start = self.free[i].start;
            self.free[i].start += len;
            if self.free[i].is_empty() {
                self.free.remove(i);
            }
            return Some(start..start + len);
        }
        (self.capacity - self.end >= len).then(|| {
            self.end += len;
            self.end - len..self.end
        })
    }

    /// Frees `range`: joined to the free ranges beside it, or given back to the end.
    fn release(&mut self, mut range: Range<u32>) {
        let i = self.free.partition_point(|r| r.start < range.start);
        if i < self.free.len() && self.free[i].start == range.end {
            range.end = self.free.remove(i).end;
        }
        if i > 0 && self.free[i - 1].end == range.start {
            range.start = self.free.remove(i - 1).start;
        }
        if range.end == self.end {
            self.end = range.start;
        } else {
            let i = self.free.partition_point(|r| r.start < range.start);
            self.free.insert(i, range);
        }
    }
}

/// The scene's occupancy grid, and what each entity's triangles counted in it, so that an
/// entity that changed is taken out by its footprint, not tested against the cells again.
pub(super) struct SceneGrid {
    pub(super) grid: OccupancyGrid,
    footprints: HashMap<Entity, Footprint>,
}

impl SceneGrid {
    /// The grid of every triangle of `mirror`, `cells` cells along its bounds' longest side.
    pub(super) fn new(mirror: &SceneMirror, cells: u32, levels: u32) -> Self {
        let mut grid = OccupancyGrid::empty(mirror.bounds(), cells, levels);
        let footprints = mirror
            .objects
            .iter()
            .map(|(entity, object)| (*entity, grid.add_tracked(object.triangles())))
            .collect();
        Self { grid, footprints }
    }

    /// Brings the grid up to the changed entities: their triangles now in, their footprints
    /// before out; `false` where one now lies outside the grid's bounds (the grid is to be made
    /// anew).
    pub(super) fn update(
        &mut self,
        mirror: &SceneMirror,
        changed: &HashMap<Entity, Option<Arc<ObjectTriangles>>>,
        work: &mut SceneWork,
    ) -> bool {
        let (lo, hi) = self.grid.bounds();
        let inside =
            |o: &ObjectTriangles| o.bounds().0.cmpge(lo).all() && o.bounds().1.cmple(hi).all();
        let now = |entity| mirror.objects.get(entity).map(|o| o.as_ref());
        if !changed.keys().filter_map(now).all(inside) {
            return false;
        }
        // in before out: the cells an object covers before and after keep a triangle
        // throughout, so they are not cleared and set again
        for (entity, before) in changed {
            let footprint = self.footprints.remove(entity);
            if let Some(now) = now(entity) {
                let footprint = self.grid.add_tracked(now.triangles());
                self.footprints.insert(*entity, footprint);
                work.grid_triangles += now.triangles().len() as u64;
            }
            if let Some(footprint) = footprint {
                self.grid.remove_footprint(&footprint);
                work.grid_triangles += before.as_ref().map_or(0, |b| b.triangles().len()) as u64;
            }
        }
        true
    }
}
