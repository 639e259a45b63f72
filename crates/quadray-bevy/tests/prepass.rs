//! The material in Bevy's prepasses, headless on lavapipe: the depth and the normal that its
//! forward prepass and its deferred G-buffer hold, read back from Bevy's own textures, against
//! quadray's CPU ground truth on each pixel's camera ray and the height field's normal at the
//! truth's hit; and the lit picture drawn wherever the prepass drew (the main pass's traced depth
//! equals the prepass's).

use crate::common::{ANGLES_DEG, MAPS, eye, height_map, unit_plane};
use bevy::asset::uuid_handle;
use bevy::camera::RenderTarget;
use bevy::camera::visibility::RenderLayers;
use bevy::core_pipeline::prepass::{
    DeferredPrepass, DepthPrepass, MotionVectorPrepass, NormalPrepass, ViewPrepassTextures,
};
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::material::OpaqueRendererMethod;
use bevy::pbr::DefaultOpaqueRendererMethod;
use bevy::prelude::*;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_sized, texture_2d, texture_depth_2d,
};
use bevy::render::render_resource::{
    BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, BufferUsages,
    CachedComputePipelineId, ComputePipelineDescriptor, PipelineCache, ShaderStages, TextureFormat,
    TextureSampleType, TextureUsages,
};
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::{RenderApp, RenderStartup};
use bevy::shader::Shader;
use glam::{DVec2, DVec3};
use quadray_bevy::{PyramidDisplacementPlugin, PyramidExtension, PyramidMaterial, depth_map};
use quadray_displace::heightmap::HeightMap;
use quadray_displace::pyramid::Addressing;
use quadray_displace::reference::{Ray, Surface, bilinear_depth, intersect};
use std::sync::{Arc, Mutex};

const SIZE: u32 = 64;
const DEPTH_SCALE: f32 = 0.1;
const CLEAR: Color = Color::srgb(1.0, 0.0, 1.0);
/// Where the depth is right, the normal may be this far off the height field's (degrees): the
/// G-buffer's 24-bit normal, Rgb10a2's and hits a fraction of a texel apart.
const NORMAL_TOLERANCE_DEG: f64 = 2.0;

const PROBE_SHADER: Handle<Shader> = uuid_handle!("0d1c3f9e-5b7a-4f57-8d3e-2a6c1b9e4f10");

/// Per pixel the depth Bevy's prepass holds and the normal of its normal prepass (forward) or of
/// its G-buffer (deferred), Bevy's own unpacking for the latter.
const PROBE_WGSL: &str = r"
#import bevy_pbr::pbr_deferred_types::unpack_24bit_normal
#import bevy_pbr::utils::octahedral_decode

@group(0) @binding(0) var depth: texture_depth_2d;
#ifdef DEFERRED
@group(0) @binding(1) var normals: texture_2d<u32>;
#else
@group(0) @binding(1) var normals: texture_2d<f32>;
#endif
@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn probe(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(depth);
    if any(id.xy >= size) {
        return;
    }
    let p = vec2<i32>(id.xy);
#ifdef DEFERRED
    let n = octahedral_decode(unpack_24bit_normal(textureLoad(normals, p, 0).a));
#else
    let n = textureLoad(normals, p, 0).xyz * 2.0 - 1.0;
#endif
    out[id.y * size.x + id.x] = vec4(textureLoad(depth, p, 0), n);
}
";

#[derive(Clone, Copy, Debug, PartialEq)]
enum Pass {
    /// Forward, with depth, normal and motion-vector prepasses.
    Forward,
    /// Deferred: the G-buffer.
    Deferred,
}

/// A camera whose prepass textures are copied into `out` every frame.
#[derive(Component, Clone, ExtractComponent)]
struct Probe {
    out: Handle<ShaderBuffer>,
    deferred: bool,
}

/// One camera: which map, angle and pass, and what is read back of it.
struct View {
    map: usize,
    angle_deg: f32,
    pass: Pass,
    camera: Entity,
    probe: Handle<ShaderBuffer>,
    picture: Handle<Image>,
    read_probe: Arc<Mutex<Option<Vec<u8>>>>,
    read_picture: Arc<Mutex<Option<Vec<u8>>>>,
}

