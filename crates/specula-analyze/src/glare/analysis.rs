//! glare as an [`Analysis`]: its options declared once, the source (a named surface, the sun,
//! or a sun sweep with its solar day) and the display resolved on the scene, one run.

use std::path::{Path, PathBuf};

use specula_params::{options, Opt, ParamKind, ParamSet};
use specula_scene::Scene;
use specula_trace::SceneAccel;

use super::sweep::{self, Day, SweepSpec};
use super::{Display, Glare, Options, Source, Sun};
use crate::analysis::eye_points::DefaultEyes;
use crate::analysis::{
    json_of, Analysis, AnalysisInfo, EyePoints, Report, ResolvedEyes, RunContext,
};
use crate::AnalyzeError;

const SOURCE: &str = "Source";
const SWEEP: &str = "Sun sweep and solar day";
const DISPLAY: &str = "Display";
const IMAGES: &str = "Images";

options! {
    /// glare's options.
    pub struct GlareOptions {
        surface: String = Opt::object("the reflecting surface (a mirror or a glass), as the scene names it")
            .required(),
        source: Option<String> = Opt::object(
            "the source (an unlit or lit surface: a window, a lamp), as the scene names it; or \
             give sun or sun_sweep").group(SOURCE),
        source_luminance: Option<f64> = Opt::number("", "cd/m²",
            "the source's luminance (its radiance scaled so that its Y equals it): the glare then \
             in cd/m² too").group(SOURCE),
        sun: Option<[f64; 2]> = Opt::numbers("AZ,EL", "°",
            "the sun as the source, in the vehicle frame: azimuth from the forward axis, positive \
             to its right (90 = right, 180 = behind); elevation above the ground plane, above 0")
            .group(SOURCE),
        sun_illuminance: f64 = Opt::number("100000", "lx",
            "the sun's direct-normal illuminance (100,000 lx is an upper bound, a high sun in a \
             clear sky; the fall at low sun is not modelled: give less)").group(SOURCE),
        sun_sweep: Option<[f64; 5]> = Opt::numbers("AZ0,AZ1,EL0,EL1,STEP", "°",
            "sweep the sun over these azimuths and elevations (vehicle frame), each eye point \
             traced once and every position looked up").group(SWEEP),
        latitude: Option<f64> = Opt::number("", "° N",
            "with sun_sweep: the site's latitude, for the solar day (with heading and date)")
            .group(SWEEP),
        heading: Option<f64> = Opt::number("", "°",
            "the vehicle's heading, a compass bearing of its forward axis (0 = north, 90 = east)")
            .group(SWEEP),
        date: Option<String> = Opt::new(ParamKind::Text { expected: "YYYY-MM-DD" }, "", "",
            "the date of the solar day").group(SWEEP),
        time_step: f64 = Opt::number("5", "min", "minutes between the solar day's looked-up times")
            .group(SWEEP),
        display: Option<String> = Opt::object(
            "a display behind the surface (an unlit or lit mesh): its contrast under the glare, \
             per pixel (with symbol_luminance, background_luminance and min_contrast)")
            .group(DISPLAY),
        symbol_luminance: Option<f64> = Opt::number("", "cd/m²", "the display's symbols' luminance")
            .group(DISPLAY),
        background_luminance: Option<f64> = Opt::number("", "cd/m²",
            "the display's background luminance").group(DISPLAY),
        min_contrast: Option<f64> = Opt::number("", "",
            "the contrast ratio below which a display pixel is washed out (ISO 15008:2017 §4.3.2 \
             sets a daylight minimum for passenger cars, not confirmed here: give the figure you \
             certify against)").group(DISPLAY),
        size: String = Opt::new(ParamKind::Text { expected: "WIDTHxHEIGHT" }, "320x240", "px",
            "each eye point's image (aimed at the surface, fitted to it)").group(IMAGES),
        threshold: f64 = Opt::number("0.001", "",
            "luminance factor (the glare's luminance over the source's) above which a pixel \
             counts as glare").group(IMAGES),
        max_depth: u32 = Opt::new(ParamKind::Integer { min: 1, max: 64 }, "8", "",
            "specular bounces a path may take (as the reference's max_depth)").group(IMAGES),
    }
}

