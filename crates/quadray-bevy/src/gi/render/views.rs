//! Prepare, each camera's side: its passes (quadray's G-buffer translated from Bevy's, the gather,
//! the composite and the cut view), made for its size and format and freed with it.

use super::light::{LightPasses, LightState};
use super::pipelines::{Draw, Pipelines, VIEW_UNIFORM_BYTES};
use crate::gi::cpu_time::CpuTimes;
use crate::gi::scene::IndirectLight;
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::render_resource::{
    CachedRenderPipelineId, PipelineCache, SpecializedRenderPipelines, TextureFormat, TextureView,
    TextureViewId,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::view::{ExtractedView, ViewTarget};
use quadray_indirect::{FLOAT_FORMAT, GBufferViews, Gather, Settings};
use std::sync::{Mutex, PoisonError};

/// A render-world camera whose passes [`drop_unused_views`] frees.
pub(super) type Unused = (
    With<ViewPasses>,
    Or<(Without<IndirectLight>, Without<ExtractedCamera>)>,
);

/// Frees the passes of a camera that lost [`IndirectLight`] or is no longer rendered (inactive,
/// or its target at zero size): Bevy keeps a render-world camera from frame to frame, and its
/// passes with it. A despawned camera's go with its render-world entity.
pub(super) fn drop_unused_views(
    mut commands: Commands,
    unused: Query<Entity, Unused>,
    times: Res<CpuTimes>,
) {
    let _span = times.render();
    for entity in &unused {
        commands.entity(entity).remove::<ViewPasses>();
    }
}

/// In Bevy's render world, on a camera that gathers: its side of the plugin, quadray's G-buffer
/// (translated from Bevy's), its gather, composite and cut view. Made for the camera's size and
/// format, and removed with its [`IndirectLight`] (or when the camera is not rendered).
#[derive(Component)]
pub struct ViewPasses {
    pub(super) settings: Settings,
    /// The light's maps the gather reads ([`LightPasses::maps_generation`]).
    pub(super) maps_generation: u64,
    /// The occupancy grid the gather walks ([`LightPasses::occupancy_generation`]).
    pub(super) occupancy_generation: u64,
    pub(super) format: TextureFormat,
    /// Position, normal, albedo.
    pub(super) gbuffer: [wgpu::TextureView; 3],
    pub(super) view_uniform: wgpu::Buffer,
    pub(super) gather: Gather,
    pub(super) composite_uniform: wgpu::Buffer,
    pub(super) composite_group: wgpu::BindGroup,
    pub(super) composite: CachedRenderPipelineId,
    /// The cut view's magnification (a `u32`).
    pub(super) cut_view_uniform: wgpu::Buffer,
    pub(super) cut_view_group: wgpu::BindGroup,
    pub(super) cut_view: CachedRenderPipelineId,
    /// The gather's counts as means per shaded pixel: VPL evaluations, texel fetches.
    pub(super) means: wgpu::Buffer,
    pub(super) means_group: wgpu::BindGroup,
    /// The G-buffer translation's bind group, by the ids of Bevy's deferred and depth views it
    /// reads.
    pub(super) gbuffer_group: Mutex<Option<([TextureViewId; 2], wgpu::BindGroup)>>,
}

/// What a camera's passes are made with: the plugin's pipelines, Bevy's pipeline cache and the
/// composite's specialisations.
type ViewPipelines<'a> = (
    &'a Pipelines,
    &'a PipelineCache,
    &'a mut SpecializedRenderPipelines<Pipelines>,
);

