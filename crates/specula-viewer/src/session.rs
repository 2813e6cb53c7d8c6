//! What the viewer shows, without a window: the live scene, the camera, one instance of each
//! registered method (created on first use, kept with its parameters and prepared state), the
//! exact method rendered progressively as the reference, the view mode and the selected object.
//! The window ([`crate::app`]) and script mode drive it the same way.

use std::rc::Rc;

use glam::Vec3;
use specula_methods::{Context, Frame, Label, LiveScene, MethodInfo, Technique};
use specula_scene::Scene;
use specula_trace::{Image, Ray};

use crate::analysis::Analysis;
use crate::orbit::OrbitCamera;

/// What the window shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewMode {
    /// The technique's image.
    Technique,
    /// The exact method's image (progressive).
    Reference,
    /// The technique left of a vertical split, the reference right of it.
    Split,
    /// The FLIP error between technique and reference, as a heat-map (black = equal).
    Error,
}

impl ViewMode {
    pub const ALL: [ViewMode; 4] = [
        ViewMode::Technique,
        ViewMode::Reference,
        ViewMode::Split,
        ViewMode::Error,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ViewMode::Technique => "technique",
            ViewMode::Reference => "reference",
            ViewMode::Split => "split",
            ViewMode::Error => "error",
        }
    }

    pub fn parse(name: &str) -> Option<ViewMode> {
        ViewMode::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Whether the view needs the reference image.
    pub fn needs_reference(self) -> bool {
        self != ViewMode::Technique
    }

    /// Whether the view needs the technique image.
    pub fn needs_technique(self) -> bool {
        self != ViewMode::Reference
    }
}

/// The time one progressive call of the reference may take, so the window stays responsive.
pub const REFERENCE_BUDGET_MS: u32 = 25;

