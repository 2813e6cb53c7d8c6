//! A test-only analysis, to hold what adding one takes to one folder and one registry line:
//! the share of the eye points that lie above a height. Its test runs it by name from the
//! command, a viewer script and the library, and finds its options in the help, the docs'
//! table and the panel with no further code.

use std::path::{Path, PathBuf};

use specula_params::{options, Opt, ParamKind, ParamSet};
use specula_scene::Scene;
use specula_trace::SceneAccel;

use crate::analysis::eye_points::DefaultEyes;
use crate::analysis::{Analysis, AnalysisInfo, EyePoints, Report, RunContext};
use crate::outcome::Outcome;
use crate::AnalyzeError;

options! {
    /// toy's options.
    pub struct ToyOptions {
        height: f64 = Opt::number("0", "m", "the height the eye points must lie above"),
        least_share: f64 = Opt::new(ParamKind::Number { min: 0.0, max: 1.0 }, "1", "",
            "the share of eye points above the height that passes"),
    }
}

pub static INFO: AnalysisInfo = AnalysisInfo {
    name: "toy",
    summary: "The share of the eye points above a height (a test-only analysis).",
    example: "specula analyze toy --height 1",
    options: ToyOptions::SPECS,
    eye_points: true,
    test_only: true,
    create: || Box::new(Toy::default()),
};

#[derive(Default)]
pub struct Toy {
    pub options: ToyOptions,
}

impl Analysis for Toy {
    fn info(&self) -> &'static AnalysisInfo {
        &INFO
    }

    fn options(&self) -> &dyn ParamSet {
        &self.options
    }

    fn options_mut(&mut self) -> &mut dyn ParamSet {
        &mut self.options
    }

    fn check(&self, scene: &Scene, eyes: &EyePoints) -> Result<(), AnalyzeError> {
        eyes.resolve(scene, DefaultEyes::Camera).map(|_| ())
    }

    fn run(
        &self,
        scene: &Scene,
        _accel: &SceneAccel,
        eyes: &EyePoints,
        context: &RunContext,
    ) -> Result<Report, AnalyzeError> {
        let eyes = eyes.resolve(scene, DefaultEyes::Camera)?;
        let total = eyes.points.len();
        let above = eyes
            .points
            .iter()
            .filter(|p| f64::from(p.y) > self.options.height)
            .count();
        context.step("eye points", total, total)?;
        let share = above as f64 / total as f64;
        let verdict = if share >= self.options.least_share {
            Outcome::Pass
        } else {
            Outcome::Fail
        };
        Ok(Report {
            analysis: INFO.name,
            verdict: Some(verdict),
            json: crate::analysis::json_of(&serde_json::json!({
                "share_above": share,
                "verdict": verdict.lower(),
            }))?,
            eyes_from: eyes.from,
            eyes: eyes.points,
            result: Box::new(share),
        })
    }

    fn summary(&self, report: &Report) -> String {
        let share: &f64 = report.result().expect("a toy report");
        format!(
            "{:.1} % of the eye points lie above {} m\n",
            share * 100.0,
            self.options.height
        )
    }

    fn checks(&self, report: &Report) -> Vec<crate::analysis::CheckRow> {
        let share: &f64 = report.result().expect("a toy report");
        vec![crate::analysis::CheckRow {
            check: "eye points above the height".into(),
            verdict: report.verdict,
            value: Some(share * 100.0),
            limit: Some(self.options.least_share * 100.0),
            margin: Some((share - self.options.least_share) * 100.0),
            uncertainty: Some(0.0),
            unit: "%",
        }]
    }

    fn write_report(
        &self,
        report: &Report,
        dir: &Path,
        _scene: &Scene,
        _accel: &SceneAccel,
    ) -> Result<PathBuf, AnalyzeError> {
        let write = |e: std::io::Error| AnalyzeError::Write {
            path: dir.display().to_string(),
            message: e.to_string(),
        };
        std::fs::create_dir_all(dir).map_err(write)?;
        let path = dir.join("report.json");
        std::fs::write(&path, &report.json).map_err(write)?;
        Ok(path)
    }
}
