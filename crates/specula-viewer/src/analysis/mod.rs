//! The viewer's analysis: any analysis of the registry (`specula_analyze::analysis::ANALYSES`)
//! on the live scene, with the options the command and scripts take (the one input model:
//! each option's text by its declared name), run by the library's [`Analysis::run`], drawn
//! over the view and run again whenever the scene moves or an option changes, so that an
//! engineer can drag the mirror and watch the blind region change. What the panel shows is
//! what `specula analyze` gives for the same options.
//!
//! **Off the window's thread, a preview first.** A change starts a job on a worker thread
//! with a copy of the scene. Where the eye points are several, it first runs from their middle
//! alone and sends that as a preview (unless that run judged something: a verdict is of every
//! eye point), then runs the whole and sends it. One job runs at a time: a change made while it
//! runs cancels it (the run stops at its next stage) and the next job takes the change, so a
//! drag shows results a job behind, never a queue of stale ones.
//!
//! **The overlay** ([`overlay`]) is computed per pixel of the view (at a fraction of its
//! resolution in the window, at full size in screenshots): the view ray's first hit in the
//! live scene decides what is drawn there.

mod overlay;
#[cfg(test)]
mod tests;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Instant;

use glam::{Vec2, Vec3};
use specula_analyze::analysis::{
    self as library, AnalysisInfo, EyePoints, Progress, Report, RunContext, ANALYSES,
};
use specula_analyze::glare::analysis::GlareResult;
use specula_analyze::mirror_view::analysis::MirrorViewResult;
use specula_analyze::AnalyzeError;
use specula_methods::LiveScene;
use specula_scene::Scene;
use specula_trace::SceneAccel;

pub use overlay::{
    project, GroundGrid, LensMap, Overlay, BLIND, REGION_SEEN, SEEN, WASHED_OUT_RGB,
};

/// What is analysed: the analysis and the options given, each as text by its declared name
/// (the command's flags and a script's keys). A change of any of it starts the analysis again.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub info: &'static AnalysisInfo,
    /// The options given, in the order given; the rest take their declared defaults.
    pub given: Vec<(&'static str, String)>,
}

/// The option an error is about, by its declared name.
fn option_of(e: &AnalyzeError) -> Option<&str> {
    match e {
        AnalyzeError::UnknownObject { role, .. }
        | AnalyzeError::AmbiguousObject { role, .. }
        | AnalyzeError::WrongMaterial { role, .. } => Some(role),
        AnalyzeError::BadOption { option, .. } => Some(option),
        AnalyzeError::Option(e) => Some(&e.name),
        _ => None,
    }
}

impl Settings {
    /// The analysis called `name` with its defaults.
    pub fn new(name: &str) -> Result<Settings, AnalyzeError> {
        let analysis = library::by_name(name)?;
        Ok(Settings {
            info: analysis.info(),
            given: Vec::new(),
        })
    }

