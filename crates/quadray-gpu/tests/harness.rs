//! The harness on whatever adapter the machine has (lavapipe in CI): a clear texture reads back
//! what was written, and a timed pass yields a positive median.

use quadray_gpu::{Gpu, GpuTimer, read_texture_rgba8};

#[test]
fn clear_reads_back_and_timestamps_time_the_pass() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("target"),
        size: wgpu::Extent3d {
            width: 70,
            height: 3,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    let mut timer = GpuTimer::new(&gpu, 1);
    for _ in 0..5 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 1.0,
                        g: 0.0,
                        b: 0.0,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
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
