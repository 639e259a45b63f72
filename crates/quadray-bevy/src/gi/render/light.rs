//! Prepare, the lights' side shared by every camera: per light view an RSM over the scene's
//! triangles and the light quadtree over it, and the scene's vertex buffer and occupancy grid.

use super::triangles::{SceneBuffer, SceneChanges, SceneGrid, SceneMirror, SceneWork};
use crate::gi::cpu_time::CpuTimes;
use crate::gi::scene::{IndirectLight, RsmSource};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use quadray_indirect::scene::Light;
use quadray_indirect::{GBufferLayout, LightQuadtree, RsmPass, Settings, TextureArray};
use quadray_indirect::{LightView, ViewMaps};

/// The lights' side, shared by every camera: an RSM over the scene's triangles and the light
/// quadtree built over it per light view.
#[derive(Resource, Default)]
pub(super) struct LightState(pub(super) Option<LightPasses>);

/// One light view's RSM and quadtree.
pub(super) struct ViewMapsPasses {
    pub(super) rsm: RsmPass,
    pub(super) quadtree: LightQuadtree,
}

pub(super) struct LightPasses {
    /// One a light view, in the order of `lights`' views; the first's cut is the one the cut
    /// view and the diagnostics show.
    pub(super) views: Vec<ViewMapsPasses>,
    /// Counts the times `views` was made anew: a camera's gather reads the maps of one.
    pub(super) maps_generation: u64,
    pub(super) rsm_size: u32,
    /// The layout the RSMs are in (the first camera's [`Settings::gbuffer_layout`]).
    pub(super) rsm_layout: GBufferLayout,
    /// The first camera's [`Settings::max_lights`], which `lights` was taken with.
    pub(super) max_lights: u32,
    /// The scene's triangles, a range an entity.
    pub(super) scene: SceneBuffer,
    /// The base colour textures the triangles sample, which every RSM binds.
    pub(super) textures: TextureArray,
    /// What the RSMs are drawn from (the first camera's [`IndirectLight::rsm_source`]).
    pub(super) source: RsmSource,
    /// The scene's bounds, which the lights' views frame: its triangles', or its meshes' (their
    /// boxes in world space) with [`RsmSource::Meshes`].
    pub(super) bounds: (Vec3, Vec3),
    pub(super) lights: Vec<Light>,
    /// The lights' RSM views, one a `views` entry.
    pub(super) light_views: Vec<LightView>,
    /// The RSMs, pyramids and cuts are to be recorded again (a light or the scene changed).
    pub(super) stale: bool,
    /// The scene's occupancy grid that indirect shadows walk, at the first camera's
    /// [`Settings::shadow_grid`] cells and [`Settings::shadow_grid_levels`] (none without
    /// indirect shadows, or at 0 cells: the gathers march the depth maps), and how many times
    /// it changed. Updated by the entities that changed; made anew over the scene's bounds
    /// when one leaves the grid's.
    pub(super) occupancy: Option<SceneGrid>,
    pub(super) occupancy_cells: (u32, u32),
    pub(super) occupancy_generation: u64,
}

impl LightPasses {
    pub(super) fn maps(&self) -> Vec<ViewMaps<'_>> {
        self.views
            .iter()
            .map(|v| ViewMaps {
                rsm: v.rsm.views(),
                quadtree: &v.quadtree,
            })
            .collect()
    }

    /// The passes of `count` light views at `settings`.
    pub(super) fn make_views(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: &Settings,
        count: usize,
    ) {
        self.views = (0..count)
            .map(|_| {
                let mut rsm = RsmPass::new(device, settings);
                rsm.set_textures(&self.textures);
                let quadtree = LightQuadtree::new(
                    device,
                    queue,
                    settings.rsm_size,
                    settings.cluster,
                    rsm.views(),
                );
                ViewMapsPasses { rsm, quadtree }
            })
            .collect();
        self.rsm_size = settings.rsm_size;
        self.rsm_layout = settings.gbuffer_layout;
        self.maps_generation += 1;
        self.stale = true;
    }
}

