//! The render world's side: per light view, quadray's RSM and light quadtree; per camera, the
//! G-buffer translated from Bevy's, quadray's gather, the additive composite into the view and,
//! on request, the cut over the RSM drawn into the tone-mapped picture.

use super::scene::{IndirectLight, IndirectLightScene};
use bevy::asset::uuid_handle;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::core_pipeline::tonemapping::tonemapping;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    texture_2d, texture_depth_2d, texture_storage_2d, uniform_buffer_sized,
};
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, CachedComputePipelineId,
    ComputePipelineDescriptor, PipelineCache, ShaderStages, StorageTextureAccess, TextureFormat,
    TextureSampleType, TextureViewId,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::sync_world::MainEntity;
use bevy::render::view::{ExtractedView, ViewTarget};
use bevy::render::{Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::Shader;
use quadray_indirect::scene::Light;
use quadray_indirect::shadows::occupancy::OccupancyGrid;
use quadray_indirect::{FLOAT_FORMAT, GBufferViews, Gather, LightQuadtree, RsmPass, Settings};
use quadray_indirect::{LightView, ViewMaps, scene::bounds_of};
use std::num::NonZero;
use std::sync::{Mutex, PoisonError};

/// Bevy's packed G-buffer translated into quadray's (`gbuffer.wgsl`).
const GBUFFER_SHADER: Handle<Shader> = uuid_handle!("5c0f3f62-8d0c-4d57-9a43-6f1f4c1f9d11");
const COUNTS_WGSL: &str = include_str!("counts.wgsl");
/// The G-buffer translation's uniform: world_from_clip, the eye (xyz), the size (two u32).
const VIEW_UNIFORM_BYTES: u64 = 64 + 16 + 16;

pub(super) fn build(app: &mut App) {
    let _ = app.world_mut().resource_mut::<Assets<Shader>>().insert(
        &GBUFFER_SHADER,
        Shader::from_wgsl(include_str!("gbuffer.wgsl"), "quadray/gi_gbuffer.wgsl"),
    );
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        return;
    };
    render_app
        .init_resource::<LightState>()
        .add_systems(RenderStartup, init_pipelines)
        .add_systems(
            Render,
            (drop_unused_views, prepare_light, prepare_views)
                .chain()
                .in_set(RenderSystems::PrepareBindGroups),
        )
        .add_systems(
            Core3d,
            (
                indirect_light_pass
                    .after(main_opaque_pass_3d)
                    .before(main_transparent_pass_3d)
                    .in_set(Core3dSystems::MainPass),
                cut_view_pass
                    .after(tonemapping)
                    .in_set(Core3dSystems::PostProcess),
            ),
        );
}

/// The composite's and the cut view's shader: quadray's engine-neutral modules, then this
/// plugin's bindings and entry points.
fn composite_source() -> String {
    use quadray_indirect::wgsl;
    [
        wgsl::prelude().as_str(),
        wgsl::NODE,
        wgsl::KERNEL,
        wgsl::CUT_RULE,
        wgsl::CUT_VIEW,
        include_str!("composite.wgsl"),
    ]
    .concat()
}

#[derive(Resource)]
struct Pipelines {
    gbuffer_layout: BindGroupLayoutDescriptor,
    gbuffer: CachedComputePipelineId,
    composite_layout: wgpu::BindGroupLayout,
    cut_view_layout: wgpu::BindGroupLayout,
    composite_module: wgpu::ShaderModule,
    /// By the view target's format.
    composite: HashMap<TextureFormat, wgpu::RenderPipeline>,
    cut_view: HashMap<TextureFormat, wgpu::RenderPipeline>,
    /// The work counts' means, for Bevy's diagnostics.
    counts: wgpu::ComputePipeline,
}

