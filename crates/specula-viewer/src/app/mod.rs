//! The window: winit events, the wgpu surface, egui, and the frame loop that decides what to
//! render. Script mode runs in the same loop, one step at a time.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;
use specula_gpu::GpuContext;
use specula_methods::{Frame, Pixels};
use specula_scene::Camera;
use specula_trace::Image;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use crate::present::{Presenter, Side};
use crate::script::Step;
use crate::session::{error_image, Session, ViewMode};
use crate::{Options, ViewerError};

mod script_run;
use script_run::{advance_script, count_script_frame, ScriptRun};

/// Degrees of orbit per pixel of mouse drag.
const ORBIT_DEG_PER_PIXEL: f32 = 0.3;
/// The view counts as moving this long after the last input, so the technique stays at the
/// reduced resolution through a series of key presses.
const INTERACTION_LINGER: Duration = Duration::from_millis(200);
/// How often the window looks for the analysis's news while it computes.
const ANALYSIS_POLL: Duration = Duration::from_millis(30);

/// Frames kept for the frame-time graph.
const GRAPH_FRAMES: usize = 180;

/// What the user can change in the panel besides the session.
pub struct Settings {
    /// The technique's resolution, as a fraction of the window's, while the view moves.
    pub interaction_scale: f32,
    /// Render the technique every frame even when nothing changed (for timing).
    pub continuous: bool,
    /// Where the split view cuts, as a fraction of the window width.
    pub split: f32,
    pub show_panel: bool,
    pub show_help: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            interaction_scale: 0.5,
            continuous: false,
            split: 0.5,
            show_panel: true,
            show_help: false,
        }
    }
}

/// The latest technique frame's figures, for the panel.
pub struct FrameStats {
    /// The label drawn (METHOD or METHOD:PRESET).
    pub method: String,
    pub width: u32,
    pub height: u32,
    pub total_ms: f64,
    pub stages: Vec<(String, f64)>,
    pub counters: Vec<(String, u64)>,
    pub warnings: Vec<String>,
    pub created: u64,
}

/// Frame-to-frame times of the window and the technique's own frame times, for the graph.
#[derive(Default)]
pub struct FrameTimes {
    pub window_ms: VecDeque<f64>,
    pub technique_ms: VecDeque<f64>,
}

impl FrameTimes {
    fn push(queue: &mut VecDeque<f64>, value: f64) {
        if queue.len() == GRAPH_FRAMES {
            queue.pop_front();
        }
        queue.push_back(value);
    }
}

/// What the panel reads and writes: everything the window shows about the session.
pub struct UiState {
    pub settings: Settings,
    pub stats: Option<FrameStats>,
    pub times: FrameTimes,
    /// The reference's progress: converged, or refining.
    pub reference_converged: bool,
    pub scene_input: String,
    /// The last thing that went wrong or happened (scene load error, saved screenshot...).
    pub message: Option<(bool, String)>,
    /// The technique must render again (camera, scene, parameter, size or method changed).
    pub dirty: bool,
    pub last_input: Instant,
    /// Where the scene begins, right of the docked panel, in egui points (last frame's).
    pub scene_left_points: f32,
}

struct Mouse {
    position: (f32, f32),
    pressed: Option<(MouseButton, (f32, f32))>,
    moved_while_pressed: bool,
    modifiers: ModifiersState,
}

struct WindowState {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    session: Session,
    presenter: Presenter,
    egui: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    ui: UiState,
    mouse: Mouse,
    last_redraw: Instant,
    /// The technique's latest image on the CPU, for the error view (read back only there).
    technique_image: Option<Image>,
    reference_image: Option<Image>,
    error_stale: bool,
    /// egui wants another frame at once (an animation, a hover).
    egui_repaint: bool,
    /// The analysis's overlay as drawn last, and what it was drawn for.
    overlay: Option<(OverlayKey, egui::TextureHandle)>,
    /// Save the next frame, as the window shows it, here.
    capture: Option<PathBuf>,
    /// Why the last window screenshot could not be saved.
    capture_failure: Option<String>,
}

/// What an overlay depends on: the analysis's outcome and chosen eye point, the scene's
/// version, the view's camera and the overlay's size.
#[derive(PartialEq)]
struct OverlayKey {
    revision: u64,
    glare_eye: usize,
    version: u64,
    camera: [f32; 10],
    size: (u32, u32),
}

/// The overlay is computed at this fraction of the window's side (a ray per pixel).
const OVERLAY_SCALE: u32 = 3;

