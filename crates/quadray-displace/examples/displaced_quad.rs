//! A displaced quad drawn by your own render pass: open a wgpu device, load a height map, build
//! its [`HeightPyramid`], and trace it per pixel in a small fragment shader that includes
//! quadray's tracing module. Writes `out/examples/displaced_quad.png` under the workspace root, or
//! the PNG file given as its argument:
//!
//! `cargo run --release -p quadray-displace --example displaced_quad [-- PICTURE.png]`
//!
//! From the workspace root, `quadray displace --map
//! assets/heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png --method pyramid --view-angle
//! 60 --azimuth 0 --light-azimuth 0 --shadows --size 256x256` draws the same surface and shadows
//! (its shading samples the albedo and the normal from textures where this one computes them).

use glam::Vec3;
use quadray_displace::heightmap::{Convention, Fit, HeightMap};
use quadray_displace::pyramid::Addressing;
use quadray_displace::{HeightPyramid, PyramidInfo, PyramidKind, TRACE_WGSL};
use std::path::{Path, PathBuf};

/// Picture side in pixels (a multiple of 64, so rows need no padding when read back).
const SIZE: u32 = 256;
/// Where the camera and the light are: the wall seen 60 degrees off its normal.
const EYE: Vec3 = Vec3::new(0.0, 0.8, -1.385_640_6);
const LIGHT: Vec3 = Vec3::new(1.6, 1.2, 0.4);

// A quad in y = 0 spanning x, z in [-4, 4] with the map repeated 8 x 8 times: tangent +u along
// +x, +v along +z, normal +y; one repeat is one world unit.
const SHADER: &str = r#"
struct Uniforms { view_proj: mat4x4f, eye: vec4f, light: vec4f, pyramid: PyramidInfo }
@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(1) var heights: texture_2d<f32>;
const DEPTH_SCALE: f32 = 0.1;

struct Varyings { @builtin(position) clip: vec4f, @location(0) world: vec3f, @location(1) uv: vec2f }

@vertex fn vs(@builtin(vertex_index) i: u32) -> Varyings {
    let c = array(vec2f(0, 0), vec2f(1, 0), vec2f(0, 1), vec2f(0, 1), vec2f(1, 0), vec2f(1, 1))[i];
    let world = vec3f(c.x * 8.0 - 4.0, 0.0, c.y * 8.0 - 4.0);
    return Varyings(u.view_proj * vec4f(world, 1.0), world, c * 8.0);
}

fn tangent(world: vec3f) -> vec3f { return vec3f(world.x, world.z, world.y); }

@fragment fn fs(in: Varyings) -> @location(0) vec4f {
    let e = ray_slope(tangent(normalize(u.eye.xyz - in.world)), DEPTH_SCALE);
    let p0 = fract(in.uv);
    let hit = pyramid_trace(heights, u.pyramid, p0, e, 0.0, u.pyramid.levels, 0, false);
    let uv = p0 + e * hit.z;
    let world = in.world + vec3f(uv.x - p0.x, -hit.z * DEPTH_SCALE, uv.y - p0.y);
    let l = normalize(u.light.xyz - world);
    let lit = pyramid_lit(heights, u.pyramid, uv, hit.z, tangent(l), DEPTH_SCALE, 0);
    // Shade the hit: a stone colour darker with depth, the normal from the depth's slope.
    let dx = vec2f(1.0 / f32(u.pyramid.size.x), 0.0);
    let dy = vec2f(0.0, 1.0 / f32(u.pyramid.size.y));
    let slope = vec2f(
        depth_bilinear(heights, u.pyramid, uv + dx) - depth_bilinear(heights, u.pyramid, uv - dx),
        depth_bilinear(heights, u.pyramid, uv + dy) - depth_bilinear(heights, u.pyramid, uv - dy),
    ) / (2.0 * vec2f(dx.x, dy.y));
    let n = normalize(vec3f(slope.x * DEPTH_SCALE, 1.0, slope.y * DEPTH_SCALE));
    let depth = depth_bilinear(heights, u.pyramid, uv);
    let srgb = floor(vec3f(220.0, 190.0, 150.0) * (1.0 - 0.55 * depth)) / 255.0;
    let albedo = select(pow((srgb + 0.055) / 1.055, vec3f(2.4)), srgb / 12.92, srgb <= vec3f(0.04045));
    var color = 0.12 * albedo;
    if lit {
        let h = normalize(l + normalize(u.eye.xyz - world));
        color += max(dot(n, l), 0.0) * albedo + 0.25 * pow(max(dot(n, h), 0.0), 48.0);
    }
    return vec4f(color, 1.0);
}
"#;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Uniforms {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    pyramid: PyramidInfo,
}

