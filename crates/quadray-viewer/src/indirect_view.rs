//! The indirect-light panel: scene, method and every parameter of the light quadtree, a fly camera
//! and the scene's lights, each of which can be dragged or animated. Frames come from `quadray_indirect::Renderer`
//! and are tone-mapped by the same code as `quadray indirect`, so the screenshot's command line
//! renders the same picture headless. A frame is rendered only when something changed.

use crate::widgets::{absolute, choice_box, limits_slider, named, named_choice_box, shell_word};
use anyhow::{Context, Result};
use glam::{Quat, Vec3};
use quadray_core::image_out::Rgba8Image;
use quadray_gpu::Gpu;
use quadray_indirect::picture::tone_map;
use quadray_indirect::scene::{BUNDLED_SCENES, scenes_dir};
use quadray_indirect::{
    ClusterSettings, FrameTiming, GBufferLayout, Method, Renderer, Scene, Settings, TileCriterion,
    TilePasses, Validity,
};
use std::path::{Path, PathBuf};

/// What the view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Show {
    Combined,
    Direct,
    Indirect,
    /// The selected clusters over the RSM.
    Cut,
}

impl Show {
    const ALL: [Show; 4] = [Show::Combined, Show::Direct, Show::Indirect, Show::Cut];

    fn name(self) -> &'static str {
        match self {
            Show::Combined => "direct + indirect",
            Show::Direct => "direct",
            Show::Indirect => "indirect",
            Show::Cut => "cut over the RSM",
        }
    }

    /// The file `quadray indirect --out F.png` writes this picture to.
    fn headless_file(self, out: &Path) -> PathBuf {
        let stem = out.file_stem().unwrap_or_default().to_string_lossy();
        match self {
            Show::Combined => out.to_path_buf(),
            Show::Direct => out.with_file_name(format!("{stem}.direct.png")),
            Show::Indirect => out.with_file_name(format!("{stem}.indirect.png")),
            Show::Cut => out.with_file_name(format!("{stem}.cut.png")),
        }
    }
}

/// Unit vector of a heading (yaw about +Y, 0 = -Z) and an elevation.
fn direction(yaw_deg: f32, pitch_deg: f32) -> Vec3 {
    let (yaw, pitch) = (yaw_deg.to_radians(), pitch_deg.to_radians());
    Vec3::new(
        pitch.cos() * yaw.sin(),
        pitch.sin(),
        -pitch.cos() * yaw.cos(),
    )
}

fn yaw_pitch(d: Vec3) -> (f32, f32) {
    let d = d.normalize();
    (
        d.x.atan2(-d.z).to_degrees(),
        d.y.clamp(-1.0, 1.0).asin().to_degrees(),
    )
}

/// The camera and lights as the viewer moves them; the loaded scene keeps the originals.
struct Pose {
    eye: Vec3,
    yaw: f32,
    pitch: f32,
    lights: Vec<LightPose>,
    /// Angle of the animated light around its dragged direction.
    light_phase: f32,
}

/// Where a light aims (a spot, the sun) or stands (a point light).
enum LightPose {
    Aim { yaw: f32, pitch: f32 },
    Place(Vec3),
}

impl Pose {
    fn of(scene: &Scene) -> Self {
        let eye = scene.camera.position;
        let (yaw, pitch) = yaw_pitch(scene.camera.target - eye);
        let lights = scene
            .lights
            .iter()
            .map(|light| match (light.direction(), light.position()) {
                (Some(d), _) => {
                    let (yaw, pitch) = yaw_pitch(d);
                    LightPose::Aim { yaw, pitch }
                }
                (None, p) => LightPose::Place(p.expect("a light without an aim has a position")),
            })
            .collect();
        Self {
            eye,
            yaw,
            pitch,
            lights,
            light_phase: 0.0,
        }
    }