pub struct App {
    options: Options,
    initial_scene: Option<(specula_scene::Scene, String)>,
    startup_message: Option<String>,
    script: Option<ScriptRun>,
    state: Option<WindowState>,
    pub result: Result<(), ViewerError>,
}

impl App {
    pub fn new(
        options: Options,
        scene: specula_scene::Scene,
        source: String,
        startup_message: Option<String>,
        steps: Option<Vec<Step>>,
    ) -> App {
        App {
            options,
            initial_scene: Some((scene, source)),
            startup_message,
            script: steps.map(|steps| ScriptRun {
                steps,
                next: 0,
                frames_left: 0,
                drag_step: None,
                timing: None,
                pending_capture: None,
            }),
            state: None,
            result: Ok(()),
        }
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), ViewerError> {
        let (width, height) = self.options.size;
        let attributes = Window::default_attributes()
            .with_title("specula")
            .with_inner_size(PhysicalSize::new(width, height))
            .with_resizable(self.script.is_none());
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| ViewerError::Window(e.to_string()))?,
        );
        let instance = specula_gpu::GpuContext::vulkan_instance();
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| ViewerError::Window(format!("cannot make a wgpu surface: {e}")))?;
        let gpu = specula_gpu::GpuContext::with_surface(&instance, Some(&surface))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| ViewerError::Window("the surface offers no format".into()))?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&gpu.device, &config);
        let presenter = Presenter::new(&gpu, format);
        let egui_renderer = egui_wgpu::Renderer::new(&gpu.device, format, Default::default());
        let egui_ctx = egui::Context::default();
        if self.script.is_some() {
            // A scripted frame shows the panel where it ends, not where it slides.
            egui_ctx.all_styles_mut(|style| style.animation_time = 0.0);
        }
        let egui = egui_winit::State::new(
            egui_ctx,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let (scene, source) = self.initial_scene.take().expect("opened once");
        let session = Session::new(
            specula_methods::Context::with_gpu(gpu),
            scene,
            &source,
            &self.options.method,
        )?;
        self.state = Some(WindowState {
            window,
            surface,
            config,
            ui: UiState {
                settings: Settings {
                    interaction_scale: self.options.interaction_scale,
                    // A script's view fills the window until it shows the panel.
                    show_panel: self.script.is_none(),
                    ..Settings::default()
                },
                stats: None,
                times: FrameTimes::default(),
                reference_converged: false,
                scene_input: source,
                message: self.startup_message.take().map(|m| (true, m)),
                dirty: true,
                last_input: Instant::now() - INTERACTION_LINGER,
                scene_left_points: 0.0,
            },
            session,
            presenter,
            egui,
            egui_renderer,
            mouse: Mouse {
                position: (0.0, 0.0),
                pressed: None,
                moved_while_pressed: false,
                modifiers: ModifiersState::empty(),
            },
            last_redraw: Instant::now(),
            technique_image: None,
            reference_image: None,
            error_stale: true,
            egui_repaint: false,
            overlay: None,
            capture: None,
            capture_failure: None,
        });
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: ViewerError) {
        self.result = Err(error);
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        if let Err(e) = self.open(event_loop) {
            self.fail(event_loop, e);
            return;
        }
        if let Some(state) = &self.state {
            state.window.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(state) = self.state.as_mut() else {
            return;
        };
        let response = state.egui.on_window_event(&state.window, &event);
        // egui asks to repaint after every redraw; the frame loop decides that itself.
        if response.repaint && event != WindowEvent::RedrawRequested {
            state.window.request_redraw();
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                state.config.width = size.width.max(1);
                state.config.height = size.height.max(1);
                state.surface.configure(
                    &state.session.ctx.gpu.as_ref().expect("viewer GPU").device,
                    &state.config,
                );
                state.ui.dirty = true;
                state.window.request_redraw();
            }
            WindowEvent::DroppedFile(path) => {
                let source = path.display().to_string();
                state.ui.scene_input = source.clone();
                load_scene(state, &source);
            }
            WindowEvent::ModifiersChanged(m) => state.mouse.modifiers = m.state(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = redraw(state, self.script.as_mut()) {
                    self.fail(event_loop, e);
                    return;
                }
                let finished = self.script.as_ref().is_some_and(|s| {
                    s.next >= s.steps.len() && s.frames_left == 0 && s.pending_capture.is_none()
                });
                if finished {
                    event_loop.exit();
                } else if wants_another_frame(state, self.script.is_some()) {
                    state.window.request_redraw();
                }
            }
            _ if self.script.is_some() => {}
            WindowEvent::KeyboardInput { event, .. }
                if !response.consumed && key(state, event_loop, &event) =>
            {
                state.window.request_redraw();
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = (position.x as f32, position.y as f32);
                let delta = (p.0 - state.mouse.position.0, p.1 - state.mouse.position.1);
                state.mouse.position = p;
                if let Some((button, start)) = state.mouse.pressed {
                    if (p.0 - start.0).abs() + (p.1 - start.1).abs() > 3.0 {
                        state.mouse.moved_while_pressed = true;
                    }
                    drag(state, button, delta);
                    state.window.request_redraw();
                }
            }
            WindowEvent::MouseInput {
                state: pressed,
                button,
                ..
            } => match pressed {
                ElementState::Pressed if !over_panel(state) => {
                    state.mouse.pressed = Some((button, state.mouse.position));
                    state.mouse.moved_while_pressed = false;
                }
                ElementState::Released => {
                    if state.mouse.pressed.is_some()
                        && !state.mouse.moved_while_pressed
                        && button == MouseButton::Left
                    {
                        let (x, y) = state.mouse.position;
                        let scene = state.scene_area();
                        let picked =
                            state
                                .session
                                .pick(x - scene.x as f32, y, scene.width, scene.height);
                        state.session.selected = picked;
                    }
                    state.mouse.pressed = None;
                    state.window.request_redraw();
                }
                _ => {}
            },
            WindowEvent::MouseWheel { delta, .. } if !response.consumed => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                state.session.camera.zoom(0.9f32.powf(lines));
                moved(&mut state.ui);
                state.window.request_redraw();
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let polling = self.state.as_ref().is_some_and(analysis_busy);
        event_loop.set_control_flow(if polling {
            ControlFlow::WaitUntil(Instant::now() + ANALYSIS_POLL)
        } else {
            ControlFlow::Wait
        });
    }

    fn new_events(&mut self, _: &ActiveEventLoop, cause: winit::event::StartCause) {
        if let (winit::event::StartCause::ResumeTimeReached { .. }, Some(state)) =
            (cause, &self.state)
        {
            state.window.request_redraw();
        }
    }
}