    pub fn name(&self) -> &'static str {
        self.info.name
    }

    /// Gives option `name` (its own or an eye point option) as `value`; an empty value takes it
    /// back to its default. Refused, naming the option, where the analysis cannot take it.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), AnalyzeError> {
        let spec = self
            .info
            .all_options()
            .find(|s| s.name == name)
            .ok_or_else(|| AnalyzeError::BadOption {
                option: "analysis",
                reason: format!(
                    "{} takes no option '{name}'; its options are {}",
                    self.info.name,
                    self.info
                        .all_options()
                        .map(|s| s.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            })?;
        let mut trial = self.clone();
        trial.given.retain(|(n, _)| *n != spec.name);
        if !value.trim().is_empty() {
            trial.given.push((spec.name, value.trim().to_string()));
        }
        trial.build()?;
        *self = trial;
        Ok(())
    }

    /// The analysis with the options given, and its eye points.
    pub fn build(&self) -> Result<(Box<dyn library::Analysis>, EyePoints), AnalyzeError> {
        let mut analysis = (self.info.create)();
        let mut eyes = EyePoints::default();
        for (name, value) in &self.given {
            analysis.set_option(&mut eyes, name, value)?;
        }
        Ok((analysis, eyes))
    }

    /// Option `name`'s value as text: given, else its default.
    pub fn value(&self, name: &str) -> String {
        if let Some((_, v)) = self.given.iter().find(|(n, _)| *n == name) {
            return v.clone();
        }
        self.info
            .all_options()
            .find(|s| s.name == name)
            .map(|s| s.default.to_string())
            .unwrap_or_default()
    }

    /// Checks the settings against `scene` as the command does before it runs.
    pub fn check(&self, scene: &Scene) -> Result<(), AnalyzeError> {
        let (analysis, eyes) = self.build()?;
        analysis.check(scene, &eyes)
    }

    /// The analysis `name` on `scene` with the first objects it can take: each object option
    /// the check complains about is given the first of the scene's objects it accepts (the
    /// first mirror for a mirror view, the first specular surface and lit source for glare, the
    /// first solid glass for a lens). None where the scene has none it accepts.
    pub fn first(scene: &Scene, name: &str) -> Option<Settings> {
        let mut settings = Settings::new(name).ok()?;
        for _ in 0..settings.info.all_options().count() {
            let error = match settings.check(scene) {
                Ok(()) => return Some(settings),
                Err(e) => e,
            };
            let spec = settings
                .info
                .all_options()
                .find(|s| s.names_an_object() && Some(s.name) == option_of(&error))?;
            let accepted = scene.meshes.iter().find(|m| {
                let mut trial = settings.clone();
                trial.set(spec.name, &m.name).is_ok()
                    && trial
                        .check(scene)
                        .err()
                        .is_none_or(|e| option_of(&e) != Some(spec.name))
            })?;
            settings.set(spec.name, &accepted.name).ok()?;
        }
        None
    }
}

/// One delivery of a job: the preview from the eye points' middle, or the whole run.
pub struct Outcome {
    pub report: Report,
    /// How many eye points see each cell of the ground (a mirror view's).
    pub ground: Option<GroundGrid>,
    /// A regulation's fields' corners on the ground (x, z).
    pub fields: Vec<[Vec2; 4]>,
    /// Whether it is the whole run (else the preview).
    pub complete: bool,
    /// How long the job took to get here, from its start (scene copy and BVH included).
    pub milliseconds: f64,
    /// How long the preview from the eye points' middle took, where there was one.
    pub preview_milliseconds: Option<f64>,
}

impl Outcome {
    /// The eye points it looked from.
    pub fn eyes(&self) -> &[Vec3] {
        &self.report.eyes
    }

    /// How long it took, in words: the preview's time where there was one.
    pub fn timing(&self) -> String {
        let eyes = self.eyes().len();
        let whole = format!(
            "{eyes} eye point{} in {:.0} ms",
            if eyes == 1 { "" } else { "s" },
            self.milliseconds
        );
        match self.preview_milliseconds {
            Some(preview) => format!("the eye points' middle in {preview:.0} ms, {whole}"),
            None => whole,
        }
    }

    fn new(report: Report, complete: bool, milliseconds: f64, preview: Option<f64>) -> Outcome {
        let mirror = report.result::<MirrorViewResult>();
        let ground = mirror.map(|m| overlay::ground_grid(&m.view));
        let fields = mirror
            .and_then(|m| m.regulation.as_ref())
            .map(|j| {
                let vehicle = &j.request.vehicle;
                let range = j.request.view.range_m;
                j.request
                    .regulation
                    .fields
                    .iter()
                    .filter_map(|f| vehicle.field_corners(f, range).ok())
                    .collect()
            })
            .unwrap_or_default();
        Outcome {
            report,
            ground,
            fields,
            complete,
            milliseconds,
            preview_milliseconds: preview,
        }
    }
}

/// What a job is for: the scene's identity and version, and the settings.
type Stamp = (u64, u64, Settings);

enum Message {
    Outcome(Box<Outcome>),
    Error(String),
}

struct Job {
    stamp: Stamp,
    cancel: Arc<AtomicBool>,
    receiver: mpsc::Receiver<Message>,
    /// Its thread has ended (everything it sent has been taken).
    ended: bool,
}

