//! NaN and infinite depths, and rays that are not numbers. `HeightMap::from_depths` and `load`
//! refuse such maps, but the struct's fields are public, as an engine's own upload fills them, and
//! a pyramid can be uploaded as built anywhere: every trace must still end within its caps (the
//! frame within the GPU wait bound), and only the rays that pass over a bad texel may change.

use crate::common;
use quadray_displace::heightmap::HeightMap;
use quadray_displace::pyramid::{Addressing, Pyramid};
use quadray_displace::scene::SurfaceKind;
use quadray_displace::{
    Frame, HeightPyramid, Method, PyramidInfo, PyramidKind, Renderer, Settings, Size, TRACE_WGSL,
};
use quadray_gpu::{Gpu, read_buffer};
use wgpu::util::DeviceExt;

const SIDE: u32 = 64;

/// The bad texels: a lone NaN, a 2x2 block of NaN, a hole (+inf) and a spike (-inf).
const BAD: [(u32, u32, f32); 7] = [
    (9, 13, f32::NAN),
    (40, 40, f32::NAN),
    (41, 40, f32::NAN),
    (40, 41, f32::NAN),
    (41, 41, f32::NAN),
    (20, 50, f32::INFINITY),
    (52, 8, f32::NEG_INFINITY),
];

/// `map` with [`BAD`]'s texels, written past `HeightMap::from_depths`'s refusal.
fn corrupted(map: &HeightMap) -> HeightMap {
    let mut bad = map.clone();
    for (x, y, value) in BAD {
        bad.depth[(y * map.width + x) as usize] = value;
    }
    bad
}

/// Whether the ray (p0, e) in uv, between depths 0 and `z_end`, passes within one texel (the
/// bilinear surface's reach) of a bad texel of a `size`^2 map read with `addressing`.
fn passes_bad_texel(ray: [f32; 4], z_end: f32, size: u32, addressing: Addressing) -> bool {
    let s = size as f32;
    let (x0, y0, ex, ey) = (ray[0] * s, ray[1] * s, ray[2] * s, ray[3] * s);
    // quarter-texel steps along the ray
    let steps = ((ex.hypot(ey) * z_end * 4.0).ceil() as u32).max(1);
    (0..=steps).any(|k| {
        let z = z_end * k as f32 / steps as f32;
        let (x, y) = ((x0 + ex * z).floor() as i64, (y0 + ey * z).floor() as i64);
        let near = |t: i64, b: u32| {
            (t - 1..=t + 1).any(|n| match addressing {
                Addressing::Wrap => n.rem_euclid(i64::from(size)) == i64::from(b),
                Addressing::Clamp => n == i64::from(b),
            })
        };
        BAD.iter().any(|&(bx, by, _)| near(x, bx) && near(y, by))
    })
}

/// Per pixel of two frames of the same view: (in the bad texels' footprint, changed, non-finite).
/// A hit changes when its depth moves by over 1e-3, it misses on one side only or a cap stopped
/// it; the footprint is the pixels whose clean ray passes a bad texel before its clean hit (and
/// for the linear searches, before the layer after it).
fn compare(
    clean: &Frame,
    bad: &Frame,
    size: u32,
    addressing: Addressing,
    overshoot: f32,
) -> Vec<(bool, bool, bool)> {
    clean
        .hits
        .iter()
        .zip(&bad.hits)
        .zip(&clean.rays)
        .filter(|((h, _), _)| h[2] != -2.0)
        .map(|((h, b), ray)| {
            let z_end = if h[2] < 0.0 {
                1.0
            } else {
                (h[2] + overshoot).min(1.0)
            };
            let footprint = passes_bad_texel(*ray, z_end, size, addressing);
            let non_finite = b.iter().any(|v| !v.is_finite());
            let changed = non_finite
                || (h[2] < 0.0) != (b[2] < 0.0)
                || (h[2] - b[2]).abs() > 1e-3
                || b[3] < 0.0;
            (footprint, changed, non_finite)
        })
        .collect()
}