pub static INFO: AnalysisInfo = AnalysisInfo {
    name: "glare",
    summary: "Whether and how brightly a source (a named surface or the sun) is seen reflected in \
              a surface, per eye point: the glare's luminance factor and luminance in cd/m², its \
              veiling ratio, solid angle and centroid, the contrast of a display behind the cover \
              under it; sun sweeps and solar days by lookup.",
    example:
        "specula analyze glare truck-cover --surface \"cover glass\" --source \"side window\" \
              --source-luminance 8000 --eyebox 0.2,0.1,5,3 --display dial --symbol-luminance 300 \
              --background-luminance 10 --min-contrast 3 --report glare-report",
    options: GlareOptions::SPECS,
    eye_points: true,
    test_only: false,
    create: || Box::new(GlareAnalysis::default()),
};

#[derive(Default)]
pub struct GlareAnalysis {
    pub options: GlareOptions,
}

/// A glare run as resolved on a scene.
#[derive(Clone, Debug)]
pub struct Plan {
    pub options: Options,
    pub eyes: ResolvedEyes,
    pub sweep: Option<(SweepSpec, Option<Day>)>,
}

/// What a glare run found, and the frame its report's plots are drawn in.
pub struct GlareResult {
    pub glare: Glare,
    /// The reflecting surface's mesh.
    pub surface: usize,
    pub frame: crate::frame::VehicleFrame,
}

fn needs(option: &'static str, reason: &str) -> AnalyzeError {
    AnalyzeError::BadOption {
        option,
        reason: reason.into(),
    }
}

/// `WIDTHxHEIGHT` in pixels.
pub fn parse_size(text: &str) -> Result<(u32, u32), AnalyzeError> {
    text.split_once('x')
        .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)))
        .ok_or_else(|| needs("size", &format!("expected WIDTHxHEIGHT, got '{text}'")))
}

impl GlareAnalysis {
    /// Which options go together: one source; a solar day's three; a display's four.
    fn check_combinations(&self) -> Result<(), AnalyzeError> {
        let o = &self.options;
        let sources = [
            ("source", o.source.is_some()),
            ("sun", o.sun.is_some()),
            ("sun_sweep", o.sun_sweep.is_some()),
        ];
        let given: Vec<&str> = sources.iter().filter(|s| s.1).map(|s| s.0).collect();
        match given.as_slice() {
            [] => {
                return Err(needs(
                    "source",
                    "glare needs a source: `source`, `sun` or `sun_sweep`",
                ))
            }
            [_] => {}
            [_, second, ..] => {
                return Err(needs(
                    second,
                    &format!(
                        "give one of `source`, `sun` and `sun_sweep`, not `{}`",
                        given.join("` and `")
                    ),
                ))
            }
        }
        let day = [o.latitude.is_some(), o.heading.is_some(), o.date.is_some()];
        if day.iter().any(|d| *d) && !(day.iter().all(|d| *d) && o.sun_sweep.is_some()) {
            return Err(needs(
                "latitude",
                "a solar day takes `latitude`, `heading` and `date` together, with `sun_sweep`",
            ));
        }
        let display = [
            o.symbol_luminance.is_some(),
            o.background_luminance.is_some(),
            o.min_contrast.is_some(),
        ];
        if display.iter().any(|d| *d) != o.display.is_some()
            || (o.display.is_some() && !display.iter().all(|d| *d))
        {
            return Err(needs(
                "display",
                "a display takes `display`, `symbol_luminance`, `background_luminance` and \
                 `min_contrast` together",
            ));
        }
        Ok(())
    }