/// Whether the cursor is over the docked panel or one of egui's windows. Asked of the last frame's layers at the
/// cursor's current position: egui's own `consumed` uses the pointer position of its last frame,
/// which is stale when a press follows a move before any frame ran.
fn over_panel(state: &WindowState) -> bool {
    let ctx = state.egui.egui_ctx();
    let (x, y) = state.mouse.position;
    // The docked panel is drawn on the background layer with the view: tell it by the scene's
    // edge.
    if x < state.scene_area().x as f32 {
        return true;
    }
    let points = egui::pos2(x, y) / ctx.pixels_per_point();
    ctx.layer_id_at(points)
        .is_some_and(|layer| layer.order != egui::Order::Background)
}

fn moved(ui: &mut UiState) {
    ui.dirty = true;
    ui.last_input = Instant::now();
}

fn interacting(state: &WindowState, script: Option<&ScriptRun>) -> bool {
    let dragging = state.mouse.pressed.is_some() && state.mouse.moved_while_pressed;
    let script_drag = script.is_some_and(|s| s.drag_step.is_some() && s.frames_left > 0);
    dragging
        || script_drag
        || (script.is_none() && state.ui.last_input.elapsed() < INTERACTION_LINGER)
}

fn wants_another_frame(state: &WindowState, scripted: bool) -> bool {
    let technique_reduced = state.session.view.needs_technique()
        && state.session.failure.is_none()
        && state.stats_size() != Some(state.scene_area().size());
    scripted
        || technique_reduced
        || state.egui_repaint
        || state.ui.dirty
        || state.ui.settings.continuous
        || (state.session.view.needs_reference() && !state.ui.reference_converged)
        || state.ui.last_input.elapsed() < INTERACTION_LINGER
}

/// Whether the analysis is computing: the window then looks for its news a few times a second
/// without drawing frames in a busy loop.
fn analysis_busy(state: &WindowState) -> bool {
    state.session.analysis.as_ref().is_some_and(|a| a.busy())
}

