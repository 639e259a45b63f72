//! One-bounce indirect light added to a G-buffer you render yourself. This program opens its own
//! wgpu device, builds a Cornell-like box with a block in code, rasterises its own G-buffer with
//! its own shader, then records quadray's passes into its encoder: the spot's RSM, the light
//! quadtree and its cut, the gather into its G-buffer, the direct light through a shadow map of
//! its own, and the radiance into its output texture.
//! Writes `out/examples/gi_gbuffer.png` under the workspace root, or the PNG file given as its
//! argument:
//!
//! `cargo run --release -p quadray-indirect --example gi_gbuffer [-- PICTURE.png]`
//!
//! The same box as a scene file is `assets/scenes/example-gi.toml`; from the workspace root,
//! `quadray indirect --scene assets/scenes/example-gi.toml --size 256x256 --rsm-size 128` draws
//! the same picture.

use glam::Vec3;
use quadray_gpu::{nearest_depth, texture_2d};
use quadray_indirect::scene::{Camera, Cone, Intensity, Light, LightKind, Scene, Vertex};
use quadray_indirect::{
    DirectLight, FLOAT_FORMAT, GBufferViews, Gather, LightQuadtree, LightView, Method, OutputPass,
    OutputTerm, RsmPass, Settings, ViewMaps,
};
use wgpu::util::DeviceExt;

/// The G-buffer the gather reads: world position (w = 1 where covered), normal towards the
/// camera, albedo; all Rgba32Float.
const GBUFFER_WGSL: &str = "
struct Camera { view_proj: mat4x4<f32>, eye: vec4<f32> }
@group(0) @binding(0) var<uniform> camera: Camera;
struct Out { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32>,
             @location(1) normal: vec3<f32>, @location(2) albedo: vec3<f32> }
@vertex fn vs(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>, @location(2) a: vec3<f32>) -> Out {
    return Out(camera.view_proj * vec4<f32>(p, 1.0), p, n, a);
}
struct GBuffer { @location(0) pos: vec4<f32>, @location(1) normal: vec4<f32>, @location(2) albedo: vec4<f32> }
@fragment fn fs(v: Out) -> GBuffer {
    var n = normalize(v.normal);
    n = select(-n, n, dot(n, camera.eye.xyz - v.world) >= 0.0);
    return GBuffer(vec4<f32>(v.world, 1.0), vec4<f32>(n, 1.0), vec4<f32>(v.albedo, 1.0));
}";

/// Two triangles a b c, a c d with the normal of their winding.
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, albedo: [f32; 3]) -> [[Vertex; 3]; 2] {
    let normal = (b - a).cross(d - a).normalize().into();
    let v = |p: Vec3| Vertex::untextured(p.into(), normal, albedo);
    [[v(a), v(b), v(c)], [v(a), v(c), v(d)]]
}

/// The six faces of the box `min`..`max`, wound outwards: bottom, top, then the sides facing
/// +z, +x, -z and -x.
fn box_faces(min: Vec3, max: Vec3) -> [[Vec3; 4]; 6] {
    let around = [
        (min.x, max.z),
        (max.x, max.z),
        (max.x, min.z),
        (min.x, min.z),
    ];
    let at = |i: usize, y: f32| {
        let (x, z) = around[i % 4];
        Vec3::new(x, y, z)
    };
    let side = |i| {
        [
            at(i, min.y),
            at(i + 1, min.y),
            at(i + 1, max.y),
            at(i, max.y),
        ]
    };
    [
        [at(3, min.y), at(2, min.y), at(1, min.y), at(0, min.y)],
        [at(0, max.y), at(1, max.y), at(2, max.y), at(3, max.y)],
        side(0),
        side(1),
        side(2),
        side(3),
    ]
}

/// A unit room open towards +z (red wall left, green right) with a white block, a spot light
/// under the ceiling and the camera in front.
fn scene() -> Scene {
    let (white, red, green) = ([0.73; 3], [0.63, 0.065, 0.05], [0.14, 0.45, 0.091]);
    let mut triangles = Vec::new();
    // the room's faces wound inwards; no wall on the camera's side
    let walls = [
        Some(white),
        Some(white),
        None,
        Some(green),
        Some(white),
        Some(red),
    ];
    for ([a, b, c, d], albedo) in box_faces(Vec3::ZERO, Vec3::ONE).into_iter().zip(walls) {
        if let Some(albedo) = albedo {
            triangles.extend(quad(d, c, b, a, albedo));
        }
    }
    // the block: 0.3 wide, 0.5 high, standing on the floor (its bottom unseen)
    let block = box_faces(Vec3::new(0.2, 0.0, 0.3), Vec3::new(0.5, 0.5, 0.6));
    for [a, b, c, d] in block.into_iter().skip(1) {
        triangles.extend(quad(a, b, c, d, white));
    }
    Scene {
        name: "gi_gbuffer".into(),
        camera: Camera {
            position: Vec3::new(0.5, 0.5, 2.4),
            target: Vec3::new(0.5, 0.5, 0.0),
            up: Vec3::Y,
            fov_y_deg: 39.0,
        },
        lights: vec![Light {
            kind: LightKind::Spot {
                position: Vec3::new(0.5, 0.97, 0.85),
                cone: Cone {
                    direction: Vec3::new(0.25, -1.0, -0.55),
                    cone_deg: 55.0,
                    falloff_deg: 15.0,
                },
            },
            intensity: Intensity::Native(Vec3::splat(2.0)),
        }],
        r_min: 0.05,
        triangles,
        // untextured: this G-buffer carries the albedo per vertex
        textures: Default::default(),
    }
}

