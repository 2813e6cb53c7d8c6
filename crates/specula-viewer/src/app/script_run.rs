//! Script mode in the window's loop: each step run in turn, up to the next that draws
//! frames, and the timing of those frames.

use super::*;
use crate::script::AnalysisStep;

/// A script being run: its steps, the one at hand, and the frames it still wants.
pub(super) struct ScriptRun {
    pub(super) steps: Vec<Step>,
    pub(super) next: usize,
    pub(super) frames_left: u32,
    pub(super) drag_step: Option<(f32, f32)>,
    /// The step now drawing frames, its first frame's time and its technique frame times.
    pub(super) timing: Option<(usize, Instant, Vec<f64>)>,
    /// A window screenshot waiting for the view to settle, and the frames drawn meanwhile.
    pub(super) pending_capture: Option<(usize, PathBuf, u32)>,
}

/// The most frames a window screenshot waits for the view to settle.
const SETTLE_FRAMES: u32 = 3_000;

/// Whether what the window shows is final: the technique's frame converged (a progressive one
/// has refined to the end), the reference too where the view shows it, and the analysis (if
/// one is on) finished for the scene and options as they are.
fn settled(state: &WindowState) -> bool {
    let view = state.session.view;
    let technique = !view.needs_technique() || !state.ui.dirty;
    let reference = !view.needs_reference() || state.ui.reference_converged;
    let analysis = state
        .session
        .analysis
        .as_ref()
        .is_none_or(|a| a.is_current(state.session.live()));
    technique && reference && analysis
}

/// A window screenshot waits for a settled view: frames are drawn until it is, then the next
/// one is captured.
fn wait_to_capture(state: &mut WindowState, script: &mut ScriptRun) -> Result<(), ViewerError> {
    let Some((index, path, waited)) = script.pending_capture.take() else {
        return Ok(());
    };
    if settled(state) {
        state.capture = Some(path);
    } else if waited >= SETTLE_FRAMES {
        return Err(ViewerError::Step {
            step: index + 1,
            message: format!("the view did not settle within {SETTLE_FRAMES} frames"),
        });
    } else {
        script.pending_capture = Some((index, path, waited + 1));
    }
    script.frames_left = 1;
    Ok(())
}

/// Runs script steps up to the next one that draws frames; returns whether this frame is a
/// scripted frame (the technique renders every scripted frame).
pub(super) fn advance_script(
    state: &mut WindowState,
    script: &mut ScriptRun,
) -> Result<(), ViewerError> {
    if let Some((yaw, pitch)) = script.drag_step {
        if script.frames_left > 0 {
            state.session.camera.orbit(yaw, pitch);
        }
    }
    if script.frames_left == 0 {
        wait_to_capture(state, script)?;
    }
    while script.frames_left == 0 && script.next < script.steps.len() {
        let index = script.next;
        script.next += 1;
        let at = |e: &dyn std::fmt::Display| ViewerError::Step {
            step: index + 1,
            message: e.to_string(),
        };
        match script.steps[index].clone() {
            Step::Method(name) => state.session.set_method(&name).map_err(|e| at(&e))?,
            Step::Reference(name) => state.session.set_reference(&name).map_err(|e| at(&e))?,
            Step::Param(setting) => state.session.set_param(&setting).map_err(|e| at(&e))?,
            Step::Orbit { yaw_deg, pitch_deg } => state.session.camera.orbit(yaw_deg, pitch_deg),
            Step::Translate { object, by } => {
                let mesh = state.session.object(&object).map_err(|e| at(&e))?;
                state.session.translate(mesh, by).map_err(|e| at(&e))?;
            }
            Step::Rotate {
                object,
                axis,
                degrees,
            } => {
                let mesh = state.session.object(&object).map_err(|e| at(&e))?;
                state
                    .session
                    .rotate(mesh, axis, degrees)
                    .map_err(|e| at(&e))?;
            }
            Step::Frames(n) => {
                script.frames_left = n;
                script.drag_step = None;
                script.timing = Some((index, Instant::now(), Vec::new()));
            }
            Step::Drag {
                yaw_deg,
                pitch_deg,
                frames,
            } => {
                script.frames_left = frames;
                script.drag_step = Some((yaw_deg / frames as f32, pitch_deg / frames as f32));
                script.timing = Some((index, Instant::now(), Vec::new()));
                state
                    .session
                    .camera
                    .orbit(yaw_deg / frames as f32, pitch_deg / frames as f32);
            }
            Step::Screenshot(path) => {
                save_view(state, &path).map_err(|e| at(&e))?;
                eprintln!("step {}: saved {}", index + 1, path.display());
                if let Some(analysis) = &state.session.analysis {
                    eprintln!(
                        "step {}: {}",
                        index + 1,
                        crate::analysis::summary(analysis, state.session.scene())
                    );
                }
            }
            Step::WindowScreenshot(path) => {
                // Drawn, settled and kept before any later step runs.
                script.pending_capture = Some((index, path, 0));
                script.frames_left = 1;
                script.drag_step = None;
            }
            Step::Panel(shown) => {
                state.ui.settings.show_panel = shown;
                // One frame lays the panel out; the view takes the rest of the window after it.
                script.frames_left = 1;
            }
            Step::Camera { eye, target } => {
                state.session.camera = crate::orbit::OrbitCamera::from_camera(&Camera {
                    eye,
                    target,
                    up: Vec3::Y,
                    fov_y_deg: state.session.camera.fov_y_deg,
                    aspect: None,
                })
            }
            Step::Analysis(step) => analysis_step(state, step, index)?,
            Step::View(mode) => state.session.view = mode,
        }
        state.ui.dirty = true;
    }
    Ok(())
}