/// Mouse drag: left orbits (Shift: pans; Ctrl: moves the selected object in the view plane),
/// right and middle pan.
fn drag(state: &mut WindowState, button: MouseButton, (dx, dy): (f32, f32)) {
    let height = state.config.height as f32;
    let pan = button != MouseButton::Left || state.mouse.modifiers.shift_key();
    if button == MouseButton::Left && state.mouse.modifiers.control_key() {
        if let Some(mesh) = state.session.selected {
            let camera = state.session.camera.camera();
            let centre = state.session.scene().meshes[mesh].bounds().center();
            let depth = (centre - camera.eye).dot(camera.frame().forward).max(1e-3);
            let metres_per_pixel =
                2.0 * depth * (camera.fov_y_deg.to_radians() * 0.5).tan() / height;
            let frame = camera.frame();
            let by = metres_per_pixel * (dx * frame.right - dy * frame.up);
            report(&mut state.ui, state.session.translate(mesh, by));
        }
    } else if pan {
        state.session.camera.pan(-dx / height, dy / height);
    } else {
        state
            .session
            .camera
            .orbit(-dx * ORBIT_DEG_PER_PIXEL, dy * ORBIT_DEG_PER_PIXEL);
    }
    moved(&mut state.ui);
}

fn report<T, E: std::fmt::Display>(ui: &mut UiState, result: Result<T, E>) {
    if let Err(e) = result {
        ui.message = Some((true, e.to_string()));
    }
}

fn load_scene(state: &mut WindowState, source: &str) {
    match state.session.load(source) {
        Ok(()) => {
            state.ui.message = Some((false, format!("loaded {source}")));
            state.reference_image = None;
            state.technique_image = None;
            moved(&mut state.ui);
        }
        Err(e) => state.ui.message = Some((true, format!("{e:#}; kept the previous scene"))),
    }
}

/// A key press; returns whether to redraw.
fn key(state: &mut WindowState, event_loop: &ActiveEventLoop, event: &KeyEvent) -> bool {
    if event.state != ElementState::Pressed {
        return false;
    }
    let shift = state.mouse.modifiers.shift_key();
    // Moves scale with what moves: the selected object's size for object keys, the distance to
    // the target for walking.
    let object_radius = state.session.selected.map_or(1.0, |m| {
        state.session.scene().meshes[m].bounds().radius().max(1e-4)
    });
    let boost = if shift { 5.0 } else { 1.0 };
    let step = object_radius * 0.05 * boost;
    let walk_step = state.session.camera.distance * 0.05 * boost;
    let degrees = 3.0 * boost;
    let camera_frame = state.session.camera.camera().frame();
    let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).try_normalize().unwrap_or(Vec3::X);
    let (right, forward) = (flat(camera_frame.right), flat(camera_frame.forward));
    let mut object_move = None;
    let mut object_turn = None;
    match &event.logical_key {
        Key::Named(NamedKey::Escape) => event_loop.exit(),
        Key::Named(NamedKey::F1) => state.ui.settings.show_help ^= true,
        Key::Named(NamedKey::F12) => screenshot(state),
        Key::Named(NamedKey::Home) => reset_view(state),
        Key::Named(NamedKey::Space) => {
            state.session.view = match state.session.view {
                ViewMode::Reference => ViewMode::Technique,
                _ => ViewMode::Reference,
            };
        }
        Key::Named(NamedKey::ArrowLeft) => object_move = Some(-right * step),
        Key::Named(NamedKey::ArrowRight) => object_move = Some(right * step),
        Key::Named(NamedKey::ArrowUp) => object_move = Some(forward * step),
        Key::Named(NamedKey::ArrowDown) => object_move = Some(-forward * step),
        Key::Named(NamedKey::PageUp) => object_move = Some(Vec3::Y * step),
        Key::Named(NamedKey::PageDown) => object_move = Some(-Vec3::Y * step),
        Key::Character(c) => match c.to_lowercase().as_str() {
            "?" => state.ui.settings.show_help ^= true,
            "t" => {
                state.session.cycle_method(if shift { -1 } else { 1 });
                state.ui.dirty = true;
            }
            "v" => {
                state.session.view = match state.session.view {
                    ViewMode::Technique => ViewMode::Split,
                    ViewMode::Split => ViewMode::Error,
                    _ => ViewMode::Technique,
                };
            }
            "p" => screenshot(state),
            "0" => reset_view(state),
            "h" => state.ui.settings.show_panel ^= true,
            "c" => state.ui.settings.continuous ^= true,
            "w" => walk(state, walk_step, 0.0, 0.0),
            "s" => walk(state, -walk_step, 0.0, 0.0),
            "a" => walk(state, 0.0, -walk_step, 0.0),
            "d" => walk(state, 0.0, walk_step, 0.0),
            "e" => walk(state, 0.0, 0.0, walk_step),
            "q" => walk(state, 0.0, 0.0, -walk_step),
            "[" => object_turn = Some((Vec3::Y, degrees)),
            "]" => object_turn = Some((Vec3::Y, -degrees)),
            "," => object_turn = Some((Vec3::X, degrees)),
            "." => object_turn = Some((Vec3::X, -degrees)),
            "+" | "=" => state.session.camera.zoom(0.9),
            "-" => state.session.camera.zoom(1.0 / 0.9),
            _ => return false,
        },
        _ => return false,
    }
    if let Some(mesh) = state.session.selected {
        if let Some(by) = object_move {
            report(&mut state.ui, state.session.translate(mesh, by));
        }
        if let Some((axis, degrees)) = object_turn {
            report(&mut state.ui, state.session.rotate(mesh, axis, degrees));
        }
    } else if object_move.is_some() || object_turn.is_some() {
        state.ui.message = Some((
            true,
            "select an object first (click it, or pick it in the panel)".into(),
        ));
    }
    moved(&mut state.ui);
    true
}