#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    #[error(transparent)]
    Technique(#[from] specula_methods::TechniqueError),
    #[error(transparent)]
    Move(#[from] specula_methods::MoveError),
    #[error(transparent)]
    Scene(#[from] specula_scene::SceneError),
    #[error(transparent)]
    Image(#[from] specula_trace::ImageError),
}

pub struct Session {
    /// Shared so that the window can hold the GPU while it changes the session.
    pub ctx: Rc<Context>,
    live: LiveScene,
    /// What the scene was loaded from: a built-in name or a file.
    pub source: String,
    pub camera: OrbitCamera,
    /// What the picker offers: every method and each of its presets
    /// ([`specula_methods::all_labels`]).
    labels: Vec<Label>,
    /// One slot per label.
    techniques: Vec<Option<Box<dyn Technique>>>,
    current: usize,
    reference: Box<dyn Technique>,
    pub view: ViewMode,
    /// The mesh the move keys and panel act on.
    pub selected: Option<usize>,
    /// Why the current technique failed on this scene; the reference is shown instead.
    pub failure: Option<String>,
    /// The analysis drawn over the view, if one is on.
    pub analysis: Option<Analysis>,
}

/// Where the label `name` is among `labels` (an unknown method or preset names the valid
/// ones).
fn position_of(labels: &[Label], name: &str) -> Result<usize, SessionError> {
    let label = Label::parse(name)?;
    Ok(labels
        .iter()
        .position(|l| *l == label)
        .expect("all_labels holds every label that parses"))
}

impl Session {
    /// A session on `scene` showing `method` (a method's name, or METHOD:PRESET).
    pub fn new(
        ctx: Context,
        scene: Scene,
        source: &str,
        method: &str,
    ) -> Result<Session, SessionError> {
        let labels = specula_methods::all_labels();
        let current = position_of(&labels, method)?;
        let mut reference = (default_reference(&ctx).create)();
        set_budget(reference.as_mut(), REFERENCE_BUDGET_MS)?;
        let mut session = Session {
            ctx: Rc::new(ctx),
            camera: OrbitCamera::from_camera(&scene.camera),
            live: LiveScene::new(scene),
            source: source.to_string(),
            techniques: labels.iter().map(|_| None).collect(),
            labels,
            current,
            reference,
            view: ViewMode::Technique,
            selected: None,
            failure: None,
            analysis: None,
        };
        session.selected = session.first_specular();
        Ok(session)
    }

    pub fn scene(&self) -> &Scene {
        self.live.scene()
    }

    pub fn live(&self) -> &LiveScene {
        &self.live
    }

    /// The current technique's method.
    pub fn method(&self) -> &'static MethodInfo {
        self.labels[self.current].info
    }

    /// The current technique's label: its method, or METHOD:PRESET.
    pub fn label(&self) -> Label {
        self.labels[self.current]
    }

    /// Every label the picker offers, in order.
    pub fn labels(&self) -> &[Label] {
        &self.labels
    }

    /// Replaces the scene by the one at `source` (built-in name or file); on error the current
    /// scene stays.
    pub fn load(&mut self, source: &str) -> Result<(), SessionError> {
        let scene = specula_scene::load(source)?;
        self.camera = OrbitCamera::from_camera(&scene.camera);
        self.live = LiveScene::new(scene);
        self.source = source.to_string();
        self.selected = self.first_specular();
        self.failure = None;
        // Its objects were the old scene's.
        self.analysis = None;
        Ok(())
    }

    /// The first mirror or lens: what a user most likely wants to move.
    fn first_specular(&self) -> Option<usize> {
        let scene = self.live.scene();
        scene
            .meshes
            .iter()
            .position(|m| scene.materials[m.material].is_specular())
    }

    /// Switches to the label `name`: a registered method, or METHOD:PRESET.
    pub fn set_method(&mut self, name: &str) -> Result<(), SessionError> {
        self.current = position_of(&self.labels, name)?;
        self.failure = None;
        Ok(())
    }

    /// The next (or previous) label.
    pub fn cycle_method(&mut self, step: isize) {
        let n = self.labels.len() as isize;
        self.current = (self.current as isize + step).rem_euclid(n) as usize;
        self.failure = None;
    }

    /// The exact method shown as the reference.
    pub fn reference_method(&self) -> &'static MethodInfo {
        self.reference.info()
    }

    /// Switches the reference to the exact method `name` (`reference` on the CPU, or
    /// `gpu-trace`).
    pub fn set_reference(&mut self, name: &str) -> Result<(), SessionError> {
        let info = specula_methods::method(name)?;
        if !info.exact {
            return Err(specula_methods::TechniqueError::BadParameter {
                technique: info.name,
                name: "reference".into(),
                value: name.into(),
                reason: "the reference must be an exact method".into(),
            }
            .into());
        }
        if info.name != self.reference.name() {
            let mut reference = (info.create)();
            set_budget(reference.as_mut(), REFERENCE_BUDGET_MS)?;
            self.reference = reference;
        }
        Ok(())
    }

    /// The current method's instance, created on first use (progressive ones get the viewer's
    /// time budget per call).
    pub fn technique(&mut self) -> Result<&mut dyn Technique, SessionError> {
        let slot = &mut self.techniques[self.current];
        if slot.is_none() {
            let mut technique = self.labels[self.current].create()?;
            set_budget(technique.as_mut(), REFERENCE_BUDGET_MS)?;
            *slot = Some(technique);
        }
        Ok(slot.as_deref_mut().expect("created above"))
    }

    /// Applies `NAME=VALUE` to the current technique.
    pub fn set_param(&mut self, setting: &str) -> Result<(), SessionError> {
        specula_methods::apply_setting(self.technique()?, setting)?;
        self.failure = None;
        Ok(())
    }

    /// The mesh named `name`.
    pub fn object(&self, name: &str) -> Result<usize, SessionError> {
        Ok(self.live.object(name)?)
    }

    /// Moves mesh `mesh` by `by` (world metres) through the update path.
    pub fn translate(&mut self, mesh: usize, by: Vec3) -> Result<(), SessionError> {
        self.live
            .translate_object(self.ctx.gpu.as_ref(), mesh, by)?;
        Ok(())
    }

    /// Turns mesh `mesh` about the world `axis` through its bounding-box centre.
    pub fn rotate(&mut self, mesh: usize, axis: Vec3, degrees: f32) -> Result<(), SessionError> {
        self.live
            .rotate_object(self.ctx.gpu.as_ref(), mesh, axis, degrees)?;
        Ok(())
    }

    /// The mesh seen through pixel (`x`, `y`) of a `width` × `height` view, if any.
    pub fn pick(&self, x: f32, y: f32, width: u32, height: u32) -> Option<usize> {
        let camera = self.camera.camera();
        let ray = Ray {
            origin: camera.eye,
            dir: camera.ray_direction(x, y, width, height),
        };
        self.live
            .accel()
            .intersect(&ray, f32::INFINITY)
            .map(|hit| hit.mesh as usize)
    }

    /// One frame of the current technique at `width` × `height`. A failure is kept in
    /// [`Session::failure`] (the window then shows the reference) and returned.
    pub fn render_technique(&mut self, width: u32, height: u32) -> Result<Frame, SessionError> {
        let camera = self.camera.camera();
        self.technique()?;
        let technique = self.techniques[self.current]
            .as_deref_mut()
            .expect("created by technique()");
        let result = technique.render(&self.ctx, &self.live, &camera, width, height);
        match result {
            Ok(frame) => Ok(frame),
            Err(e) => {
                self.failure = Some(e.to_string());
                Err(e.into())
            }
        }
    }

    /// One progressive step of the reference at `width` × `height` (check `converged`).
    pub fn render_reference(&mut self, width: u32, height: u32) -> Result<Frame, SessionError> {
        let camera = self.camera.camera();
        Ok(self
            .reference
            .render(&self.ctx, &self.live, &camera, width, height)?)
    }

    /// The reference image at `width` × `height`, refined until converged.
    pub fn converged_reference(&mut self, width: u32, height: u32) -> Result<Image, SessionError> {
        loop {
            let frame = self.render_reference(width, height)?;
            if frame.converged {
                return Ok(frame.image(&self.ctx)?);
            }
        }
    }

    /// The current view at `width` × `height` as an image on the CPU, complete (the reference
    /// converged, the analysis finished and drawn over it): what a screenshot saves.
    pub fn view_image(
        &mut self,
        width: u32,
        height: u32,
        split: f32,
    ) -> Result<Image, SessionError> {
        let mut image = self.view_image_alone(width, height, split)?;
        if let Some(analysis) = &mut self.analysis {
            analysis.finish(&self.live);
            if let Some(overlay) =
                analysis.overlay(&self.live, &self.camera.camera(), width, height)
            {
                draw_overlay(&mut image, &overlay);
            }
        }
        Ok(image)
    }

    /// Advances the analysis (see [`Analysis::update`]); returns whether what it shows changed.
    pub fn update_analysis(&mut self) -> bool {
        match &mut self.analysis {
            Some(analysis) => analysis.update(&self.live),
            None => false,
        }
    }

    fn view_image_alone(
        &mut self,
        width: u32,
        height: u32,
        split: f32,
    ) -> Result<Image, SessionError> {
        let technique = match self.view.needs_technique() && self.failure.is_none() {
            true => {
                let frame = self.render_technique(width, height)?;
                Some(frame.image(&self.ctx)?)
            }
            false => None,
        };
        let Some(technique) = technique else {
            return self.converged_reference(width, height);
        };
        Ok(match self.view {
            ViewMode::Technique => technique,
            ViewMode::Reference => unreachable!("needs no technique image"),
            ViewMode::Split => {
                split_image(&technique, &self.converged_reference(width, height)?, split)
            }
            ViewMode::Error => error_image(&self.converged_reference(width, height)?, &technique),
        })
    }
}

/// The exact method a session shows as its reference: `gpu-trace` on a GPU that is not a CPU
/// (there it is much faster than the CPU reference, and equal to it), else the CPU reference
/// (on lavapipe the CPU reference is the faster of the two, and progressive).
pub fn default_reference(ctx: &Context) -> &'static MethodInfo {
    let real_gpu = ctx.gpu.as_ref().is_some_and(|g| !g.is_software());
    if real_gpu {
        &specula_methods::gpu_trace::INFO
    } else {
        specula_methods::exact_method()
    }
}

