//! `OutputPass` into caller textures of every format it takes, against the radiance the gather
//! read back in f32 (the Rgba32Float path is the frame itself).

use quadray_gpu::{Gpu, read_buffer, texture_2d};
use quadray_indirect::{Method, OutputPass, OutputTerm, Renderer, Scene, Settings};

/// Writes the renderer's last frame into a fresh texture of `format` and reads it back as f32
/// (`texel_bytes` per texel, decoded by `decode`).
fn written(
    gpu: &Gpu,
    renderer: &Renderer,
    format: wgpu::TextureFormat,
    texel_bytes: u32,
    decode: impl Fn(&[u8]) -> f32,
) -> Vec<[f32; 4]> {
    let s = renderer.settings();
    let (d, q) = (&gpu.device, &gpu.queue);
    let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC;
    let texture = texture_2d(d, "output", (s.size.width, s.size.height), format, usage);
    let pass = OutputPass::new(d, format, OutputTerm::Combined).unwrap();
    let bytes_per_row = s.size.width * texel_bytes;
    assert_eq!(bytes_per_row % wgpu::COPY_BYTES_PER_ROW_ALIGNMENT, 0);
    let buffer = d.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: u64::from(bytes_per_row * s.size.height),
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = d.create_command_encoder(&Default::default());
    pass.record(
        d,
        &mut encoder,
        renderer.gather(),
        &texture.create_view(&Default::default()),
    );
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bytes_per_row),
                rows_per_image: None,
            },
        },
        texture.size(),
    );
    q.submit([encoder.finish()]);
    let bytes = read_buffer(gpu, &buffer).unwrap();
    let channel = (texel_bytes / 4) as usize;
    bytes
        .chunks_exact(texel_bytes as usize)
        .map(|t| std::array::from_fn(|c| decode(&t[c * channel..(c + 1) * channel])))
        .collect()
}

/// A format, its bytes per texel, its decoder, and the value and tolerance it should hold for an
/// f32 radiance.
type Case<'a> = (
    wgpu::TextureFormat,
    u32,
    &'a dyn Fn(&[u8]) -> f32,
    &'a dyn Fn(f32) -> (f32, f32),
);

#[test]
fn output_pass_writes_rgba16float_and_rgba8unorm_like_the_f32_frame() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let settings = Settings::sized(64, 48, 32);
    let mut renderer = Renderer::new(&gpu, &Scene::cornell(), settings).unwrap();
    let truth = renderer.render_frame(Method::Quadtree).unwrap().combined();
    let brightest = truth.iter().flatten().fold(0f32, |m, &v| m.max(v));
    assert!(brightest > 0.1, "the frame is lit ({brightest})");
    let half = |b: &[u8]| half::f16::from_le_bytes([b[0], b[1]]).to_f32();
    let unorm = |b: &[u8]| f32::from(b[0]) / 255.0;
    // f16: 11 significant bits, and Vulkan lets the conversion round or truncate, so one ulp
    // (at most 2^-10 of the value; subnormals near 0); unorm8: the clamped value to 1/255
    // (rounded: half a step).
    let cases: [Case; 2] = [
        (wgpu::TextureFormat::Rgba16Float, 8, &half, &|v| {
            (v, v.abs() / 1024.0 + 1e-7)
        }),
        (wgpu::TextureFormat::Rgba8Unorm, 4, &unorm, &|v| {
            (v.clamp(0.0, 1.0), 0.5 / 255.0 + 1e-6)
        }),
    ];
    for (format, texel_bytes, decode, expected) in cases {
        let pixels = written(&gpu, &renderer, format, texel_bytes, decode);
        assert_eq!(pixels.len(), truth.len());
        for (i, (got, want)) in pixels.iter().zip(&truth).enumerate() {
            for c in 0..3 {
                let (value, tolerance) = expected(want[c]);
                assert!(
                    (got[c] - value).abs() <= tolerance,
                    "{format:?} pixel {i} channel {c}: {} against {value}",
                    got[c]
                );
            }
            assert_eq!(got[3], 1.0, "{format:?} alpha at pixel {i}");
        }
    }
}