    /// The scene with this pose's camera and lights; `animated`: the light of that number
    /// circles its dragged direction (or position).
    fn apply(&self, base: &Scene, animated: Option<usize>) -> Scene {
        let mut scene = base.clone();
        scene.camera.position = self.eye;
        scene.camera.target = self.eye + direction(self.yaw, self.pitch);
        for (i, (light, pose)) in scene.lights.iter_mut().zip(&self.lights).enumerate() {
            let phase = Some(i) == animated;
            match *pose {
                LightPose::Aim { yaw, pitch } => {
                    let mut aim = direction(yaw, pitch);
                    if phase {
                        // circle 15 degrees around the dragged direction
                        let axis = Quat::from_axis_angle(aim, self.light_phase)
                            * aim.any_orthonormal_vector();
                        aim = Quat::from_axis_angle(axis, 15f32.to_radians()) * aim;
                    }
                    light.aim(aim);
                }
                LightPose::Place(position) => {
                    let circle = if phase {
                        let (sin, cos) = self.light_phase.sin_cos();
                        0.05 * base.extent() * Vec3::new(cos, 0.0, sin)
                    } else {
                        Vec3::ZERO
                    };
                    light.place(position + circle);
                }
            }
        }
        scene
    }

    /// Turns the light of that number by `degrees` about the vertical: a spot's or the sun's aim,
    /// a point light's position about the scene's middle.
    fn turn_light(&mut self, light: usize, degrees: f32, middle: Vec3) {
        match &mut self.lights[light] {
            LightPose::Aim { yaw, .. } => *yaw += degrees,
            LightPose::Place(position) => {
                *position =
                    middle + Quat::from_rotation_y(-degrees.to_radians()) * (*position - middle);
            }
        }
    }
}

pub struct IndirectView {
    gpu: &'static Gpu,
    scenes: Vec<PathBuf>,
    pub scene: usize,
    /// The scene as loaded (index into `scenes`) and the pose moved from it.
    loaded: Option<(usize, Scene, Pose)>,
    renderer: Option<Renderer<'static>>,
    pub settings: Settings,
    pub method: Method,
    pub show: Show,
    pub exposure: f32,
    /// The light that right drags, scripted turns and the animation move (an index into the
    /// scene's lights; the last one where the scene has fewer).
    pub light: usize,
    pub animate_light: bool,
    /// The camera moved: shade again with the light's buffers reused.
    redraw: bool,
    /// The light or the quadtree changed: rebuild RSM, pyramid and cut too.
    rebuild: bool,
    picture: Option<Rgba8Image>,
    texture: Option<egui::TextureHandle>,
    pub timing: Option<FrameTiming>,
    pub cut_summary: Option<String>,
    pub error: Option<String>,
}

impl IndirectView {
    /// The view of the bundled scenes plus `extra`, starting at `start` (a scene file's path).
    pub fn new(
        gpu: &'static Gpu,
        extra: Option<PathBuf>,
        method: Method,
        show: Show,
        rsm_size: Option<u32>,
    ) -> Self {
        let mut scenes: Vec<PathBuf> = BUNDLED_SCENES
            .iter()
            .map(|s| absolute(scenes_dir().join(s)))
            .collect();
        let scene = match extra {
            Some(path) => {
                scenes.push(absolute(path));
                scenes.len() - 1
            }
            None => 0,
        };
        // a CPU rasterizer shades a 512^2 RSM's cut at a few frames per second at best
        let rsm_size = rsm_size.unwrap_or(if gpu.is_software() { 128 } else { 512 });
        Self {
            gpu,
            scenes,
            scene,
            loaded: None,
            renderer: None,
            settings: Settings {
                rsm_size,
                ..Settings::DEFAULT
            },
            method,
            show,
            exposure: 1.0,
            light: 0,
            animate_light: false,
            redraw: true,
            rebuild: true,
            picture: None,
            texture: None,
            timing: None,
            cut_summary: None,
            error: None,
        }
    }

