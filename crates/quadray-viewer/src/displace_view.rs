//! The displacement panel: map, surface and method pickers, every parameter, an orbit camera and a
//! moving light; the frame is drawn by `quadray_displace::Renderer::draw` into an offscreen
//! texture that egui shows, so what a person sees is exactly what `quadray displace` renders.

use crate::widgets::{absolute, choice_box, limits_slider, shell_word};
use anyhow::Result;
use quadray_core::image_out::Rgba8Image;
use quadray_displace::cone::ConeMapJob;
use quadray_displace::heightmap::{Convention, Fit, HeightMap};
use quadray_displace::maps::{BUNDLED, assets_dir, load_color};
use quadray_displace::scene::{SurfaceKind, View};
use quadray_displace::{Layers, Lod, Method, Renderer, Settings, Size, Targets};
use quadray_gpu::{Gpu, GpuTimer, read_texture_rgba8};
use std::path::{Path, PathBuf};

/// A height map the viewer can show: a bundled one or one from the command line.
#[derive(Clone, Debug, PartialEq)]
pub struct MapChoice {
    pub name: String,
    pub path: PathBuf,
    pub convention: Convention,
    pub color: Option<PathBuf>,
    pub surface: SurfaceKind,
}

impl MapChoice {
    pub fn bundled() -> Vec<MapChoice> {
        BUNDLED
            .iter()
            .map(|b| MapChoice {
                name: b.name.to_string(),
                path: absolute(assets_dir().join(b.file)),
                convention: b.convention,
                color: b.color.map(|c| absolute(assets_dir().join(c))),
                surface: b.surface,
            })
            .collect()
    }
}

pub struct DisplaceView {
    pub maps: Vec<MapChoice>,
    pub map: usize,
    pub surface: SurfaceKind,
    pub settings: Settings,
    pub animate_light: bool,
    loaded: Option<(usize, SurfaceKind, Renderer)>,
    target: Option<(
        wgpu::Texture,
        wgpu::TextureView,
        wgpu::TextureView,
        egui::TextureId,
    )>,
    timer: GpuTimer,
    pub gpu_ms: Option<f64>,
    pub error: Option<String>,
    /// The cone map being built for the loaded map and surface, off the UI thread.
    cone_job: Option<(usize, SurfaceKind, ConeMapJob)>,
    /// How far that build has come, while the cone method waits for it.
    pub cone_progress: Option<f32>,
}

impl DisplaceView {
    pub fn new(gpu: &Gpu, maps: Vec<MapChoice>, map: usize, settings: Settings) -> Self {
        let surface = maps[map].surface;
        Self {
            maps,
            map,
            surface,
            settings,
            animate_light: false,
            loaded: None,
            target: None,
            timer: GpuTimer::new(gpu, 1),
            gpu_ms: None,
            error: None,
            cone_job: None,
            cone_progress: None,
        }
    }