#[derive(Resource)]
struct Views(Vec<View>);

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<PyramidMaterial>>,
    mut images: ResMut<Assets<Image>>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    let plane = meshes.add(unit_plane());
    let mut views = Vec::new();
    for (map, path) in MAPS.iter().enumerate() {
        let depth = height_map(&assets, path);
        for angle_deg in ANGLES_DEG {
            for pass in [Pass::Forward, Pass::Deferred] {
                let layer = RenderLayers::layer(views.len() + 1);
                let mut extension = PyramidExtension::new(depth.clone(), DEPTH_SCALE);
                extension.lod = false;
                // Deferred through the app's DefaultOpaqueRendererMethod, forward by choice.
                let method = match pass {
                    Pass::Forward => OpaqueRendererMethod::Forward,
                    Pass::Deferred => OpaqueRendererMethod::Auto,
                };
                commands.spawn((
                    Mesh3d(plane.clone()),
                    MeshMaterial3d(materials.add(PyramidMaterial {
                        base: StandardMaterial {
                            opaque_render_method: method,
                            ..default()
                        },
                        extension,
                    })),
                    layer.clone(),
                ));
                let blank: Vec<f32> = (0..SIZE * SIZE)
                    .flat_map(|_| [-1.0, 0.0, 0.0, 0.0])
                    .collect();
                let mut probe = ShaderBuffer::new(bytemuck::cast_slice(&blank), default());
                probe.buffer_description.usage |= BufferUsages::COPY_SRC;
                let probe = buffers.add(probe);
                let mut target =
                    Image::new_target_texture(SIZE, SIZE, TextureFormat::Rgba8UnormSrgb, None);
                target.texture_descriptor.usage |= TextureUsages::COPY_SRC;
                let picture = images.add(target);
                let mut camera = commands.spawn((
                    Camera3d::default(),
                    RenderTarget::Image(picture.clone().into()),
                    Tonemapping::None,
                    Msaa::Off,
                    Transform::from_translation(eye(angle_deg)).looking_at(Vec3::ZERO, Vec3::Y),
                    layer,
                    DepthPrepass,
                    Probe {
                        out: probe.clone(),
                        deferred: pass == Pass::Deferred,
                    },
                ));
                match pass {
                    Pass::Forward => camera.insert((NormalPrepass, MotionVectorPrepass)),
                    Pass::Deferred => camera.insert(DeferredPrepass),
                };
                views.push(View {
                    map,
                    angle_deg,
                    pass,
                    camera: camera.id(),
                    probe,
                    picture,
                    read_probe: Arc::default(),
                    read_picture: Arc::default(),
                });
            }
        }
    }
    commands.insert_resource(Views(views));
}

#[derive(Resource)]
struct ProbePipelines {
    /// Forward, deferred.
    layouts: [BindGroupLayoutDescriptor; 2],
    pipelines: [CachedComputePipelineId; 2],
}

fn init_probe(mut commands: Commands, cache: Res<PipelineCache>) {
    let layout = |normals| {
        BindGroupLayoutDescriptor::new(
            "probe",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    texture_depth_2d(),
                    texture_2d(normals),
                    storage_buffer_sized(false, None),
                ),
            ),
        )
    };
    let layouts = [
        layout(TextureSampleType::Float { filterable: false }),
        layout(TextureSampleType::Uint),
    ];
    let pipelines = [0, 1].map(|i| {
        cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some("probe".into()),
            layout: vec![layouts[i].clone()],
            shader: PROBE_SHADER,
            shader_defs: if i == 1 {
                vec!["DEFERRED".into()]
            } else {
                vec![]
            },
            entry_point: Some("probe".into()),
            ..default()
        })
    });
    commands.insert_resource(ProbePipelines { layouts, pipelines });
}

fn probe_pass(
    view: ViewQuery<(&ViewPrepassTextures, &Probe)>,
    pipelines: Res<ProbePipelines>,
    cache: Res<PipelineCache>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    mut ctx: RenderContext,
) {
    let (prepass, probe) = view.into_inner();
    let i = usize::from(probe.deferred);
    let normals = if probe.deferred {
        prepass.deferred_view()
    } else {
        prepass.normal_view()
    };
    let (Some(pipeline), Some(depth), Some(normals), Some(out)) = (
        cache.get_compute_pipeline(pipelines.pipelines[i]),
        prepass.depth_view(),
        normals,
        buffers.get(&probe.out),
    ) else {
        return;
    };
    let layout = cache.get_bind_group_layout(&pipelines.layouts[i]);
    let group = ctx.render_device().create_bind_group(
        "probe",
        &layout,
        &BindGroupEntries::sequential((depth, normals, out.buffer.as_entire_binding())),
    );
    let mut pass = ctx.command_encoder().begin_compute_pass(&default());
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &group, &[]);
    pass.dispatch_workgroups(SIZE.div_ceil(8), SIZE.div_ceil(8), 1);
}