    /// Renders when something changed and returns the picture's texture and size in pixels.
    pub fn draw(
        &mut self,
        ctx: &egui::Context,
        size: [u32; 2],
        dt: f32,
    ) -> Option<(egui::TextureId, [u32; 2])> {
        self.settings.size.width = size[0].clamp(16, 4096);
        self.settings.size.height = size[1].clamp(16, 4096);
        if self.animate_light
            && let Some((_, _, pose)) = &mut self.loaded
        {
            pose.light_phase += dt * std::f32::consts::TAU / 4.0;
            self.rebuild = true;
        }
        match self.render() {
            Ok(Some(picture)) => {
                let image = egui::ColorImage::from_rgba_unmultiplied(
                    [picture.width as usize, picture.height as usize],
                    bytemuck::cast_slice(&picture.pixels),
                );
                match &mut self.texture {
                    Some(t) => t.set(image, egui::TextureOptions::NEAREST),
                    None => {
                        self.texture =
                            Some(ctx.load_texture("indirect", image, egui::TextureOptions::NEAREST))
                    }
                }
                self.picture = Some(picture);
                self.error = None;
            }
            Ok(None) => {}
            Err(e) => self.error = Some(format!("{e:#}")),
        }
        let picture = self.picture.as_ref()?;
        Some((self.texture.as_ref()?.id(), [picture.width, picture.height]))
    }

    /// Loads the scene and (re)makes the renderer as the choices require, then renders a new
    /// picture if anything changed since the last one.
    fn render(&mut self) -> Result<Option<Rgba8Image>> {
        let gpu = self.gpu;
        if !matches!(&self.loaded, Some((i, ..)) if *i == self.scene) {
            self.renderer = None;
            self.loaded = None;
            let path = &self.scenes[self.scene];
            let scene = Scene::load(path)?;
            let pose = Pose::of(&scene);
            self.light = self.light.min(scene.lights.len() - 1);
            self.loaded = Some((self.scene, scene, pose));
        }
        let (_, base, pose) = self.loaded.as_ref().expect("loaded above");
        let scene = pose.apply(base, self.animated());
        self.settings.validate().map_err(anyhow::Error::msg)?;
        let same_sizes = |r: &Renderer| {
            let s = r.settings();
            Settings {
                cluster: s.cluster,
                ..self.settings.clone()
            } == *s
        };
        if !self.renderer.as_ref().is_some_and(same_sizes) {
            self.renderer = None;
            self.renderer = Some(Renderer::new(gpu, &scene, self.settings.clone())?);
            self.rebuild = true;
        }
        let renderer = self.renderer.as_mut().expect("made above");
        if renderer.settings().cluster != self.settings.cluster {
            renderer.set_cluster(self.settings.cluster)?;
            self.rebuild = true;
        }
        if !(self.redraw || self.rebuild) {
            return Ok(None);
        }
        renderer.set_view(&scene)?;
        self.timing = renderer.time(self.method, self.rebuild, 1)?;
        self.redraw = false;
        self.rebuild = false;
        let (w, h) = (self.settings.size.width, self.settings.size.height);
        let frame = renderer.read_frame()?;
        self.cut_summary = None;
        let cut = if self.show == Show::Cut && self.method == Method::QuadtreeTiles {
            // the per-tile cuts: the list of the tile at the centre of the view
            let cut = renderer.read_tile_cut_at(w / 2, h / 2)?;
            self.cut_summary = Some(format!("{} clusters in the centre tile's cut", cut.len()));
            Some(cut)
        } else if self.method == Method::Quadtree || self.show == Show::Cut {
            // the other methods do not store the cut (the per-level passes select the same set)
            if self.method != Method::Quadtree {
                renderer.build_cut()?;
            }
            let cut = renderer.read_cut()?;
            self.cut_summary = Some(format!("{} clusters in the cut", cut.len()));
            Some(cut)
        } else {
            None
        };
        Ok(Some(match self.show {
            Show::Combined => tone_map(w, h, &frame.combined(), self.exposure),
            Show::Direct => tone_map(w, h, &frame.direct, self.exposure),
            Show::Indirect => tone_map(w, h, &frame.indirect, self.exposure),
            Show::Cut => renderer.cut_view(cut.as_deref().unwrap_or_default())?,
        }))
    }

    /// The settings the picture is drawn with: sub-sampling and interleaving only where the
    /// method sub-samples (the sliders keep their values for the methods that do; `quadray
    /// indirect` refuses them for the others), and interleaving only at full resolution.
    fn shown_settings(&self) -> Settings {
        let s = &self.settings;
        let (subsample, interleave) = match self.method.subsamples() {
            false => (1, 1),
            true if s.subsample > 1 => (s.subsample, 1),
            true => (1, s.interleave),
        };
        Settings {
            subsample,
            interleave,
            ..s.clone()
        }
    }

