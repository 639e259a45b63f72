//! quadray's own renderer: one map on one of its surfaces, drawn with any method by the surface
//! pass, on the same [`HeightPyramid`]s a user would build.

use super::height_pyramid::{HeightPyramid, PyramidKind};
use super::pyramid_build::PyramidBuilder;
use super::surface_pass::{
    COLOR_FORMAT, DEPTH_FORMAT, DebugTargets, FrameParams, Geometry, HIT_FORMAT, MapParams,
    MapTextures, SEARCH_FORMAT, SurfacePass, Targets,
};
use crate::cone::{ConeMap, ConeMapJob};
use crate::heightmap::HeightMap;
use crate::method::Method;
use crate::pyramid::Addressing;
use crate::reference::Ray;
use crate::scene::{Plane, SurfaceKind, View, mesh_grid};
use crate::{DisplaceError, Settings};
use glam::DVec2;
use quadray_core::image_out::Rgba8Image;
use quadray_core::settings::Limits;
use quadray_core::stats::Summary;
use quadray_gpu::{Gpu, GpuTimer, read_texture_f32, read_texture_rgba8, texture_2d};
use wgpu::util::DeviceExt;

/// What one frame produced, read back.
pub struct Frame {
    /// The picture.
    pub color: Rgba8Image,
    /// Per pixel: hit u, hit v, hit depth (-1: left the map, -2: no surface), iterations
    /// (negative: stopped by the cap).
    pub hits: Vec<[f32; 4]>,
    /// Per pixel: the ray's p0 and e.
    pub rays: Vec<[f32; 4]>,
    /// Per pixel: the texels the search read (every textureLoad of the trace).
    pub fetches: Vec<f32>,
    /// Per pixel: whether the light's ray is blocked (self-shadowing on, a traced method).
    pub in_shadow: Vec<bool>,
}

impl Frame {
    /// The rays the GPU reports it traced, one per pixel (None where no surface shows).
    pub fn traced_rays(&self) -> Vec<Option<Ray>> {
        self.rays
            .iter()
            .zip(&self.hits)
            .map(|(r, h)| {
                (h[2] != -2.0).then(|| Ray {
                    p0: DVec2::new(r[0].into(), r[1].into()),
                    e: DVec2::new(r[2].into(), r[3].into()),
                })
            })
            .collect()
    }
}

/// One map on one surface, ready to render with any method.
pub struct Renderer {
    pass: SurfacePass,
    map: HeightMap,
    addressing: Addressing,
    surface: SurfaceKind,
    params: wgpu::Buffer,
    point: HeightPyramid,
    gradients: wgpu::TextureView,
    albedo: wgpu::TextureView,
    point_group: wgpu::BindGroup,
    conservative_group: wgpu::BindGroup,
    /// Built the first time the cone method draws (or handed in): the group binding the cone
    /// map, and the CPU build's seconds where known.
    cone: Option<(wgpu::BindGroup, Option<f64>)>,
    /// The mesh baseline's repeats of the map in the last frame's view (`Plane::tiles_in_view`).
    mesh_tiles_in_view: Vec<u32>,
    triangles: wgpu::Buffer,
    vertex_count: u32,
}