fn walk(state: &mut WindowState, forward: f32, right: f32, up: f32) {
    state.session.camera.walk(forward, right, up);
}

fn reset_view(state: &mut WindowState) {
    state.session.camera = crate::orbit::OrbitCamera::from_camera(&state.session.scene().camera);
}

/// Saves the current view at the window size, without UI, to the next free
/// `specula-N.png` in the current directory.
fn screenshot(state: &mut WindowState) {
    let path = (1..)
        .map(|n| PathBuf::from(format!("specula-{n}.png")))
        .find(|p| !p.exists())
        .expect("some free name");
    let result = save_view(state, &path);
    state.ui.message = Some(match result {
        Ok(()) => (false, format!("saved {}", path.display())),
        Err(e) => (true, format!("screenshot failed: {e}")),
    });
}

fn save_view(state: &mut WindowState, path: &std::path::Path) -> Result<(), ViewerError> {
    let (w, h) = state.scene_area().size();
    let split = state.ui.settings.split;
    let image = state.session.view_image(w, h, split)?;
    image
        .save_png(path)
        .map_err(crate::session::SessionError::from)?;
    Ok(())
}

fn redraw(state: &mut WindowState, mut script: Option<&mut ScriptRun>) -> Result<(), ViewerError> {
    if let Some(script) = script.as_deref_mut() {
        advance_script(state, script)?;
    }
    let now = Instant::now();
    FrameTimes::push(
        &mut state.ui.times.window_ms,
        (now - state.last_redraw).as_secs_f64() * 1e3,
    );
    state.last_redraw = now;
    let window = (state.config.width, state.config.height);
    let scene = state.scene_area();
    let technique_size = technique_size(state, script.as_deref());
    let ctx = state.session.ctx.clone();
    let gpu = ctx.gpu.as_ref().expect("the viewer opens a GPU");
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("viewer"),
        });

    let view = state.session.view;
    let show_technique = view.needs_technique() && state.session.failure.is_none();
    if show_technique {
        if let Some(frame) = render_technique(state, script.as_deref_mut(), technique_size)? {
            show_technique_frame(state, gpu, &mut encoder, &frame, view)?;
        }
    } else {
        state.ui.dirty = false;
    }
    let needs_reference = view.needs_reference() || state.session.failure.is_some();
    if needs_reference {
        render_reference(state, scene.width, scene.height)?;
    }
    let split = (view == ViewMode::Split && show_technique).then_some(state.ui.settings.split);
    show_reference(state, gpu, view, needs_reference, show_technique);
    if view == ViewMode::Error && show_technique {
        show_error_map(state, gpu);
    }

    update_overlay(state);
    let egui = run_egui(state, gpu, &mut encoder, window);
    if !present(state, gpu, encoder, egui, scene, split) {
        return Ok(());
    }
    if let Some(failure) = state.capture_failure.take() {
        match &script {
            Some(script) => {
                return Err(ViewerError::Step {
                    step: script.next,
                    message: failure,
                })
            }
            None => state.ui.message = Some((true, failure)),
        }
    }
    if let Some(script) = script {
        count_script_frame(state, script);
    }
    Ok(())
}

