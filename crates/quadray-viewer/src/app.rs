//! The window: winit events, the wgpu surface, egui's panel, and the frame loop.

use crate::args::{Args, Technique};
use crate::displace_view::{DisplaceView, MapChoice};
use crate::indirect_view::IndirectView;
use crate::legibility::{Legibility, Scrolling};
use anyhow::{Context, Result};
use quadray_core::image_out::Rgba8Image;
use quadray_displace::Settings;
use quadray_gpu::Gpu;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

const PANEL_WIDTH: f32 = 300.0;

pub fn run(args: Args, maps: Vec<MapChoice>, start: usize, settings: Settings) -> Result<()> {
    let event_loop =
        EventLoop::new().context("no window system (is DISPLAY or WAYLAND_DISPLAY set?)")?;
    let mut app = App {
        args,
        start: Some((maps, start, settings)),
        state: None,
        result: Ok(()),
    };
    event_loop.run_app(&mut app)?;
    app.result
}

struct App {
    args: Args,
    start: Option<(Vec<MapChoice>, usize, Settings)>,
    state: Option<State>,
    result: Result<()>,
}

struct State {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// Lives as long as the program: the indirect renderer borrows it.
    gpu: &'static Gpu,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    technique: Technique,
    displace: DisplaceView,
    /// Made when first shown.
    indirect: Option<IndirectView>,
    last_frame: Instant,
    /// Wall time of the last frame's work (render, read back, panel, present), smoothed; the
    /// time between frames says nothing when frames come only on input.
    frame_ms: f32,
    frames_drawn: u32,
    status: String,
    /// When egui wants the next frame; `None`: only on input (nothing moves).
    repaint_at: Option<Instant>,
    /// What of the side panel the last frame let a person read.
    legibility: Option<Legibility>,
}

