//! The window, its frame loop and its input.
//!
//! A frame: the script's actions for it (scripted mode), the panel, the edits it made;
//! a tessellation only when something it depends on changed (parameters, the model, the
//! animated points) or when the drawn stage's newest status asks for a rerun after its
//! buffers overflowed; then one draw of the output, the panel over it, the copy to the
//! surface. A still scene costs the draw and the panel.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tessera_wgpu::image_out::{read_rgba, save_png, COLOR_FORMAT};
use tessera_wgpu::{wgpu, GpuTimer, Kernels, RenderOptions};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::camera::{Axis, Orbit};
use crate::gpu::{Gpu, Painter, Targets};
use crate::panel::{self, Request, Shown, View};
use crate::scene::{Model, Params, RunTime, Tessellator};
use crate::script::{Action, Script, Setting, Step};
use crate::stats::{write_json, FrameRate, FrameStats};

/// Animation time per frame in scripted mode, seconds: runs repeat on any machine.
pub const SCRIPT_STEP: f64 = 1.0 / 30.0;

/// What the command line asked for.
pub struct Options {
    pub size: (u32, u32),
    pub up: Axis,
    pub split_non_manifold: bool,
    pub panel: bool,
    pub scripted: Option<Scripted>,
}

/// `--frames N` and what goes with it.
pub struct Scripted {
    pub frames: u32,
    pub screenshot: Option<PathBuf>,
    pub script: Script,
    pub stats_json: Option<PathBuf>,
}

/// Opens the window on `model` and runs until it is closed (or, scripted, until the
/// last frame). The error is one line.
pub fn run(options: Options, model: Model) -> Result<(), String> {
    let event_loop = EventLoop::new().map_err(|e| format!("no window system: {e}"))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App {
        options,
        model: Some(model),
        running: None,
        outcome: Ok(()),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| format!("the window's event loop failed: {e}"))?;
    app.outcome
}