/// The technique's size: the window's, or while the view moves the window's times the
/// interaction scale.
fn technique_size(state: &WindowState, script: Option<&ScriptRun>) -> (u32, u32) {
    let (width, height) = state.scene_area().size();
    let reduced = interacting(state, script);
    let scale = if reduced {
        state.ui.settings.interaction_scale
    } else {
        1.0
    };
    (
        ((width as f32 * scale).round() as u32).max(1),
        ((height as f32 * scale).round() as u32).max(1),
    )
}

/// Renders the technique at `(tw, th)` when its last frame is stale (anything changed, a
/// continuous or scripted run, another size), keeping its figures for the panel and the
/// script's timing. Returns the frame; None when the last one still stands, or when the
/// technique failed outside a script (the session keeps the failure for the panel). In a
/// script a failure is the step's error.
fn render_technique(
    state: &mut WindowState,
    script: Option<&mut ScriptRun>,
    (tw, th): (u32, u32),
) -> Result<Option<Frame>, ViewerError> {
    let scripted = script.is_some();
    let technique_stale = state.ui.dirty
        || state.ui.settings.continuous
        || scripted
        || state.stats_size() != Some((tw, th));
    if !technique_stale {
        return Ok(None);
    }
    match state.session.render_technique(tw, th) {
        Ok(frame) => {
            state.ui.stats = Some(FrameStats {
                method: state.session.label().to_string(),
                width: tw,
                height: th,
                total_ms: frame.total_milliseconds(),
                stages: frame
                    .stages
                    .iter()
                    .map(|s| (s.stage.clone(), s.milliseconds))
                    .collect(),
                counters: frame.counters.clone(),
                warnings: frame.warnings.clone(),
                created: frame.created().total(),
            });
            FrameTimes::push(&mut state.ui.times.technique_ms, frame.total_milliseconds());
            if let Some(script) = script {
                if let Some((_, _, times)) = &mut script.timing {
                    times.push(frame.total_milliseconds());
                }
            }
            // A progressive technique keeps the frame stale until it converges.
            state.ui.dirty = !frame.converged;
            Ok(Some(frame))
        }
        Err(e) if scripted => Err(ViewerError::Step {
            step: script.as_ref().map_or(0, |s| s.next),
            message: e.to_string(),
        }),
        Err(_) => {
            state.ui.dirty = false;
            Ok(None)
        }
    }
}

/// Shows a new technique `frame` on the left; in the error view keeps its image on the CPU
/// for the error map instead.
fn show_technique_frame(
    state: &mut WindowState,
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    frame: &Frame,
    view: ViewMode,
) -> Result<(), ViewerError> {
    // In the error view the left image is the error map: the technique's frame is not shown
    // (a copy recorded here would also land after the map's write, which the queue runs first).
    if view != ViewMode::Error {
        match &frame.pixels {
            Pixels::Texture(texture) => {
                state
                    .presenter
                    .show_texture(gpu, encoder, Side::Left, texture)
            }
            Pixels::Image(image) => state.presenter.show_image(gpu, Side::Left, image),
        }
    } else {
        let image = frame.image(&state.session.ctx);
        state.technique_image = Some(image.map_err(crate::session::SessionError::from)?);
        state.error_stale = true;
    }
    Ok(())
}

/// The reference's next step at the window's size; its image is read back unless it was
/// converged already and still is.
fn render_reference(state: &mut WindowState, width: u32, height: u32) -> Result<(), ViewerError> {
    let frame = state.session.render_reference(width, height)?;
    let converged_before = state.ui.reference_converged;
    state.ui.reference_converged = frame.converged;
    if !(converged_before && frame.converged && state.reference_image.is_some()) {
        state.reference_image = Some(
            frame
                .image(&state.session.ctx)
                .map_err(crate::session::SessionError::from)?,
        );
        state.error_stale = true;
    }
    Ok(())
}

/// Shows the reference's image: on the right of a split view, else on the left (also in place
/// of a technique that cannot be shown).
fn show_reference(
    state: &mut WindowState,
    gpu: &GpuContext,
    view: ViewMode,
    needs_reference: bool,
    show_technique: bool,
) {
    let reference_side = if view == ViewMode::Split && show_technique {
        Side::Right
    } else {
        Side::Left
    };
    if needs_reference && view != ViewMode::Error || !show_technique {
        if let Some(image) = &state.reference_image {
            state.presenter.show_image(gpu, reference_side, image);
        }
    }
}