impl Renderer {
    /// [`Renderer::time`]'s frames: a median needs one, ten thousand take minutes at 1080p on
    /// a software rasterizer.
    pub const TIMED_FRAMES: Limits<u32> = Limits::closed(1, 10_000);
    /// `color`: the albedo texture; `None` tints by depth.
    pub fn new(
        gpu: &Gpu,
        map: &HeightMap,
        color: Option<&Rgba8Image>,
        surface: SurfaceKind,
    ) -> Self {
        let (device, queue) = (&gpu.device, &gpu.queue);
        let addressing = surface.addressing();
        let builder = PyramidBuilder::new(device);
        let point = builder.build(device, queue, map, PyramidKind::Point);
        let conservative = builder.build(device, queue, map, PyramidKind::Conservative(addressing));
        let tinted;
        let color = match color {
            Some(c) => c,
            None => {
                tinted = tint_by_depth(map);
                &tinted
            }
        };
        let albedo = quadray_gpu::texture_2d_with_data(
            device,
            queue,
            "albedo",
            (color.width, color.height),
            wgpu::TextureFormat::Rgba8UnormSrgb,
            color.pixels.as_flattened(),
        );
        let albedo = albedo.create_view(&Default::default());
        let gradients = upload_gradients(gpu, map).create_view(&Default::default());
        let plane = Plane::of(surface);
        let v4 = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        let params = SurfacePass::map_params(
            device,
            &MapParams {
                plane_origin: v4(plane.origin),
                plane_u: v4(plane.u),
                plane_v: v4(plane.v),
                pyramid: point.info(addressing),
                tile_world: surface.tile_world(),
                mesh_grid: mesh_grid(map.width, map.height),
                tiles: surface.tiles(),
                _pad: 0,
            },
        );
        let pass = SurfacePass::new(device);
        let group = |pyramid: &HeightPyramid| {
            map_group(
                &pass,
                device,
                &params,
                pyramid.view(),
                &point,
                &gradients,
                &albedo,
            )
        };
        let (point_group, conservative_group) = (group(&point), group(&conservative));
        let vertices = surface.vertices();
        let triangles = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("surface triangles"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        Self {
            pass,
            map: map.clone(),
            addressing,
            surface,
            params,
            point,
            gradients,
            albedo,
            point_group,
            conservative_group,
            cone: None,
            mesh_tiles_in_view: Vec::new(),
            triangles,
            vertex_count: vertices.len() as u32,
        }
    }

    /// The surface the map is drawn on.
    pub fn surface(&self) -> SurfaceKind {
        self.surface
    }

    /// Seconds the CPU took to build the cone map (the cone method's preprocessing), once a cone
    /// frame was drawn.
    pub fn cone_build_seconds(&self) -> Option<f64> {
        self.cone.as_ref().and_then(|(_, seconds)| *seconds)
    }

    /// Whether the cone method has its cone map (else its first frame builds it).
    pub fn has_cone_map(&self) -> bool {
        self.cone.is_some()
    }

    /// Builds the cone map now, calling `row_done` as each row of the map is finished (see
    /// [`ConeMap::build_with_progress`]), instead of in the cone method's first frame.
    pub fn build_cone_map(&mut self, gpu: &Gpu, row_done: impl Fn() + Sync) {
        let start = std::time::Instant::now();
        let cones = ConeMap::build_with_progress(&self.map, self.addressing, row_done);
        let seconds = start.elapsed().as_secs_f64();
        self.set_cone_map(gpu, &cones, Some(seconds))
            .expect("built from the renderer's own map");
    }

    /// A build of this renderer's cone map on a thread of its own; hand its result to
    /// [`Renderer::set_cone_map`].
    pub fn cone_map_job(&self) -> ConeMapJob {
        ConeMapJob::spawn(self.map.clone(), self.addressing)
    }

    /// Uses `cones` for the cone method from now on (built on another thread, or kept from an
    /// earlier run); `build_seconds` is what [`Renderer::cone_build_seconds`] reports.
    pub fn set_cone_map(
        &mut self,
        gpu: &Gpu,
        cones: &ConeMap,
        build_seconds: Option<f64>,
    ) -> Result<(), DisplaceError> {
        if (cones.width, cones.height) != (self.map.width, self.map.height) {
            return Err(DisplaceError::Settings(format!(
                "a {}x{} cone map for a {}x{} height map",
                cones.width, cones.height, self.map.width, self.map.height
            )));
        }
        let texture = cones.upload(&gpu.device, &gpu.queue);
        let group = map_group(
            &self.pass,
            &gpu.device,
            &self.params,
            &texture.create_view(&Default::default()),
            &self.point,
            &self.gradients,
            &self.albedo,
        );
        self.cone = Some((group, build_seconds));
        Ok(())
    }

    /// Builds the cone map the first time the cone method draws.
    fn prepare(&mut self, gpu: &Gpu, method: Method) {
        if method == Method::Cone && !self.has_cone_map() {
            self.build_cone_map(gpu, || {});
        }
    }

    /// Memory the method needs beyond the albedo, in bytes.
    pub fn memory_bytes(&self, method: Method) -> u64 {
        let (width, height) = (self.map.width, self.map.height);
        let texels = u64::from(width) * u64::from(height);
        let padded = u64::from(width.next_power_of_two()) * u64::from(height.next_power_of_two());
        match method {
            // Pyramid levels above 0 add a third of the padded level 0; normal map RGBA16F.
            Method::Pyramid | Method::PyramidAscend | Method::PyramidBilinear => {
                padded * 4 * 4 / 3 + texels * 8
            }
            // The cone map: depth and ratio as two floats.
            Method::Cone => texels * 8 + texels * 8,
            Method::Mesh => {
                // The paper's figure 20 counts a vertex buffer (position + normal) per grid point.
                let vertices = (u64::from(mesh_grid(width, height)) + 1).pow(2);
                vertices * 24 + texels * 4 + texels * 8
            }
            _ => texels * 4 + texels * 8,
        }
    }

    fn write_frame(&mut self, gpu: &Gpu, s: &Settings, view: &View) {
        let params = FrameParams::new(s, view, self.map.levels());
        self.pass.write_frame(&gpu.queue, &params);
        if s.method == Method::Mesh {
            self.mesh_tiles_in_view = Plane::of(self.surface).tiles_in_view(
                self.surface.tiles(),
                s.depth_scale * self.surface.tile_world(),
                view.view_proj,
            );
        }
    }

    fn targets(gpu: &Gpu, s: &Settings, debug_outputs: bool) -> Vec<wgpu::Texture> {
        let make = |format, label| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
            texture_2d(
                &gpu.device,
                label,
                (s.size.width, s.size.height),
                format,
                usage,
            )
        };
        let mut t = vec![make(COLOR_FORMAT, "color"), make(DEPTH_FORMAT, "depth")];
        if debug_outputs {
            t.push(make(HIT_FORMAT, "hits"));
            t.push(make(HIT_FORMAT, "rays"));
            t.push(make(SEARCH_FORMAT, "search"));
        }
        t
    }

    fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        method: Method,
        targets: Targets,
        debug: Option<DebugTargets>,
        timer: Option<&GpuTimer>,
    ) {
        self.prepare(gpu, method);
        let map_group = match (&self.cone, method) {
            (Some((cone_group, _)), Method::Cone) => cone_group,
            _ if method.describe().conservative_pyramid => &self.conservative_group,
            _ => &self.point_group,
        };
        let geometry = if method == Method::Mesh {
            Geometry::MeshGrid {
                grid: mesh_grid(self.map.width, self.map.height),
                tiles: &self.mesh_tiles_in_view,
            }
        } else {
            Geometry::Triangles(&self.triangles, self.vertex_count)
        };
        self.pass.record(
            &gpu.device,
            encoder,
            method,
            map_group,
            geometry,
            targets,
            debug,
            timer.and_then(|t| t.render_pass(0)),
        );
    }

    /// Draws one frame into an application's own targets, seen from `view`. `timer`, when given,
    /// times the pass as its query 0.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        s: &Settings,
        view: &View,
        targets: Targets,
        timer: Option<&GpuTimer>,
    ) -> Result<(), DisplaceError> {
        self.check(s)?;
        self.write_frame(gpu, s, view);
        self.encode(gpu, encoder, s.method, targets, None, timer);
        Ok(())
    }

    fn check(&self, s: &Settings) -> Result<(), DisplaceError> {
        s.validate().map_err(DisplaceError::Settings)?;
        if s.method == Method::Mesh && !self.surface.is_planar() {
            return Err(DisplaceError::Settings(format!(
                "the mesh baseline displaces a flat grid; the {:?} surface is curved",
                self.surface
            )));
        }
        Ok(())
    }

    /// Renders one frame with the hit and ray outputs and reads everything back.
    pub fn render(&mut self, gpu: &Gpu, s: &Settings) -> Result<Frame, DisplaceError> {
        self.check(s)?;
        self.write_frame(gpu, s, &View::of(self.surface, s));
        let targets = Self::targets(gpu, s, true);
        let views: Vec<_> = targets
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        gpu.checked(|| {
            self.encode(
                gpu,
                &mut encoder,
                s.method,
                Targets {
                    color: &views[0],
                    depth: &views[1],
                },
                Some(DebugTargets {
                    hits: &views[2],
                    rays: &views[3],
                    search: &views[4],
                }),
                None,
            )
        })?;
        gpu.submit(frame_work("displacement frame", s), encoder.finish());
        let search = read_texture_f32(gpu, &targets[4], 0, 2)?;
        let pixels = |v: Vec<f32>| -> Vec<[f32; 4]> {
            v.chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect()
        };
        Ok(Frame {
            color: Rgba8Image::from_bytes(
                s.size.width,
                s.size.height,
                &read_texture_rgba8(gpu, &targets[0])?,
            ),
            hits: pixels(read_texture_f32(gpu, &targets[2], 0, 4)?),
            rays: pixels(read_texture_f32(gpu, &targets[3], 0, 4)?),
            fetches: search.iter().step_by(2).copied().collect(),
            in_shadow: search.iter().skip(1).step_by(2).map(|&s| s > 0.5).collect(),
        })
    }

    /// GPU time of the shading pass alone (colour target only, as an application would draw),
    /// median of `frames` frames after two warm-up frames. `None` without timestamp queries.
    pub fn time(
        &mut self,
        gpu: &Gpu,
        s: &Settings,
        frames: usize,
    ) -> Result<Option<Summary>, DisplaceError> {
        self.check(s)?;
        let view = View::of(self.surface, s);
        let targets = Self::targets(gpu, s, false);
        let views: Vec<_> = targets
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let mut timer = GpuTimer::new(gpu, 1);
        for frame in 0..frames + 2 {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            gpu.checked(|| {
                self.draw(
                    gpu,
                    &mut encoder,
                    s,
                    &view,
                    Targets {
                        color: &views[0],
                        depth: &views[1],
                    },
                    Some(&timer),
                )
            })??;
            timer.resolve(&mut encoder);
            gpu.submit(frame_work("timed displacement frame", s), encoder.finish());
            timer.collect(gpu)?;
            if frame == 1 {
                timer.clear();
            }
        }
        Ok(timer.summaries()[0])
    }
}