struct App {
    options: Options,
    /// The first model, until the window opens.
    model: Option<Model>,
    running: Option<Running>,
    outcome: Result<(), String>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Drag {
    Orbit,
    Pan,
}

struct Running {
    // The surface (in `gpu`) is dropped before the window it draws on.
    gpu: Gpu,
    painter: Painter,
    targets: Option<Targets>,
    egui_renderer: egui_wgpu::Renderer,
    egui_state: egui_winit::State,
    egui_ctx: egui::Context,
    kernels: Kernels,
    tess: Tessellator,
    timer: Option<GpuTimer>,
    params: Params,
    /// The parameters of the last run recorded, and its view where the mesh follows it.
    ran_with: Option<(Params, Option<tessera_wgpu::View>)>,
    view: View,
    orbit: Orbit,
    /// Something the output depends on changed since the last run.
    dirty: bool,
    anim_time: f64,
    last_run: Option<RunTime>,
    /// Wall time of the newest GPU run without timestamps, set when it completes.
    submission_ms: Arc<Mutex<Option<f64>>>,
    cpu_ms: Option<f64>,
    frame: u32,
    last_frame_start: Option<Instant>,
    rate: FrameRate,
    stats: FrameStats,
    rows: Vec<FrameStats>,
    cursor: Option<PhysicalPosition<f64>>,
    drag: Option<Drag>,
    occluded: bool,
    load_error: Option<String>,
    run_error: Option<String>,
    /// The scene's viewport in pixels (right of the panel).
    viewport: [f32; 4],
    assets: Vec<PathBuf>,
    adapter_name: String,
    window: Arc<Window>,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: String) {
        if self.outcome.is_ok() {
            self.outcome = Err(e);
        }
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        let Some(model) = self.model.take() else {
            return Ok(());
        };
        let o = &self.options;
        let attributes = Window::default_attributes()
            .with_title(format!("tessera — {}", model.name()))
            .with_inner_size(PhysicalSize::new(o.size.0, o.size.1));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| format!("opening the window failed: {e}"))?,
        );
        let gpu = Gpu::new(
            event_loop.owned_display_handle(),
            window.clone(),
            o.scripted.is_none(),
        )?;
        let painter = Painter::new(&gpu);
        let egui_ctx = egui::Context::default();
        egui_ctx.set_theme(egui::Theme::Light);
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            window.as_ref(),
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(
            &gpu.device,
            COLOR_FORMAT,
            egui_wgpu::RendererOptions {
                msaa_samples: 1,
                ..Default::default()
            },
        );
        let kernels = Kernels::new(&gpu.device);
        let timer = GpuTimer::new(&gpu.device, &gpu.queue);
        let params = Params::defaults(&model);
        let view = View {
            wireframe: false,
            patch_tint: false,
            up: o.up,
            animate: false,
            split_non_manifold: o.split_non_manifold,
        };
        self.running = Some(Running {
            adapter_name: gpu.adapter_name(),
            painter,
            targets: None,
            egui_renderer,
            egui_state,
            egui_ctx,
            tess: Tessellator::new(kernels.clone(), model),
            kernels,
            timer,
            params,
            ran_with: None,
            view,
            orbit: Orbit::new(o.up),
            dirty: true,
            anim_time: 0.0,
            last_run: None,
            submission_ms: Arc::new(Mutex::new(None)),
            cpu_ms: None,
            frame: 0,
            last_frame_start: None,
            rate: FrameRate::default(),
            stats: FrameStats::default(),
            rows: Vec::new(),
            cursor: None,
            drag: None,
            occluded: false,
            load_error: None,
            run_error: None,
            viewport: [0.0; 4],
            assets: shipped_assets(),
            window,
            gpu,
        });
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_none() {
            if let Err(e) = self.open(event_loop) {
                self.fail(event_loop, e);
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let scripted = self.options.scripted.as_ref().map(|s| s.frames);
        let Some(r) = self.running.as_mut() else {
            return;
        };
        let outcome = match &event {
            WindowEvent::CloseRequested => match scripted {
                Some(n) => Err(format!("the window was closed at frame {} of {n}", r.frame)),
                None => Ok(false),
            },
            WindowEvent::RedrawRequested => r.frame(&self.options),
            _ => {
                match &event {
                    WindowEvent::Resized(size) => r.gpu.resize(size.width, size.height),
                    WindowEvent::Occluded(o) => r.occluded = *o,
                    WindowEvent::DroppedFile(path) => {
                        r.load(path);
                    }
                    _ => {}
                }
                let response = r.egui_state.on_window_event(&r.window, &event);
                if !response.consumed {
                    r.input(&event);
                }
                Ok(true)
            }
        };
        match outcome {
            Ok(true) => {}
            Ok(false) => event_loop.exit(),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(r) = self.running.as_ref() else {
            return;
        };
        let size = r.window.inner_size();
        let hidden = size.width == 0 || size.height == 0 || r.occluded;
        if hidden && self.options.scripted.is_none() {
            // Nothing to draw: sleep until the window comes back.
            event_loop.set_control_flow(ControlFlow::Wait);
        } else {
            event_loop.set_control_flow(ControlFlow::Poll);
            r.window.request_redraw();
        }
    }
}

impl Running {
    /// Camera and keys, for input the panel did not take.
    fn input(&mut self, event: &WindowEvent) {
        let pointer_on_panel = self.egui_ctx.egui_wants_pointer_input();
        match event {
            WindowEvent::MouseInput { state, button, .. } => match state {
                ElementState::Pressed if !pointer_on_panel => {
                    self.drag = match button {
                        MouseButton::Left => Some(Drag::Orbit),
                        MouseButton::Right | MouseButton::Middle => Some(Drag::Pan),
                        _ => self.drag,
                    }
                }
                ElementState::Released => self.drag = None,
                _ => {}
            },
            WindowEvent::CursorMoved { position, .. } => {
                if let (Some(drag), Some(last)) = (self.drag, self.cursor) {
                    let (dx, dy) = ((position.x - last.x) as f32, (position.y - last.y) as f32);
                    match drag {
                        Drag::Orbit => self.orbit.orbit(-0.01 * dx, 0.01 * dy),
                        Drag::Pan => {
                            let h = self.viewport[3].max(1.0);
                            let pose = self.pose();
                            self.orbit.pan(&pose, -dx / h, dy / h);
                        }
                    }
                }
                self.cursor = Some(*position);
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } if !pointer_on_panel => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.orbit.zoom(1.1f32.powf(steps));
            }
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed
                    && !self.egui_ctx.egui_wants_keyboard_input() =>
            {
                match &event.logical_key {
                    Key::Character(c) if c.eq_ignore_ascii_case("f") => self.orbit.home(),
                    Key::Named(NamedKey::Home) => self.orbit.home(),
                    _ => {}
                }
            }
            _ => {}
        }
    }

    /// The scene's viewport in whole pixels (at least one each way).
    fn viewport_px(&self) -> (u32, u32) {
        let [_, _, w, h] = self.viewport;
        (w.max(1.0) as u32, h.max(1.0) as u32)
    }

    /// Where the orbit stands now.
    fn pose(&self) -> tessera_wgpu::Pose {
        self.orbit.pose(self.tess.model.bounds, self.viewport_px())
    }

    /// The view drawn now.
    fn view(&self) -> tessera_wgpu::View {
        self.orbit.view(self.tess.model.bounds, self.viewport_px())
    }

    /// Opens `path`; on failure the open model stays and the panel shows the error.
    fn load(&mut self, path: &Path) -> bool {
        match Model::load(path, self.view.split_non_manifold) {
            Ok(model) => {
                for w in &model.warnings {
                    eprintln!("warning: {w}");
                }
                self.params = self.params.for_model(self.tess.model.kind(), &model);
                self.tess = Tessellator::new(self.kernels.clone(), model);
                if self.view.animate {
                    self.tess.animate(Some(self.anim_time), self.view.up);
                }
                self.orbit.home();
                self.window
                    .set_title(&format!("tessera — {}", self.tess.model.name()));
                self.load_error = None;
                self.run_error = None;
                self.dirty = true;
                true
            }
            Err(e) => {
                self.load_error = Some(e.to_string());
                false
            }
        }
    }

    /// One script step.
    fn apply(&mut self, script: &Script, step: &Step) -> Result<(), String> {
        let kind = self.tess.model.kind();
        match &step.action {
            Action::Orbit { yaw, pitch } => self.orbit.orbit(yaw.to_radians(), pitch.to_radians()),
            Action::Zoom(f) => self.orbit.zoom(*f),
            Action::Pan { right, up } => {
                let pose = self.pose();
                self.orbit.pan(&pose, *right, *up);
            }
            Action::Frame => self.orbit.home(),
            Action::Up(axis) => self.set_up(*axis),
            Action::Animate(on) => self.view.animate = on.unwrap_or(!self.view.animate),
            Action::Reset => self.reset_animation(),
            Action::Load(path) => {
                if !self.load(path) {
                    eprintln!(
                        "warning: {}: keeping {}: {}",
                        script.error_at(step, "load failed"),
                        self.tess.model.name(),
                        self.load_error.as_deref().unwrap_or("")
                    );
                }
            }
            // After the frame is drawn.
            Action::Screenshot(_) => {}
            Action::Set(s) => {
                let p = &mut self.params;
                let wrong = |what: &str| script.error_at(step, what);
                use crate::scene::Kind;
                match *s {
                    Setting::Method(m) => {
                        if !crate::scene::Method::of(kind).contains(&m) {
                            return Err(wrong(&format!(
                                "method {} is not one for {} (it takes {})",
                                m.name(),
                                self.tess.model.name(),
                                crate::scene::Method::of(kind)
                                    .iter()
                                    .map(|m| m.name())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            )));
                        }
                        p.method = m;
                    }
                    Setting::Threshold(t) if kind == Kind::Bezier => p.threshold = t,
                    Setting::Threshold(_) => return Err(wrong(
                        "threshold is a Bézier setting; Catmull-Clark meshes take tolerance-rel",
                    )),
                    Setting::ToleranceRel(t) if kind == Kind::CatmullClark => {
                        p.tolerance_rel = t;
                        p.pixels = None;
                    }
                    Setting::TolerancePx(px) if kind == Kind::CatmullClark => p.pixels = Some(px),
                    Setting::CullBackfaces(c) if kind == Kind::CatmullClark => p.cull_backfaces = c,
                    Setting::CullBackfaces(_) => {
                        return Err(wrong("cull-backfaces is a Catmull-Clark setting"))
                    }
                    Setting::TolerancePx(_) => return Err(wrong(
                        "tolerance-px is a Catmull-Clark setting; Bézier surfaces take threshold",
                    )),
                    Setting::ToleranceRel(_) => return Err(wrong(
                        "tolerance-rel is a Catmull-Clark setting; Bézier surfaces take threshold",
                    )),
                    Setting::MaxDepth(d) => {
                        let limit = Params::depth_limit(kind);
                        if d > limit {
                            return Err(wrong(&format!("max-depth {d}: at most {limit} here")));
                        }
                        match kind {
                            Kind::Bezier => p.bezier_depth = d,
                            Kind::CatmullClark => p.cc_depth = d,
                        }
                    }
                    Setting::FirstSplit(f) => p.first_split = f,
                    Setting::Segments(n) => p.segments = n,
                    Setting::Wireframe(w) => self.view.wireframe = w,
                    Setting::PatchTint(t) => self.view.patch_tint = t,
                    Setting::Backend(b) => p.backend = b,
                }
            }
        }
        Ok(())
    }

    fn set_up(&mut self, up: Axis) {
        if up != self.view.up || up != self.orbit.up {
            self.view.up = up;
            self.orbit.set_up(up);
            if self.view.animate {
                self.dirty = true;
            }
        }
    }

    fn reset_animation(&mut self) {
        self.anim_time = 0.0;
        self.tess.animate(None, self.view.up);
        self.dirty = true;
    }

    /// One frame. `Ok(false)` when a scripted run is over.
    fn frame(&mut self, options: &Options) -> Result<bool, String> {
        let start = Instant::now();
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            // Minimised: nothing to draw, and a surface is never configured at 0.
            return Ok(true);
        }
        let max = self.gpu.device.limits().max_texture_dimension_2d;
        if self.gpu.size() != (size.width.min(max), size.height.min(max)) {
            self.gpu.resize(size.width, size.height);
        }
        self.gpu.reconfigure_if_needed();
        let scripted = options.scripted.as_ref();

        if let Some(s) = scripted {
            let steps: Vec<Step> = s.script.at(self.frame).cloned().collect();
            for step in &steps {
                self.apply(&s.script, step)?;
            }
        }

        // The panel, on copies of the settings.
        let mut raw = self.egui_state.take_egui_input(&self.window);
        if scripted.is_some() {
            raw.time = Some(self.frame as f64 * SCRIPT_STEP);
            raw.predicted_dt = SCRIPT_STEP as f32;
        }
        let mut params = self.params;
        let mut view = self.view;
        let mut requests = Vec::new();
        let mut panel_right = 0.0f32;
        let wgpu_errors = self.gpu.errors();
        let mut full = {
            let shown = Shown {
                model: &self.tess.model,
                stats: &self.stats,
                fps: self.rate.fps(),
                wireframe_available: self.painter.mesh.wireframe_available(),
                timestamps: self.timer.is_some(),
                adapter: &self.adapter_name,
                assets: &self.assets,
                load_error: self.load_error.as_deref(),
                run_error: self.run_error.as_deref(),
                wgpu_errors: &wgpu_errors,
            };
            self.egui_ctx.run_ui(raw, |ui| {
                if options.panel {
                    // Wide enough for its controls, and the model keeps most of a small window.
                    let avail = ui.available_width();
                    let r = egui::Panel::left("tessera panel")
                        .default_size((0.45 * avail).clamp(160.0, 280.0))
                        .max_size((0.6 * avail).max(160.0))
                        .show(ui, |ui| panel::contents(ui, &shown, &mut params, &mut view));
                    panel_right = r.response.rect.right();
                    requests = r.inner;
                }
            })
        };
        self.egui_state
            .handle_platform_output(&self.window, full.platform_output);
        // The panel's textures go up now, so that no return below leaves a delta
        // unapplied; those to free wait for the submission.
        let mut textures = std::mem::take(&mut full.textures_delta);
        for (id, deltas) in textures.set.drain() {
            for delta in &deltas {
                self.egui_renderer
                    .update_texture(&self.gpu.device, &self.gpu.queue, id, delta);
            }
        }
        let free: Vec<egui::TextureId> = textures.free.drain().collect();

        // The panel's edits.
        if view.up != self.view.up {
            self.set_up(view.up);
        }
        // (A change of `split_non_manifold` comes with the panel's request to reload.)
        self.view = View {
            up: self.view.up,
            ..view
        };
        self.params = params;
        for request in requests {
            match request {
                Request::Load(path) => {
                    self.load(&path);
                }
                Request::Frame => self.orbit.home(),
                Request::ResetAnimation => self.reset_animation(),
            }
        }

        // Animation: time advances while it is on (by a fixed step when scripted).
        let dt = match (scripted, self.last_frame_start) {
            (Some(_), _) => SCRIPT_STEP,
            (None, Some(t)) => t.elapsed().as_secs_f64().min(0.1),
            (None, None) => 0.0,
        };
        if self.view.animate {
            self.anim_time += dt;
            self.tess.animate(Some(self.anim_time), self.view.up);
            self.dirty = true;
        }
        // The scene right of the panel: the view drawn, and tessellated for in pixels.
        let ppp = full.pixels_per_point;
        let (w, h) = self.gpu.size();
        let left = (panel_right * ppp).clamp(0.0, w as f32);
        self.viewport = [left, 0.0, w as f32 - left, h as f32];
        let drawn_view = self.view();
        let follows = self
            .params
            .follows_view(self.tess.model.kind())
            .then_some(drawn_view);
        if self.ran_with != Some((self.params, follows)) || self.tess.grow_pending() {
            self.dirty = true;
        }

        // Tessellation, on its own submission (so that its wall time is its own).
        let mut tessellated = false;
        if self.dirty {
            self.dirty = false;
            self.ran_with = Some((self.params, follows));
            let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
            let t0 = Instant::now();
            match self.tess.record(
                &self.gpu.device,
                &self.gpu.queue,
                &self.params,
                &drawn_view,
                &mut encoder,
                self.timer.as_mut(),
            ) {
                Ok(run) => {
                    self.gpu.queue.submit([encoder.finish()]);
                    match run {
                        RunTime::Submission => {
                            let slot = self.submission_ms.clone();
                            self.gpu.queue.on_submitted_work_done(move || {
                                if let Ok(mut s) = slot.lock() {
                                    *s = Some(t0.elapsed().as_secs_f64() * 1e3);
                                }
                            });
                        }
                        RunTime::Cpu(ms) => self.cpu_ms = Some(ms),
                        RunTime::Timestamps => {}
                    }
                    self.last_run = Some(run);
                    self.run_error = None;
                    tessellated = true;
                }
                Err(e) => {
                    if let Some(s) = scripted {
                        return Err(format!("frame {} of {}: {e}", self.frame, s.frames));
                    }
                    self.run_error = Some(e);
                }
            }
        }

        // The draw: the scene, the panel, the copy to the surface.
        self.painter.mesh.prepare(
            &self.gpu.queue,
            &drawn_view,
            &RenderOptions {
                wireframe: self.view.wireframe,
                patch_tint: self.view.patch_tint,
                ..RenderOptions::default()
            },
        );
        if self.targets.as_ref().map(|t| t.size) != Some((w, h)) {
            self.targets = Some(self.painter.targets(&self.gpu.device, (w, h)));
        }
        let Some(targets) = self.targets.as_ref() else {
            return Ok(true);
        };
        let device = &self.gpu.device;
        let queue = &self.gpu.queue;
        let mut encoder = device.create_command_encoder(&Default::default());
        self.painter
            .draw_scene(&mut encoder, targets, self.tess.output(), self.viewport);
        let jobs = self.egui_ctx.tessellate(full.shapes, ppp);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [w, h],
            pixels_per_point: ppp,
        };
        let extra = self
            .egui_renderer
            .update_buffers(device, queue, &mut encoder, &jobs, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("tessera-demo panel"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &targets.frame_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            self.egui_renderer.render(&mut pass, &jobs, &screen);
        }
        let surface_texture = self.gpu.acquire(&self.window);
        if let Some(st) = &surface_texture {
            let view = st.texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(self.gpu.view_format),
                ..Default::default()
            });
            self.painter.present_copy(&mut encoder, targets, &view);
        }
        self.gpu
            .queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        if let Some(st) = surface_texture {
            self.window.pre_present_notify();
            self.gpu.queue.present(st);
        }
        self.gpu.reconfigure_if_needed();
        for id in &free {
            self.egui_renderer.free_texture(id);
        }

        if scripted.is_some() {
            // Each frame's figures are its own: wait for its work and its statuses.
            self.gpu
                .device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| format!("waiting for the GPU: {e}"))?;
        }
        let keep = scripted.is_some_and(|s| s.stats_json.is_some());
        self.record_stats(start, tessellated, keep);

        let Some(s) = scripted else {
            self.frame += 1;
            return Ok(true);
        };
        let errors = self.gpu.errors();
        if !errors.is_empty() {
            return Err(format!("wgpu: {}", errors.join("; ")));
        }
        for step in s.script.at(self.frame) {
            if let Action::Screenshot(path) = &step.action {
                self.screenshot(path)
                    .map_err(|e| s.script.error_at(step, e))?;
            }
        }
        self.frame += 1;
        if self.frame < s.frames {
            return Ok(true);
        }
        if let Some(path) = &s.screenshot {
            self.screenshot(path)?;
        }
        if let Some(path) = &s.stats_json {
            write_json(path, &self.rows)?;
        }
        let errors = self.gpu.errors();
        if !errors.is_empty() {
            return Err(format!("wgpu: {}", errors.join("; ")));
        }
        Ok(false)
    }

    /// This frame's figures; kept for `--stats-json` where `keep`.
    fn record_stats(&mut self, start: Instant, tessellated: bool, keep: bool) {
        let counts = self.tess.counts(&self.gpu.device).unwrap_or_default();
        let (mut gpu_ms, mut wall_ms) = (None, None);
        match self.last_run {
            Some(RunTime::Timestamps) => {
                gpu_ms = self
                    .timer
                    .as_mut()
                    .and_then(|t| t.try_read_ms(&self.gpu.device))
            }
            Some(RunTime::Submission) => wall_ms = self.submission_ms.lock().ok().and_then(|s| *s),
            Some(RunTime::Cpu(_)) => wall_ms = self.cpu_ms,
            None => {}
        }
        if let Some(last) = self.last_frame_start {
            self.rate
                .push(start.duration_since(last).max(Duration::from_micros(1)));
        }
        self.last_frame_start = Some(start);
        self.stats = FrameStats {
            frame: self.frame,
            triangles: counts.triangles,
            vertices: counts.vertices,
            patches: self.tess.model.patches,
            guaranteed_bound: counts.guaranteed_bound,
            tolerance_px: self
                .params
                .follows_view(self.tess.model.kind())
                .then_some(counts.tolerance_px)
                .flatten(),
            culled_patches: self
                .params
                .follows_view(self.tess.model.kind())
                .then_some(counts.culled_patches)
                .flatten(),
            gpu_ms,
            wall_ms,
            frame_ms: start.elapsed().as_secs_f64() * 1e3,
            growths: counts.growths,
            tessellated,
            overflowed: counts.overflowed,
        };
        if keep {
            self.rows.push(self.stats.clone());
        }
    }

    /// Saves the frame just drawn (the texture the surface was given).
    fn screenshot(&self, path: &Path) -> Result<(), String> {
        let Some(targets) = &self.targets else {
            return Err(format!("{}: no frame was drawn", path.display()));
        };
        let image = read_rgba(&self.gpu.device, &self.gpu.queue, &targets.frame)
            .map_err(|e| e.to_string())?;
        save_png(&image, path).map_err(|e| e.to_string())
    }
}