    /// The `quadray indirect` command that renders this view headless.
    pub fn command_line(&self, out: &Path) -> Option<String> {
        let (index, base, pose) = self.loaded.as_ref()?;
        let scene = pose.apply(base, self.animated());
        let v = |p: [f32; 3]| format!("{},{},{}", p[0], p[1], p[2]);
        let several = scene.lights.len() > 1;
        let lights = scene.lights.iter().enumerate().flat_map(|(i, light)| {
            let number = if several {
                format!("{}:", i + 1)
            } else {
                String::new()
            };
            let position = light.position().map(|p| (p, "position"));
            let direction = light.direction().map(|d| (d, "direction"));
            [position, direction]
                .into_iter()
                .flatten()
                .map(move |(vector, what)| {
                    format!("--light-{what} {number}{}", v(vector.to_array()))
                })
        });
        let words = [
            "quadray indirect --scene".to_string(),
            shell_word(&self.scenes[*index]),
            format!("--method {}", self.method),
        ]
        .into_iter()
        .chain(self.shown_settings().to_args())
        .chain([
            format!("--exposure {}", self.exposure),
            format!("--camera-position {}", v(scene.camera.position.to_array())),
            format!("--camera-target {}", v(scene.camera.target.to_array())),
        ])
        .chain(lights)
        .chain(["--frames 1 --out".into(), shell_word(out)]);
        Some(words.collect::<Vec<_>>().join(" "))
    }

    /// Saves the picture shown as a PNG and the command line that reproduces it beside it
    /// (`.txt`; the picture is the one the command writes to the file named in its comment).
    pub fn screenshot(&self, path: &Path) -> Result<String> {
        let picture = self.picture.as_ref().context("nothing drawn yet")?;
        picture.save_png(path)?;
        let out = path.with_extension("headless.png");
        let cmd = self.command_line(&out).context("no scene loaded")?;
        let shown = self.show.headless_file(&out);
        std::fs::write(
            path.with_extension("txt"),
            format!(
                "{cmd}\n# the picture shown is the command's {}\n",
                shown.display()
            ),
        )?;
        Ok(cmd)
    }

    /// Turns the camera by `degrees` and the selected light by `light_degrees` (scripted runs).
    pub fn spin(&mut self, degrees: f32, light_degrees: f32) {
        if let Some((_, base, pose)) = &mut self.loaded {
            pose.yaw += degrees;
            self.redraw = true;
            if light_degrees != 0.0 {
                let (lo, hi) = base.bounds();
                pose.turn_light(self.light, light_degrees, (lo + hi) / 2.0);
                self.rebuild = true;
            }
        }
    }

    /// The light the animation circles, when it is on.
    fn animated(&self) -> Option<usize> {
        self.animate_light.then_some(self.light)
    }

