//! quadray's own renderer of a [`Scene`]: its triangles in a vertex buffer, its G-buffer, and
//! the public passes (an RSM and a light quadtree per light view, the gather summing them, the
//! direct light through a shadow map per light view) recorded in one encoder per frame, timed
//! per pass. The CLI, the viewer and the benchmarks render through it.

use crate::IndirectError;
use crate::direct::pass::DirectLight;
use crate::frame::{CutNode, Frame, FrameTiming, Pass, Receiver, Vpl, WorkCounts};
use crate::gathers::gather::Gather;
use crate::gathers::resources::ViewMaps;
use crate::gbuffer::GBufferPass;
use crate::light::node::{CutCounts, cut_class_capacity};
use crate::light::quadtree::LightQuadtree;
use crate::light::rsm::{RsmPass, TextureArray};
use crate::light::view::LightView;
use crate::method::Method;
use crate::picture::{cut_view, cut_view_zoom};
use crate::scene::Scene;
use crate::settings::{ClusterSettings, Settings, TILE};
use crate::shadows::occupancy::OccupancyGrid;
use crate::tiles::TILE_ENTRY_INDEX_BITS;
use quadray_core::image_out::Rgba8Image;
use quadray_gpu::{Gpu, GpuTimer};
use std::collections::BTreeMap;
use wgpu::util::DeviceExt;

/// One pass of a frame: which, and what it records into an encoder.
type FrameStep<'a> = (Pass, Box<dyn Fn(&mut wgpu::CommandEncoder) + 'a>);

/// One light view's passes: its RSM and the quadtree built from it.
struct ViewPasses {
    rsm: RsmPass,
    quadtree: LightQuadtree,
}

/// Everything one scene needs on the GPU at one set of sizes.
pub struct Renderer<'g> {
    gpu: &'g Gpu,
    settings: Settings,
    vertices: wgpu::Buffer,
    vertex_count: u32,
    /// One a light view of the scene's first [`Settings::max_lights`] lights.
    views: Vec<ViewPasses>,
    gbuffer: GBufferPass,
    gather: Gather,
    direct: DirectLight,
    /// The scene's bounds, which the sun's shadow map is fitted within.
    bounds: (glam::Vec3, glam::Vec3),
    /// A timer for all passes; `None` when the adapter has no timestamp queries.
    timer: GpuTimer,
}

