//! One interface for every analysis, modelled on the techniques' `Technique`: an analysis has
//! its [`AnalysisInfo`] (name, summary, example, its options declared once in an
//! [`options!`](specula_params::options) block), holds its options, and [`Analysis::run`]s on
//! a scene from the eye points ([`EyePoints`], declared once for all) to a [`Report`]: the
//! verdict, the JSON document `--json` writes, and the typed result its summary, its report
//! folder and the viewer's overlay read. The command's flags, the viewer's script keys and
//! panel controls, and the docs' option tables are all made from the declarations
//! ([`specula_params::OptionSpec`]), so the three front ends take the same inputs with the
//! same defaults and give the same answer.
//!
//! Adding an analysis is one folder with its `Analysis` impl and one line in [`analyses!`]'s
//! list (docs/architecture.md).

pub mod eye_points;

use std::any::Any;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use specula_params::{apply_option, OptionSpec, ParamSet};
use specula_scene::Scene;
use specula_trace::SceneAccel;

pub use eye_points::{EyePoints, ResolvedEyes};

use crate::outcome::Outcome;
use crate::AnalyzeError;

/// What a registry entry says about an analysis.
pub struct AnalysisInfo {
    /// The name front ends use: `specula analyze NAME`, a script's `kind`.
    pub name: &'static str,
    /// One paragraph: what it answers.
    pub summary: &'static str,
    /// An example command, for the help.
    pub example: &'static str,
    /// Its options, declared once.
    pub options: &'static [OptionSpec],
    /// Whether it looks from eye points ([`EyePoints`]'s options apply).
    pub eye_points: bool,
    /// Built for tests only: front ends run it by name but do not list it.
    pub test_only: bool,
    pub create: fn() -> Box<dyn Analysis>,
}

impl std::fmt::Debug for AnalysisInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "AnalysisInfo({})", self.name)
    }
}

/// An analysis is known by its name (the registry holds each once).
impl PartialEq for AnalysisInfo {
    fn eq(&self, other: &AnalysisInfo) -> bool {
        self.name == other.name
    }
}

impl AnalysisInfo {
    /// Every option it takes, its own then the eye points', in the order front ends list them.
    pub fn all_options(&self) -> impl Iterator<Item = &'static OptionSpec> {
        let eyes: &'static [OptionSpec] = if self.eye_points {
            EyePoints::SPECS
        } else {
            &[]
        };
        self.options.iter().chain(eyes)
    }
}

/// How far a run has got: `done` of `total` steps (eye points, gaze rows, mirror poses) of the
/// stage it names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    pub stage: &'static str,
    pub done: usize,
    pub total: usize,
}

/// What a run is given besides the scene: its progress's receiver and the flag that cancels it
/// (checked between eye points, gaze rows and poses; a cancelled run ends with
/// [`AnalyzeError::Cancelled`]).
pub struct RunContext<'a> {
    pub progress: &'a (dyn Fn(Progress) + Sync),
    pub cancel: &'a AtomicBool,
}

impl RunContext<'_> {
    /// Reports progress, and ends the run where it was cancelled.
    pub fn step(&self, stage: &'static str, done: usize, total: usize) -> Result<(), AnalyzeError> {
        (self.progress)(Progress { stage, done, total });
        self.check()
    }

    /// `total` steps of `stage` as the analyses' functions count them: called with how many
    /// are done.
    pub fn counter(&self, stage: &'static str, total: usize) -> impl Fn(usize) + Sync + '_ {
        move |done| (self.progress)(Progress { stage, done, total })
    }

    pub fn check(&self) -> Result<(), AnalyzeError> {
        if self.cancel.load(Ordering::Relaxed) {
            Err(AnalyzeError::Cancelled)
        } else {
            Ok(())
        }
    }
}

/// What a run found.
pub struct Report {
    pub analysis: &'static str,
    /// The verdict, where the run judged something (a regulation, a standard).
    pub verdict: Option<Outcome>,
    /// The JSON document, pretty-printed (`--json`, report.json, the viewer's
    /// `analysis_json`): written from the typed report, so that its numbers read as their own
    /// type writes them (an f32's shortest digits).
    pub json: String,
    /// The eye points it looked from (a lens: the eye's centre of rotation), and the option
    /// they came from (`eye` for the camera's eye where none was given).
    pub eyes: Vec<glam::Vec3>,
    pub eyes_from: &'static str,
    /// The analysis's own result, for its summary, its report folder and the viewer.
    pub result: Box<dyn Any + Send + Sync>,
}

/// `document` as the report's JSON text.
pub fn json_of(document: &impl serde::Serialize) -> Result<String, AnalyzeError> {
    serde_json::to_string_pretty(document).map_err(|e| AnalyzeError::BadOption {
        option: "json",
        reason: e.to_string(),
    })
}