/// What a frame of `s` is, for the error of a GPU wait that runs out.
fn frame_work(what: &str, s: &Settings) -> String {
    format!(
        "{what} {}x{} ({})",
        s.size.width,
        s.size.height,
        s.method.name()
    )
}

/// The per-map bind group with `traced` (a pyramid or the cone map) in the pyramid's slot.
fn map_group(
    pass: &SurfacePass,
    device: &wgpu::Device,
    params: &wgpu::Buffer,
    traced: &wgpu::TextureView,
    point: &HeightPyramid,
    gradients: &wgpu::TextureView,
    albedo: &wgpu::TextureView,
) -> wgpu::BindGroup {
    let textures = MapTextures {
        pyramid: traced,
        depth_map: point.view(),
        normal_map: gradients,
        color_map: albedo,
    };
    pass.map_group(device, params, textures)
}

/// Depth gradients per unit of uv at texel centres (central differences), filtered by the sampler
/// and turned into normals in the shader with the frame's depth scale: n ~ (grad * s, 1).
fn upload_gradients(gpu: &Gpu, map: &HeightMap) -> wgpu::Texture {
    let (w, h) = (i64::from(map.width), i64::from(map.height));
    let d = |i: i64, j: i64| map.at(i.rem_euclid(w) as u32, j.rem_euclid(h) as u32);
    let mut texels: Vec<half::f16> = Vec::with_capacity((w * h * 4) as usize);
    for j in 0..h {
        for i in 0..w {
            let du = (d(i + 1, j) - d(i - 1, j)) * 0.5 * w as f32;
            let dv = (d(i, j + 1) - d(i, j - 1)) * 0.5 * h as f32;
            texels.extend([du, dv, 0.0, 0.0].map(half::f16::from_f32));
        }
    }
    quadray_gpu::texture_2d_with_data(
        &gpu.device,
        &gpu.queue,
        "depth gradients",
        (map.width, map.height),
        wgpu::TextureFormat::Rgba16Float,
        bytemuck::cast_slice(&texels),
    )
}

/// An albedo for maps without a colour image: warm stone, darker with depth.
fn tint_by_depth(map: &HeightMap) -> Rgba8Image {
    let mut img = Rgba8Image::new(map.width, map.height, [0, 0, 0, 255]);
    for (px, d) in img.pixels.iter_mut().zip(&map.depth) {
        let k = 1.0 - 0.55 * d;
        *px = [(220.0 * k) as u8, (190.0 * k) as u8, (150.0 * k) as u8, 255];
    }
    img
}