fn init_pipelines(
    mut commands: Commands,
    device: Res<RenderDevice>,
    pipeline_cache: Res<PipelineCache>,
) {
    let gbuffer_layout = BindGroupLayoutDescriptor::new(
        "quadray gi gbuffer",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                texture_2d(TextureSampleType::Uint),
                texture_depth_2d(),
                uniform_buffer_sized(false, NonZero::new(VIEW_UNIFORM_BYTES)),
                texture_storage_2d(FLOAT_FORMAT, StorageTextureAccess::WriteOnly),
                texture_storage_2d(FLOAT_FORMAT, StorageTextureAccess::WriteOnly),
                texture_storage_2d(FLOAT_FORMAT, StorageTextureAccess::WriteOnly),
            ),
        ),
    );
    let gbuffer = pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("quadray gi gbuffer".into()),
        layout: vec![gbuffer_layout.clone()],
        shader: GBUFFER_SHADER,
        entry_point: Some("translate".into()),
        ..default()
    });
    let device = device.wgpu_device();
    let fragment_buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let storage = wgpu::BufferBindingType::Storage { read_only: true };
    let uniform = wgpu::BufferBindingType::Uniform;
    let composite_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("quadray gi composite"),
        entries: &[fragment_buffer(0, storage), fragment_buffer(1, uniform)],
    });
    let cut_view_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("quadray gi cut view"),
        entries: &[
            fragment_buffer(2, uniform),
            fragment_buffer(3, storage),
            fragment_buffer(4, uniform),
        ],
    });
    let composite_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("quadray gi composite"),
        source: wgpu::ShaderSource::Wgsl(composite_source().into()),
    });
    let counts_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("quadray gi counts"),
        source: wgpu::ShaderSource::Wgsl(COUNTS_WGSL.into()),
    });
    let counts = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("quadray gi counts"),
        layout: None,
        module: &counts_module,
        entry_point: Some("mean_counts"),
        compilation_options: Default::default(),
        cache: None,
    });
    commands.insert_resource(Pipelines {
        gbuffer_layout,
        gbuffer,
        composite_layout,
        cut_view_layout,
        composite_module,
        composite: HashMap::default(),
        cut_view: HashMap::default(),
        counts,
    });
}

/// What a pipeline of the composite's shader draws.
#[derive(Clone, Copy)]
enum Draw {
    /// The indirect light, added.
    Composite,
    /// The cut view, over what is there.
    CutView,
}

/// The composite's shader's pipeline for `draw` into a target of `format` (made once a format).
fn composite_pipeline(
    device: &wgpu::Device,
    pipelines: &mut Pipelines,
    draw: Draw,
    format: TextureFormat,
) -> wgpu::RenderPipeline {
    let Pipelines {
        composite,
        cut_view,
        composite_layout,
        cut_view_layout,
        composite_module: module,
        ..
    } = pipelines;
    let (cache, layout, entry_point, blend) = match draw {
        Draw::Composite => {
            let add = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let keep = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let blend = wgpu::BlendState {
                color: add,
                alpha: keep,
            };
            (composite, &*composite_layout, "add_indirect", Some(blend))
        }
        Draw::CutView => (cut_view, &*cut_view_layout, "draw_cut_view", None),
    };
    if let Some(pipeline) = cache.get(&format) {
        return pipeline.clone();
    }
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry_point),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entry_point),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry_point),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
    cache.insert(format, pipeline.clone());
    pipeline
}

/// The lights' side, shared by every camera: an RSM over the scene's triangles and the light
/// quadtree built over it per light view.
#[derive(Resource, Default)]
struct LightState(Option<LightPasses>);

/// One light view's RSM and quadtree.
struct ViewMapsPasses {
    rsm: RsmPass,
    quadtree: LightQuadtree,
}

struct LightPasses {
    /// One a light view, in the order of `lights`' views; the first's cut is the one the cut
    /// view and the diagnostics show.
    views: Vec<ViewMapsPasses>,
    /// Counts the times `views` was made anew: a camera's gather reads the maps of one.
    maps_generation: u64,
    rsm_size: u32,
    /// The first camera's [`Settings::max_lights`], which `lights` was taken with.
    max_lights: u32,
    vertices: Option<(wgpu::Buffer, u32)>,
    generation: u64,
    lights: Vec<Light>,
    /// The lights' RSM views, one a `views` entry.
    light_views: Vec<LightView>,
    /// The RSMs, pyramids and cuts are to be recorded again (a light or the scene changed).
    stale: bool,
    /// The scene's occupancy grid that indirect shadows walk, at the first camera's
    /// [`Settings::shadow_grid`] cells and [`Settings::shadow_grid_levels`] (none without
    /// indirect shadows, or at 0 cells: the gathers march the depth maps), and how many times
    /// it was made.
    occupancy: Option<OccupancyGrid>,
    occupancy_cells: (u32, u32),
    occupancy_generation: u64,
}