    /// The options resolved on `scene`.
    pub fn plan(&self, scene: &Scene, eyes: &EyePoints) -> Result<Plan, AnalyzeError> {
        self.check_combinations()?;
        let o = &self.options;
        let surface = crate::object(scene, "surface", &o.surface)?;
        let sun = |[azimuth_deg, elevation_deg]: [f64; 2]| Sun {
            azimuth_deg,
            elevation_deg,
            illuminance_lx: o.sun_illuminance,
        };
        let source = match (&o.source, o.sun) {
            (Some(name), _) => Source::Named(crate::object(scene, "source", name)?),
            (None, Some(at)) => Source::Sun(sun(at)),
            // A sweep: the position is each of the sweep's in turn.
            (None, None) => Source::Sun(sun([0.0, 45.0])),
        };
        let display = match &o.display {
            Some(name) => Some(Display {
                mesh: crate::object(scene, "display", name)?,
                symbol_cd_m2: o.symbol_luminance.unwrap_or_default(),
                background_cd_m2: o.background_luminance.unwrap_or_default(),
                min_contrast: o.min_contrast.unwrap_or_default(),
            }),
            None => None,
        };
        let (width, height) = parse_size(&o.size)?;
        let options = Options {
            surface,
            source,
            source_luminance: o.source_luminance,
            display,
            width,
            height,
            max_depth: o.max_depth,
            threshold: o.threshold,
        };
        options.validate(scene)?;
        let sweep = o.sun_sweep.map(|[az0, az1, el0, el1, step_deg]| {
            let spec = SweepSpec {
                azimuth: [az0, az1],
                elevation: [el0, el1],
                step_deg,
            };
            let day = o.latitude.map(|latitude_deg| Day {
                latitude_deg,
                heading_deg: o.heading.unwrap_or_default(),
                date: o.date.clone().unwrap_or_default(),
                step_min: o.time_step,
            });
            (spec, day)
        });
        Ok(Plan {
            options,
            eyes: eyes.resolve(scene, DefaultEyes::Camera)?,
            sweep,
        })
    }
}

impl Analysis for GlareAnalysis {
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
        self.plan(scene, eyes).map(|_| ())
    }

    fn run(
        &self,
        scene: &Scene,
        accel: &SceneAccel,
        eyes: &EyePoints,
        context: &RunContext,
    ) -> Result<Report, AnalyzeError> {
        let plan = self.plan(scene, eyes)?;
        let (points, frame) = (&plan.eyes.points, &plan.eyes.frame);
        let progress = context.counter("eye points", points.len());
        let glare = match &plan.sweep {
            Some((spec, day)) => sweep::sweep(
                scene,
                accel,
                points,
                frame,
                &plan.options,
                spec,
                day.as_ref(),
                &progress,
            )?,
            None => super::analyze(scene, accel, points, frame, &plan.options, &progress)?,
        };
        context.check()?;
        let json = json_of(&glare.report)?;
        Ok(Report {
            analysis: INFO.name,
            verdict: None,
            json,
            eyes: points.clone(),
            eyes_from: plan.eyes.from,
            result: Box::new(GlareResult {
                glare,
                surface: plan.options.surface,
                frame: *frame,
            }),
        })
    }

    fn summary(&self, report: &Report) -> String {
        let result: &GlareResult = report.result().expect("a glare report");
        super::summary::text(&result.glare.report)
    }

    fn checks(&self, report: &Report) -> Vec<crate::analysis::CheckRow> {
        use crate::analysis::CheckRow;
        let result: &GlareResult = report.result().expect("a glare report");
        let r = &result.glare.report;
        let mut rows = vec![CheckRow::figure(
            "eye points with glare",
            r.share_with_glare * 100.0,
            "%",
        )];
        if let Some(k) = r.worst_eye {
            let e = &r.eyes[k];
            rows.push(CheckRow::figure(
                "worst eye point's luminance factor",
                e.max_luminance_factor,
                "",
            ));
            if let Some(l) = e.max_luminance_cd_m2 {
                rows.push(CheckRow::figure("worst eye point's luminance", l, "cd/m²"));
            }
        }
        rows
    }

    fn write_report(
        &self,
        report: &Report,
        dir: &Path,
        _scene: &Scene,
        _accel: &SceneAccel,
    ) -> Result<PathBuf, AnalyzeError> {
        let result: &GlareResult = report.result().expect("a glare report");
        super::report::write_glare(dir, &result.glare, &result.frame)
    }
}