/// The error view: the FLIP map of the technique's image against the converged reference, on
/// the left, when either image is new; the technique renders again when its image is missing
/// or of another size.
fn show_error_map(state: &mut WindowState, gpu: &GpuContext) {
    if !(state.error_stale && state.ui.reference_converged) {
        return;
    }
    if state.technique_image.is_none() {
        state.ui.dirty = true;
    }
    if let (Some(reference), Some(technique)) = (&state.reference_image, &state.technique_image) {
        if (reference.width, reference.height) == (technique.width, technique.height) {
            let map = error_image(reference, technique);
            state.presenter.show_image(gpu, Side::Left, &map);
            state.error_stale = false;
        } else {
            state.ui.dirty = true;
        }
    }
}

/// Takes the analysis's news and draws its overlay again where anything it depends on
/// changed.
fn update_overlay(state: &mut WindowState) {
    state.session.update_analysis();
    let Some(analysis) = &state.session.analysis else {
        state.overlay = None;
        return;
    };
    let camera = state.session.camera.camera();
    let scene = state.scene_area();
    let size = (
        scene.width.div_ceil(OVERLAY_SCALE),
        scene.height.div_ceil(OVERLAY_SCALE),
    );
    let key = OverlayKey {
        revision: analysis.revision,
        glare_eye: analysis.glare_eye(),
        version: state.session.live().version(),
        camera: [
            camera.eye.x,
            camera.eye.y,
            camera.eye.z,
            camera.target.x,
            camera.target.y,
            camera.target.z,
            camera.up.x,
            camera.up.y,
            camera.up.z,
            camera.fov_y_deg,
        ],
        size,
    };
    if state.overlay.as_ref().is_some_and(|(k, _)| *k == key) {
        return;
    }
    let Some(overlay) = analysis.overlay(state.session.live(), &camera, size.0, size.1) else {
        state.overlay = None;
        return;
    };
    let image = egui::ColorImage::from_rgba_unmultiplied(
        [overlay.width as usize, overlay.height as usize],
        overlay.pixels.as_flattened(),
    );
    let texture = match state.overlay.take() {
        Some((_, mut texture)) => {
            texture.set(image, egui::TextureOptions::LINEAR);
            texture
        }
        None => state.egui.egui_ctx().load_texture(
            "analysis overlay",
            image,
            egui::TextureOptions::LINEAR,
        ),
    };
    state.overlay = Some((key, texture));
}

/// A frame of egui ready to draw: its triangles, the screen they are for, the texture changes
/// (those to free are freed after drawing) and the command buffers its buffer updates need.
struct EguiFrame {
    jobs: Vec<egui::ClippedPrimitive>,
    screen: egui_wgpu::ScreenDescriptor,
    textures_delta: egui::TexturesDelta,
    extra: Vec<wgpu::CommandBuffer>,
}

/// Runs the panel for this frame (loading the scene it asks for), then uploads egui's new
/// textures and writes its buffers, recording into `encoder`.
fn run_egui(
    state: &mut WindowState,
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (width, height): (u32, u32),
) -> EguiFrame {
    let raw_input = state.egui.take_egui_input(&state.window);
    let egui_ctx = state.egui.egui_ctx().clone();
    let mut load_request = None;
    let overlay = state.overlay.as_ref().map(|(_, texture)| texture.id());
    let scene_left = state.ui.scene_left_points;
    let mut output = egui_ctx.run_pass(raw_input, |ctx| {
        if let Some(texture) = overlay {
            // Under the panel, over the scene's part of the window.
            let mut scene = ctx.content_rect();
            scene.min.x = scene_left;
            ctx.layer_painter(egui::LayerId::background()).image(
                texture,
                scene,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                egui::Color32::WHITE,
            );
        }
        load_request = crate::panel::show(ctx, &mut state.session, &mut state.ui);
        if let Some(analysis) = &state.session.analysis {
            let mut scene = ctx.content_rect();
            scene.min.x = scene_left;
            crate::analysis_panel::legend(ctx, scene, analysis);
        }
    });
    state
        .egui
        .handle_platform_output(&state.window, output.platform_output);
    state.egui_repaint = output
        .viewport_output
        .get(&egui::ViewportId::ROOT)
        .is_some_and(|v| v.repaint_delay.is_zero());
    if let Some(source) = load_request {
        load_scene(state, &source);
    }
    let jobs = egui_ctx.tessellate(output.shapes, output.pixels_per_point);
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [width, height],
        pixels_per_point: output.pixels_per_point,
    };
    // egui checks that every texture change is applied: drain them.
    let mut textures_delta = std::mem::take(&mut output.textures_delta);
    for (id, deltas) in textures_delta.set.drain() {
        for delta in &deltas {
            state
                .egui_renderer
                .update_texture(&gpu.device, &gpu.queue, id, delta);
        }
    }
    let extra =
        state
            .egui_renderer
            .update_buffers(&gpu.device, &gpu.queue, encoder, &jobs, &screen);
    EguiFrame {
        jobs,
        screen,
        textures_delta,
        extra,
    }
}