/// quadray's renderer, which builds its pyramids on the GPU, on a map with bad texels against the
/// clean map, every searching method on a tiled and a clamped surface. (Where the GPU's `min`
/// drops a NaN operand, as lavapipe's does, the builder makes a NaN texel a hole; the test below
/// covers a `min` that keeps it.)
#[test]
fn nan_and_infinite_texels_change_only_the_rays_that_pass_over_them() {
    let gpu = Gpu::new().expect("a GPU adapter");
    let clean = common::procedural(SIDE, SIDE);
    let bad = corrupted(&clean);
    let mut seen_bad = 0;
    for surface in [SurfaceKind::Wall, SurfaceKind::Terrain] {
        let mut renderers = [&clean, &bad].map(|m| Renderer::new(&gpu, m, None, surface));
        for method in [
            Method::Pyramid,
            Method::PyramidAscend,
            Method::PyramidBilinear,
            Method::Pom,
            Method::Relief,
        ] {
            for angle in [30.0, 70.0] {
                let s = Settings {
                    method,
                    view_angle_deg: angle,
                    size: Size::new(96, 96),
                    ..Default::default()
                };
                // a frame that never ends is an error of the bounded wait, not a hang
                let [a, b] = renderers
                    .each_mut()
                    .map(|r| r.render(&gpu, &s).expect("the frame finishes"));
                let overshoot = match method {
                    Method::Pom | Method::Relief => 1.0 / s.layers.min as f32,
                    _ => 0.0,
                };
                let pixels = compare(&a, &b, SIDE, surface.addressing(), overshoot);
                let count = |f: &dyn Fn(&(bool, bool, bool)) -> bool| {
                    pixels.iter().filter(|p| f(p)).count()
                };
                let footprint = count(&|p| p.0);
                let changed = count(&|p| p.1);
                let non_finite = count(&|p| p.2);
                let stray = count(&|p| p.1 && !p.0);
                println!(
                    "{surface:?} {method} {angle} deg: {} covered, {footprint} over a bad texel, {changed} changed ({non_finite} non-finite), {stray} changed elsewhere",
                    pixels.len()
                );
                assert_eq!(
                    stray, 0,
                    "{surface:?} {method} {angle} deg: a bad texel changed rays that do not pass it"
                );
                assert!(
                    footprint * 4 < pixels.len(),
                    "{surface:?} {method} {angle} deg: the footprint ({footprint} of {}) must leave most pixels to compare",
                    pixels.len()
                );
                seen_bad += changed;
            }
        }
    }
    assert!(
        seen_bad > 0,
        "no ray met a bad texel: the test shows nothing"
    );
}

/// A user's compute shader around `trace.wgsl`: per ray (p0, e), `pyramid_trace` on the point
/// pyramid (entry `point`) or `bilinear_trace` (entry `bilinear`): z, iterations, missed, capped.
const TRACER_WGSL: &str = "
@group(0) @binding(0) var point_pyramid: texture_2d<f32>;
@group(0) @binding(1) var conservative: texture_2d<f32>;
@group(0) @binding(2) var<uniform> info: PyramidInfo;
@group(0) @binding(3) var<storage, read> rays: array<vec4f>;
@group(0) @binding(4) var<storage, read_write> hits: array<vec4f>;

fn store(i: u32, t: TraceHit) {
    hits[i] = vec4f(t.z, f32(t.iterations), select(0.0, 1.0, t.missed), select(0.0, 1.0, t.capped));
}

@compute @workgroup_size(64)
fn point(@builtin(global_invocation_id) id: vec3u) {
    if id.x < arrayLength(&rays) {
        let r = rays[id.x];
        store(id.x, pyramid_trace(point_pyramid, info, r.xy, r.zw, 0.0, info.levels, 0, false));
    }
}