fn set_budget(technique: &mut dyn Technique, budget_ms: u32) -> Result<(), SessionError> {
    if technique.info().param("budget_ms").is_some() {
        specula_methods::apply_setting(technique, &format!("budget_ms={budget_ms}"))?;
    }
    Ok(())
}

/// Blends `overlay` (sRGB, straight alpha, any size: sampled at the nearest pixel) over
/// `image` (linear radiance).
pub fn draw_overlay(image: &mut Image, overlay: &crate::analysis::Overlay) {
    for y in 0..image.height {
        let oy = (y as u64 * overlay.height as u64 / image.height as u64) as u32;
        for x in 0..image.width {
            let ox = (x as u64 * overlay.width as u64 / image.width as u64) as u32;
            let [r, g, b, a] = overlay.pixels[(oy * overlay.width + ox) as usize];
            if a == 0 {
                continue;
            }
            let colour = Vec3::new(r as f32, g as f32, b as f32) / 255.0;
            let colour = Vec3::from_array(colour.to_array().map(srgb_to_linear));
            let pixel = &mut image.pixels[(y * image.width + x) as usize];
            *pixel = pixel.lerp(colour, a as f32 / 255.0);
        }
    }
}

/// `left` where x < `split` × width, `right` elsewhere (same size).
pub fn split_image(left: &Image, right: &Image, split: f32) -> Image {
    let cut = (split.clamp(0.0, 1.0) * left.width as f32).round() as u32;
    let mut out = left.clone();
    for y in 0..out.height {
        for x in cut..out.width {
            let i = (y * out.width + x) as usize;
            out.pixels[i] = right.pixels[i];
        }
    }
    out
}