pub(super) fn prepare_light(
    mut mirror: ResMut<SceneMirror>,
    cameras: Query<&IndirectLight, With<ExtractedCamera>>,
    (device, queue): (Res<RenderDevice>, Res<RenderQueue>),
    mut state: ResMut<LightState>,
    mut work: ResMut<SceneWork>,
    mut warned: Local<Option<String>>,
    times: Res<CpuTimes>,
) {
    let _span = times.render();
    // taken every frame: the lights' side made anew takes the whole scene
    let changes = mirror.take_changes();
    let Some(camera) = cameras.iter().next() else {
        // no camera gathers: the lights' maps are freed, and made anew for the next one
        state.0 = None;
        return;
    };
    let device = device.wgpu_device();
    let settings = &camera.settings;
    // the light's passes are sized by the settings: refuse what the gather would refuse
    if let Err(e) = settings.validate() {
        let message = format!("quadray indirect light: the settings are refused: {e}");
        if warned.as_ref() != Some(&message) {
            warn!("{message}");
            *warned = Some(message);
        }
        state.0 = None;
        return;
    }
    let work = &mut *work;
    let cells = if settings.indirect_shadows {
        settings.shadow_grid
    } else {
        0
    };
    let levels = settings.shadow_grid_levels;
    let mut made = false;
    // taken every frame, as the changes
    let textures_changed = std::mem::take(&mut mirror.textures_changed);
    let l = state.0.get_or_insert_with(|| {
        made = true;
        LightPasses {
            textures: upload_textures(device, &queue, &mirror, work),
            views: Vec::new(),
            maps_generation: 0,
            rsm_size: 0,
            rsm_layout: settings.gbuffer_layout,
            max_lights: settings.max_lights,
            scene: SceneBuffer::new(device, &queue, &mirror, work),
            source: camera.rsm_source,
            bounds: mirror.bounds_of(camera.rsm_source),
            lights: Vec::new(),
            light_views: Vec::new(),
            stale: true,
            occupancy: None,
            occupancy_cells: (0, 0),
            occupancy_generation: 0,
        }
    });
    let cluster = settings.cluster;
    for view in &mut l.views {
        if view.quadtree.cluster() != cluster {
            view.quadtree.set_cluster(&queue, cluster);
            l.stale = true;
        }
    }
    let mut grid_current = l.occupancy_cells == (cells, levels) && !made;
    match &changes {
        SceneChanges::None => {}
        SceneChanges::All => {
            if !made {
                l.scene = SceneBuffer::new(device, &queue, &mirror, work);
            }
            grid_current = false;
        }
        SceneChanges::Some(changed) => {
            if !made && !l.scene.update(&queue, &mirror, changed, work) {
                l.scene = SceneBuffer::new(device, &queue, &mirror, work);
            }
            if let Some(grid) = l.occupancy.as_mut().filter(|_| grid_current) {
                grid_current = grid.update(&mirror, changed, work);
                l.occupancy_generation += 1;
            }
        }
    }
    if textures_changed && !made {
        // (every layer's side at most quadray's MAX_SIDE, wgpu's default limit)
        l.textures = upload_textures(device, &queue, &mirror, work);
        for view in &mut l.views {
            view.rsm.set_textures(&l.textures);
        }
        l.stale = true;
    }
    if l.source != camera.rsm_source {
        l.source = camera.rsm_source;
        l.stale = true;
    }
    // the triangles' RSMs are drawn anew when the scene changed, the meshes' when their draws
    // do (`prepare_mesh_rsm`); the maps' projections follow the scene's bounds
    let meshes = l.source == RsmSource::Meshes;
    let changed = !matches!(changes, SceneChanges::None);
    l.stale |= changed && !meshes;
    if changed || meshes {
        let bounds = mirror.bounds_of(l.source);
        if bounds != l.bounds {
            l.bounds = bounds;
            l.lights.clear();
        }
    }
    if !grid_current {
        l.occupancy = (cells > 0).then(|| {
            work.grids_made += 1;
            SceneGrid::new(&mirror, cells, levels)
        });
        l.occupancy_cells = (cells, levels);
        l.occupancy_generation += 1;
    }
    let lights: Vec<Light> = mirror
        .lights
        .iter()
        .take(settings.max_lights as usize)
        .copied()
        .collect();
    let resized = l.rsm_size != settings.rsm_size || l.rsm_layout != settings.gbuffer_layout;
    if l.lights != lights || resized {
        l.light_views = lights
            .iter()
            .flat_map(|light| LightView::of_light(light, l.bounds))
            .collect();
        if l.views.len() != l.light_views.len() || resized {
            l.make_views(device, &queue, settings, l.light_views.len());
        }
        for (view, light_view) in l.views.iter().zip(&l.light_views) {
            view.rsm.set_light(&queue, light_view);
        }
        l.lights = lights;
        l.stale = true;
    }
    l.max_lights = settings.max_lights;
}

/// The scene's base colour textures on the GPU.
fn upload_textures(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mirror: &SceneMirror,
    work: &mut SceneWork,
) -> TextureArray {
    work.textures_uploaded += 1;
    TextureArray::new(device, queue, &mirror.textures)
}