/// The analysis the panel shows: its settings, its running job and its latest outcome.
pub struct Analysis {
    pub settings: Settings,
    job: Option<Job>,
    /// The stamp of the shown outcome (or error).
    shown_stamp: Option<Stamp>,
    shown: Option<Outcome>,
    /// Why the last job failed (bad settings: an eyebox of 0 points, a range of 0...).
    pub error: Option<String>,
    /// Bumped whenever the shown outcome changes: the overlay is drawn again.
    pub revision: u64,
    /// The glare eye point the overlay shows (None: the one nearest the eye points' middle).
    pub selected_eye: Option<usize>,
    /// What the lens overlay maps: mean power or cylinder.
    pub lens_map: LensMap,
}

impl Analysis {
    pub fn new(settings: Settings) -> Analysis {
        Analysis {
            settings,
            job: None,
            shown_stamp: None,
            shown: None,
            error: None,
            revision: 0,
            selected_eye: None,
            lens_map: LensMap::MeanPower,
        }
    }

    pub fn outcome(&self) -> Option<&Outcome> {
        self.shown.as_ref()
    }

    fn stamp(&self, live: &LiveScene) -> Stamp {
        (live.id(), live.version(), self.settings.clone())
    }

    /// Whether the shown outcome is complete and for the live scene and the settings as they
    /// are.
    pub fn is_current(&self, live: &LiveScene) -> bool {
        self.job.is_none()
            && self.shown_stamp.as_ref() == Some(&self.stamp(live))
            && (self.error.is_some() || self.shown.as_ref().is_some_and(|o| o.complete))
    }

    /// Takes what the running job delivered and starts the next job where the scene or the
    /// settings changed (cancelling a stale one). Returns whether the shown outcome changed.
    /// Call once a frame.
    pub fn update(&mut self, live: &LiveScene) -> bool {
        let mut messages = Vec::new();
        let mut ended = false;
        if let Some(job) = &self.job {
            loop {
                match job.receiver.try_recv() {
                    Ok(message) => messages.push((job.stamp.clone(), message)),
                    Err(mpsc::TryRecvError::Empty) => break,
                    Err(mpsc::TryRecvError::Disconnected) => {
                        ended = true;
                        break;
                    }
                }
            }
        }
        if let Some(job) = &mut self.job {
            job.ended = ended;
        }
        let mut changed = !messages.is_empty();
        for (stamp, message) in messages {
            self.take(stamp, message);
        }
        if let Some(job) = &self.job {
            if job.ended {
                let delivered = self.shown_stamp.as_ref() == Some(&job.stamp)
                    && (self.error.is_some() || self.shown.as_ref().is_some_and(|o| o.complete));
                let cancelled = job.cancel.load(Ordering::Relaxed);
                let stamp = job.stamp.clone();
                self.job = None;
                if !delivered && !cancelled {
                    // Only a panic ends a job early; say so rather than start it again forever.
                    self.take(
                        stamp,
                        Message::Error("the analysis stopped without a result".into()),
                    );
                    changed = true;
                }
            }
        }
        let wanted = self.stamp(live);
        if let Some(job) = &self.job {
            if job.stamp != wanted {
                job.cancel.store(true, Ordering::Relaxed);
            }
        }
        if self.job.is_none() && self.shown_stamp.as_ref() != Some(&wanted) {
            self.start(live, wanted);
        }
        changed
    }

    /// Cancels the running job: it stops at its next stage, and the shown outcome stays.
    pub fn cancel(&mut self) {
        if let Some(job) = &self.job {
            job.cancel.store(true, Ordering::Relaxed);
        }
    }

    /// Runs [`Analysis::update`] until the outcome is complete and current (script mode,
    /// screenshots, tests).
    pub fn finish(&mut self, live: &LiveScene) {
        loop {
            self.update(live);
            if self.is_current(live) {
                return;
            }
            if let Some(job) = &self.job {
                match job.receiver.recv() {
                    Ok(message) => {
                        let stamp = job.stamp.clone();
                        self.take(stamp, message);
                    }
                    // Ended: the next update says how.
                    Err(_) => continue,
                }
            }
        }
    }

    /// Whether a job is running or due: the window keeps drawing frames meanwhile.
    pub fn busy(&self) -> bool {
        self.job.is_some()
    }

