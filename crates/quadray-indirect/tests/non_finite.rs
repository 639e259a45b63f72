//! NaN, infinities and zero normals in a caller's G-buffer and RSM (the scene loaders refuse such
//! geometry, the public passes take whatever textures they are given): the frame ends, a bad
//! texel acts exactly as an empty one, and nothing non-finite reaches any pixel.

use quadray_gpu::{Gpu, read_buffer, read_texture_f32, texture_2d};
use quadray_indirect::reference::compare;
use quadray_indirect::{
    DirectLight, FLOAT_FORMAT, GBufferLayout, GBufferViews, Gather, LightQuadtree, LightView,
    Method, OutputPass, OutputTerm, Renderer, RsmPass, RsmViews, Scene, Settings, ViewMaps,
};
use wgpu::util::DeviceExt;

const NAN: f32 = f32::NAN;
const INF: f32 = f32::INFINITY;

/// G-buffer texels made bad: (x, y, position, normal); (16, 16) is a corner of its tile, whose
/// receiver the per-tile cuts' shared clusters are gathered at.
const BAD_RECEIVERS: [(u32, u32, [f32; 3], [f32; 3]); 6] = [
    (10, 20, [NAN, 0.5, 0.5], [0.0, 1.0, 0.0]),
    (50, 12, [0.5, INF, 0.5], [0.0, 1.0, 0.0]),
    (22, 33, [0.5, 0.5, 0.5], [NAN, NAN, NAN]),
    (30, 30, [0.5, 0.5, 0.5], [0.0, 0.0, 0.0]),
    (45, 50, [0.5, 0.5, 0.5], [0.0, 0.0, 0.0]),
    (16, 16, [0.5, 0.5, 0.5], [0.0, 0.0, 0.0]),
];

/// Three textures' texels, row-major: a G-buffer (position, normal, albedo) or an RSM (flux,
/// position, normal).
type Texels = [Vec<[f32; 4]>; 3];

fn settings() -> Settings {
    Settings {
        samples: 64,
        ..Settings::sized(64, 64, 32)
    }
}

/// The scene's G-buffer (from quadray's own renderer, read back) and its RSM.
fn clean_inputs(gpu: &Gpu, scene: &Scene) -> (Texels, Texels) {
    let (d, q) = (&gpu.device, &gpu.queue);
    let s = settings();
    let mut renderer = Renderer::new(gpu, scene, s.clone()).unwrap();
    renderer.render_frame(Method::Quadtree).unwrap();
    let texel = |v: [f32; 3], w: f32| [v[0], v[1], v[2], w];
    let receivers = renderer.read_receivers().unwrap();
    let gbuffer = [0, 1, 2].map(|k| {
        receivers
            .iter()
            .map(|r| {
                r.map_or([0.0; 4], |r| {
                    texel([r.position, r.normal, r.albedo][k], 1.0)
                })
            })
            .collect()
    });
    // the wide layout, whose three targets the inputs copy
    let wide = Settings {
        gbuffer_layout: GBufferLayout::Wide,
        ..s.clone()
    };
    let rsm = RsmPass::new(d, &wide);
    rsm.set_light(q, &LightView::of_scene(scene, 1)[0]);
    let vertices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("vertices"),
        contents: bytemuck::cast_slice(&scene.triangles),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let mut encoder = d.create_command_encoder(&Default::default());
    rsm.record(
        &mut encoder,
        vertices.slice(..),
        scene.triangles.len() as u32 * 3,
        None,
    );
    gpu.submit("rsm", encoder.finish());
    let rsm = [0, 1, 2].map(|k| {
        let floats = read_texture_f32(gpu, &rsm.textures()[k], 0, 4).unwrap();
        floats
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    });
    (gbuffer, rsm)
}

