//! `quadray smoke`: every GPU pass of every technique at a tiny size, one at a time, each
//! submitted alone and waited for within the bound, then the frame as quadray times it (one
//! submission, timestamp queries); one line each (`done` and its wall time, or the error naming
//! where it stopped). The first minutes on a new GPU: a pass that hangs or
//! faults costs seconds and is named. `scripts/gpu-tables.sh` runs each case in its own process
//! (`--case`), under its own timeout, with the validation layer where the machine has it.

use anyhow::{Context, Result};
use clap::Args;
use quadray_displace::gpu::PyramidBuilder;
use quadray_displace::maps::BUNDLED;
use quadray_displace::pyramid::Addressing;
use quadray_displace::{Lod, PyramidKind, Renderer as DisplaceRenderer};
use quadray_gpu::Gpu;
use quadray_indirect::scene::{Intensity, Light, LightKind};
use quadray_indirect::{
    Method as IndirectMethod, Renderer as IndirectRenderer, Scene, Settings, TilePasses,
};
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct SmokeArgs {
    /// Print the case names, one a line, and exit.
    #[arg(long)]
    list: bool,
    /// Run only this case (default: every case in this process, stopping at the first error).
    #[arg(long)]
    case: Option<String>,
    /// The frames' side in pixels.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(8..=256))]
    size: u32,
}

/// Told each pass that finished and its wall time.
type Done<'a> = &'a mut dyn FnMut(&str, Duration);

/// A case's work: its passes on a GPU at a frame side.
type CaseRun = Box<dyn Fn(&Gpu, u32, Done) -> Result<()>>;

/// One case: a technique's passes with one configuration.
struct Case {
    name: String,
    run: CaseRun,
}

/// A variant of the indirect settings.
type Change = fn(&mut Settings);

/// The one cut's indirect shadows from corners every 4 pixels, interleaved at 2.
fn with_corners(s: &mut Settings) {
    s.indirect_shadows = true;
    s.shadow_corners = Some(4);
    s.interleave = 2;
}

fn cases() -> Vec<Case> {
    let mut cases = vec![Case {
        name: "displace-pyramid-build".into(),
        run: Box::new(|gpu, _, done| pyramid_build(gpu, done)),
    }];
    for method in quadray_displace::Method::ALL {
        cases.push(Case {
            name: format!("displace-{}", method.name()),
            run: Box::new(move |gpu, size, done| {
                displace_frame(gpu, size, method, Lod::Level(0), false, done)
            }),
        });
    }
    for (name, lod, shadows) in [
        ("lod-auto", Lod::Auto, false),
        ("shadows", Lod::Level(0), true),
    ] {
        cases.push(Case {
            name: format!("displace-pyramid-{name}"),
            run: Box::new(move |gpu, size, done| {
                let method = quadray_displace::Method::Pyramid;
                displace_frame(gpu, size, method, lod, shadows, done)
            }),
        });
    }
    for method in IndirectMethod::ALL {
        cases.push(Case {
            name: format!("indirect-{method}"),
            run: Box::new(move |gpu, size, done| {
                indirect_passes(gpu, size, &Scene::cornell(), method, |_| {}, done)
            }),
        });
    }
    let variants: [(&str, IndirectMethod, Change); 4] = [
        // the occupancy grid walked (the depth maps marched where it cannot tell)
        ("indirect-shadows", IndirectMethod::DEFAULT, |s| {
            s.indirect_shadows = true
        }),
        // the one cut's shadows from corner receivers, interleaved (its rejoin recomputes some
        // pixels from their own walks)
        (
            "indirect-shadow-corners",
            IndirectMethod::Quadtree,
            with_corners,
        ),
        // the depth maps marched alone
        ("indirect-shadows-march", IndirectMethod::Quadtree, |s| {
            s.indirect_shadows = true;
            s.shadow_grid = 0;
        }),
        ("indirect-subsample", IndirectMethod::Rsm, |s| {
            s.subsample = 2
        }),
    ];
    for (name, method, change) in variants {
        cases.push(Case {
            name: name.into(),
            run: Box::new(move |gpu, size, done| {
                indirect_passes(gpu, size, &Scene::cornell(), method, change, done)
            }),
        });
    }
    // eight light views summed: the spot's, the sun's orthographic map, a point light's six faces
    let lights: [(&str, IndirectMethod, Change); 4] = [
        ("indirect-lights", IndirectMethod::DEFAULT, |_| {}),
        // the per-tile cuts' split passes, lists, walks and sums, each view's after the last's,
        // sixteen tiles' walks a workgroup
        (
            "indirect-lights-shadows-split",
            IndirectMethod::DEFAULT,
            |s| {
                s.indirect_shadows = true;
                s.tile_passes = TilePasses::Split;
                s.tile_walk_lanes = 4;
            },
        ),
        // a corners' pass a light view, each before its view's sum, eight corners a workgroup
        (
            "indirect-lights-shadow-corners",
            IndirectMethod::Quadtree,
            |s| {
                with_corners(s);
                s.shadow_corner_lanes = 8;
            },
        ),
        ("indirect-lights-subsample", IndirectMethod::Quadtree, |s| {
            s.subsample = 2
        }),
    ];
    for (name, method, change) in lights {
        cases.push(Case {
            name: name.into(),
            run: Box::new(move |gpu, size, done| {
                indirect_passes(gpu, size, &three_lights(), method, change, done)
            }),
        });
    }
    cases.push(Case {
        name: "indirect-temporal".into(),
        run: Box::new(indirect_temporal),
    });
    cases.push(Case {
        name: "indirect-output".into(),
        run: Box::new(indirect_output),
    });
    cases.push(Case {
        name: "indirect-cut-view".into(),
        run: Box::new(indirect_cut_view),
    });
    cases
}