/// The FLIP heat-map of `test` against `reference`, as linear radiance for display.
pub fn error_image(reference: &Image, test: &Image) -> Image {
    let flip = specula_compare::metrics::flip_map(reference, test);
    let heat = specula_compare::metrics::heat_map(&flip, reference.width, reference.height);
    let mut out = Image::new(reference.width, reference.height);
    for (pixel, rgb) in out.pixels.iter_mut().zip(heat.pixels()) {
        *pixel = Vec3::from_array(rgb.0.map(|c| srgb_to_linear(c as f32 / 255.0)));
    }
    out
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cpu_session(method: &str) -> Session {
        let scene = specula_scene::load("door-mirror").unwrap();
        Session::new(Context::default(), scene, "door-mirror", method).unwrap()
    }

    #[test]
    fn a_failing_technique_is_reported_and_the_view_falls_back_to_the_reference() {
        // No GPU in this context: envmap cannot render, and says why.
        let mut session = cpu_session("envmap");
        assert!(session.render_technique(32, 24).is_err());
        let failure = session.failure.clone().expect("failure kept for the panel");
        assert!(failure.contains("needs a GPU"), "{failure}");
        let shown = session.view_image(32, 24, 0.5).unwrap();
        let reference = session.converged_reference(32, 24).unwrap();
        assert_eq!(shown.pixels, reference.pixels);
        // Choosing a method again clears the failure and tries it again.
        session.set_method("reference").unwrap();
        assert!(session.failure.is_none());
        assert!(session.render_technique(32, 24).is_ok());
    }

    #[test]
    fn vertex_tracing_refines_while_nothing_moves_and_restarts_from_the_preview_after_a_move() {
        let scene = specula_scene::load("truck-cover").unwrap();
        let mut session =
            Session::new(Context::default(), scene, "truck-cover", "vertex-tracing").unwrap();
        // The viewer's own budget, cut to 1 ms so that refinement takes several frames.
        assert_eq!(
            session.technique().unwrap().parameter("budget_ms"),
            REFERENCE_BUDGET_MS.to_string()
        );
        session.set_param("budget_ms=1").unwrap();
        // The cover by its vertices (at this size `tracing=auto` traces it per pixel).
        session.set_param("tracing=vertices").unwrap();
        let counter = |frame: &Frame, name: &str| {
            frame
                .counters
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, v)| *v)
                .unwrap()
        };
        let preview = session.render_technique(192, 144).unwrap();
        assert!(!preview.converged);
        assert_eq!(
            counter(&preview, "edges split"),
            0,
            "first the Gouraud preview"
        );
        let mut frames = 1;
        let mut split = 0;
        let converged = loop {
            let frame = session.render_technique(192, 144).unwrap();
            frames += 1;
            assert!(frame.converged || counter(&frame, "edges split") >= split);
            split = counter(&frame, "edges split");
            if frame.converged {
                break frame;
            }
            assert!(frames < 10_000);
        };
        assert!(
            frames > 2,
            "refinement shown over several frames ({frames})"
        );
        assert!(counter(&converged, "edges split") > 0);
        // A converged view stays as it is.
        let again = session.render_technique(192, 144).unwrap();
        assert!(again.converged);
        assert_eq!(
            again.image(&session.ctx).unwrap().pixels,
            converged.image(&session.ctx).unwrap().pixels
        );
        // Anything that moves starts over from the preview.
        let dial = session.object("dial").unwrap();
        session.translate(dial, Vec3::new(0.0, 0.01, 0.0)).unwrap();
        let restarted = session.render_technique(192, 144).unwrap();
        assert!(!restarted.converged);
        assert_eq!(counter(&restarted, "edges split"), 0);
    }

    #[test]
    fn the_picker_offers_each_preset_and_its_instance_runs_the_preset() {
        let mut session = cpu_session("reference");
        let offered: Vec<String> = session.labels().iter().map(|l| l.to_string()).collect();
        for name in specula_methods::registry::SEED_TECHNIQUES {
            let plain = offered.iter().position(|l| l == name).unwrap();
            assert_eq!(offered[plain + 1], format!("{name}:paper"), "beside {name}");
        }
        session.set_method("vertex-tracing:paper").unwrap();
        assert_eq!(session.label().to_string(), "vertex-tracing:paper");
        assert_eq!(session.technique().unwrap().parameter("tree_weight"), "0");
        session.cycle_method(-1);
        assert_eq!(session.label().to_string(), "vertex-tracing");
        assert_eq!(
            session.technique().unwrap().parameter("tree_weight"),
            "0.02"
        );
        let unknown = session.set_method("vertex-tracing:fast").unwrap_err();
        assert!(
            unknown.to_string().contains("vertex-tracing:paper"),
            "{unknown}"
        );
    }

    #[test]
    fn a_scene_that_fails_to_load_keeps_the_previous_one() {
        let mut session = cpu_session("reference");
        let error = session.load("/nowhere/scene.toml").unwrap_err().to_string();
        assert!(
            error.contains("/nowhere/scene.toml: cannot read: no such file"),
            "{error}"
        );
        assert_eq!(session.source, "door-mirror");
        assert!(session
            .scene()
            .meshes
            .iter()
            .any(|m| m.name == "door mirror"));
    }

    #[test]
    fn picking_the_image_centre_selects_the_mirror_and_moves_reach_the_reference() {
        let mut session = cpu_session("reference");
        let mirror = session.object("door mirror").unwrap();
        assert_eq!(
            session.selected,
            Some(mirror),
            "the first mirror is selected"
        );
        assert_eq!(session.pick(32.0, 24.0, 64, 48), Some(mirror));
        let before = session.converged_reference(64, 48).unwrap();
        session.translate(mirror, Vec3::new(0.0, 0.3, 0.0)).unwrap();
        let after = session.converged_reference(64, 48).unwrap();
        assert_ne!(
            before.pixels, after.pixels,
            "the reference restarts after a move"
        );
        assert_ne!(session.pick(32.0, 24.0, 64, 48), Some(mirror));
    }

    #[test]
    fn the_reference_is_the_cpu_one_on_lavapipe_and_gpu_trace_can_be_chosen() {
        // Without a GPU, and on a CPU adapter, the CPU reference is the default.
        assert_eq!(
            cpu_session("reference").reference_method().name,
            "reference"
        );
        let Some(ctx) = specula_methods::test_context("viewer reference choice") else {
            return;
        };
        let on_cpu_adapter = ctx.gpu.as_ref().is_some_and(|g| g.is_software());
        let expected = if on_cpu_adapter {
            "reference"
        } else {
            "gpu-trace"
        };
        let scene = specula_scene::load("door-mirror").unwrap();
        let mut session = Session::new(ctx, scene, "door-mirror", "envmap").unwrap();
        assert_eq!(session.reference_method().name, expected);
        session.set_reference("reference").unwrap();
        let cpu = session.converged_reference(48, 36).unwrap();
        session.set_reference("gpu-trace").unwrap();
        assert_eq!(session.reference_method().name, "gpu-trace");
        let gpu = session.converged_reference(48, 36).unwrap();
        let largest = cpu
            .pixels
            .iter()
            .zip(&gpu.pixels)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0, f32::max);
        assert!(
            largest < 1e-4,
            "gpu-trace differs from the CPU by {largest}"
        );
        let error = session.set_reference("envmap").unwrap_err().to_string();
        assert!(error.contains("exact"), "{error}");
    }

    #[test]
    fn split_takes_the_left_image_left_of_the_cut() {
        let mut left = Image::new(4, 1);
        let mut right = Image::new(4, 1);
        left.pixels.fill(Vec3::ONE);
        right.pixels.fill(Vec3::splat(0.5));
        let split = split_image(&left, &right, 0.25);
        assert_eq!(
            split.pixels,
            vec![
                Vec3::ONE,
                Vec3::splat(0.5),
                Vec3::splat(0.5),
                Vec3::splat(0.5)
            ]
        );
    }
}