/// An analysis step: on or off, the camera at its overview, its JSON written.
fn analysis_step(
    state: &mut WindowState,
    step: AnalysisStep,
    index: usize,
) -> Result<(), ViewerError> {
    let at = |e: &dyn std::fmt::Display| ViewerError::Step {
        step: index + 1,
        message: e.to_string(),
    };
    match step {
        AnalysisStep::Off => state.session.analysis = None,
        AnalysisStep::Camera => {
            let fov = state.session.camera.fov_y_deg;
            let camera = state
                .session
                .analysis
                .as_ref()
                .and_then(|a| a.overview(fov))
                .ok_or_else(|| at(&"camera = \"analysis\": no analysis is on"))?;
            state.session.camera = crate::orbit::OrbitCamera::from_camera(&camera);
        }
        AnalysisStep::On(request) => {
            let settings = request.settings.clone();
            settings
                .check(state.session.scene())
                .map_err(|e| at(&e.to_string().replace('`', "")))?;
            let mut analysis = crate::analysis::Analysis::new(settings);
            if let Some(map) = request.lens_map {
                analysis.lens_map = map;
            }
            analysis.finish(state.session.live());
            if let Some(error) = &analysis.error {
                return Err(at(error));
            }
            eprintln!(
                "step {}: {}",
                index + 1,
                crate::analysis::summary(&analysis, state.session.scene())
            );
            if let Some(outcome) = analysis.outcome() {
                // What the panel shows as the eye points the result was judged from.
                eprintln!(
                    "step {}: {}",
                    index + 1,
                    crate::analysis_panel::eye_points_text(&outcome.report)
                );
            }
            state.session.analysis = Some(analysis);
        }
        AnalysisStep::Json(path) => {
            let mut analysis = state
                .session
                .analysis
                .take()
                .ok_or_else(|| at(&"analysis_json: no analysis is on"))?;
            analysis.finish(state.session.live());
            let written = match analysis.json() {
                Some(json) => std::fs::write(&path, json)
                    .map_err(|e| format!("writing {}: {e}", path.display())),
                None => Err(format!(
                    "analysis_json: the analysis has no result ({})",
                    analysis.error.as_deref().unwrap_or("none yet")
                )),
            };
            state.session.analysis = Some(analysis);
            written.map_err(|e| at(&e))?;
            eprintln!("step {}: wrote {}", index + 1, path.display());
        }
    }
    Ok(())
}

/// Prints a finished `frames` or `drag` step's rates: window frames per second and the
/// technique's median frame time.
fn report_script_timing(state: &WindowState, script: &mut ScriptRun) {
    if script.frames_left > 0 {
        return;
    }
    if let Some((index, start, mut times)) = script.timing.take() {
        let seconds = start.elapsed().as_secs_f64();
        times.sort_by(f64::total_cmp);
        let median = times.get(times.len() / 2).copied().unwrap_or(0.0);
        let stats = state.ui.stats.as_ref();
        eprintln!(
            "step {}: {} frames of {} at {}x{} (technique at {}x{}): {:.1} fps; technique median {:.1} ms",
            index + 1,
            times.len(),
            state.session.label(),
            state.config.width,
            state.config.height,
            stats.map_or(0, |s| s.width),
            stats.map_or(0, |s| s.height),
            times.len() as f64 / seconds.max(1e-9),
            median
        );
    }
}

/// Counts a presented frame against the script's `frames` or `drag` step; the step's last
/// frame reports its timing and ends its drag.
pub(super) fn count_script_frame(state: &WindowState, script: &mut ScriptRun) {
    if script.frames_left > 0 {
        script.frames_left -= 1;
        if script.frames_left == 0 {
            report_script_timing(state, script);
            script.drag_step = None;
        }
    }
}