pub fn run(args: SmokeArgs) -> Result<()> {
    let cases = cases();
    if args.list {
        for case in &cases {
            println!("{}", case.name);
        }
        return Ok(());
    }
    let chosen: Vec<&Case> = match &args.case {
        Some(name) => vec![cases.iter().find(|c| &c.name == name).with_context(|| {
            format!("no smoke case `{name}` (`quadray smoke --list` names them)")
        })?],
        None => cases.iter().collect(),
    };
    let gpu = Gpu::new()?;
    println!(
        "{} (waits bounded at {:?})",
        gpu.describe(),
        gpu.wait_bound()
    );
    for case in chosen {
        let start = Instant::now();
        let mut done = |pass: &str, took: Duration| {
            println!(
                "{}/{pass}: done in {:.1} ms",
                case.name,
                took.as_secs_f64() * 1e3
            );
        };
        if let Err(e) = (case.run)(&gpu, args.size, &mut done) {
            println!(
                "{}: stopped after {:.1} s: {e:#}",
                case.name,
                start.elapsed().as_secs_f64()
            );
            return Err(e.context(format!("smoke case {}", case.name)));
        }
    }
    Ok(())
}

/// Times `f` and reports it as `pass`.
fn step<T>(done: Done, pass: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let start = Instant::now();
    let out = f()?;
    done(pass, start.elapsed());
    Ok(out)
}

/// The bundled tiles map at 256^2: every pass runs as on the full map, the mesh baseline's grid
/// in seconds on a software rasterizer.
fn tiles_map() -> Result<quadray_displace::heightmap::HeightMap> {
    Ok(quadray_displace::maps::resized(&BUNDLED[0].load()?, 256))
}

/// The GPU pyramid build of the bundled map, both kinds, each submitted alone.
fn pyramid_build(gpu: &Gpu, done: Done) -> Result<()> {
    let map = tiles_map()?;
    let builder = PyramidBuilder::new(&gpu.device);
    for (name, kind) in [
        ("point", PyramidKind::Point),
        (
            "conservative-wrap",
            PyramidKind::Conservative(Addressing::Wrap),
        ),
        (
            "conservative-clamp",
            PyramidKind::Conservative(Addressing::Clamp),
        ),
    ] {
        step(done, name, || {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            gpu.checked(|| {
                builder.record(&gpu.device, &gpu.queue, &mut encoder, &map, kind, None)
            })?;
            gpu.submit(
                format!(
                    "the {name} pyramid build of a {}x{} map",
                    map.width, map.height
                ),
                encoder.finish(),
            );
            Ok(gpu.wait("the pyramid build")?)
        })?;
    }
    step(done, "timed", || {
        let mut timer = quadray_gpu::GpuTimer::new(gpu, 1);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let writes = timer.compute_pass(0);
        let kind = PyramidKind::Point;
        gpu.checked(|| builder.record(&gpu.device, &gpu.queue, &mut encoder, &map, kind, writes))?;
        timer.resolve(&mut encoder);
        gpu.submit("a timed pyramid build", encoder.finish());
        Ok(timer.collect(gpu)?)
    })?;
    Ok(())
}

/// One displacement frame of `method`: the renderer's setup (its pyramid builds), then the frame
/// and its read-backs.
fn displace_frame(
    gpu: &Gpu,
    size: u32,
    method: quadray_displace::Method,
    lod: Lod,
    shadows: bool,
    done: Done,
) -> Result<()> {
    let bundled = &BUNDLED[0];
    let map = tiles_map()?;
    let color = bundled.load_color()?;
    let mut renderer = step(done, "setup", || {
        let renderer = DisplaceRenderer::new(gpu, &map, color.as_ref(), bundled.surface);
        gpu.wait("the renderer's pyramid builds")?;
        Ok(renderer)
    })?;
    if method == quadray_displace::Method::Cone {
        step(done, "cone-map", || {
            renderer.build_cone_map(gpu, || {});
            Ok(gpu.wait("the cone map's upload")?)
        })?;
    }
    let settings = quadray_displace::Settings {
        method,
        size: quadray_displace::Size::new(size, size),
        lod,
        shadows,
        ..quadray_displace::Settings::DEFAULT
    };
    step(done, "frame", || Ok(renderer.render(gpu, &settings)?))?;
    step(done, "timed", || Ok(renderer.time(gpu, &settings, 1)?))?;
    Ok(())
}