    /// The renderer for the chosen map and surface, loading the map when the choice changed.
    fn renderer<'a>(
        loaded: &'a mut Option<(usize, SurfaceKind, Renderer)>,
        maps: &[MapChoice],
        map: usize,
        surface: SurfaceKind,
        gpu: &Gpu,
    ) -> Result<&'a mut Renderer> {
        let stale = !matches!(loaded, Some((m, s, _)) if *m == map && *s == surface);
        if stale {
            let choice = &maps[map];
            let height = HeightMap::load(&choice.path, choice.convention, Fit::Exact)?;
            let color = choice.color.as_deref().map(load_color).transpose()?;
            *loaded = Some((
                map,
                surface,
                Renderer::new(gpu, &height, color.as_ref(), surface),
            ));
        }
        Ok(&mut loaded.as_mut().expect("loaded above").2)
    }

    /// Draws the frame at `size` pixels into the offscreen target and returns its egui texture.
    /// A cone map is built on its own thread while the last frame stays up, unless `wait` (a
    /// scripted run, whose frames must show what was asked).
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        egui_renderer: &mut egui_wgpu::Renderer,
        size: [u32; 2],
        dt: f32,
        wait: bool,
    ) -> Option<egui::TextureId> {
        let size = [size[0].clamp(16, 4096), size[1].clamp(16, 4096)];
        if self.animate_light {
            self.settings.light_azimuth_deg = (self.settings.light_azimuth_deg + 40.0 * dt) % 360.0;
        }
        self.settings.size = Size::new(size[0], size[1]);
        let resized =
            !matches!(&self.target, Some((t, ..)) if t.width() == size[0] && t.height() == size[1]);
        if resized {
            let make = |format, usage| {
                quadray_gpu::texture_2d(
                    &gpu.device,
                    "viewer frame",
                    (size[0], size[1]),
                    format,
                    usage,
                )
            };
            let color = make(
                wgpu::TextureFormat::Rgba8UnormSrgb,
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
            );
            let depth = make(
                wgpu::TextureFormat::Depth32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            );
            let color_view = color.create_view(&Default::default());
            let depth_view = depth.create_view(&Default::default());
            let id = match self.target.take() {
                Some((.., id)) => {
                    egui_renderer.update_egui_texture_from_wgpu_texture(
                        &gpu.device,
                        &color_view,
                        wgpu::FilterMode::Nearest,
                        id,
                    );
                    id
                }
                None => egui_renderer.register_native_texture(
                    &gpu.device,
                    &color_view,
                    wgpu::FilterMode::Nearest,
                ),
            };
            self.target = Some((color, color_view, depth_view, id));
        }
        let (_, color_view, depth_view, _) = self.target.as_ref().expect("created above");
        let result = (|| -> Result<()> {
            let renderer =
                Self::renderer(&mut self.loaded, &self.maps, self.map, self.surface, gpu)?;
            self.cone_progress = None;
            if self.settings.method == Method::Cone && !renderer.has_cone_map() && !wait {
                let key = (self.map, self.surface);
                if !matches!(&self.cone_job, Some((m, s, _)) if (*m, *s) == key) {
                    self.cone_job = Some((key.0, key.1, renderer.cone_map_job()));
                }
                let (.., job) = self.cone_job.as_ref().expect("set above");
                if !job.is_finished() {
                    self.cone_progress = Some(job.progress());
                    return Ok(());
                }
                let (.., job) = self.cone_job.take().expect("set above");
                let (cones, seconds) = job.finish();
                renderer.set_cone_map(gpu, &cones, Some(seconds))?;
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let view = View::of(self.surface, &self.settings);
            let targets = Targets {
                color: color_view,
                depth: depth_view,
            };
            renderer.draw(
                gpu,
                &mut encoder,
                &self.settings,
                &view,
                targets,
                Some(&self.timer),
            )?;
            self.timer.resolve(&mut encoder);
            gpu.submit("the viewer's displacement frame", encoder.finish());
            self.timer.collect(gpu)?;
            self.gpu_ms = self.timer.summaries()[0].map(|s| s.median_ms);
            self.timer.clear();
            Ok(())
        })();
        self.error = result.err().map(|e| e.to_string());
        self.target.as_ref().map(|(.., id)| *id)
    }

    /// The `quadray displace` command that renders this view headless.
    pub fn command_line(&self, out: &Path) -> String {
        let choice = &self.maps[self.map];
        let mut cmd = format!(
            "quadray displace --map {} --convention {} --surface {} {}",
            shell_word(&choice.path),
            choice.convention.name(),
            self.surface.name(),
            self.settings.to_args().join(" "),
        );
        if let Some(c) = &choice.color {
            cmd += &format!(" --color {}", shell_word(c));
        }
        cmd + &format!(" --out {}", shell_word(out))
    }

    /// Saves the frame as a PNG and the command line that reproduces it beside it (`.txt`).
    pub fn screenshot(&self, gpu: &Gpu, path: &Path) -> Result<String> {
        let Some((texture, ..)) = &self.target else {
            anyhow::bail!("nothing drawn yet");
        };
        let bytes = read_texture_rgba8(gpu, texture)?;
        Rgba8Image::from_bytes(texture.width(), texture.height(), &bytes).save_png(path)?;
        let cmd = self.command_line(&path.with_extension("headless.png"));
        std::fs::write(path.with_extension("txt"), format!("{cmd}\n"))?;
        Ok(cmd)
    }

    /// The control panel.
    pub fn controls(&mut self, ui: &mut egui::Ui) {
        let s = &mut self.settings;
        let maps: Vec<usize> = (0..self.maps.len()).collect();
        choice_box(ui, "map", &mut self.map, &maps, |i| {
            self.maps[i].name.clone()
        });
        choice_box(ui, "surface", &mut self.surface, &SurfaceKind::ALL, |k| {
            k.name().into()
        });
        choice_box(ui, "method", &mut s.method, &Method::ALL, |m| {
            m.name().into()
        });
        ui.label(s.method.describe().help);
        if ui
            .button("reset")
            .on_hover_text("this method's settings as the demo and the benchmarks show it")
            .clicked()
        {
            *s = Settings {
                size: s.size,
                ..s.method.shown()
            };
        }
        // The sliders span each setting's limits (their interactive part where declared).
        let view_angle = Settings::VIEW_ANGLE;
        ui.add(limits_slider(
            &mut s.view_angle_deg,
            view_angle,
            "view angle",
        ));
        ui.add(limits_slider(
            &mut s.azimuth_deg,
            Settings::AZIMUTH,
            "azimuth",
        ));
        ui.add(limits_slider(&mut s.zoom, Settings::ZOOM, "zoom"));
        ui.add(limits_slider(
            &mut s.depth_scale,
            Settings::DEPTH_SCALE,
            "depth scale",
        ));
        ui.add(limits_slider(
            &mut s.layers.min,
            Layers::COUNT,
            "layers min",
        ));
        ui.add(limits_slider(
            &mut s.layers.max,
            Layers::COUNT,
            "layers max",
        ));
        s.layers.max = s.layers.max.max(s.layers.min);
        ui.add(limits_slider(
            &mut s.binary_steps,
            Settings::BINARY_STEPS,
            "binary steps",
        ));
        let mut auto = s.lod == Lod::Auto;
        ui.checkbox(&mut auto, "LOD from derivatives");
        if auto {
            s.lod = Lod::Auto;
        } else {
            let mut level = match s.lod {
                Lod::Level(l) => l,
                Lod::Auto => 0,
            };
            ui.add(egui::Slider::new(&mut level, 0..=12).text("finest level"));
            s.lod = Lod::Level(level);
        }
        ui.checkbox(&mut s.shadows, "self-shadowing");
        ui.checkbox(&mut s.show_iterations, "iteration heat map");
        ui.add(limits_slider(
            &mut s.light_azimuth_deg,
            Settings::AZIMUTH,
            "light azimuth",
        ));
        ui.checkbox(&mut self.animate_light, "animate light (L)");
        if s.method == Method::Mesh && self.surface == SurfaceKind::Torus {
            ui.colored_label(egui::Color32::YELLOW, "mesh needs a flat surface");
        }
    }

    /// A view angle moved by the mouse or the keys, kept within its limits.
    fn tilt(view_angle_deg: f32) -> f32 {
        view_angle_deg.clamp(Settings::VIEW_ANGLE.min, Settings::VIEW_ANGLE.max)
    }

    /// Orbit with the left button, move the light with the right, zoom with the wheel.
    pub fn handle_pointer(&mut self, response: &egui::Response, ui: &egui::Ui) {
        let s = &mut self.settings;
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            s.azimuth_deg = (s.azimuth_deg - d.x * 0.3 + 540.0) % 360.0 - 180.0;
            s.view_angle_deg = Self::tilt(s.view_angle_deg - d.y * 0.3);
        }
        if response.dragged_by(egui::PointerButton::Secondary) {
            s.light_azimuth_deg =
                (s.light_azimuth_deg + response.drag_delta().x * 0.5).rem_euclid(360.0);
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            let (near, far) = Settings::ZOOM.interactive_range();
            s.zoom = (s.zoom * (1.0 - scroll * 0.002)).clamp(near, far);
        }
    }

    /// Keyboard: W/S tilt, A/D orbit, Q/E zoom, L animates the light.
    pub fn handle_keys(&mut self, ui: &egui::Ui, dt: f32) {
        let s = &mut self.settings;
        ui.input(|i| {
            let rate = 60.0 * dt;
            if i.key_down(egui::Key::W) {
                s.view_angle_deg = Self::tilt(s.view_angle_deg - rate);
            }
            if i.key_down(egui::Key::S) {
                s.view_angle_deg = Self::tilt(s.view_angle_deg + rate);
            }
            if i.key_down(egui::Key::A) {
                s.azimuth_deg -= rate;
            }
            if i.key_down(egui::Key::D) {
                s.azimuth_deg += rate;
            }
            if i.key_down(egui::Key::Q) {
                s.zoom = (s.zoom * (1.0 - dt)).max(Settings::ZOOM.interactive_range().0);
            }
            if i.key_down(egui::Key::E) {
                s.zoom = (s.zoom * (1.0 + dt)).min(Settings::ZOOM.interactive_range().1);
            }
            if i.key_pressed(egui::Key::L) {
                self.animate_light = !self.animate_light;
            }
        });
    }
}