impl Report {
    /// The analysis's own result as `T` (None for another analysis's).
    pub fn result<T: 'static>(&self) -> Option<&T> {
        self.result.downcast_ref()
    }
}

/// One judged or measured check of a report, as a spreadsheet row takes it (`analyze --csv`).
#[derive(Clone, Debug, PartialEq)]
pub struct CheckRow {
    /// What is checked: a field, a mirror rule, a standard's tolerance, a figure.
    pub check: String,
    /// Its verdict, where it is judged.
    pub verdict: Option<Outcome>,
    pub value: Option<f64>,
    pub limit: Option<f64>,
    pub margin: Option<f64>,
    pub uncertainty: Option<f64>,
    pub unit: &'static str,
}

impl CheckRow {
    /// A figure that is not judged.
    pub fn figure(check: &str, value: f64, unit: &'static str) -> CheckRow {
        CheckRow {
            check: check.to_string(),
            verdict: None,
            value: Some(value),
            limit: None,
            margin: None,
            uncertainty: None,
            unit,
        }
    }
}

/// An analysis: it holds its options, runs, and tells its report in words and in a folder.
pub trait Analysis: Send {
    fn info(&self) -> &'static AnalysisInfo;
    fn options(&self) -> &dyn ParamSet;
    fn options_mut(&mut self) -> &mut dyn ParamSet;

    /// Checks the options against the scene without running (an unknown object, a bad
    /// combination): what front ends call before a long run.
    fn check(&self, scene: &Scene, eyes: &EyePoints) -> Result<(), AnalyzeError>;

    /// Runs on `scene` from `eyes`.
    fn run(
        &self,
        scene: &Scene,
        accel: &SceneAccel,
        eyes: &EyePoints,
        context: &RunContext,
    ) -> Result<Report, AnalyzeError>;

    /// The report in words, as the terminal prints it.
    fn summary(&self, report: &Report) -> String;

    /// The report's checks (what was judged) or, where nothing was, its key figures: a row
    /// each, in the report's order.
    fn checks(&self, report: &Report) -> Vec<CheckRow>;

    /// Writes the report folder (report.html, report.json, plots) into `dir`; returns the HTML
    /// page's path.
    fn write_report(
        &self,
        report: &Report,
        dir: &Path,
        scene: &Scene,
        accel: &SceneAccel,
    ) -> Result<PathBuf, AnalyzeError>;
}

impl dyn Analysis {
    /// Sets option `name` (its own, or an eye point option into `eyes`) from its text.
    pub fn set_option(
        &mut self,
        eyes: &mut EyePoints,
        name: &str,
        value: &str,
    ) -> Result<(), AnalyzeError> {
        let info = self.info();
        let result = if info.eye_points && EyePoints::SPECS.iter().any(|s| s.name == name) {
            apply_option(EyePoints::SPECS, eyes, info.name, name, value)
        } else if info.options.iter().any(|s| s.name == name) {
            apply_option(info.options, self.options_mut(), info.name, name, value)
        } else {
            let names: Vec<&str> = info.all_options().map(|s| s.name).collect();
            return Err(AnalyzeError::BadOption {
                option: "analysis",
                reason: format!(
                    "{} takes no option '{name}'; its options are {}",
                    info.name,
                    names.join(", ")
                ),
            });
        };
        result.map_err(AnalyzeError::from)
    }
}

/// Declares the registry: every analysis, in the order front ends list them.
macro_rules! analyses {
    ($($(#[$attr:meta])* $module:ident :: $info:ident),* $(,)?) => {
        /// Every analysis, in the order front ends list them.
        pub static ANALYSES: &[&AnalysisInfo] = &[$($(#[$attr])* &crate::$module::$info),*];
    };
}

analyses! {
    mirror_view::INFO,
    glare::INFO,
    lens::INFO,
    // What adding an analysis takes, held by its own test: one folder and this line.
    #[cfg(any(test, feature = "toy"))]
    toy_analysis::INFO,
}

/// The analysis called `name`, made with its default options.
pub fn by_name(name: &str) -> Result<Box<dyn Analysis>, AnalyzeError> {
    ANALYSES
        .iter()
        .find(|a| a.name == name)
        .map(|a| (a.create)())
        .ok_or_else(|| {
            let names: Vec<&str> = ANALYSES.iter().map(|a| a.name).collect();
            AnalyzeError::BadOption {
                option: "analysis",
                reason: format!(
                    "unknown analysis '{name}'; the analyses are {}",
                    names.join(", ")
                ),
            }
        })
}

/// The option table of `info` for its docs page (its own options, then the eye points').
pub fn options_table(info: &AnalysisInfo) -> String {
    let specs: Vec<OptionSpec> = info.all_options().copied().collect();
    specula_params::options_table(&specs)
}