fn app() -> App {
    crate::common::headless_app(|app| {
        let _ = app
            .world_mut()
            .resource_mut::<Assets<Shader>>()
            .insert(&PROBE_SHADER, Shader::from_wgsl(PROBE_WGSL, "probe.wgsl"));
        app.insert_resource(DefaultOpaqueRendererMethod::deferred())
            .insert_resource(ClearColor(CLEAR))
            .add_plugins((
                PyramidDisplacementPlugin,
                ExtractComponentPlugin::<Probe>::default(),
            ))
            .add_systems(Startup, setup);
        app.sub_app_mut(RenderApp)
            .add_systems(RenderStartup, init_probe)
            .add_systems(Core3d, probe_pass.in_set(Core3dSystems::PostProcess));
    })
}

/// The height field's normal at `p` in world space (the plane's u along +x, v along +z), by
/// the shader's rule: central differences of the bilinear surface one texel apart.
fn height_field_normal(map: &HeightMap, p: DVec2) -> DVec3 {
    let texel = 1.0 / map.texels_per_uv();
    let d = |q: DVec2| bilinear_depth(map, Addressing::Wrap, q);
    let du = (d(p + DVec2::X * texel.x) - d(p - DVec2::X * texel.x)) / (2.0 * texel.x);
    let dv = (d(p + DVec2::Y * texel.y) - d(p - DVec2::Y * texel.y)) / (2.0 * texel.y);
    let s = f64::from(DEPTH_SCALE);
    DVec3::new(s * du, 1.0, s * dv).normalize()
}

/// What one view's prepass holds against the truth.
struct Agreement {
    covered: usize,
    wrong_depth: usize,
    worst_normal_deg: f64,
    /// Pixels the prepass drew that the lit picture left at the clear colour.
    unlit: usize,
}

fn measure(view: &View, map: &HeightMap, clip_from_world: Mat4, eye: Vec3) -> Agreement {
    let probe: Vec<[f32; 4]> =
        bytemuck::pod_collect_to_vec(view.read_probe.lock().unwrap().as_ref().unwrap());
    let picture = view.read_picture.lock().unwrap().clone().unwrap();
    let world_from_clip = clip_from_world.inverse().as_dmat4();
    let eye = eye.as_dvec3();
    let texel = 1.0 / f64::from(map.width);
    let s = f64::from(DEPTH_SCALE);
    let mut a = Agreement {
        covered: 0,
        wrong_depth: 0,
        worst_normal_deg: 0.0,
        unlit: 0,
    };
    for (i, [depth, nx, ny, nz]) in probe.into_iter().enumerate() {
        let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
        let ndc = DVec2::new(
            (f64::from(x) + 0.5) / f64::from(SIZE) * 2.0 - 1.0,
            1.0 - (f64::from(y) + 0.5) / f64::from(SIZE) * 2.0,
        );
        // The pixel's ray on the CPU: from the eye through the pixel's centre to the plane y = 0.
        let far = world_from_clip.project_point3(ndc.extend(0.5));
        let dir = (far - eye).normalize();
        let on_plane = eye + dir * (-eye.y / dir.y);
        let truth =
            (dir.y < 0.0 && on_plane.x.abs() <= 0.5 && on_plane.z.abs() <= 0.5).then(|| {
                let towards = -dir;
                let ray = Ray {
                    p0: DVec2::new(on_plane.x + 0.5, on_plane.z + 0.5),
                    e: -DVec2::new(towards.x, towards.z) / towards.y * s,
                };
                let hit = intersect(map, Addressing::Wrap, Surface::Point, ray)
                    .expect("a tiling map stops every ray");
                let world = DVec3::new(hit.uv.x - 0.5, -hit.z * s, hit.uv.y - 0.5);
                (world, height_field_normal(map, hit.uv))
            });
        let drawn = depth > 0.0;
        if !drawn && truth.is_none() {
            continue;
        }
        a.covered += 1;
        if drawn && picture[i * 4..i * 4 + 3] == [255, 0, 255] {
            a.unlit += 1;
        }
        let Some((world, normal)) = truth.filter(|_| drawn) else {
            a.wrong_depth += 1;
            continue;
        };
        let seen = world_from_clip.project_point3(ndc.extend(f64::from(depth)));
        if (seen - world).length() > texel {
            a.wrong_depth += 1;
            continue;
        }
        let stored = DVec3::new(nx.into(), ny.into(), nz.into()).normalize();
        let off = stored.angle_between(normal).to_degrees();
        a.worst_normal_deg = a.worst_normal_deg.max(off);
    }
    a
}

