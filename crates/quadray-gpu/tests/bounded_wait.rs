//! Every wait on the GPU is bounded: a shader that never finishes makes [`Gpu::wait`] return an
//! error naming the work, the adapter and the bound, within the bound, and the process still
//! exits. The stalling GPU work runs in a child process (this test binary again), so that the
//! suite's own device stays healthy.

use quadray_gpu::{Gpu, GpuError, GpuTimer, ResolveEncoder, WAIT_BOUND_ENV};
use std::io::Read;
use std::ops::Range;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Set in the child that runs the stalling shader.
const CHILD: &str = "QUADRAY_TEST_STALL_CHILD";
/// The bound the child waits with.
const BOUND_S: u64 = 2;

/// Years of work on any device: 2^32 workgroups of 64 invocations, each adding to one counter
/// 65,535 times. (Lavapipe ends every loop after 65,535 iterations, so one invocation cannot
/// run forever there, and it folds a loop of plain arithmetic away; atomics it keeps.)
const ENDLESS: &str = "
@group(0) @binding(0) var<storage, read_write> data: array<atomic<u32>>;
@compute @workgroup_size(64)
fn main() {
    let n = atomicLoad(&data[0]);
    for (var i = 0u; i < n; i++) {
        atomicAdd(&data[1], i);
    }
}";

/// The child: submits the endless shader, waits, prints the error, exits (dropping the device).
#[test]
#[ignore = "run by a_shader_that_never_ends_is_an_error_within_the_bound in a child process"]
fn stall_child() {
    if std::env::var_os(CHILD).is_none() {
        return;
    }
    let gpu = Gpu::new().unwrap();
    let module = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("endless"),
            source: wgpu::ShaderSource::Wgsl(ENDLESS.into()),
        });
    let pipeline = gpu
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("endless"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
    let data = wgpu::util::DeviceExt::create_buffer_init(
        &gpu.device,
        &wgpu::util::BufferInitDescriptor {
            label: Some("endless data"),
            contents: bytemuck::cast_slice(&[65_535u32, 0]),
            usage: wgpu::BufferUsages::STORAGE,
        },
    );
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: data.as_entire_binding(),
        }],
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(65_535, 65_535, 1);
    }
    gpu.submit("the endless test shader", encoder.finish());
    let start = Instant::now();
    let error = gpu.wait("the test's stall").unwrap_err();
    println!("after {:.2} s: {error}", start.elapsed().as_secs_f64());
    assert!(matches!(error, GpuError::Timeout { .. }));
    drop(gpu);
    println!("device dropped");
}

#[test]
fn a_shader_that_never_ends_is_an_error_within_the_bound() {
    let start = Instant::now();
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "bounded_wait::stall_child",
            "--ignored",
            "--nocapture",
        ])
        .env(CHILD, "1")
        .env(WAIT_BOUND_ENV, BOUND_S.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The child must exit on its own; a minute is the test's own bound.
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("the process did not exit within 60 s of a {BOUND_S} s bound");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let took = start.elapsed();
    let stdout = read_all(child.stdout.take());
    let stderr = read_all(child.stderr.take());
    assert!(status.success(), "{stdout}{stderr}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("after "))
        .unwrap_or_else(|| panic!("no error printed: {stdout}"));
    let waited: f64 = line[6..].split(' ').next().unwrap().parse().unwrap();
    assert!(
        (BOUND_S as f64 * 0.9..BOUND_S as f64 + 3.0).contains(&waited),
        "the error came after {waited} s, not at the {BOUND_S} s bound: {line}"
    );
    for part in [
        "did not finish the endless test shader within 2 s",
        "waited for: the test's stall",
        "llvmpipe",
        WAIT_BOUND_ENV,
    ] {
        assert!(line.contains(part), "`{part}` missing from: {line}");
    }
    assert!(stdout.contains("device dropped"), "{stdout}");
    println!(
        "{line}; the process exited after {:.1} s",
        took.as_secs_f64()
    );
}

#[test]
fn an_absurd_bound_is_refused_by_name() {
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "bounded_wait::bound_child",
            "--ignored",
            "--nocapture",
        ])
        .env(CHILD, "1")
        .env(WAIT_BOUND_ENV, "forever")
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = read_all(child.stdout.take());
    assert!(child.wait().unwrap().success(), "{stdout}");
    assert!(
        stdout.contains(
            "QUADRAY_GPU_WAIT_S=forever: the bound on a wait for the GPU is seconds in 0.1..86400"
        ),
        "{stdout}"
    );
}

#[test]
#[ignore = "run by an_absurd_bound_is_refused_by_name in a child process"]
fn bound_child() {
    if std::env::var_os(CHILD).is_some() {
        println!("{}", Gpu::new().err().expect("refused"));
    }
}

/// Only the passes given timestamp writes are resolved: resolving a query that no pass wrote
/// waits forever on NVIDIA's driver (wgpu's Vulkan backend copies with the wait flag), which is
/// how `quadray indirect` hung on an H200. wgpu's validation takes such a resolve, so the test
/// records the queries `resolve` encodes.
#[test]
fn the_timer_resolves_only_the_passes_that_wrote() {
    let gpu = Gpu::new().unwrap();
    assert!(
        gpu.has_timestamps,
        "{}: no timestamp queries",
        gpu.describe()
    );
    let timer = GpuTimer::new(&gpu, 4);
    let _ = timer.compute_pass(1);
    let _ = timer.render_pass(3);
    // a span's middle recording writes nothing: the pass is resolved once its end is written
    let _ = timer.span(true, false, || timer.compute_pass(2));
    assert_eq!(timer.passes_to_resolve(), [1, 3]);
    let mut recorded = ResolveRecorder::default();
    timer.resolve(&mut recorded);
    assert_eq!(recorded.queries, [2..4, 6..8]);
    assert!(timer.passes_to_resolve().is_empty());
    let mut again = ResolveRecorder::default();
    timer.resolve(&mut again);
    assert!(again.queries.is_empty(), "{:?}", again.queries);
}

/// The query ranges a [`GpuTimer::resolve`] records.
#[derive(Default)]
struct ResolveRecorder {
    queries: Vec<Range<u32>>,
}

impl ResolveEncoder for ResolveRecorder {
    fn resolve_query_set(
        &mut self,
        _: &wgpu::QuerySet,
        queries: Range<u32>,
        _: &wgpu::Buffer,
        _: u64,
    ) {
        self.queries.push(queries);
    }

    fn copy_buffer_to_buffer(
        &mut self,
        _: &wgpu::Buffer,
        _: u64,
        _: &wgpu::Buffer,
        _: u64,
        _: u64,
    ) {
    }
}

/// All that a child's pipe gives until it closes.
fn read_all(pipe: Option<impl Read>) -> String {
    let mut text = String::new();
    pipe.unwrap().read_to_string(&mut text).unwrap();
    text
}