/// The bundled tile map (16-bit PNG, white = high).
fn tile_map() -> HeightMap {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let file = root.join("assets/heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png");
    HeightMap::load(&file, Convention::Height, Fit::Exact).expect("the bundled tile map")
}

/// Draws the displaced quad on `device` and reads the picture back.
fn render(device: &wgpu::Device, queue: &wgpu::Queue, map: &HeightMap) -> image::RgbaImage {
    let pyramid = HeightPyramid::build_gpu(device, queue, map, PyramidKind::Point);
    let view = glam::Mat4::look_at_rh(EYE, Vec3::ZERO, Vec3::Y);
    let proj = glam::Mat4::perspective_rh(50f32.to_radians(), 1.0, 0.01, 100.0);
    let uniforms = Uniforms {
        view_proj: (proj * view).to_cols_array_2d(),
        eye: EYE.extend(0.0).to_array(),
        light: LIGHT.extend(0.0).to_array(),
        pyramid: pyramid.info(Addressing::Wrap),
    };
    let buffer = wgpu::util::DeviceExt::create_buffer_init(
        device,
        &wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::bytes_of(&uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        },
    );
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty,
        count: None,
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[
            entry(
                0,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(size_of::<Uniforms>() as u64),
                },
            ),
            entry(
                1,
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
            ),
        ],
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(pyramid.view()),
            },
        ],
    });
    // The tracing module first, then our own code.
    let source = format!("{TRACE_WGSL}\n{SHADER}");
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("displaced quad"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: None,
        layout: Some(
            &device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            }),
        ),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let extent = wgpu::Extent3d {
        width: SIZE,
        height: SIZE,
        depth_or_array_layers: 1,
    };
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: u64::from(SIZE * SIZE * 4),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let view = target.create_view(&Default::default());
        let sky = wgpu::Color {
            r: 0.16,
            g: 0.18,
            b: 0.22,
            a: 1.0,
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(sky),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..6, 0..1);
    }
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(SIZE * 4),
                rows_per_image: None,
            },
        },
        extent,
    );
    let frame = queue.submit([encoder.finish()]);
    readback
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.expect("map the readback"));
    // Bounded: a frame that never ends (a driver fault, a shader that loops) is an error here,
    // not a program that never returns.
    device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(frame),
            timeout: Some(std::time::Duration::from_secs(60)),
        })
        .expect("the frame finished within 60 s");
    let bytes = readback.slice(..).get_mapped_range().to_vec();
    image::RgbaImage::from_raw(SIZE, SIZE, bytes).expect("SIZE x SIZE RGBA")
}

fn main() {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
        .expect("a GPU adapter (on Linux without a GPU: mesa-vulkan-drivers)");
    let (device, queue) =
        pollster::block_on(adapter.request_device(&Default::default())).expect("a device");
    let picture = render(&device, &queue, &tile_map());
    let path = std::env::args_os().nth(1).map_or_else(
        || {
            let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../out/examples");
            std::fs::create_dir_all(&out).expect("create out/examples");
            let out = std::fs::canonicalize(out).expect("out/examples");
            out.join("displaced_quad.png")
        },
        PathBuf::from,
    );
    picture.save(&path).expect("write the picture");
    println!("{}", path.display());
}