    /// The control panel; marks what a change invalidates.
    pub fn controls(&mut self, ui: &mut egui::Ui) {
        let before = (self.scene, self.method, self.show, self.exposure);
        let scenes: Vec<usize> = (0..self.scenes.len()).collect();
        choice_box(ui, "scene", &mut self.scene, &scenes, |i| {
            scene_name(&self.scenes[i])
        });
        if let Some((_, base, _)) = &self.loaded {
            let lights: Vec<usize> = (0..base.lights.len()).collect();
            choice_box(ui, "light (right drag, L)", &mut self.light, &lights, |i| {
                format!("{}: {}", i + 1, base.lights[i].kind_name())
            });
        }
        choice_box(ui, "method", &mut self.method, &Method::ALL, |m| {
            m.name().into()
        });
        choice_box(ui, "show", &mut self.show, &Show::ALL, |v| v.name().into());
        ui.add(
            egui::Slider::new(&mut self.exposure, 0.05..=20.0)
                .logarithmic(true)
                .text("exposure"),
        );
        let s = &mut self.settings;
        let mut rsm_log = s.rsm_size.ilog2();
        let (smallest, largest) = Settings::RSM_SIZE.interactive_range();
        ui.add(
            egui::Slider::new(&mut rsm_log, smallest.ilog2()..=largest.ilog2())
                .custom_formatter(|v, _| format!("{}", 1u32 << v as u32))
                .text("RSM size"),
        );
        if 1 << rsm_log != s.rsm_size {
            s.rsm_size = 1 << rsm_log;
            // levels chosen on the old RSM follow the new one's defaults again
            s.cluster.start_level = None;
            s.cluster.limit_level = None;
        }
        // the direct light's shadow maps: their default follows the window until one is chosen
        let mut shadow_log = s.shadow_map_size_or_default().ilog2();
        let (smallest, largest) = Settings::SHADOW_MAP_SIZE.interactive_range();
        ui.add(
            egui::Slider::new(&mut shadow_log, smallest.ilog2()..=largest.ilog2())
                .custom_formatter(|v, _| format!("{}", 1u32 << v as u32))
                .text("shadow map size"),
        );
        if 1 << shadow_log != s.shadow_map_size_or_default() {
            s.shadow_map_size = Some(1 << shadow_log);
        }
        named_choice_box(
            ui,
            "G-buffer and RSM layout",
            &mut s.gbuffer_layout,
            &GBufferLayout::ALL,
            |l| l.name().into(),
        );
        let levels = s.levels();
        let (mut start, mut limit) = (levels.start, levels.limit);
        ui.add(egui::Slider::new(&mut start, 0..=rsm_log).text("start level"));
        ui.add(egui::Slider::new(&mut limit, 0..=start).text("limit level"));
        let c = &mut s.cluster;
        if (start, limit) != (levels.start, levels.limit) {
            (c.start_level, c.limit_level) = (Some(start), Some(limit.min(start)));
        }
        let (depth, normal) = (
            ClusterSettings::DEPTH_THRESHOLD,
            ClusterSettings::NORMAL_THRESHOLD,
        );
        ui.add(limits_slider(
            &mut c.depth_threshold,
            depth,
            "depth threshold",
        ));
        ui.add(limits_slider(
            &mut c.normal_threshold,
            normal,
            "normal threshold",
        ));
        let mut recursive = c.validity == Validity::Recursive;
        ui.checkbox(&mut recursive, "recursive validity");
        c.validity = if recursive {
            Validity::Recursive
        } else {
            Validity::Local
        };
        ui.checkbox(&mut c.flux_weighted, "flux-weighted means");
        ui.add(limits_slider(
            &mut s.samples,
            Settings::SAMPLES,
            "RSM samples",
        ));
        let subsampling = format!("sub-sampling ({})", Method::subsampling_names().join(", "));
        named(ui, self.method.subsamples(), &subsampling, |ui| {
            ui.add(limits_slider(&mut s.subsample, Settings::SUBSAMPLE, ""))
        });
        let interleaving = format!("interleaving ({})", Method::subsampling_names().join(", "));
        named(ui, self.method.subsamples(), &interleaving, |ui| {
            ui.add(limits_slider(&mut s.interleave, Settings::INTERLEAVE, ""))
        });
        let criterion = s.tile_criterion;
        named_choice_box(
            ui,
            "tile criterion (quadtree-tiles)",
            &mut s.tile_criterion,
            &TileCriterion::ALL,
            |c| c.name().into(),
        );
        if s.tile_criterion != criterion {
            // the two criteria compare different things with the fraction
            s.tile_error = None;
        }
        let mut tile_error = s.tile_error_or_default();
        let error = Settings::TILE_ERROR;
        named(ui, true, "tile error (quadtree-tiles)", |ui| {
            ui.add(limits_slider(&mut tile_error, error, ""))
        });
        if tile_error != s.tile_error_or_default() {
            s.tile_error = Some(tile_error);
        }
        let share = "shared beyond, tile extents (quadtree-tiles, 0: off)";
        named(ui, true, share, |ui| {
            ui.add(limits_slider(&mut s.tile_share, Settings::TILE_SHARE, ""))
        });
        let deblock = "deblocking, pixels each side (quadtree-tiles, 0: off)";
        named(ui, true, deblock, |ui| {
            ui.add(limits_slider(
                &mut s.tile_deblock,
                Settings::TILE_DEBLOCK,
                "",
            ))
        });
        // marching 8 points per receiver and cluster halves the error to the ground truth with
        // visibility on the leak scene and the Cornell box (BENCHMARKS.md)
        ui.checkbox(&mut s.indirect_shadows, "indirect shadows (quadtree)");
        let mut spacing = s.shadow_corners_or_default();
        let corners = "shadow corners every, pixels (quadtree, 0: each pixel walks)";
        named(ui, s.indirect_shadows, corners, |ui| {
            ui.add(limits_slider(&mut spacing, Settings::SHADOW_CORNERS, ""))
        });
        if spacing != s.shadow_corners_or_default() {
            s.shadow_corners = Some(spacing);
        }
        let shared = "shadow rays shared within, box over distance (quadtree-tiles, 0: off)";
        named(ui, s.indirect_shadows, shared, |ui| {
            let angle = Settings::TILE_SHADOW_ANGLE;
            ui.add(limits_slider(&mut s.tile_shadow_angle, angle, ""))
        });
        named_choice_box(
            ui,
            "tile passes (quadtree-tiles with shadows)",
            &mut s.tile_passes,
            &TilePasses::ALL,
            |p| p.name().into(),
        );
        let mut temporal = s.temporal_weight < 1.0;
        ui.checkbox(&mut temporal, "temporal filter (reprojected)");
        s.temporal_weight = if temporal {
            self.method.moving_light_temporal_weight()
        } else {
            1.0
        };
        ui.checkbox(&mut self.animate_light, "animate light (L)");
        if self.method == Method::Reference {
            let work =
                f64::from(s.size.width) * f64::from(s.size.height) * f64::from(s.rsm_size).powi(2);
            ui.colored_label(
                egui::Color32::YELLOW,
                format!(
                    "brute force: {:.2} G kernel evaluations a frame",
                    work / 1e9
                ),
            );
        }
        if before != (self.scene, self.method, self.show, self.exposure) {
            // a method's first frame builds the buffers it needs
            self.rebuild |= before.1 != self.method;
            self.redraw = true;
        }
    }