#[test]
#[ignore = "run under the validation layer by validation::every_pass_passes_the_layer, in a child process"]
fn prepass_and_gbuffer_hold_the_traced_surface() {
    let mut app = app();
    app.update(); // Startup: the scene and its views.
    let views: Vec<_> = app
        .world()
        .resource::<Views>()
        .0
        .iter()
        .map(|v| {
            (
                v.probe.clone(),
                v.picture.clone(),
                v.read_probe.clone(),
                v.read_picture.clone(),
            )
        })
        .collect();
    for (probe, picture, read_probe, read_picture) in views {
        app.world_mut()
            .spawn(Readback::buffer(probe))
            .observe(move |e: On<ReadbackComplete>| {
                *read_probe.lock().unwrap() = Some(e.data.clone())
            });
        app.world_mut().spawn(Readback::texture(picture)).observe(
            move |e: On<ReadbackComplete>| *read_picture.lock().unwrap() = Some(e.data.clone()),
        );
    }
    // The maps load, the pyramids are built, the pipelines compile; then every probe sees the
    // plane in its prepass. The lit pictures get a few hundred frames more to show it (a main
    // pass rejected by the prepass's depth never does), then a few frames more.
    let seen =
        |app: &App, read: fn(&View) -> bool| app.world().resource::<Views>().0.iter().all(read);
    let drawn = |v: &View| {
        v.read_probe.lock().unwrap().as_ref().is_some_and(|b| {
            bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(b)
                .iter()
                .any(|p| p[0] > 0.0)
        })
    };
    let lit = |v: &View| {
        v.read_picture
            .lock()
            .unwrap()
            .as_ref()
            .is_some_and(|b| b.chunks_exact(4).any(|p| p[..3] != [255, 0, 255]))
    };
    let mut frames = 0;
    while !seen(&app, drawn) {
        assert!(frames < 3000, "no prepass after {frames} frames");
        app.update();
        frames += 1;
    }
    for _ in 0..300 {
        if seen(&app, lit) {
            break;
        }
        app.update();
    }
    for _ in 0..5 {
        app.update();
    }

    let world = app.world();
    let images = world.resource::<Assets<Image>>();
    let assets = world.resource::<AssetServer>();
    let maps: Vec<HeightMap> = MAPS
        .iter()
        .map(|path| {
            let handle: Handle<Image> = assets.get_handle(*path).expect("the map was loaded");
            depth_map(
                path,
                images.get(&handle).expect("the map's CPU data is kept"),
            )
            .unwrap()
        })
        .collect();
    for view in &world.resource::<Views>().0 {
        let entity = world.entity(view.camera);
        let camera = entity.get::<Camera>().unwrap();
        let transform = entity.get::<GlobalTransform>().unwrap();
        let clip_from_world = camera.clip_from_view() * transform.to_matrix().inverse();
        let a = measure(
            view,
            &maps[view.map],
            clip_from_world,
            transform.translation(),
        );
        let what = format!(
            "{} at {} degrees, {:?}",
            MAPS[view.map], view.angle_deg, view.pass
        );
        let wrong = a.wrong_depth as f64 / a.covered.max(1) as f64;
        println!(
            "{what}: {} covered, wrong-depth fraction {wrong:.5}, worst normal {:.2} degrees off, \
             unlit {}",
            a.covered, a.worst_normal_deg, a.unlit
        );
        assert!(
            a.covered > (SIZE * SIZE / 8) as usize,
            "{what}: only {} pixels covered",
            a.covered
        );
        assert!(wrong <= 0.001, "{what}: wrong-depth fraction {wrong}");
        assert!(
            a.worst_normal_deg <= NORMAL_TOLERANCE_DEG,
            "{what}: a normal {} degrees off",
            a.worst_normal_deg
        );
        assert_eq!(
            a.unlit, 0,
            "{what}: the main pass lost pixels the prepass drew"
        );
    }
}