fn indirect_settings(size: u32, change: impl Fn(&mut Settings)) -> Settings {
    let mut settings = Settings {
        size: quadray_indirect::Size::new(size, size),
        rsm_size: size.next_power_of_two(),
        ..Settings::DEFAULT
    };
    change(&mut settings);
    settings
}

/// The Cornell box lit by its spot, a point light and the sun.
fn three_lights() -> Scene {
    let mut scene = Scene::cornell();
    let white = |v: f32| Intensity::Native(glam::Vec3::splat(v));
    scene.lights.extend([
        Light {
            kind: LightKind::Point {
                position: glam::Vec3::new(0.75, 0.55, 0.7),
            },
            intensity: white(0.4),
        },
        Light {
            kind: LightKind::Directional {
                direction: glam::Vec3::new(-0.25, -0.5, -1.0),
            },
            intensity: white(1.0),
        },
    ]);
    scene
}

/// One indirect frame of `method` on `scene`, pass by pass, then its read-back.
fn indirect_passes(
    gpu: &Gpu,
    size: u32,
    scene: &Scene,
    method: IndirectMethod,
    change: impl Fn(&mut Settings),
    done: Done,
) -> Result<()> {
    let settings = indirect_settings(size, change);
    let mut renderer = step(done, "setup", || {
        Ok(IndirectRenderer::new(gpu, scene, settings)?)
    })?;
    renderer.render_pass_by_pass(method, |pass, took| done(pass.name(), took))?;
    step(done, "readback", || Ok(renderer.read_frame()?))?;
    // the frames as quadray times them: one encoder, every pass's timestamps resolved
    step(done, "timed", || Ok(renderer.time(method, true, 2)?))?;
    Ok(())
}

/// The temporal filter with a moving camera and light: three frames of the default method.
fn indirect_temporal(gpu: &Gpu, size: u32, done: Done) -> Result<()> {
    let mut scene = Scene::cornell();
    let settings = indirect_settings(size, |s| s.temporal_weight = 0.5);
    let mut renderer = step(done, "setup", || {
        Ok(IndirectRenderer::new(gpu, &scene, settings)?)
    })?;
    for frame in 0..3 {
        step(done, &format!("frame-{frame}"), || {
            renderer.render(IndirectMethod::DEFAULT, true, false)?;
            Ok(renderer.read_frame()?)
        })?;
        scene = scene.light_turned(3.0).camera_orbited(3.0);
        renderer.set_view(&scene)?;
    }
    Ok(())
}

/// The output pass into a caller's texture of each format it writes, after a frame.
fn indirect_output(gpu: &Gpu, size: u32, done: Done) -> Result<()> {
    let scene = Scene::cornell();
    let settings = indirect_settings(size, |_| {});
    let mut renderer = step(done, "setup", || {
        Ok(IndirectRenderer::new(gpu, &scene, settings)?)
    })?;
    step(done, "frame", || {
        Ok(renderer.render_frame(IndirectMethod::DEFAULT)?)
    })?;
    for format in [
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Rgba16Float,
        wgpu::TextureFormat::Rgba8Unorm,
    ] {
        step(done, &format!("{format:?}"), || {
            let pass = quadray_indirect::OutputPass::new(
                &gpu.device,
                format,
                quadray_indirect::OutputTerm::Combined,
            )?;
            let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC;
            let texture =
                quadray_gpu::texture_2d(&gpu.device, "output", (size, size), format, usage);
            let view = texture.create_view(&Default::default());
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            gpu.checked(|| pass.record(&gpu.device, &mut encoder, renderer.gather(), &view))?;
            gpu.submit(format!("the output pass into {format:?}"), encoder.finish());
            Ok(gpu.wait("the output pass")?)
        })?;
    }
    Ok(())
}

/// The cut view: the one cut and a tile's cut drawn over the RSM.
fn indirect_cut_view(gpu: &Gpu, size: u32, done: Done) -> Result<()> {
    let scene = Scene::cornell();
    let settings = indirect_settings(size, |_| {});
    let mut renderer = step(done, "setup", || {
        Ok(IndirectRenderer::new(gpu, &scene, settings)?)
    })?;
    step(done, "cut", || {
        renderer.build_cut()?;
        let cut = renderer.read_cut()?;
        Ok(renderer.cut_view(&cut)?)
    })?;
    step(done, "tile-cut", || {
        renderer.render(IndirectMethod::DEFAULT, true, false)?;
        let cut = renderer.read_tile_cut_at(size / 2, size / 2)?;
        Ok(renderer.cut_view(&cut)?)
    })?;
    Ok(())
}