    /// Look with the left button, aim the selected light with the right (a point light moves
    /// over the ground plane), move with the wheel.
    pub fn handle_pointer(&mut self, response: &egui::Response, ui: &egui::Ui) {
        let Some((_, base, pose)) = &mut self.loaded else {
            return;
        };
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            pose.yaw += d.x * 0.3;
            pose.pitch = (pose.pitch - d.y * 0.3).clamp(-89.0, 89.0);
            self.redraw = true;
        }
        if response.dragged_by(egui::PointerButton::Secondary) {
            let d = response.drag_delta();
            match &mut pose.lights[self.light] {
                LightPose::Aim { yaw, pitch } => {
                    *yaw += d.x * 0.3;
                    *pitch = (*pitch - d.y * 0.3).clamp(-89.9, 89.9);
                }
                LightPose::Place(position) => {
                    let forward = direction(pose.yaw, 0.0);
                    let right = forward.cross(Vec3::Y);
                    *position += (right * d.x - forward * d.y) * 0.002 * base.extent();
                }
            }
            self.rebuild = true;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                pose.eye += direction(pose.yaw, pose.pitch) * scroll * 0.001 * base.extent();
                self.redraw = true;
            }
        }
    }

    /// Keyboard: W/S forward and back, A/D sideways, Q/E down and up, L animates the light.
    pub fn handle_keys(&mut self, ui: &egui::Ui, dt: f32) {
        let Some((_, base, pose)) = &mut self.loaded else {
            return;
        };
        let forward = direction(pose.yaw, pose.pitch);
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        let step = 0.25 * base.extent() * dt;
        ui.input(|i| {
            for (key, dir) in [
                (egui::Key::W, forward),
                (egui::Key::S, -forward),
                (egui::Key::D, right),
                (egui::Key::A, -right),
                (egui::Key::E, Vec3::Y),
                (egui::Key::Q, -Vec3::Y),
            ] {
                if i.key_down(key) {
                    pose.eye += dir * step;
                    self.redraw = true;
                }
            }
            if i.key_pressed(egui::Key::L) {
                self.animate_light = !self.animate_light;
                self.rebuild = true;
            }
        });
    }
}

/// A scene file's name without its extension.
fn scene_name(path: &Path) -> String {
    path.file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned())
}