impl State {
    fn new(
        event_loop: &ActiveEventLoop,
        args: &Args,
        start: (Vec<MapChoice>, usize, Settings),
    ) -> Result<Self> {
        let (w, h) = (args.displace.size.width, args.displace.size.height);
        let attributes = Window::default_attributes()
            .with_title("quadray")
            .with_inner_size(winit::dpi::LogicalSize::new(
                w as f64 + PANEL_WIDTH as f64,
                h.max(560) as f64,
            ));
        let window = Arc::new(event_loop.create_window(attributes)?);
        let instance = Gpu::instance();
        let surface = instance.create_surface(window.clone())?;
        let gpu: &'static Gpu = Box::leak(Box::new(Gpu::for_surface(&instance, Some(&surface))?));
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .context("the adapter cannot present to this window")?;
        // egui blends in gamma space and wants a non-sRGB target; the 3-D view is an sRGB
        // texture, so it is decoded on sampling and encoded again by egui's shader.
        let caps = surface.get_capabilities(&gpu.adapter);
        if let Some(plain) = caps.formats.iter().find(|f| !f.is_srgb()) {
            config.format = *plain;
        }
        surface.configure(&gpu.device, &config);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&gpu.device, config.format, Default::default());
        let (maps, map, settings) = start;
        let displace = DisplaceView::new(gpu, maps, map, settings);
        Ok(Self {
            window,
            surface,
            config,
            gpu,
            egui_ctx,
            egui_state,
            egui_renderer,
            technique: args.technique,
            displace,
            indirect: None,
            last_frame: Instant::now(),
            frame_ms: 0.0,
            frames_drawn: 0,
            status: String::new(),
            repaint_at: Some(Instant::now()),
            legibility: None,
        })
    }

    fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface.configure(&self.gpu.device, &self.config);
    }

    /// One frame; returns true when a scripted run is over.
    fn redraw(&mut self, args: &Args) -> Result<bool> {
        let now = Instant::now();
        let dt = (now - self.last_frame).as_secs_f32().min(0.1);
        self.last_frame = now;
        let scripted = args.frames.is_some();
        self.prepare(args, scripted);
        let raw = self.egui_state.take_egui_input(&self.window);
        if scripted {
            self.egui_ctx.request_repaint();
        }
        let mut save = false;
        let Self {
            egui_ctx,
            technique,
            displace,
            indirect,
            gpu,
            egui_renderer,
            status,
            frame_ms,
            ..
        } = self;
        let gpu: &'static Gpu = gpu;
        let mut panel = None;
        let full = egui_ctx.run_ui(raw, |ui| {
            let shown = egui::Panel::left("controls")
                .exact_size(PANEL_WIDTH)
                .show(ui, |ui| {
                    // the widgets the panel's contents make, in the order made
                    let layer = ui.layer_id();
                    let made = |ui: &egui::Ui| {
                        ui.ctx()
                            .viewport(|v| v.this_pass.widgets.get_layer(layer).count())
                    };
                    let first = made(ui);
                    let (clicked, scrolling) =
                        side_panel(ui, technique, displace, indirect, status, *frame_ms);
                    save |= clicked;
                    let widgets: Vec<egui::WidgetRect> = ui.ctx().viewport(|v| {
                        let all = v.this_pass.widgets.get_layer(layer);
                        all.skip(first).copied().collect()
                    });
                    (scrolling, widgets)
                });
            // the panel as far as the window shows it (its content may run on below)
            panel = Some((shown.response.rect.intersect(ui.max_rect()), shown.inner));
            egui::CentralPanel::default().show(ui, |ui| {
                let shown = indirect
                    .as_mut()
                    .filter(|_| *technique == Technique::Indirect);
                save |= central_view(ui, args, displace, shown, gpu, egui_renderer, dt);
            });
        });
        self.legibility = panel.map(|(rect, (scrolling, widgets))| {
            Legibility::of(rect, Some(&scrolling), &widgets, &full.shapes)
        });
        self.finish(args, full, save, now)
    }

    /// Before the panel: the indirect view, made when first shown, and a scripted run's turn of
    /// the camera after its first frame.
    fn prepare(&mut self, args: &Args, scripted: bool) {
        if self.technique == Technique::Indirect && self.indirect.is_none() {
            let mut view = IndirectView::new(
                self.gpu,
                args.scene.clone(),
                args.indirect_method,
                args.show,
                args.rsm_size,
            );
            view.light = args.light as usize - 1;
            self.indirect = Some(view);
        }
        if scripted && self.frames_drawn > 0 {
            match (self.technique, &mut self.indirect) {
                (Technique::Indirect, Some(view)) => view.spin(args.spin, args.light_spin),
                _ => self.displace.settings.azimuth_deg += args.spin,
            }
        }
    }

    /// After the panel: egui's platform output, when the next frame is due, the screenshot (asked
    /// for, or at the end of a scripted run), the paint and the frame's smoothed work time;
    /// returns true when a scripted run is over.
    fn finish(
        &mut self,
        args: &Args,
        full: egui::FullOutput,
        save: bool,
        started: Instant,
    ) -> Result<bool> {
        self.egui_state
            .handle_platform_output(&self.window, full.platform_output);
        // a frame only when something moves: a CPU rasterizer idles instead of redrawing
        self.repaint_at = full
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .and_then(|v| Instant::now().checked_add(v.repaint_delay));
        self.frames_drawn += 1;
        let done = args.frames.is_some_and(|n| self.frames_drawn >= n);
        let saving = save || done;
        if saving {
            let shot = &args.screenshot;
            let cmd = match (&self.indirect, self.technique) {
                (Some(view), Technique::Indirect) => view.screenshot(shot)?,
                _ => self.displace.screenshot(self.gpu, shot)?,
            };
            if let Some(legibility) = &self.legibility {
                let path = shot.with_extension("panel.txt");
                std::fs::write(&path, legibility.report())
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            self.status = format!("saved {}", shot.display());
            println!("{cmd}");
        }
        let window = saving.then(|| args.screenshot.with_extension("window.png"));
        self.paint(
            full.shapes,
            full.textures_delta,
            full.pixels_per_point,
            window.as_deref(),
        )?;
        let work_ms = started.elapsed().as_secs_f32() * 1e3;
        self.frame_ms = if self.frame_ms == 0.0 {
            work_ms
        } else {
            self.frame_ms * 0.8 + work_ms * 0.2
        };
        Ok(done)
    }

    /// Paints egui's frame into the window and, given `capture`, into a PNG there too.
    fn paint(
        &mut self,
        shapes: Vec<egui::epaint::ClippedShape>,
        textures: egui::TexturesDelta,
        ppp: f32,
        capture: Option<&Path>,
    ) -> Result<()> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.gpu.device, &self.config);
                return Ok(());
            }
            // Occluded or timed out: skip this frame.
            _ => return Ok(()),
        };
        let jobs = self.egui_ctx.tessellate(shapes, ppp);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: ppp,
        };
        for (id, delta) in &textures.set {
            self.egui_renderer
                .update_texture(&self.gpu.device, &self.gpu.queue, *id, delta);
        }
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        let extra = self.egui_renderer.update_buffers(
            &self.gpu.device,
            &self.gpu.queue,
            &mut encoder,
            &jobs,
            &screen,
        );
        let view = frame.texture.create_view(&Default::default());
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[quadray_gpu::cleared_attachment(&view, wgpu::Color::BLACK)],
                ..Default::default()
            });
            self.egui_renderer
                .render(&mut pass.forget_lifetime(), &jobs, &screen);
        }
        self.gpu
            .queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        if let Some(path) = capture {
            self.capture(&jobs, &screen, path)?;
        }
        self.window.pre_present_notify();
        frame.present();
        for id in &textures.free {
            self.egui_renderer.free_texture(id);
        }
        Ok(())
    }
}