/// Draws the images (cut at `split`) into the scene's part of the window and egui over the
/// whole window's surface, submits `encoder` and presents. Returns false, drawing nothing, when the surface was lost or
/// outdated: it is configured again and another redraw asked for.
fn present(
    state: &mut WindowState,
    gpu: &GpuContext,
    mut encoder: wgpu::CommandEncoder,
    mut egui: EguiFrame,
    scene: SceneArea,
    split: Option<f32>,
) -> bool {
    let (width, height) = (state.config.width, state.config.height);
    let surface_texture = match state.surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
        other => {
            // Lost or outdated: configure again and draw next time.
            log::warn!("surface: {other:?}");
            state.surface.configure(&gpu.device, &state.config);
            state.window.request_redraw();
            for id in egui.textures_delta.free.drain() {
                state.egui_renderer.free_texture(&id);
            }
            return false;
        }
    };
    let target = surface_texture
        .texture
        .create_view(&wgpu::TextureViewDescriptor::default());
    // A window screenshot draws the same frame once more, into a texture it can read back.
    let capture = state.capture.take().map(|path| {
        let texture = gpu.create_texture(&wgpu::TextureDescriptor {
            label: Some("window screenshot"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: state.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        (path, texture)
    });
    let capture_view = capture
        .as_ref()
        .map(|(_, t)| t.create_view(&wgpu::TextureViewDescriptor::default()));
    for target in std::iter::once(&target).chain(capture_view.as_ref()) {
        state
            .presenter
            .draw(gpu, &mut encoder, target, scene.viewport(), split);
        let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("egui"),
            color_attachments: &[specula_gpu::util::color_attachment(
                target,
                wgpu::LoadOp::Load,
            )],
            ..Default::default()
        });
        state
            .egui_renderer
            .render(&mut pass.forget_lifetime(), &egui.jobs, &egui.screen);
    }
    gpu.queue.submit(
        egui.extra
            .into_iter()
            .chain(std::iter::once(encoder.finish())),
    );
    gpu.queue.present(surface_texture);
    for id in egui.textures_delta.free.drain() {
        state.egui_renderer.free_texture(&id);
    }
    if let Some((path, texture)) = capture {
        let saved = save_texture(gpu, &texture, &path);
        if saved.is_ok() {
            eprintln!("saved the window to {}", path.display());
        }
        state.capture_failure = saved.err();
    }
    true
}

/// Saves an 8-bit RGBA or BGRA texture (sRGB-encoded or not: the bytes are the window's) as PNG.
fn save_texture(
    gpu: &GpuContext,
    texture: &wgpu::Texture,
    path: &std::path::Path,
) -> Result<(), String> {
    let mut bytes = gpu.read_texture(texture, 0).map_err(|e| e.to_string())?;
    let bgra = matches!(
        texture.format(),
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    for texel in bytes.chunks_exact_mut(4) {
        if bgra {
            texel.swap(0, 2);
        }
        texel[3] = 255;
    }
    image::RgbaImage::from_raw(texture.width(), texture.height(), bytes)
        .ok_or("the window's texture has an unexpected size")?
        .save(path)
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// The part of the window the scene is drawn in: right of the docked panel, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SceneArea {
    x: u32,
    width: u32,
    height: u32,
}

impl SceneArea {
    fn size(self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn viewport(self) -> crate::present::Viewport {
        crate::present::Viewport {
            x: self.x,
            width: self.width,
            height: self.height,
        }
    }
}

impl WindowState {
    /// The scene's part of the window: all of it right of the panel as egui laid it out last.
    fn scene_area(&self) -> SceneArea {
        let pixels_per_point = self.egui.egui_ctx().pixels_per_point();
        let left = (self.ui.scene_left_points * pixels_per_point)
            .round()
            .max(0.0) as u32;
        let x = left.min(self.config.width.saturating_sub(1));
        SceneArea {
            x,
            width: self.config.width - x,
            height: self.config.height,
        }
    }

    fn stats_size(&self) -> Option<(u32, u32)> {
        self.ui
            .stats
            .as_ref()
            .filter(|s| s.method == self.session.label().to_string())
            .map(|s| (s.width, s.height))
    }
}
