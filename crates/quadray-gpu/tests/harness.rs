//! The harness on whatever adapter the machine has (lavapipe in CI): a clear texture reads back
//! what was written, and a timed pass yields a positive median.

use quadray_gpu::{Gpu, GpuTimer, cleared_attachment, read_texture_rgba8, texture_2d};

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
        assert!(summary.median_ms >= 0.0 && summary.samples >= 1);
    }
}
