//! `specula view`: every technique and the reference, interactively, on one live scene.
//!
//! A winit window with a wgpu surface and egui panels ([`app`], [`panel`]) drives a windowless
//! [`session::Session`]: the live scene (objects moved through the update path), an orbit
//! camera ([`orbit`]), one instance of each registered method, and the exact method refined
//! progressively on CPU threads as the reference. The [`analysis`] panel runs `specula
//! analyze`'s mirror-view and glare on the live scene off the window's thread and draws them over
//! the view. Script mode ([`script`]) runs the same loop from a TOML file of steps, for tests and
//! repeatable captures.

pub mod analysis;
pub mod analysis_panel;
pub mod app;
pub mod orbit;
pub mod panel;
pub mod present;
pub mod script;
pub mod session;

use std::path::PathBuf;

pub use session::{Session, SessionError, ViewMode};

#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error(transparent)]
    Script(#[from] script::ScriptError),
    #[error("step {step}: {message}")]
    Step { step: usize, message: String },
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error(transparent)]
    Gpu(#[from] specula_gpu::GpuError),
    #[error("window: {0}")]
    Window(String),
}

/// What `specula view` was asked for.
pub struct Options {
    /// Built-in scene name or scene file.
    pub scene: String,
    /// The technique shown first.
    pub method: String,
    /// Window size in pixels.
    pub size: (u32, u32),
    /// Run these steps and exit instead of waiting for the user.
    pub script: Option<PathBuf>,
    /// The technique's resolution while the view moves, as a fraction of the window's side
    /// (the panel's "resolution while moving").
    pub interaction_scale: f32,
    /// Materials given to the scene's objects (`--material`), applied to the scene opened at
    /// the start; one that names an object the scene lacks is an error as the scene's own are.
    pub materials: Vec<specula_scene::MaterialOverride>,
}

/// Opens the window and runs until it is closed (or the script ends). A scene that fails to
/// load opens the built-in default scene with the error shown (in script mode: the error).
pub fn run(options: Options) -> Result<(), ViewerError> {
    specula_methods::Label::parse(&options.method).map_err(SessionError::from)?;
    let steps = options.script.as_deref().map(script::load).transpose()?;
    let loaded = specula_scene::load(&options.scene).and_then(|mut scene| {
        scene.apply_material_overrides(&options.materials)?;
        Ok(scene)
    });
    let (scene, source, message) = match loaded {
        Ok(scene) => (scene, options.scene.clone(), None),
        Err(e) if steps.is_none() => {
            let fallback = specula_scene::builtin::DEFAULT_SCENE;
            let scene = specula_scene::load(fallback).map_err(SessionError::from)?;
            (
                scene,
                fallback.to_string(),
                Some(format!("{e}; showing {fallback}")),
            )
        }
        Err(e) => return Err(SessionError::from(e).into()),
    };
    let event_loop = winit::event_loop::EventLoop::new()
        .map_err(|e| ViewerError::Window(format!("cannot open a window (is DISPLAY set? under no display run `xvfb-run -a specula view ...`): {e}")))?;
    let mut app = app::App::new(options, scene, source, message, steps);
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewerError::Window(e.to_string()))?;
    app.result
}