    fn take(&mut self, stamp: Stamp, message: Message) {
        match message {
            Message::Outcome(outcome) => {
                self.error = None;
                self.shown = Some(*outcome);
            }
            Message::Error(error) => {
                self.error = Some(error);
                self.shown = None;
            }
        }
        self.shown_stamp = Some(stamp);
        self.revision += 1;
        if let Some(k) = self.selected_eye {
            if self.shown.as_ref().is_none_or(|o| k >= o.eyes().len()) {
                self.selected_eye = None;
            }
        }
    }

    fn start(&mut self, live: &LiveScene, stamp: Stamp) {
        let (sender, receiver) = mpsc::channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let scene = live.scene().clone();
        let settings = stamp.2.clone();
        let job_cancel = cancel.clone();
        std::thread::spawn(move || {
            let started = Instant::now();
            let result = run(&scene, &settings, &job_cancel, started, &|outcome| {
                // The window may have gone: nothing to tell then.
                let _ = sender.send(Message::Outcome(Box::new(outcome)));
            });
            match result {
                Err(AnalyzeError::Cancelled) | Ok(()) => {}
                Err(e) => {
                    let _ = sender.send(Message::Error(e.to_string().replace('`', "")));
                }
            }
        });
        self.job = Some(Job {
            stamp,
            cancel,
            receiver,
            ended: false,
        });
    }

    /// The glare eye point the overlay shows: the selected one, else the one nearest the eye
    /// points' middle.
    pub fn glare_eye(&self) -> usize {
        if let Some(k) = self.selected_eye {
            return k;
        }
        let Some(outcome) = &self.shown else {
            return 0;
        };
        let eyes = outcome.eyes();
        let middle = eyes.iter().copied().sum::<Vec3>() / eyes.len().max(1) as f32;
        (0..eyes.len())
            .min_by(|a, b| {
                let distance = |k: usize| eyes[k].distance(middle);
                distance(*a).total_cmp(&distance(*b))
            })
            .unwrap_or(0)
    }

    /// The JSON document of the shown, complete outcome (what `--json` writes).
    pub fn json(&self) -> Option<&str> {
        self.shown
            .as_ref()
            .filter(|o| o.complete)
            .map(|o| o.report.json.as_str())
    }
}

/// A job: a preview from the eye points' middle where they are several (delivered unless it
/// judged something), then (unless cancelled) the whole run, each handed to `deliver`.
fn run(
    scene: &Scene,
    settings: &Settings,
    cancel: &AtomicBool,
    started: Instant,
    deliver: &dyn Fn(Outcome),
) -> Result<(), AnalyzeError> {
    let accel = SceneAccel::new(scene);
    let (analysis, eyes) = settings.build()?;
    analysis.check(scene, &eyes)?;
    let context = RunContext {
        progress: &|_: Progress| {},
        cancel,
    };
    let ms = || started.elapsed().as_secs_f64() * 1e3;
    let mut preview_milliseconds = None;
    if let Some(preview) = preview_eyes(scene, &*analysis, &eyes) {
        let report = analysis.run(scene, &accel, &preview, &context)?;
        if report.verdict.is_none() {
            let at = ms();
            preview_milliseconds = Some(at);
            deliver(Outcome::new(report, false, at, Some(at)));
        }
    }
    let report = analysis.run(scene, &accel, &eyes, &context)?;
    deliver(Outcome::new(report, true, ms(), preview_milliseconds));
    Ok(())
}

/// The eye points' middle alone, where the analysis looks from several.
fn preview_eyes(
    scene: &Scene,
    analysis: &dyn library::Analysis,
    eyes: &EyePoints,
) -> Option<EyePoints> {
    if !analysis.info().eye_points {
        return None;
    }
    let resolved = eyes
        .resolve(scene, library::eye_points::DefaultEyes::Camera)
        .ok()?;
    (resolved.points.len() > 1).then(|| EyePoints {
        eye: vec![resolved.reference],
        forward: eyes.forward,
        ..EyePoints::default()
    })
}