impl LightPasses {
    fn maps(&self) -> Vec<ViewMaps<'_>> {
        self.views
            .iter()
            .map(|v| ViewMaps {
                rsm: v.rsm.views(),
                quadtree: &v.quadtree,
            })
            .collect()
    }

    /// The passes of `count` light views at `settings`.
    fn make_views(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: &Settings,
        count: usize,
    ) {
        self.views = (0..count)
            .map(|_| {
                let rsm = RsmPass::new(device, settings.rsm_size);
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
        self.maps_generation += 1;
        self.stale = true;
    }
}

/// A render-world camera whose passes [`drop_unused_views`] frees.
type Unused = (
    With<ViewPasses>,
    Or<(Without<IndirectLight>, Without<ExtractedCamera>)>,
);

/// Frees the passes of a camera that lost [`IndirectLight`] or is no longer rendered (inactive,
/// or its target at zero size): Bevy keeps a render-world camera from frame to frame, and its
/// passes with it. A despawned camera's go with its render-world entity.
fn drop_unused_views(mut commands: Commands, unused: Query<Entity, Unused>) {
    for entity in &unused {
        commands.entity(entity).remove::<ViewPasses>();
    }
}

fn prepare_light(
    scene: Option<Res<IndirectLightScene>>,
    cameras: Query<&IndirectLight, With<ExtractedCamera>>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut state: ResMut<LightState>,
    mut warned: Local<Option<String>>,
) {
    let Some(camera) = cameras.iter().next() else {
        // no camera gathers: the lights' maps are freed, and made anew for the next one
        state.0 = None;
        return;
    };
    let Some(scene) = scene else { return };
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
    let l = state.0.get_or_insert_with(|| LightPasses {
        views: Vec::new(),
        maps_generation: 0,
        rsm_size: 0,
        max_lights: settings.max_lights,
        vertices: None,
        generation: u64::MAX,
        lights: Vec::new(),
        light_views: Vec::new(),
        stale: true,
        occupancy: None,
        occupancy_cells: (0, 0),
        occupancy_generation: 0,
    });
    let cluster = settings.cluster;
    for view in &mut l.views {
        if view.quadtree.cluster() != cluster {
            view.quadtree.set_cluster(&queue, cluster);
            l.stale = true;
        }
    }
    let cells = if settings.indirect_shadows {
        settings.shadow_grid
    } else {
        0
    };
    let levels = settings.shadow_grid_levels;
    if l.generation != scene.generation || l.occupancy_cells != (cells, levels) {
        // (rebuilt with every change of the scene: a few milliseconds for thousands of
        // triangles at 64 cells)
        l.occupancy =
            (cells > 0).then(|| OccupancyGrid::with_levels(&scene.triangles, cells, levels));
        l.occupancy_cells = (cells, levels);
        l.occupancy_generation += 1;
    }
    if l.generation != scene.generation {
        l.generation = scene.generation;
        l.vertices = (!scene.triangles.is_empty()).then(|| {
            use wgpu::util::DeviceExt;
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("quadray gi triangles"),
                contents: bytemuck::cast_slice(scene.triangles.as_slice()),
                usage: wgpu::BufferUsages::VERTEX,
            });
            (buffer, scene.triangles.len() as u32 * 3)
        });
        // the maps' projections follow the scene's bounds
        l.lights.clear();
    }
    let lights: Vec<Light> = scene
        .lights
        .iter()
        .take(settings.max_lights as usize)
        .copied()
        .collect();
    if l.lights != lights || l.rsm_size != settings.rsm_size {
        let bounds = bounds_of(
            scene
                .triangles
                .iter()
                .flatten()
                .map(|v| glam::Vec3::from(v.position)),
        );
        l.light_views = lights
            .iter()
            .flat_map(|light| LightView::of_light(light, bounds))
            .collect();
        if l.views.len() != l.light_views.len() || l.rsm_size != settings.rsm_size {
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

/// In Bevy's render world, on a camera that gathers: its side of the plugin, quadray's G-buffer
/// (translated from Bevy's), its gather, composite and cut view. Made for the camera's size and
/// format, and removed with its [`IndirectLight`] (or when the camera is not rendered).
#[derive(Component)]
pub struct ViewPasses {
    settings: Settings,
    /// The light's maps the gather reads ([`LightPasses::maps_generation`]).
    maps_generation: u64,
    /// The occupancy grid the gather walks ([`LightPasses::occupancy_generation`]).
    occupancy_generation: u64,
    format: TextureFormat,
    /// Position, normal, albedo.
    gbuffer: [wgpu::TextureView; 3],
    view_uniform: wgpu::Buffer,
    gather: Gather,
    composite_uniform: wgpu::Buffer,
    composite_group: wgpu::BindGroup,
    composite: wgpu::RenderPipeline,
    /// The cut view's magnification (a `u32`).
    cut_view_uniform: wgpu::Buffer,
    cut_view_group: wgpu::BindGroup,
    cut_view: wgpu::RenderPipeline,
    /// The gather's counts as means per shaded pixel: VPL evaluations, texel fetches.
    means: wgpu::Buffer,
    means_group: wgpu::BindGroup,
    /// The G-buffer translation's bind group, by the ids of Bevy's deferred and depth views it
    /// reads.
    gbuffer_group: Mutex<Option<([TextureViewId; 2], wgpu::BindGroup)>>,
}

impl ViewPasses {
    fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: Settings,
        light: &LightPasses,
        pipelines: &mut Pipelines,
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
        let views = GBufferViews {
            position: &gbuffer[0],
            normal: &gbuffer[1],
            albedo: &gbuffer[2],
        };
        let mut gather = Gather::new(device, &settings, &light.maps(), views)?;
        if let Some(grid) = &light.occupancy {
            gather.set_occupancy(device, queue, grid, views);
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
            layout: &pipelines.cut_view_layout,
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
            layout: &pipelines.composite_layout,
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
            layout: &pipelines.counts.get_bind_group_layout(0),
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
            composite: composite_pipeline(device, pipelines, Draw::Composite, format),
            cut_view_uniform,
            cut_view_group,
            cut_view: composite_pipeline(device, pipelines, Draw::CutView, format),
            means,
            means_group,
            gbuffer_group: Mutex::new(None),
        })
    }
}