/// The public passes on input textures of the caller's (a G-buffer and an RSM), made once for
/// every frame of a test: their pipelines are the costliest part of a frame on lavapipe.
struct Passes {
    gbuffer: [wgpu::Texture; 3],
    rsm: [wgpu::Texture; 3],
    quadtree: LightQuadtree,
    gather: Gather,
    /// The direct light, its shadow maps drawn from the scene's triangles.
    direct: DirectLight,
    vertices: (wgpu::Buffer, u32),
    output: wgpu::Texture,
    output_pass: OutputPass,
}

impl Passes {
    fn new(gpu: &Gpu, scene: &Scene) -> Self {
        let (d, q) = (&gpu.device, &gpu.queue);
        let s = settings();
        let size = (s.size.width, s.size.height);
        let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
        let inputs = |size| [0, 1, 2].map(|_| texture_2d(d, "input", size, FLOAT_FORMAT, usage));
        let (gbuffer, rsm) = (inputs(size), inputs((s.rsm_size, s.rsm_size)));
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let ([g_pos, g_normal, g_albedo], [flux, position, normal]) =
            (gbuffer.each_ref().map(view), rsm.each_ref().map(view));
        let rsm_views = RsmViews::Wide {
            flux: &flux,
            position: &position,
            normal: &normal,
        };
        let gbuffer_views = GBufferViews::Wide {
            position: &g_pos,
            normal: &g_normal,
            albedo: &g_albedo,
        };
        let quadtree = LightQuadtree::new(d, q, s.rsm_size, s.cluster, rsm_views);
        let maps = [ViewMaps {
            rsm: rsm_views,
            quadtree: &quadtree,
        }];
        let gather = Gather::new(d, &s, &maps, gbuffer_views).unwrap();
        let lights = LightView::of_scene(scene, 1);
        gather.set_lights(q, &lights, scene.r_min);
        let aspect = size.0 as f32 / size.1 as f32;
        let view_proj = scene.camera_view_proj(aspect);
        gather.set_camera(q, view_proj, scene.camera.position);
        let direct = DirectLight::new(d, &gather);
        direct.set_lights(q, &lights, view_proj, scene.bounds());
        let vertices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vertices"),
            contents: bytemuck::cast_slice(&scene.triangles),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let output = texture_2d(
            d,
            "output",
            size,
            FLOAT_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
        );
        let output_pass = OutputPass::new(d, FLOAT_FORMAT, OutputTerm::Combined).unwrap();
        Self {
            gbuffer,
            rsm,
            quadtree,
            gather,
            direct,
            vertices: (vertices, scene.triangles.len() as u32 * 3),
            output,
            output_pass,
        }
    }

    /// One frame of `method` on the caller's `gbuffer` and `rsm`: the indirect light (rgb) and
    /// the combined radiance the output pass writes (rgb).
    fn frame(
        &self,
        gpu: &Gpu,
        gbuffer: &Texels,
        rsm: &Texels,
        method: Method,
    ) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        let d = &gpu.device;
        for (texture, texels) in self
            .gbuffer
            .iter()
            .chain(&self.rsm)
            .zip(gbuffer.iter().chain(rsm))
        {
            gpu.queue.write_texture(
                texture.as_image_copy(),
                bytemuck::cast_slice(texels),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(texture.width() * 16),
                    rows_per_image: None,
                },
                texture.size(),
            );
        }
        let mut encoder = d.create_command_encoder(&Default::default());
        self.quadtree.record_build(&mut encoder, None);
        self.quadtree.record_cut(&mut encoder, None);
        self.gather
            .record_indirect(&mut encoder, method, &[&self.quadtree], None);
        let (vertices, count) = &self.vertices;
        self.direct
            .record_shadow_maps(&mut encoder, vertices.slice(..), *count, None);
        self.direct.record(&mut encoder, &self.gather, None);
        self.output_pass.record(
            d,
            &mut encoder,
            &self.gather,
            &self.output.create_view(&Default::default()),
        );
        gpu.submit(format!("{method} on bad inputs"), encoder.finish());
        // the waits are bounded: a frame that never ends fails here
        let indirect: Vec<[f32; 4]> =
            bytemuck::pod_collect_to_vec(&read_buffer(gpu, self.gather.indirect()).unwrap());
        let combined = read_texture_f32(gpu, &self.output, 0, 4).unwrap();
        (
            indirect.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            combined
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
        )
    }
}