impl State {
    /// The window as painted, panel and view: egui's frame painted again into a texture of the
    /// window's size and format, read back and saved to `path`.
    fn capture(
        &mut self,
        jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
        path: &Path,
    ) -> Result<()> {
        let (width, height) = (self.config.width, self.config.height);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let texture = quadray_gpu::texture_2d(
            &self.gpu.device,
            "window capture",
            (width, height),
            self.config.format,
            usage,
        );
        let view = texture.create_view(&Default::default());
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui capture"),
                color_attachments: &[quadray_gpu::cleared_attachment(&view, wgpu::Color::BLACK)],
                ..Default::default()
            });
            self.egui_renderer
                .render(&mut pass.forget_lifetime(), jobs, screen);
        }
        self.gpu.queue.submit([encoder.finish()]);
        let bytes = quadray_gpu::read_texture_rgba8(self.gpu, &texture)?;
        let bgra = matches!(
            self.config.format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let pixels = bytes
            .chunks_exact(4)
            .map(|p| match bgra {
                true => [p[2], p[1], p[0], 255],
                false => [p[0], p[1], p[2], 255],
            })
            .collect();
        Rgba8Image {
            width,
            height,
            pixels,
        }
        .save_png(path)?;
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(start) = self.start.take() {
            match State::new(event_loop, &self.args, start) {
                Ok(state) => self.state = Some(state),
                Err(e) => {
                    self.result = Err(e);
                    event_loop.exit();
                }
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(state) = self.state.as_mut() else {
            return;
        };
        let response = state.egui_state.on_window_event(&state.window, &event);
        // egui asks to repaint after every event, the redraw itself included: not after that one
        if response.repaint && event != WindowEvent::RedrawRequested {
            state.window.request_redraw();
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::KeyboardInput { event: key, .. }
                if key.logical_key
                    == winit::keyboard::Key::Named(winit::keyboard::NamedKey::Escape) =>
            {
                event_loop.exit()
            }
            WindowEvent::Resized(size) => state.resize(size.width, size.height),
            WindowEvent::RedrawRequested => match state.redraw(&self.args) {
                Ok(true) => event_loop.exit(),
                Ok(false) => {}
                Err(e) => {
                    self.result = Err(e);
                    event_loop.exit();
                }
            },
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(state) = &self.state else {
            return;
        };
        match state.repaint_at {
            Some(at) if at <= Instant::now() => state.window.request_redraw(),
            Some(at) => event_loop.set_control_flow(ControlFlow::WaitUntil(at)),
            None => event_loop.set_control_flow(ControlFlow::Wait),
        }
    }
}

/// The side panel: the choice of technique, the shown one's timings and errors and the screenshot
/// button, then its controls, which scroll (the figures first, so that they are in view whatever
/// the window's height, laid out in the frame they change). Returns whether the button was
/// clicked and where the scrolling part shows its content.
fn side_panel(
    ui: &mut egui::Ui,
    technique: &mut Technique,
    displace: &mut DisplaceView,
    indirect: &mut Option<IndirectView>,
    status: &str,
    frame_ms: f32,
) -> (bool, Scrolling) {
    ui.horizontal(|ui| {
        ui.selectable_value(technique, Technique::Displace, "Displacement");
        ui.selectable_value(technique, Technique::Indirect, "Indirect light");
    });
    ui.separator();
    let shown = indirect
        .as_mut()
        .filter(|_| *technique == Technique::Indirect);
    match shown.as_deref() {
        Some(view) => indirect_figures(ui, view, frame_ms),
        None => displace_figures(ui, displace, frame_ms),
    }
    let save = ui.button("Save screenshot + command (P)").clicked();
    if !status.is_empty() {
        ui.label(status);
    }
    ui.separator();
    // a bar in view (egui's floats, unseen until hovered) tells that there is more below
    ui.spacing_mut().scroll = egui::style::ScrollStyle::solid();
    let controls = egui::ScrollArea::vertical()
        .auto_shrink(false)
        .scroll_bar_visibility(egui::scroll_area::ScrollBarVisibility::AlwaysVisible)
        .show(ui, |ui| match shown {
            Some(view) => {
                view.controls(ui);
                ui.small(
                    "Drag: look. Right drag: aim (or move) the selected light. W/A/S/D, Q/E, \
                     wheel: move. L: animate the selected light. P: screenshot.",
                );
            }
            None => {
                displace.controls(ui);
                ui.small(
                    "Drag: orbit. Right drag: light. Wheel or Q/E: zoom. W/A/S/D: move. \
                     L: animate light. P: screenshot.",
                );
            }
        });
    let scrolling = Scrolling {
        view: controls.inner_rect,
        content: egui::Rect::from_min_size(
            controls.inner_rect.min - controls.state.offset,
            controls.content_size,
        ),
    };
    (save, scrolling)
}

/// The indirect view's passes' GPU times, the cut's summary and any error.
fn indirect_figures(ui: &mut egui::Ui, view: &IndirectView, frame_ms: f32) {
    if let Some(t) = &view.timing {
        // in the order the frame runs them
        for pass in quadray_indirect::Pass::ALL {
            if let Some(ms) = t.passes.get(pass.name()) {
                ui.monospace(format!("{:<9}{ms:9.3} ms", pass.name()));
            }
        }
        ui.label(format!("GPU {:.3} ms  frame {frame_ms:.1} ms", t.total_ms));
    } else {
        ui.label(format!("GPU n/a  frame {frame_ms:.1} ms"));
    }
    if let Some(summary) = &view.cut_summary {
        ui.label(summary);
    }
    if let Some(e) = &view.error {
        ui.colored_label(egui::Color32::LIGHT_RED, e);
    }
}

/// The displacement view's GPU time, the cone map's build and any error.
fn displace_figures(ui: &mut egui::Ui, displace: &DisplaceView, frame_ms: f32) {
    ui.label(format!(
        "GPU {}  frame {:.1} ms",
        displace
            .gpu_ms
            .map_or("n/a".into(), |t| format!("{t:.3} ms")),
        frame_ms
    ));
    if let Some(p) = displace.cone_progress {
        ui.label(format!("building the cone map: {:.0}%", p * 100.0));
    }
    if let Some(e) = &displace.error {
        ui.colored_label(egui::Color32::LIGHT_RED, e);
    }
}

/// The 3-D view of the shown technique (`indirect` when it is shown) at the panel's size in
/// pixels (a scripted run's: the frame size), with the pointer and keys handled; asks for the
/// next frame while something moves. Returns whether P was pressed.
fn central_view(
    ui: &mut egui::Ui,
    args: &Args,
    displace: &mut DisplaceView,
    mut indirect: Option<&mut IndirectView>,
    gpu: &'static Gpu,
    egui_renderer: &mut egui_wgpu::Renderer,
    dt: f32,
) -> bool {
    let scripted = args.frames.is_some();
    let points = ui.available_size();
    let ppp = ui.ctx().pixels_per_point();
    let pixels = if scripted {
        [args.displace.size.width, args.displace.size.height]
    } else {
        [(points.x * ppp) as u32, (points.y * ppp) as u32]
    };
    let shown = |size: [u32; 2]| {
        let full = egui::vec2(size[0] as f32, size[1] as f32) / ppp;
        // the cut view is larger than the frame: fit it
        full * (points.x / full.x).min(points.y / full.y).min(1.0)
    };
    let sense = egui::Sense::click_and_drag();
    match &mut indirect {
        Some(view) => {
            if let Some((id, size)) = view.draw(ui.ctx(), pixels, dt) {
                let image = egui::Image::new(egui::load::SizedTexture::new(id, shown(size)));
                let response = ui.add(image.sense(sense));
                view.handle_pointer(&response, ui);
            }
            view.handle_keys(ui, dt);
        }
        None => {
            if let Some(id) = displace.draw(gpu, egui_renderer, pixels, dt, scripted) {
                let image = egui::Image::new(egui::load::SizedTexture::new(id, shown(pixels)));
                let response = ui.add(image.sense(sense));
                displace.handle_pointer(&response, ui);
            }
            displace.handle_keys(ui, dt);
        }
    }
    // held keys move the camera and an animated light moves by itself
    let animating = indirect
        .as_ref()
        .map_or(displace.animate_light, |view| view.animate_light);
    if animating || ui.input(|i| !i.keys_down.is_empty()) {
        ui.ctx().request_repaint();
    } else if displace.cone_progress.is_some() {
        // poll the cone map's build without redrawing the 3-D view meanwhile
        ui.ctx()
            .request_repaint_after(std::time::Duration::from_millis(200));
    }
    ui.input(|i| i.key_pressed(egui::Key::P))
}