impl<'g> Renderer<'g> {
    /// Uploads `scene` and builds every pass for `settings` (an RSM and a quadtree for each
    /// light view of the scene's first [`Settings::max_lights`] lights; a warning names the
    /// lights left out); refuses settings that make no picture with [`IndirectError::Settings`].
    pub fn new(gpu: &'g Gpu, scene: &Scene, settings: Settings) -> Result<Self, IndirectError> {
        settings.validate().map_err(IndirectError::Settings)?;
        let mut needs = Gather::limit_needs(&settings);
        needs.extend(DirectLight::limit_needs(&settings));
        needs.extend(TextureArray::limit_needs(&scene.textures));
        quadray_gpu::check_limits(&gpu.device.limits(), &gpu.describe(), &needs)?;
        let left_out = scene
            .lights
            .len()
            .saturating_sub(settings.max_lights as usize);
        if left_out > 0 {
            tracing::warn!(
                "scene {}: {left_out} of its {} lights left out (--max-lights {})",
                scene.name,
                scene.lights.len(),
                settings.max_lights
            );
        }
        let view_count = LightView::of_scene(scene, settings.max_lights).len();
        let (d, q) = (&gpu.device, &gpu.queue);
        let renderer = gpu.checked(|| {
            let textures = TextureArray::new(d, q, &scene.textures);
            let views: Vec<ViewPasses> = (0..view_count)
                .map(|_| {
                    let mut rsm = RsmPass::new(d, &settings);
                    rsm.set_textures(&textures);
                    let quadtree =
                        LightQuadtree::new(d, q, settings.rsm_size, settings.cluster, rsm.views());
                    ViewPasses { rsm, quadtree }
                })
                .collect();
            let size = (settings.size.width, settings.size.height);
            let gbuffer = GBufferPass::new(d, size, settings.gbuffer_layout, &textures);
            let maps: Vec<ViewMaps> = views
                .iter()
                .map(|v| ViewMaps {
                    rsm: v.rsm.views(),
                    quadtree: &v.quadtree,
                })
                .collect();
            let mut gather = Gather::new(d, &settings, &maps, gbuffer.views())?;
            if settings.indirect_shadows && settings.shadow_grid > 0 {
                let grid = OccupancyGrid::with_levels(
                    &scene.triangles,
                    settings.shadow_grid,
                    settings.shadow_grid_levels,
                );
                gather.set_occupancy(d, q, &grid, gbuffer.views());
            }
            let direct = DirectLight::new(d, &gather);
            let vertices = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("vertices"),
                contents: bytemuck::cast_slice(&scene.triangles),
                usage: wgpu::BufferUsages::VERTEX,
            });
            Ok::<_, IndirectError>(Self {
                gpu,
                settings: settings.clone(),
                vertices,
                vertex_count: (scene.triangles.len() * 3) as u32,
                views,
                gbuffer,
                gather,
                direct,
                bounds: scene.bounds(),
                timer: GpuTimer::new(gpu, Pass::ALL.len() as u32),
            })
        })??;
        renderer.set_view(scene)?;
        Ok(renderer)
    }

    /// The settings frames are rendered with.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Moves the camera and the lights to the scene's (its geometry must be the one the renderer
    /// was made with, its lights as many views: a light may move or turn, not change its kind);
    /// the next frame must `rebuild` if a light moved.
    pub fn set_view(&self, scene: &Scene) -> Result<(), IndirectError> {
        let q = &self.gpu.queue;
        let lights = LightView::of_scene(scene, self.settings.max_lights);
        if lights.len() != self.views.len() {
            return Err(IndirectError::Settings(format!(
                "the scene's lights make {} light views, the renderer was made for {}",
                lights.len(),
                self.views.len()
            )));
        }
        for (view, light) in self.views.iter().zip(&lights) {
            view.rsm.set_light(q, light);
        }
        self.gather.set_lights(q, &lights, scene.r_min);
        let s = self.settings();
        let view_proj = scene.camera_view_proj(s.size.width as f32 / s.size.height as f32);
        let eye = scene.camera.position;
        self.gbuffer.set_camera(q, view_proj, eye);
        self.gather.set_camera(q, view_proj, eye);
        self.direct.set_lights(q, &lights, view_proj, self.bounds);
        Ok(())
    }

    /// Changes the quadtree's parameters; the next frame with `rebuild` uses them.
    pub fn set_cluster(&mut self, cluster: ClusterSettings) -> Result<(), IndirectError> {
        let settings = Settings {
            cluster,
            ..self.settings().clone()
        };
        settings.validate().map_err(IndirectError::Settings)?;
        for view in &mut self.views {
            view.quadtree.set_cluster(&self.gpu.queue, cluster);
        }
        self.gather.reset_history();
        self.settings = settings;
        Ok(())
    }

    /// Renders one frame of `method`. With `rebuild` the light-dependent work (RSM, pyramid,
    /// validity, cut) is redone, as when the light moves; without it those buffers are reused.
    /// With `timed` the passes' GPU times are recorded.
    pub fn render(
        &mut self,
        method: Method,
        rebuild: bool,
        timed: bool,
    ) -> Result<(), IndirectError> {
        let gpu = self.gpu;
        let run = self.passes_run(method, rebuild);
        let timer = timed.then_some(&self.timer);
        gpu.checked(|| {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            for (_, record) in self.frame_steps(method, &run, timer) {
                record(&mut encoder);
            }
            if let Some(timer) = timer {
                timer.resolve(&mut encoder);
            }
            let names: Vec<_> = run.iter().map(|p| p.name()).collect();
            gpu.submit(
                format!("{}: {}", self.frame_work(method), names.join(", ")),
                encoder.finish(),
            );
        })?;
        if timed {
            self.timer.collect(gpu)?;
        }
        Ok(())
    }

    /// Renders one frame of `method` from scratch one pass at a time: each pass submitted alone
    /// and waited for (bounded), `done` told its pass and wall time. Slow; for finding the pass
    /// that hangs or faults on a new GPU (`quadray smoke`): the error names it.
    pub fn render_pass_by_pass(
        &mut self,
        method: Method,
        mut done: impl FnMut(Pass, std::time::Duration),
    ) -> Result<(), IndirectError> {
        let gpu = self.gpu;
        let run = self.passes_run(method, true);
        for (pass, record) in self.frame_steps(method, &run, None) {
            let start = std::time::Instant::now();
            gpu.checked(|| {
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                record(&mut encoder);
                gpu.submit(
                    format!("the {} pass of {}", pass.name(), self.frame_work(method)),
                    encoder.finish(),
                );
            })?;
            gpu.wait(&format!("the {} pass", pass.name()))?;
            done(pass, start.elapsed());
        }
        Ok(())
    }

    /// What a frame of `method` is, for the error of a GPU wait that runs out.
    fn frame_work(&self, method: Method) -> String {
        let s = &self.settings;
        format!(
            "an indirect frame {}x{} ({}, RSM {}^2)",
            s.size.width,
            s.size.height,
            method.name(),
            s.rsm_size
        )
    }

    /// The passes of `run` as steps that record into an encoder, in frame order. The pyramid's
    /// step records the validity too; the gather's the upsampling.
    fn frame_steps<'a>(
        &'a self,
        method: Method,
        run: &[Pass],
        timer: Option<&'a GpuTimer>,
    ) -> Vec<FrameStep<'a>> {
        let slot = move |pass: Pass| timer.map(|t| (t, pass as u32));
        let mut steps: Vec<FrameStep<'a>> = Vec::new();
        // a pass recorded once a light view is timed from the first view's start to the last's end
        let views = self.views.len();
        let each_view =
            move |encoder: &mut wgpu::CommandEncoder,
                  record: &dyn Fn(&mut wgpu::CommandEncoder, &ViewPasses)| {
                for (i, view) in self.views.iter().enumerate() {
                    match timer {
                        Some(t) => t.span(i == 0, i + 1 == views, || record(encoder, view)),
                        None => record(encoder, view),
                    }
                }
            };
        if run.contains(&Pass::Rsm) {
            steps.push((
                Pass::Rsm,
                Box::new(move |encoder| {
                    each_view(encoder, &|encoder, view| {
                        view.rsm.record(
                            encoder,
                            self.vertices.slice(..),
                            self.vertex_count,
                            slot(Pass::Rsm),
                        )
                    })
                }),
            ));
        }
        if run.contains(&Pass::Pyramid) {
            steps.push((
                Pass::Pyramid,
                Box::new(move |encoder| {
                    each_view(encoder, &|encoder, view| {
                        let slots = timer.map(|t| (t, Pass::Pyramid as u32, Pass::Validity as u32));
                        view.quadtree.record_build(encoder, slots)
                    })
                }),
            ));
        }
        if run.contains(&Pass::Cut) {
            steps.push((
                Pass::Cut,
                Box::new(move |encoder| {
                    each_view(encoder, &|encoder, view| {
                        view.quadtree.record_cut(encoder, slot(Pass::Cut))
                    })
                }),
            ));
        }
        if run.contains(&Pass::GBuffer) {
            steps.push((
                Pass::GBuffer,
                Box::new(move |encoder| {
                    self.gbuffer.record(
                        encoder,
                        self.vertices.slice(..),
                        self.vertex_count,
                        timer.and_then(|t| t.render_pass(Pass::GBuffer as u32)),
                    )
                }),
            ));
        }
        if run.contains(&Pass::Indirect) {
            steps.push((
                Pass::Indirect,
                Box::new(move |encoder| {
                    let slots = timer.map(|t| (t, Pass::Indirect as u32, Pass::Upsample as u32));
                    self.gather
                        .record_indirect(encoder, method, &self.quadtrees(), slots)
                }),
            ));
        }
        if run.contains(&Pass::ShadowMap) {
            steps.push((
                Pass::ShadowMap,
                Box::new(move |encoder| {
                    self.direct.record_shadow_maps(
                        encoder,
                        self.vertices.slice(..),
                        self.vertex_count,
                        slot(Pass::ShadowMap),
                    )
                }),
            ));
        }
        if run.contains(&Pass::Direct) {
            steps.push((
                Pass::Direct,
                Box::new(move |encoder| {
                    self.direct
                        .record(encoder, &self.gather, slot(Pass::Direct))
                }),
            ));
        }
        steps
    }

    /// The first light view's passes (the only one of a spot or a directional light): what the
    /// read-backs of one RSM, quadtree or cut show.
    fn first_view(&self) -> &ViewPasses {
        &self.views[0]
    }

    /// Every light view's quadtree, in order.
    fn quadtrees(&self) -> Vec<&LightQuadtree> {
        self.views.iter().map(|v| &v.quadtree).collect()
    }

    /// How many light views the frames sum (a spot or a directional light one, a point light
    /// six).
    pub fn view_count(&self) -> usize {
        self.views.len()
    }

    /// Rebuilds the RSM, the quadtree and the compacted cut without shading anything: the cut
    /// to read ([`Self::read_cut`]) beside a frame of a method that keeps none, leaving that
    /// frame and the temporal filter's average as they are.
    pub fn build_cut(&mut self) -> Result<(), IndirectError> {
        let gpu = self.gpu;
        let light = [Pass::Rsm, Pass::Pyramid, Pass::Cut];
        gpu.checked(|| {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            for (_, record) in self.frame_steps(Method::Quadtree, &light, None) {
                record(&mut encoder);
            }
            gpu.submit(
                format!("the cut of {}", self.frame_work(Method::Quadtree)),
                encoder.finish(),
            );
        })?;
        Ok(())
    }

    /// The passes a frame of `method` records (the timer's slots of the others hold stale times).
    pub fn passes_run(&self, method: Method, rebuild: bool) -> Vec<Pass> {
        let mut passes = Vec::new();
        if rebuild {
            passes.push(Pass::Rsm);
            if method.builds_quadtree() {
                passes.extend([Pass::Pyramid, Pass::Validity]);
            }
            if method == Method::Quadtree {
                passes.push(Pass::Cut);
            }
        }
        // the sun's shadow map follows the camera: drawn every frame, as the G-buffer
        passes.extend([Pass::GBuffer, Pass::Indirect, Pass::ShadowMap, Pass::Direct]);
        if self.settings().reconstructs(method) {
            passes.push(Pass::Upsample);
        }
        passes
    }

    /// Renders `frames` timed frames of `method` (rebuilding the light's buffers each frame with
    /// `rebuild`) and returns the median GPU time of each pass; `None` without timestamp queries.
    pub fn time(
        &mut self,
        method: Method,
        rebuild: bool,
        frames: u32,
    ) -> Result<Option<FrameTiming>, IndirectError> {
        self.timer.clear();
        for _ in 0..frames {
            self.render(method, rebuild, true)?;
        }
        if !self.timer.enabled() || frames == 0 {
            return Ok(None);
        }
        let run = self.passes_run(method, rebuild);
        let passes: BTreeMap<&'static str, f64> = Pass::ALL
            .into_iter()
            .zip(self.timer.summaries())
            .filter(|(p, _)| run.contains(p))
            .filter_map(|(p, s)| s.map(|s| (p.name(), s.median_ms)))
            .collect();
        Ok(Some(FrameTiming {
            total_ms: passes.values().sum(),
            passes,
            frames,
        }))
    }

    /// The gather the frames are shaded with (to write them into your own texture with an
    /// [`super::OutputPass`]).
    pub fn gather(&self) -> &Gather {
        &self.gather
    }

    /// Whether the adapter has timestamp queries, so that timings can be taken at all.
    pub fn has_timestamps(&self) -> bool {
        self.timer.enabled()
    }

    /// Renders one frame of `method` from scratch, untimed, and reads it back.
    pub fn render_frame(&mut self, method: Method) -> Result<Frame, IndirectError> {
        self.render(method, true, false)?;
        self.read_frame()
    }

    fn read_vec4(&self, buffer: &wgpu::Buffer) -> Result<Vec<[f32; 4]>, IndirectError> {
        let bytes = quadray_gpu::read_buffer(self.gpu, buffer)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// The last frame's indirect and direct light.
    pub fn read_frame(&self) -> Result<Frame, IndirectError> {
        let indirect = self.read_vec4(self.gather.indirect())?;
        let direct = self.read_vec4(self.gather.direct())?;
        let counts: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&quadray_gpu::read_buffer(
            self.gpu,
            self.gather.counts(),
        )?);
        let rgb = |v: Vec<[f32; 4]>| v.into_iter().map(xyz).collect();
        let s = self.settings();
        Ok(Frame {
            counts: WorkCounts {
                shaded_pixels: direct.iter().filter(|p| p[3] > 0.5).count() as u32,
                vpl_evaluations: counts.iter().map(|c| u64::from(c[0])).sum(),
                texel_fetches: counts.iter().map(|c| u64::from(c[1])).sum(),
                bound_evaluations: counts.iter().map(|c| u64::from(c[2])).sum(),
                refused_splits: counts.iter().map(|c| u64::from(c[3])).sum(),
            },
            width: s.size.width,
            height: s.size.height,
            recomputed: indirect.iter().filter(|p| p[3] > 0.5).count() as u32,
            indirect: rgb(indirect),
            direct: rgb(direct),
        })
    }

    /// Number of clusters in the first light view's compacted cut (after a `Quadtree` frame with
    /// rebuild).
    pub fn clusters_in_cut(&self) -> Result<u32, IndirectError> {
        let bytes = quadray_gpu::read_buffer(self.gpu, self.first_view().quadtree.cut_count())?;
        Ok(bytemuck::pod_read_unaligned(&bytes[..4]))
    }

    /// The clusters of the first light view's compacted cut (after a `Quadtree` frame with
    /// rebuild), in no order.
    pub fn read_cut(&self) -> Result<Vec<CutNode>, IndirectError> {
        let quadtree = &self.first_view().quadtree;
        let bytes = quadray_gpu::read_buffer(self.gpu, quadtree.cut_count())?;
        let counts: CutCounts = bytemuck::pod_read_unaligned(&bytes);
        let clusters = self.read_vec4(quadtree.cut())?;
        // three vec4 a cluster; the normal's w holds the node's index
        let segment = 3 * cut_class_capacity(self.settings().rsm_size) as usize;
        Ok(clusters
            .chunks(segment)
            .zip(&counts[1..])
            .flat_map(|(class, &count)| class.chunks_exact(3).take(count as usize))
            .map(|c| CutNode::at(self.settings().rsm_size, c[2][3].to_bits()))
            .collect())
    }

    /// The per-tile cuts of the last [`Method::QuadtreeTiles`] frame's last light view: each
    /// tile's clusters (tiles of 8x8 pixels, row-major; empty where the tile sees no geometry),
    /// in no order; no tiles before the first such frame.
    pub fn read_tile_cuts(&self) -> Result<Vec<Vec<CutNode>>, IndirectError> {
        let s = self.settings();
        let capacity = s.tile_capacity_or_default() as usize;
        let Some((sizes, lists)) = self.read_tile_lists()? else {
            return Ok(Vec::new());
        };
        Ok(sizes
            .iter()
            .enumerate()
            .map(|(tile, size)| {
                let list = &lists[tile * capacity..][..size[0] as usize];
                list.iter()
                    .map(|&entry| {
                        CutNode::at(s.rsm_size, entry & ((1 << TILE_ENTRY_INDEX_BITS) - 1))
                    })
                    .collect()
            })
            .collect())
    }

    /// [`crate::picture::cut_view`] of `cut` over this renderer's RSM at
    /// [`crate::picture::cut_view_zoom`]: the one cut ([`Self::read_cut`]) or a tile's
    /// ([`Self::read_tile_cut_at`]).
    pub fn cut_view(&self, cut: &[CutNode]) -> Result<Rgba8Image, IndirectError> {
        let rsm_size = self.settings().rsm_size;
        Ok(cut_view(
            rsm_size,
            &self.read_nodes()?,
            cut,
            cut_view_zoom(rsm_size),
        ))
    }

    /// The cut of the tile that lights pixel `(x, y)` in the last [`Method::QuadtreeTiles`]
    /// frame (empty before such a frame or where the tile sees no geometry): what
    /// [`crate::picture::cut_view`] draws for the per-tile cuts.
    pub fn read_tile_cut_at(&self, x: u32, y: u32) -> Result<Vec<CutNode>, IndirectError> {
        let size = self.settings().size;
        if x >= size.width || y >= size.height {
            return Err(IndirectError::Settings(format!(
                "pixel ({x}, {y}) is outside the {}x{} picture",
                size.width, size.height
            )));
        }
        let tile = (y / TILE * size.width.div_ceil(TILE) + x / TILE) as usize;
        Ok(self
            .read_tile_cuts()?
            .into_iter()
            .nth(tile)
            .unwrap_or_default())
    }

    /// Per tile of the last [`Method::QuadtreeTiles`] frame (as [`Self::read_tile_cuts`]), the
    /// nodes whose error it estimated ([`crate::TileCriterion::Estimate`]) and the VPL
    /// evaluations that took (counted in [`WorkCounts::vpl_evaluations`] too).
    pub fn read_tile_estimates(&self) -> Result<Vec<(u32, u32)>, IndirectError> {
        Ok(self.read_tile_lists()?.map_or_else(Vec::new, |(sizes, _)| {
            sizes.iter().map(|s| (s[2], s[3])).collect()
        }))
    }

    /// The per-tile cuts' records (length, refused splits, nodes estimated, their evaluations) and
    /// lists, `None` before the first frame that drew them.
    #[allow(clippy::type_complexity)]
    fn read_tile_lists(&self) -> Result<Option<(Vec<[u32; 4]>, Vec<u32>)>, IndirectError> {
        let Some((cuts, sizes)) = self.gather.tile_lists() else {
            return Ok(None);
        };
        let read = |buffer| quadray_gpu::read_buffer(self.gpu, buffer);
        let (tx, ty) = self.settings().tiles();
        let mut sizes: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&read(sizes)?);
        sizes.truncate((tx * ty) as usize);
        Ok(Some((sizes, bytemuck::pod_collect_to_vec(&read(cuts)?))))
    }

    /// The first light view's RSM flux per texel, row-major (what its cut clusters).
    pub fn read_rsm_flux(&self) -> Result<Vec<[f32; 3]>, IndirectError> {
        let texels = self.gather.read_rsm(self.gpu, 0)?;
        Ok(texels.into_iter().map(|[flux, ..]| xyz(flux)).collect())
    }

    /// The first light view's quadtree as built: per node (flux rgb + texel count, position + depth, normal +
    /// validity), finest level first.
    pub fn read_nodes(&self) -> Result<Vec<[[f32; 4]; 3]>, IndirectError> {
        let flat = self.read_vec4(self.first_view().quadtree.nodes())?;
        Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// What bounds each node of the first light view's quadtree, as built: the box of its VPLs' positions (lo,
    /// hi; empty nodes hold lo > hi) with the cosine of its normal cone's half-angle in lo's w
    /// (the cone's axis is the node's mean normal), finest level first.
    pub fn read_node_bounds(&self) -> Result<Vec<[[f32; 4]; 2]>, IndirectError> {
        let flat = self.read_vec4(self.first_view().quadtree.bounds())?;
        Ok(flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
    }

    /// Every light view's VPLs (texels that see geometry), view after view, for the CPU
    /// reference: the light the frames sum.
    pub fn read_vpls(&self) -> Result<Vec<Vpl>, IndirectError> {
        let mut vpls = Vec::new();
        for view in 0..self.views.len() {
            let texels = self.gather.read_rsm(self.gpu, view)?;
            vpls.extend(
                texels
                    .into_iter()
                    .filter(|[_, _, normal]| normal[3] > 0.5)
                    .map(|[flux, position, normal]| Vpl {
                        flux: xyz(flux),
                        position: xyz(position),
                        normal: xyz(normal),
                    }),
            );
        }
        Ok(vpls)
    }

    /// The G-buffer as the gather reads it, for the CPU reference.
    pub fn read_receivers(&self) -> Result<Vec<Option<Receiver>>, IndirectError> {
        let texels = self.gather.read_gbuffer(self.gpu)?;
        Ok(texels
            .into_iter()
            .map(|[position, normal, albedo]| {
                (position[3] > 0.5).then(|| Receiver {
                    position: xyz(position),
                    normal: xyz(normal),
                    albedo: xyz(albedo),
                })
            })
            .collect())
    }
}

fn xyz(p: [f32; 4]) -> [f32; 3] {
    [p[0], p[1], p[2]]
}