impl ViewPasses {
    pub(super) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: Settings,
        light: &LightPasses,
        (pipelines, cache, specialized): ViewPipelines,
        format: TextureFormat,
    ) -> Result<Self, quadray_indirect::IndirectError> {
        let size = wgpu::Extent3d {
            width: settings.size.width,
            height: settings.size.height,
            depth_or_array_layers: 1,
        };
        let gbuffer = ["position", "normal", "albedo"].map(|label| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: FLOAT_FORMAT,
                    usage: wgpu::TextureUsages::STORAGE_BINDING
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        });
        // the wide layout: the translation writes storage textures, which cost no raster output
        let views = GBufferViews::Wide {
            position: &gbuffer[0],
            normal: &gbuffer[1],
            albedo: &gbuffer[2],
        };
        let mut gather = Gather::new(device, &settings, &light.maps(), views)?;
        if let Some(grid) = &light.occupancy {
            gather.set_occupancy(device, queue, &grid.grid, views);
        }
        let uniform = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let view_uniform = uniform("quadray gi view", VIEW_UNIFORM_BYTES);
        let composite_uniform = uniform("quadray gi composite", 16);
        let cut_view_uniform = uniform("quadray gi cut view", 16);
        let quadtree = &light.views[0].quadtree;
        let cut_view_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("quadray gi cut view"),
            layout: &cache.get_bind_group_layout(&pipelines.cut_view_layout),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: quadtree.params().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: quadtree.nodes().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: cut_view_uniform.as_entire_binding(),
                },
            ],
        });
        let composite_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("quadray gi composite"),
            layout: &cache.get_bind_group_layout(&pipelines.composite_layout),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: gather.indirect().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: composite_uniform.as_entire_binding(),
                },
            ],
        });
        let means = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("quadray gi count means"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let means_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("quadray gi counts"),
            layout: &cache.get_bind_group_layout(&pipelines.counts_layout),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: gather.counts().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&gbuffer[0]),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: means.as_entire_binding(),
                },
            ],
        });
        Ok(Self {
            settings,
            maps_generation: light.maps_generation,
            occupancy_generation: light.occupancy_generation,
            format,
            gbuffer,
            view_uniform,
            gather,
            composite_uniform,
            composite_group,
            composite: specialized.specialize(cache, pipelines, (Draw::Composite, format)),
            cut_view_uniform,
            cut_view_group,
            cut_view: specialized.specialize(cache, pipelines, (Draw::CutView, format)),
            means,
            means_group,
            gbuffer_group: Mutex::new(None),
        })
    }
}

impl ViewPasses {
    /// The G-buffer translation's bind group over Bevy's `deferred` and `depth` views, made
    /// again only when Bevy makes those anew (a resize).
    pub(super) fn gbuffer_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        deferred: &TextureView,
        depth: &TextureView,
    ) -> wgpu::BindGroup {
        let key = [deferred.id(), depth.id()];
        let mut cached = lock(&self.gbuffer_group);
        if let Some((k, group)) = &*cached
            && *k == key
        {
            return group.clone();
        }
        let resources = [
            wgpu::BindingResource::TextureView(deferred),
            wgpu::BindingResource::TextureView(depth),
            self.view_uniform.as_entire_binding(),
            wgpu::BindingResource::TextureView(&self.gbuffer[0]),
            wgpu::BindingResource::TextureView(&self.gbuffer[1]),
            wgpu::BindingResource::TextureView(&self.gbuffer[2]),
        ];
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("quadray gi gbuffer"),
            layout,
            entries: &resources
                .into_iter()
                .enumerate()
                .map(|(i, resource)| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource,
                })
                .collect::<Vec<_>>(),
        });
        *cached = Some((key, group.clone()));
        group
    }
}

/// The value behind `mutex`, also after a panic elsewhere (every value here is whole).
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

/// What [`prepare_views`] reads of each camera with [`IndirectLight`].
pub(super) type Views<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        &'static IndirectLight,
        &'static ExtractedView,
        &'static ExtractedCamera,
        &'static ViewTarget,
        Option<&'static ViewPrepassTextures>,
        Option<&'static mut ViewPasses>,
    ),
>;