@compute @workgroup_size(64)
fn bilinear(@builtin(global_invocation_id) id: vec3u) {
    if id.x < arrayLength(&rays) {
        let r = rays[id.x];
        store(id.x, bilinear_trace(conservative, point_pyramid, info, r.xy, r.zw, 0));
    }
}
";

/// Traces `rays` with `entry` of [`TRACER_WGSL`] over the two pyramids: per ray (z, iterations,
/// missed, capped).
fn trace(
    gpu: &Gpu,
    pyramids: [&HeightPyramid; 2],
    info: &PyramidInfo,
    rays: &[[f32; 4]],
    entry: &str,
) -> Vec<[f32; 4]> {
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("tracer"),
        source: wgpu::ShaderSource::Wgsl(format!("{TRACE_WGSL}\n{TRACER_WGSL}").into()),
    });
    let texture = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let storage = |read_only| wgpu::BufferBindingType::Storage { read_only };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[
            texture(0),
            texture(1),
            buffer(2, wgpu::BufferBindingType::Uniform),
            buffer(3, storage(true)),
            buffer(4, storage(false)),
        ],
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(
            &device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            }),
        ),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let init = |contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents,
            usage,
        })
    };
    let info = init(bytemuck::bytes_of(info), wgpu::BufferUsages::UNIFORM);
    let rays_buffer = init(bytemuck::cast_slice(rays), wgpu::BufferUsages::STORAGE);
    let hits = init(
        &vec![0; std::mem::size_of_val(rays)],
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(pyramids[0].view()),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(pyramids[1].view()),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: info.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: rays_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: hits.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
    }
    gpu.submit(format!("{entry} traces"), encoder.finish());
    bytemuck::pod_collect_to_vec(&read_buffer(gpu, &hits).expect("the traces finish"))
}

/// `pyramid` as a GPU whose `min` returns NaN when either side is NaN builds it from a map with
/// the bad texels: a NaN or -inf in every level-0 texel within `reach` of it (1: the conservative
/// level 0's neighbourhood) and every node above; a +inf in the point level 0 alone (any `min`
/// keeps the other texels' bound above it).
fn poisoned(mut pyramid: Pyramid, reach: i64) -> Pyramid {
    for (x, y, value) in BAD {
        for (dx, dy) in (-reach..=reach).flat_map(|dy| (-reach..=reach).map(move |dx| (dx, dy))) {
            let at = |t: u32, d: i64| Addressing::Wrap.texel(i64::from(t) + d, SIDE);
            let (x, y) = (at(x, dx), at(y, dy));
            for (k, level) in pyramid.levels.iter_mut().enumerate() {
                let width = (SIDE >> k).max(1);
                let node = &mut level[((y >> k) * width + (x >> k)) as usize];
                if value.is_nan() || value < *node || (k == 0 && reach == 0) {
                    *node = value;
                }
            }
        }
    }
    pyramid
}

/// Rays over the map: a grid of starts, each at two view angles and four azimuths, with the
/// default depth scale.
fn grid_rays(angles_deg: &[f32]) -> Vec<[f32; 4]> {
    let depth_scale = Settings::DEFAULT.depth_scale;
    let mut rays = Vec::new();
    for j in 0..32 {
        for i in 0..32 {
            let p0 = [(i as f32 + 0.5) / 32.0, (j as f32 + 0.37) / 32.0];
            for &angle in angles_deg {
                for azimuth in [0.3f32, 2.0, 3.9, 5.1] {
                    let (sin, cos) = angle.to_radians().sin_cos();
                    let v = [sin * azimuth.cos(), sin * azimuth.sin()];
                    rays.push([
                        p0[0],
                        p0[1],
                        -v[0] / cos * depth_scale,
                        -v[1] / cos * depth_scale,
                    ]);
                }
            }
        }
    }
    rays
}