/// Pixels with a non-finite channel.
fn non_finite(image: &[[f32; 3]]) -> usize {
    image
        .iter()
        .filter(|p| p.iter().any(|c| !c.is_finite()))
        .count()
}

/// Pixels whose value differs between two images beyond float noise (1e-5 of the pixel's value,
/// or 1e-7 of the brightest): the compacted cut's clusters are appended by atomics, so their
/// order, and the sums' rounding, change from run to run.
fn differing(a: &[[f32; 3]], b: &[[f32; 3]]) -> Vec<usize> {
    let peak = b.iter().flatten().fold(0f32, |m, &v| m.max(v.abs()));
    let noise = |v: f32| 1e-5 * v.abs() + 1e-7 * peak;
    (0..a.len())
        .filter(|&i| {
            (0..3).any(|c| {
                let d = (a[i][c] - b[i][c]).abs();
                d.is_nan() || d > noise(b[i][c])
            })
        })
        .collect()
}

/// The G-buffer with each of [`BAD_RECEIVERS`]' texels made bad, or cleared (no geometry).
fn with_receivers(gbuffer: &Texels, width: u32, bad: bool) -> Texels {
    let mut out = gbuffer.clone();
    for (x, y, position, normal) in BAD_RECEIVERS {
        let i = (y * width + x) as usize;
        assert_eq!(gbuffer[0][i][3], 1.0, "({x}, {y}) must see geometry");
        if bad {
            out[0][i] = [position[0], position[1], position[2], 1.0];
            out[1][i] = [normal[0], normal[1], normal[2], 1.0];
        } else {
            for texture in &mut out {
                texture[i] = [0.0; 4];
            }
        }
    }
    out
}

/// Every method on a G-buffer with NaN and infinite positions, NaN and zero normals: the frame
/// is exactly the one where those texels see no geometry, so no NaN leaves them; the methods that
/// shade each pixel on its own change no other pixel than the bad ones, the per-tile cuts only
/// pixels of the bad ones' tiles (whose cut, boxes and shared clusters they were part of).
#[test]
fn bad_g_buffer_texels_act_as_empty_ones_and_change_no_other_pixel() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let scene = Scene::cornell();
    let width = settings().size.width;
    let (gbuffer, rsm) = clean_inputs(&gpu, &scene);
    let bad = with_receivers(&gbuffer, width, true);
    let cleared = with_receivers(&gbuffer, width, false);
    let bad_pixels: Vec<usize> = BAD_RECEIVERS
        .iter()
        .map(|&(x, y, ..)| (y * width + x) as usize)
        .collect();
    let tile_of = |i: usize| (i as u32 % width / 8, i as u32 / width / 8);
    // a tile shares its list, and the deblocking filter reaches half a tile past it
    let shared_with = |b: usize, i: usize| {
        let ((tx, ty), (x, y)) = (tile_of(b), (i as u32 % width, i as u32 / width));
        let near = |t: u32, v: u32| (t * 8).saturating_sub(4) <= v && v < t * 8 + 12;
        near(tx, x) && near(ty, y)
    };
    let passes = Passes::new(&gpu, &scene);
    for method in Method::ALL {
        let (clean_indirect, clean_combined) = passes.frame(&gpu, &gbuffer, &rsm, method);
        let (indirect, combined) = passes.frame(&gpu, &bad, &rsm, method);
        let (empty_indirect, empty_combined) = passes.frame(&gpu, &cleared, &rsm, method);
        let changed = differing(&indirect, &clean_indirect);
        let elsewhere: Vec<usize> = match method {
            Method::QuadtreeTiles => changed
                .iter()
                .copied()
                .filter(|&i| bad_pixels.iter().all(|&b| !shared_with(b, i)))
                .collect(),
            _ => changed
                .iter()
                .copied()
                .filter(|i| !bad_pixels.contains(i))
                .collect(),
        };
        let kept: Vec<usize> = (0..indirect.len())
            .filter(|i| !bad_pixels.contains(i))
            .collect();
        let pick = |image: &[[f32; 3]]| kept.iter().map(|&i| image[i]).collect::<Vec<_>>();
        let error = compare(&pick(&combined), &pick(&clean_combined));
        println!(
            "{method}: {} bad texels, {} non-finite pixels, {} pixels changed ({} outside what \
             the method shares), rel L1 {:.2e} and rel max {:.2e} over the other pixels",
            bad_pixels.len(),
            non_finite(&indirect) + non_finite(&combined),
            changed.len(),
            elsewhere.len(),
            error.rel_l1,
            error.rel_max,
        );
        assert_eq!(
            (non_finite(&indirect), non_finite(&combined)),
            (0, 0),
            "{method}: non-finite pixels"
        );
        assert!(
            differing(&indirect, &empty_indirect).is_empty()
                && differing(&combined, &empty_combined).is_empty(),
            "{method}: bad texels must shade as empty ones"
        );
        assert!(
            elsewhere.is_empty(),
            "{method}: pixels {elsewhere:?} changed, away from every bad texel"
        );
    }
}