/// The picture's size and the quadtree's defaults for a 128^2 RSM.
fn settings() -> Settings {
    Settings::sized(256, 256, 128)
}

/// Renders the scene (direct + one bounce) and returns linear radiance, rgba per pixel.
fn render(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> Result<Vec<[f32; 4]>, Box<dyn std::error::Error>> {
    let (scene, s) = (scene(), settings());
    let size = (s.size.width, s.size.height);
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("vertices"),
        contents: bytemuck::cast_slice(&scene.triangles),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let vertex_count = scene.triangles.len() as u32 * 3;

    // Our own G-buffer pass.
    let target = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    let view = |format| {
        texture_2d(device, "gbuffer", size, format, target).create_view(&Default::default())
    };
    let gbuffer = [(); 3].map(|_| view(FLOAT_FORMAT));
    let depth = view(wgpu::TextureFormat::Depth32Float);
    let view_proj = scene.camera_view_proj(s.size.width as f32 / s.size.height as f32);
    let camera = view_proj.to_cols_array();
    let eye = scene.camera.position;
    let camera = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("camera"),
        contents: bytemuck::cast_slice(&[&camera[..], &[eye[0], eye[1], eye[2], 1.0]].concat()),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("gbuffer"),
        source: wgpu::ShaderSource::Wgsl(GBUFFER_WGSL.into()),
    });
    let gbuffer_targets = [(); 3].map(|_| Some(FLOAT_FORMAT.into()));
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("gbuffer"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[wgpu::VertexBufferLayout {
                array_stride: size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
            }],
        },
        primitive: Default::default(),
        depth_stencil: Some(nearest_depth(wgpu::TextureFormat::Depth32Float)),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &gbuffer_targets,
        }),
        multiview_mask: None,
        cache: None,
    });
    let camera_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: camera.as_entire_binding(),
        }],
    });

    // quadray's passes on our device: the RSM, the quadtree over it, the gather into our G-buffer.
    let lights = LightView::of_scene(&scene, s.max_lights);
    let rsm = RsmPass::new(device, &s);
    rsm.set_light(queue, &lights[0]);
    let quadtree = LightQuadtree::new(device, queue, s.rsm_size, s.cluster, rsm.views());
    // the wide layout: each quantity whole (a compact G-buffer gives its depth instead)
    let views = GBufferViews::Wide {
        position: &gbuffer[0],
        normal: &gbuffer[1],
        albedo: &gbuffer[2],
    };
    let maps = [ViewMaps {
        rsm: rsm.views(),
        quadtree: &quadtree,
    }];
    let gather = Gather::new(device, &s, &maps, views)?;
    gather.set_lights(queue, &lights, scene.r_min);
    // the direct light: a shadow map a light view, sized for the picture
    let direct = DirectLight::new(device, &gather);
    direct.set_lights(queue, &lights, view_proj, scene.bounds());
    let output_pass = OutputPass::new(device, FLOAT_FORMAT, OutputTerm::Combined)?;
    let output_usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC;
    let output = texture_2d(device, "output", size, FLOAT_FORMAT, output_usage);

    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let attachment = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &[
                attachment(&gbuffer[0]),
                attachment(&gbuffer[1]),
                attachment(&gbuffer[2]),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &camera_group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.draw(0..vertex_count, 0..1);
    }
    rsm.record(&mut encoder, vertices.slice(..), vertex_count, None);
    quadtree.record_build(&mut encoder, None);
    quadtree.record_cut(&mut encoder, None);
    gather.record_indirect(&mut encoder, Method::DEFAULT, &[&quadtree], None);
    direct.record_shadow_maps(&mut encoder, vertices.slice(..), vertex_count, None);
    direct.record(&mut encoder, &gather, None);
    output_pass.record(
        device,
        &mut encoder,
        &gather,
        &output.create_view(&Default::default()),
    );

    // Read the output back (256 pixels of 16 bytes: rows already 256-byte aligned).
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: u64::from(s.size.width * s.size.height) * 16,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        output.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(s.size.width * 16),
                rows_per_image: None,
            },
        },
        output.size(),
    );
    let frame = queue.submit([encoder.finish()]);
    readback
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.expect("map the readback"));
    // Bounded: a frame that never ends (a driver fault, a shader that loops) is an error here,
    // not a program that never returns.
    device.poll(wgpu::PollType::Wait {
        submission_index: Some(frame),
        timeout: Some(std::time::Duration::from_secs(60)),
    })?;
    let pixels = bytemuck::pod_collect_to_vec(&readback.slice(..).get_mapped_range());
    Ok(pixels)
}

/// Linear radiance to 8-bit sRGB with quadray's tone curve (1 - exp(-x)).
fn to_png(width: u32, height: u32, radiance: &[[f32; 4]]) -> image::RgbaImage {
    let rgb: Vec<[f32; 3]> = radiance.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let picture = quadray_indirect::picture::tone_map(width, height, &rgb, 1.0);
    image::RgbaImage::from_raw(width, height, picture.pixels.concat()).expect("sized")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    // three Rgba32Float targets (48 bytes a sample) exceed the default limit of 32: ask for the
    // adapter's own limits
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: adapter.limits(),
        ..Default::default()
    }))?;
    let radiance = render(&device, &queue)?;
    let s = settings();
    let path = std::env::args_os().nth(1).map_or_else(
        || {
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../out/examples/gi_gbuffer.png")
        },
        std::path::PathBuf::from,
    );
    std::fs::create_dir_all(path.parent().unwrap())?;
    to_png(s.size.width, s.size.height, &radiance).save(&path)?;
    println!("{}", path.display());
    Ok(())
}