/// The shipped models: `assets/teaset/*` (the teaset files), `assets/opensubdiv/*.obj`,
/// `assets/catmull_clark/*.obj`, from the source tree's `assets` or `./assets`.
pub fn shipped_assets() -> Vec<PathBuf> {
    let root = assets_dir();
    let mut out = Vec::new();
    for (dir, ext) in [
        ("teaset", None),
        ("opensubdiv", Some("obj")),
        ("catmull_clark", Some("obj")),
    ] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_file())
            .filter(|p| match ext {
                Some(ext) => p.extension().and_then(|e| e.to_str()) == Some(ext),
                // The teaset files have no extension (README.md aside).
                None => p.extension().is_none(),
            })
            .collect();
        files.sort();
        out.extend(files);
    }
    out
}

/// `assets/` of the source tree the binary was built from, else of the current directory.
pub fn assets_dir() -> PathBuf {
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    if built.is_dir() {
        built
    } else {
        PathBuf::from("assets")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_menu_lists_the_shipped_models() {
        let assets = shipped_assets();
        let names: Vec<String> = assets
            .iter()
            .map(|p| {
                p.file_name()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect();
        for want in [
            "teapot",
            "teacup",
            "teaspoon",
            "catmark_torus.obj",
            "catmark_car.obj",
            "spot_control_mesh.obj",
        ] {
            assert!(names.iter().any(|n| n == want), "{want} in {names:?}");
        }
        assert!(!names
            .iter()
            .any(|n| n.ends_with(".md") || n.ends_with(".txt")));
    }
}