/// One line of figures for the script's log and the panel's summary.
pub fn summary(analysis: &Analysis, scene: &Scene) -> String {
    let Some(outcome) = analysis.outcome() else {
        return match &analysis.error {
            Some(e) => format!("analysis failed: {e}"),
            None => "analysis running".into(),
        };
    };
    let timing = outcome.timing();
    let report = &outcome.report;
    let figures = if let Some(m) = report.result::<MirrorViewResult>() {
        mirror_line(m, scene)
    } else if let Some(r) = report.result::<specula_analyze::lens::Report>() {
        lens_line(r)
    } else if let Some(g) = report.result::<GlareResult>() {
        glare_line(&g.glare.report)
    } else {
        // An analysis without a line of its own here: the first line of its summary.
        let text = match analysis.settings.build() {
            Ok((built, _)) => built.summary(report),
            Err(e) => return format!("analysis failed: {e}"),
        };
        format!("{}: {}", report.analysis, text.lines().next().unwrap_or(""))
    };
    format!("{figures}; {timing}")
}

fn mirror_line(m: &MirrorViewResult, scene: &Scene) -> String {
    let name = &scene.meshes[m.mirror].name;
    if let Some(j) = &m.regulation {
        let v = &j.verdict;
        let fields: Vec<String> = v
            .fields
            .iter()
            .map(|f| {
                format!(
                    "'{}' {:.2} % ± {:.2} % seen, body {:.2} %, margin {:.2} m: {}",
                    f.name,
                    f.figures.seen_share * 100.0,
                    f.figures.seen_share_uncertainty * 100.0,
                    f.figures.hidden_by_vehicle_share * 100.0,
                    f.figures.outer_margin_m.min(f.figures.near_margin_m),
                    f.figures.verdict.word()
                )
            })
            .collect();
        return format!(
            "{} of '{name}': {}; {}; mirror checks {}",
            v.name,
            v.verdict.word(),
            fields.join("; "),
            specula_analyze::outcome::Outcome::all(v.mirror_checks.iter().map(|c| c.verdict))
                .word()
        );
    }
    let f = &m.view.report.figures;
    let region = match (f.region_seen_by_any, f.blind_area_m2) {
        (Some(any), Some(blind)) => format!(
            ", region seen by any {:.1} %, by all {:.1} %, blind {:.2} m²",
            any * 100.0,
            f.region_seen_by_all.unwrap_or(any) * 100.0,
            blind
        ),
        _ => String::new(),
    };
    format!(
        "mirror-view of '{name}': horizontal {:.2}°, vertical {:.2}°, {:.4} sr, ground {:.2} m²{region}",
        f.horizontal_deg, f.vertical_deg, f.solid_angle_sr, f.ground_area_m2
    )
}

fn lens_line(r: &specula_analyze::lens::Report) -> String {
    let c = &r.centre;
    let number = |v: Option<f64>| {
        v.map(|v| format!("{v:.3}"))
            .unwrap_or_else(|| "outside".into())
    };
    let largest_cylinder = r
        .grid
        .iter()
        .filter_map(|c| c.cylinder_d)
        .fold(0.0, |a: f64, c| a.max(c.abs()));
    format!(
        "lens '{}': centre {} / {} × {} D, the largest cylinder over ±{}° × ±{}° {:.3} D",
        r.lens,
        number(c.sphere_d),
        number(c.cylinder_d),
        c.axis_deg.map(|a| format!("{a:.0}")).unwrap_or_default(),
        r.gaze.h_max_deg,
        r.gaze.v_max_deg,
        largest_cylinder
    )
}

fn glare_line(r: &specula_analyze::glare::Report) -> String {
    let worst = match r.worst_eye {
        Some(k) => format!(
            "worst eye point {} (luminance factor {:.4}, {} cd/m², veiling ratio {})",
            k + 1,
            r.eyes[k].max_luminance_factor,
            specula_analyze::glare::luminance_text(r.eyes[k].max_luminance_cd_m2),
            specula_analyze::glare::veiling_text(r.eyes[k].max_veiling_ratio)
        ),
        None => "no glare".into(),
    };
    format!(
        "glare of '{}' in '{}': seen from {:.0} % of the eye points, {worst}",
        r.source,
        r.surface,
        r.share_with_glare * 100.0
    )
}

/// Every analysis's name, in the registry's order (the panel's choices; a test-only one is
/// run by name but not listed).
pub fn names() -> impl Iterator<Item = &'static str> {
    ANALYSES.iter().filter(|a| !a.test_only).map(|a| a.name)
}