pub(super) fn prepare_views(
    mut commands: Commands,
    mut views: Views,
    light: Res<LightState>,
    (device, queue): (Res<RenderDevice>, Res<RenderQueue>),
    (pipelines, pipeline_cache, mut specialized): (
        Res<Pipelines>,
        Res<PipelineCache>,
        ResMut<SpecializedRenderPipelines<Pipelines>>,
    ),
    mut warned: Local<HashMap<Entity, String>>,
    times: Res<CpuTimes>,
) {
    let _span = times.render();
    // (a camera that comes back after it went away warns again)
    warned.retain(|entity, _| views.contains(*entity));
    let Some(l) = light.0.as_ref() else { return };
    let device = device.wgpu_device();
    for (entity, gi, view, camera, target, prepass, passes) in &mut views {
        let mut warn = |message: String| {
            if warned.get(&entity) != Some(&message) {
                warn!("quadray indirect light on camera {entity}: {message}");
                warned.insert(entity, message);
            }
        };
        let problem = if prepass.and_then(|p| p.deferred.as_ref()).is_none() {
            Some(
                "the camera has no deferred G-buffer: render its materials deferred \
                 (insert the resource DefaultOpaqueRendererMethod::deferred())",
            )
        } else if !camera.hdr {
            Some(
                "the camera renders without Hdr, so Bevy tone-maps in its lighting shaders and the \
                  bounce would be added after: keep the Hdr component IndirectLight brings",
            )
        } else if target.sampled_main_texture().is_some() {
            Some(
                "MSAA is on, and Bevy's deferred G-buffer needs it off: add Msaa::Off to the camera",
            )
        } else {
            None
        };
        if let Some(problem) = problem {
            warn(format!("{problem}; no indirect light is added"));
            commands.entity(entity).remove::<ViewPasses>();
            continue;
        }
        let Some(size) = camera.physical_viewport_size.filter(|s| s.x > 0 && s.y > 0) else {
            continue;
        };
        let mut settings = gi.settings.clone();
        settings.size = quadray_indirect::Size {
            width: size.x,
            height: size.y,
        };
        if let Err(e) = settings.validate() {
            warn(format!(
                "its settings are refused: {e}; no indirect light is added"
            ));
            commands.entity(entity).remove::<ViewPasses>();
            continue;
        }
        // one set of light quadtrees serves every camera: made by the first camera's settings
        if settings.rsm_size != l.rsm_size
            || settings.gbuffer_layout != l.rsm_layout
            || settings.max_lights != l.max_lights
            || l.views
                .iter()
                .any(|v| v.quadtree.cluster() != settings.cluster)
        {
            warn(
                "its RSM size, G-buffer layout, light count or cluster settings differ from the \
                 first IndirectLight camera's, which the lights' quadtrees are built with: give \
                 every camera the same; no indirect light is added"
                    .into(),
            );
            commands.entity(entity).remove::<ViewPasses>();
            continue;
        }
        if l.views.is_empty() {
            // no light to gather from (a warning said why)
            commands.entity(entity).remove::<ViewPasses>();
            continue;
        }
        let format = target.main_texture_format();
        let current = |p: &Mut<ViewPasses>| {
            p.settings == settings && p.format == format && p.maps_generation == l.maps_generation
        };
        let mut made = None;
        let passes = match passes.filter(current) {
            Some(passes) => passes.into_inner(),
            None => match ViewPasses::new(
                device,
                &queue,
                settings,
                l,
                (&pipelines, &pipeline_cache, &mut specialized),
                format,
            ) {
                Ok(p) => made.insert(p),
                Err(e) => {
                    warn(format!("{e}; no indirect light is added"));
                    commands.entity(entity).remove::<ViewPasses>();
                    continue;
                }
            },
        };
        if passes.occupancy_generation != l.occupancy_generation {
            let [position, normal, albedo] = &passes.gbuffer;
            let views = GBufferViews::Wide {
                position,
                normal,
                albedo,
            };
            if let Some(grid) = &l.occupancy {
                passes
                    .gather
                    .set_occupancy(device, &queue, &grid.grid, views);
            }
            passes.occupancy_generation = l.occupancy_generation;
        }
        let clip_from_world = view
            .clip_from_world
            .unwrap_or_else(|| view.clip_from_view * view.world_from_view.to_matrix().inverse());
        let eye = view.world_from_view.translation();
        passes.gather.set_camera(&queue, clip_from_world, eye);
        passes.gather.set_lights(&queue, &l.light_views, gi.r_min);
        let mut uniform: Vec<f32> = clip_from_world.inverse().to_cols_array().to_vec();
        uniform.extend([eye.x, eye.y, eye.z, 1.0]);
        uniform.extend([f32::from_bits(size.x), f32::from_bits(size.y), 0.0, 0.0]);
        queue.write_buffer(&passes.view_uniform, 0, bytemuck::cast_slice(&uniform));
        let composite = [size.x, camera.exposure.to_bits(), 0, 0];
        queue.write_buffer(
            &passes.composite_uniform,
            0,
            bytemuck::cast_slice(&composite),
        );
        let zoom = [cut_view_zoom(&passes.settings), 0, 0, 0];
        queue.write_buffer(&passes.cut_view_uniform, 0, bytemuck::cast_slice(&zoom));
        // inserted once written: new passes record in this frame's pass already, and unwritten
        // they would add no light (a frame without the bounce)
        if let Some(made) = made {
            commands.entity(entity).insert(made);
        }
    }
}

/// The cut view's magnification: the RSM at up to half the picture's shorter side, at least
/// one pixel a texel.
pub(super) fn cut_view_zoom(settings: &Settings) -> u32 {
    let shorter = settings.size.width.min(settings.size.height);
    (shorter / 2 / settings.rsm_size).max(1)
}