/// What [`prepare_views`] reads of each camera with [`IndirectLight`].
type Views<'w, 's> = Query<
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

fn prepare_views(
    mut commands: Commands,
    mut views: Views,
    light: Res<LightState>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    mut pipelines: ResMut<Pipelines>,
    mut warned: Local<HashMap<Entity, String>>,
) {
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
            || settings.max_lights != l.max_lights
            || l.views
                .iter()
                .any(|v| v.quadtree.cluster() != settings.cluster)
        {
            warn(
                "its RSM size, light count or cluster settings differ from the first \
                 IndirectLight camera's, which the lights' quadtrees are built with: give every \
                 camera the same; no indirect light is added"
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
            None => match ViewPasses::new(device, &queue, settings, l, &mut pipelines, format) {
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
            let views = GBufferViews {
                position,
                normal,
                albedo,
            };
            if let Some(grid) = &l.occupancy {
                passes.gather.set_occupancy(device, &queue, grid, views);
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
fn cut_view_zoom(settings: &Settings) -> u32 {
    let shorter = settings.size.width.min(settings.size.height);
    (shorter / 2 / settings.rsm_size).max(1)
}

/// Records, for one camera: the light's RSM, pyramid and cut when they are stale, the G-buffer
/// translation, the gather, the debug copy and the composite into the view.
fn indirect_light_pass(
    view: ViewQuery<(
        &ViewPasses,
        &ViewTarget,
        &ViewPrepassTextures,
        &IndirectLight,
        &MainEntity,
    )>,
    mut light: ResMut<LightState>,
    pipelines: Res<Pipelines>,
    pipeline_cache: Res<PipelineCache>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    mut ctx: RenderContext,
) {
    let (passes, target, prepass, gi, camera) = view.into_inner();
    let Some(l) = light.0.as_mut().filter(|_| gi.enabled) else {
        return;
    };
    let (Some((vertices, vertex_count)), Some(_)) = (&l.vertices, l.views.first()) else {
        return;
    };
    let Some(translate) = pipeline_cache.get_compute_pipeline(pipelines.gbuffer) else {
        return;
    };
    let (Some(deferred), Some(depth)) = (prepass.deferred_view(), prepass.depth_view()) else {
        return;
    };
    // made again only when Bevy's prepass textures are (a resize)
    let key = [deferred.id(), depth.id()];
    let mut cached = lock(&passes.gbuffer_group);
    let group = match &*cached {
        Some((k, group)) if *k == key => group.clone(),
        _ => {
            let layout = pipeline_cache.get_bind_group_layout(&pipelines.gbuffer_layout);
            let resources = [
                wgpu::BindingResource::TextureView(deferred),
                wgpu::BindingResource::TextureView(depth),
                passes.view_uniform.as_entire_binding(),
                wgpu::BindingResource::TextureView(&passes.gbuffer[0]),
                wgpu::BindingResource::TextureView(&passes.gbuffer[1]),
                wgpu::BindingResource::TextureView(&passes.gbuffer[2]),
            ];
            let group =
                ctx.render_device()
                    .wgpu_device()
                    .create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("quadray gi gbuffer"),
                        layout: &layout,
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
    };
    drop(cached);
    // Bevy's diagnostics (with its RenderDiagnosticsPlugin), under the camera's own path: GPU
    // time of the light's passes, the gather and the composite, the gather's work per shaded
    // pixel; and the lights' cut's size, shared
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let encoder = ctx.command_encoder();
    let camera_path = camera_diagnostics(camera.id());
    let whole = diagnostics.time_span(encoder, camera_path.clone());
    if l.stale {
        let span = diagnostics.time_span(encoder, "light");
        for view in &l.views {
            view.rsm
                .record(encoder, vertices.slice(..), *vertex_count, None);
            view.quadtree.record_build(encoder, None);
            view.quadtree.record_cut(encoder, None);
        }
        l.stale = false;
        span.end(encoder);
    }
    // gathered every frame: Bevy's G-buffer can change while the camera and the light stand still
    // (a mesh uploaded or a pipeline compiled frames after the scene's triangles arrived)
    let span = diagnostics.time_span(encoder, "gather");
    let size = passes.settings.size;
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("quadray gi gbuffer"),
            timestamp_writes: None,
        });
        pass.set_pipeline(translate);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(size.width.div_ceil(8), size.height.div_ceil(8), 1);
    }
    let quadtrees: Vec<&LightQuadtree> = l.views.iter().map(|v| &v.quadtree).collect();
    passes
        .gather
        .record_indirect(encoder, gi.method, &quadtrees, None);
    span.end(encoder);
    if diagnostics.is_some() {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("quadray gi counts"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipelines.counts);
        pass.set_bind_group(0, &passes.means_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    if let Some(debug) = gi.debug_indirect.as_ref().and_then(|h| buffers.get(h)) {
        let indirect = passes.gather.indirect();
        if debug.buffer.size() >= indirect.size() {
            encoder.copy_buffer_to_buffer(indirect, 0, &debug.buffer, 0, indirect.size());
        }
    }
    let span = diagnostics.time_span(encoder, "composite");
    draw_over(
        encoder,
        "quadray gi composite",
        target.main_texture_view(),
        (&passes.composite, &passes.composite_group),
        None,
    );
    span.end(encoder);
    whole.end(encoder);
    if diagnostics.is_some() {
        let cut = l.views[0].quadtree.cut_count().slice(0..4);
        diagnostics.record_u32(encoder, &cut, "quadray_gi/cut_clusters");
        let evaluations = passes.means.slice(0..4);
        let path = format!("{camera_path}/vpl_evaluations_per_pixel");
        diagnostics.record_f32(encoder, &evaluations, path);
        let fetches = passes.means.slice(4..8);
        let path = format!("{camera_path}/texel_fetches_per_pixel");
        diagnostics.record_f32(encoder, &fetches, path);
    }
}

/// The diagnostics' path of `camera`'s passes and counts, below Bevy's `render/`.
pub(super) fn camera_diagnostics(camera: Entity) -> String {
    format!("quadray_gi/camera_{camera}")
}

/// The value behind `mutex`, also after a panic elsewhere (every value here is whole).
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Draws the cut over the RSM into the tone-mapped picture's top-left corner, for a camera whose
/// [`IndirectLight::cut_view`] is on (and whose bounce is: the cut is built with it).
fn cut_view_pass(
    view: ViewQuery<(&ViewPasses, &ViewTarget, &IndirectLight)>,
    light: Res<LightState>,
    mut ctx: RenderContext,
) {
    let (passes, target, gi) = view.into_inner();
    if !(gi.cut_view && gi.enabled) || light.0.as_ref().is_none_or(|l| l.views.is_empty()) {
        return;
    }
    let size = passes.settings.size;
    let side = passes.settings.rsm_size * cut_view_zoom(&passes.settings);
    draw_over(
        ctx.command_encoder(),
        "quadray gi cut view",
        target.main_texture_view(),
        (&passes.cut_view, &passes.cut_view_group),
        Some((side.min(size.width), side.min(size.height))),
    );
}

/// Draws a full-screen triangle of the composite's shader over what `view` holds, within the
/// top-left `scissor` (width, height) when one is given.
fn draw_over(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    view: &wgpu::TextureView,
    (pipeline, group): (&wgpu::RenderPipeline, &wgpu::BindGroup),
    scissor: Option<(u32, u32)>,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    });
    if let Some((width, height)) = scissor {
        pass.set_scissor_rect(0, 0, width, height);
    }
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.draw(0..3, 0..1);
}
