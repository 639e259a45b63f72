//! The occupancy grid's walk on the GPU (`occupancy.wgsl`, `grid_visibility`) against its CPU
//! twin ([`OccupancyGrid::walk`]) on segments between random points of the leak scene's
//! surfaces, through a grid of one level and one of two: the same answers from the same word
//! fetches in the same steps.

use crate::contract::{
    bind_group, compute_pipeline, layout, pipeline_layout, shader_module, storage_buffer,
    storage_entry, whole,
};
use crate::scene::{Scene, scenes_dir};
use crate::shadows::occupancy::{HEADER_WORDS, OccupancyGrid, Walk};
use crate::wgsl;
use glam::Vec3;
use quadray_core::random::SplitMix;
use wgpu::util::DeviceExt;

/// A segment: a receiver and its normal, a cluster and its normal (w unused).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Segment {
    x: [f32; 4],
    n: [f32; 4],
    xp: [f32; 4],
    np: [f32; 4],
}

const ENTRY: &str = "
struct Segment { x: vec4<f32>, n: vec4<f32>, xp: vec4<f32>, np: vec4<f32> }
@group(0) @binding(0) var<storage, read> grid: array<u32>;
@group(0) @binding(1) var<storage, read> segments: array<Segment>;
@group(0) @binding(2) var<storage, read_write> seen: array<vec3<u32>>;
fn occupancy_dims() -> vec3<u32> { return vec3<u32>(grid[0], grid[1], grid[2]); }
fn occupancy_levels() -> u32 { return grid[3]; }
fn occupancy_origin() -> vec3<f32> { return bitcast<vec3<f32>>(vec3<u32>(grid[4], grid[5], grid[6])); }
fn occupancy_cell() -> f32 { return bitcast<f32>(grid[7]); }
fn occupancy_word(i: u32) -> u32 { return grid[OCCUPANCY_HEADER + i]; }
@compute @workgroup_size(64)
fn walk(@builtin(global_invocation_id) id: vec3<u32>) {
if (id.x < arrayLength(&segments)) {
    let s = segments[id.x];
    let verdict = grid_visibility(s.x.xyz, s.n.xyz, s.xp.xyz, s.np.xyz);
    seen[id.x] = vec3<u32>(verdict, fetches, walk_steps);
}
}
";

/// Each segment's `grid_visibility` (visible, blocked, `None` unknown), its fetches and its
/// loop's steps, for each grid.
fn walks_on_the_gpu(
    grids: &[OccupancyGrid],
    segments: &[Segment],
) -> Vec<Vec<(Option<bool>, u32, u32)>> {
    let gpu = quadray_gpu::Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let d = &gpu.device;
    let group_layout = layout(
        d,
        "grid walks",
        &[
            storage_entry::<[u32; HEADER_WORDS + 1]>(0, true),
            storage_entry::<Segment>(1, true),
            storage_entry::<[u32; 4]>(2, false),
        ],
    );
    let module = shader_module(d, "grid walks", &[wgsl::NODE, wgsl::OCCUPANCY, ENTRY]);
    let pipeline = compute_pipeline(
        d,
        &pipeline_layout(d, &[&group_layout]),
        &module,
        "walk",
        &[],
    );
    let buffer = |label, contents: &[u8]| {
        d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let input = buffer("segments", bytemuck::cast_slice(segments));
    let walk = |grid: &OccupancyGrid| {
        let words = buffer("grid", bytemuck::cast_slice(&grid.gpu_words()));
        let output = storage_buffer(d, "seen", segments.len() as u64 * 16);
        let group = bind_group(
            d,
            "grid walks",
            &group_layout,
            vec![whole(&words), whole(&input), whole(&output)],
        );
        let mut encoder = d.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups((segments.len() as u32).div_ceil(64), 1, 1);
        }
        gpu.queue.submit([encoder.finish()]);
        let bytes = quadray_gpu::read_buffer(&gpu, &output).unwrap();
        bytemuck::pod_collect_to_vec::<u8, [u32; 4]>(&bytes)
            .into_iter()
            .map(|[verdict, fetches, steps, _]| {
                ((verdict != 2).then_some(verdict == 1), fetches, steps)
            })
            .collect()
    };
    grids.iter().map(walk).collect()
}

/// Segments between random points of random triangles (with their normals); every fifth ends
/// at a point with a zero normal (a cluster of many directions).
fn segments(scene: &Scene, count: usize) -> Vec<Segment> {
    let mut random = SplitMix(7);
    let mut point = || {
        let t = &scene.triangles
            [(random.next_f32() * scene.triangles.len() as f32) as usize % scene.triangles.len()];
        let (mut u, mut v) = (random.next_f32(), random.next_f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = |i: usize| Vec3::from(t[i].position);
        let x = p(0) + (p(1) - p(0)) * u + (p(2) - p(0)) * v;
        (
            x.extend(0.0).to_array(),
            Vec3::from(t[0].normal).extend(0.0).to_array(),
        )
    };
    (0..count)
        .map(|i| {
            let ((x, n), (xp, mut np)) = (point(), point());
            if i % 5 == 0 {
                np = [0.0; 4];
            }
            Segment { x, n, xp, np }
        })
        .collect()
}

#[test]
fn the_gpu_walks_the_grid_as_the_cpu_does() {
    let scene = Scene::load(&scenes_dir().join("leak.toml")).unwrap();
    let cases = segments(&scene, 4096);
    let grids = [1, 2].map(|levels| OccupancyGrid::with_levels(&scene.triangles, 48, levels));
    let gpu = walks_on_the_gpu(&grids, &cases);
    for (grid, gpu) in grids.iter().zip(gpu) {
        let levels = if grid.is_two_level() { 2 } else { 1 };
        let cpu: Vec<Walk> = cases
            .iter()
            .map(|s| {
                let v = |a: [f32; 4]| Vec3::from_slice(&a[..3]);
                grid.walk(v(s.x), v(s.n), v(s.xp), v(s.np))
            })
            .collect();
        let count = |answer| cpu.iter().filter(|w| w.visible == answer).count();
        let (visible, unknown) = (count(Some(true)), count(None));
        let differ = cpu
            .iter()
            .zip(&gpu)
            .filter(|(a, b)| (a.visible, a.fetches, a.steps) != **b)
            .count();
        let fetches: u32 = cpu.iter().map(|w| w.fetches).sum();
        let cells: u32 = cpu.iter().map(|w| w.cells).sum();
        let steps: u32 = cpu.iter().map(|w| w.steps).sum();
        println!(
            "{levels} levels: of {} segments on the CPU {visible} visible, {unknown} unknown; \
             the GPU differs on {differ} (answer, fetches or steps); {fetches} words fetched \
             and {steps} steps for {cells} cells crossed",
            cases.len()
        );
        // a word a brick (and a half of a set cell's sub-cells): a walk crossing several
        // cells of a word reads it once
        assert!(
            fetches * 2 <= cells,
            "{levels} levels: {fetches} words fetched for {cells} cells"
        );
        // (points on the boxes' thin edges start inside the box beside them)
        assert!(
            unknown < cases.len() / 2,
            "{levels} levels: {unknown} unknown"
        );
        // both answers are common (a tenth of the segments are visible: most join points on
        // the boxes' outer faces or in the other room), so that a walk that always says one of
        // them fails
        assert!(
            (cases.len() / 20..cases.len() * 19 / 20).contains(&visible),
            "{levels} levels: {visible}"
        );
        // a tie at a cell's corner may go either way in floating point
        assert!(
            differ * 1000 <= cases.len(),
            "{levels} levels: {differ} differ"
        );
    }
}