/// trace.wgsl on its own, over pyramids with NaN and infinities at every level above the bad
/// texels (what a GPU whose min propagates NaN builds): the rays that do not pass a bad texel
/// hit where they hit on the clean pyramids, none is stopped by a cap, and a ray that is not a
/// number misses at once. With a small iteration cap, the bilinear trace stops within it (plus
/// one search) however many refinement rounds the ray needs.
#[test]
fn traces_over_nan_pyramids_end_and_change_only_the_rays_over_bad_texels() {
    let gpu = Gpu::new().expect("a GPU adapter");
    let (device, queue) = (&gpu.device, &gpu.queue);
    let map = common::procedural(SIDE, SIDE);
    let conservative = PyramidKind::Conservative(Addressing::Wrap);
    let upload = |pyramid: &Pyramid, kind| HeightPyramid::upload(device, queue, pyramid, kind);
    let point = Pyramid::build(&map);
    let bilinear = Pyramid::build_conservative(&map, Addressing::Wrap);
    let clean = [
        upload(&point, PyramidKind::Point),
        upload(&bilinear, conservative),
    ];
    let bad = [
        upload(&poisoned(point, 0), PyramidKind::Point),
        upload(&poisoned(bilinear, 1), conservative),
    ];
    let info = PyramidInfo::new(SIDE, SIDE, Addressing::Wrap);
    let mut rays = grid_rays(&[30.0, 70.0]);
    let not_numbers = [
        [f32::NAN, 0.5, 0.1, 0.1],
        [0.5, 0.5, f32::NAN, 0.0],
        [0.5, 0.5, f32::INFINITY, 0.1],
        [f32::NEG_INFINITY, 0.5, 0.0, 0.1],
    ];
    rays.extend(not_numbers);
    let numbers = rays.len() - not_numbers.len();
    for entry in ["point", "bilinear"] {
        let a = trace(&gpu, [&clean[0], &clean[1]], &info, &rays, entry);
        let b = trace(&gpu, [&bad[0], &bad[1]], &info, &rays, entry);
        let mut footprint = 0;
        let mut changed = 0;
        for (i, ((h, g), ray)) in a.iter().zip(&b).zip(&rays).take(numbers).enumerate() {
            assert!(
                h[3] == 0.0 && g[3] == 0.0,
                "{entry} ray {i} {ray:?}: capped"
            );
            let z_end = if h[2] > 0.0 { 1.0 } else { h[0] };
            let over = passes_bad_texel(*ray, z_end, SIDE, Addressing::Wrap);
            let moved = !g[0].is_finite() || (h[0] - g[0]).abs() > 1e-3 || h[2] != g[2];
            assert!(
                over || !moved,
                "{entry} ray {i} {ray:?}: {h:?} on the clean pyramid, {g:?} on the bad one"
            );
            footprint += usize::from(over);
            changed += usize::from(moved);
        }
        let most = b[..numbers].iter().map(|h| h[1]).fold(0.0, f32::max);
        println!(
            "{entry}: {numbers} rays, {footprint} over a bad texel, {changed} changed; at most {most} steps"
        );
        assert!(changed > 0, "{entry}: no ray met a bad texel");
        for (ray, hit) in not_numbers.iter().zip(&b[numbers..]) {
            assert_eq!(
                hit[1..],
                [0.0, 1.0, 0.0],
                "{entry}: the ray {ray:?} must miss at once"
            );
        }
    }
    let capped = PyramidInfo {
        iteration_cap: 16,
        ..info
    };
    let grazing = grid_rays(&[80.0, 85.0]);
    let hits = trace(&gpu, [&clean[0], &clean[1]], &capped, &grazing, "bilinear");
    let stopped = hits.iter().filter(|h| h[3] > 0.0).count();
    let most = hits.iter().map(|h| h[1]).fold(0.0, f32::max);
    println!(
        "bilinear at an iteration cap of 16: {stopped} of {} stopped, at most {most} steps",
        hits.len()
    );
    assert!(
        stopped > 0 && most <= 2.0 * 16.0 + 4.0,
        "{stopped} stopped, {most} steps"
    );
}
