//! The harness on the adapter the suite runs on (lavapipe): a clear texture reads back what was
//! written, and a timed pass yields a plausible median; and that adapter is the software one the
//! suite documents, unless a hardware one is explicitly allowed.

use quadray_gpu::{Gpu, GpuTimer, cleared_attachment, read_texture_rgba8, texture_2d};

/// Set to run the suite on a hardware adapter: its tolerances and figures are lavapipe's.
const ANY_ADAPTER: &str = "QUADRAY_TEST_ANY_ADAPTER";

#[test]
fn the_suite_runs_on_lavapipe() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let name = gpu.adapter.get_info().name;
    let lavapipe = gpu.is_software() && name.contains("llvmpipe");
    assert!(
        lavapipe || std::env::var_os(ANY_ADAPTER).is_some(),
        "the GPU tests opened {}, not Mesa's software Vulkan driver (lavapipe, `llvmpipe`) whose \
         results the suite and BENCHMARKS.md document: run scripts/setup.sh and pick it with \
         WGPU_ADAPTER_NAME=llvmpipe, or set {ANY_ADAPTER}=1 to run the suite on this adapter",
        gpu.describe()
    );
}

#[test]
fn clear_reads_back_and_timestamps_time_the_pass() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let texture = texture_2d(
        &gpu.device,
        "target",
        (70, 3),
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let view = texture.create_view(&Default::default());
    let mut timer = GpuTimer::new(&gpu, 1);
    for _ in 0..5 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear"),
            color_attachments: &[cleared_attachment(&view, wgpu::Color::RED)],
            timestamp_writes: timer.render_pass(0),
            ..Default::default()
        });
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        timer.collect(&gpu).unwrap();
    }
    let pixels = read_texture_rgba8(&gpu, &texture).unwrap();
    assert_eq!(pixels.len(), 70 * 3 * 4);
    assert!(pixels.chunks(4).all(|p| p == [255, 0, 0, 255]));
    if gpu.has_timestamps {
        let summary = timer.summaries()[0].expect("five timed frames");
        // Clearing 70x3 texels: a few microseconds to a millisecond; a wrong timestamp period or
        // begin/end pair shows up as a tiny or a huge figure.
        assert!(
            summary.median_ms > 1e-4 && summary.median_ms < 50.0,
            "median {} ms",
            summary.median_ms
        );
        assert!(
            (1..=5).contains(&summary.samples),
            "{} samples",
            summary.samples
        );
        assert!(summary.p10_ms <= summary.median_ms && summary.median_ms <= summary.p90_ms);
    }
}