/// Every method on an RSM with NaN and infinite flux, a NaN position and a zero normal among its
/// lit texels: the indirect light is exactly that of the RSM with those texels cleared (no VPL
/// there), and no pixel of the frame is non-finite.
#[test]
fn bad_rsm_texels_act_as_empty_ones() {
    let gpu = Gpu::new().expect("an adapter (run scripts/setup.sh for lavapipe)");
    let scene = Scene::cornell();
    let (gbuffer, rsm) = clean_inputs(&gpu, &scene);
    let lit: Vec<usize> = (0..rsm[2].len()).filter(|&i| rsm[2][i][3] > 0.5).collect();
    // four lit texels spread over the RSM: NaN flux, infinite flux, NaN position, zero normal
    let picked = [0, 1, 2, 3].map(|k| lit[lit.len() * (2 * k + 1) / 8]);
    let mut bad = rsm.clone();
    bad[0][picked[0]][0] = NAN;
    bad[0][picked[1]][1] = INF;
    bad[1][picked[2]][2] = NAN;
    bad[2][picked[3]] = [0.0, 0.0, 0.0, 1.0];
    let mut cleared = rsm.clone();
    for &i in &picked {
        for texture in &mut cleared {
            texture[i] = [0.0; 4];
        }
    }
    let passes = Passes::new(&gpu, &scene);
    for method in Method::ALL {
        let (indirect, combined) = passes.frame(&gpu, &gbuffer, &bad, method);
        let (empty_indirect, _) = passes.frame(&gpu, &gbuffer, &cleared, method);
        let (clean_indirect, _) = passes.frame(&gpu, &gbuffer, &rsm, method);
        let error = compare(&indirect, &clean_indirect);
        println!(
            "{method}: {} of {} lit RSM texels bad: {} non-finite pixels, rel L1 {:.2e} against the clean RSM",
            picked.len(),
            lit.len(),
            non_finite(&indirect) + non_finite(&combined),
            error.rel_l1,
        );
        assert_eq!(
            (non_finite(&indirect), non_finite(&combined)),
            (0, 0),
            "{method}: non-finite pixels"
        );
        assert!(
            differing(&indirect, &empty_indirect).is_empty(),
            "{method}: bad RSM texels must light as empty ones"
        );
    }
}
