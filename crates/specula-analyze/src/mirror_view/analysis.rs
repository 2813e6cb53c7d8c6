//! mirror-view as an [`Analysis`]: its options declared once, resolved on a scene by one rule
//! each (the eye points by [`EyePoints`], the vehicle layout by [`vehicle_layout`]), run with
//! its regulation's verdict and pose search as options of the one run.

use std::path::{Path, PathBuf};

use glam::Vec3;
use specula_params::{options, Opt, ParamKind, ParamSet};
use specula_scene::Scene;
use specula_trace::SceneAccel;

use super::{MirrorView, Obstacles, Options, Precision, Region};
use crate::analysis::eye_points::DefaultEyes;
use crate::analysis::{
    json_of, Analysis, AnalysisInfo, EyePoints, Report, ResolvedEyes, RunContext,
};
use crate::mirror_surface::{MirrorSurface, SurfaceModel};
use crate::regulation::{self as reg, Adjustment, EyeRule, Side, Vehicle, VehicleReport, Verdict};
use crate::AnalyzeError;

const GROUND: &str = "Ground and precision";
const REGULATION: &str = "Regulation (UN R46, FMVSS 111)";

options! {
    /// mirror-view's options.
    pub struct MirrorViewOptions {
        mirror: String = Opt::object("the mirror, as the scene names it (NAME#k for a component)")
            .required(),
        ground: Option<f32> = Opt::number("", "m",
            "the ground plane's height Y (default: the lowest point of the scene)").group(GROUND),
        range: f32 = Opt::number("100", "m",
            "ground farther than this from an eye point, horizontally, is not counted")
            .group(GROUND),
        region: Option<[f64; 4]> = Opt::numbers("X0,Z0,X1,Z1", "m",
            "a required region on the ground").group(GROUND),
        tolerance: f64 = Opt::number("0.005", "",
            "refinement stops when the solid angle and the areas change by less than this share")
            .group(GROUND),
        tolerance_deg: f64 = Opt::number("0.05", "°",
            "... and the extents by less than this many degrees").group(GROUND),
        surface: Option<SurfaceModel> = Opt::new(ParamKind::Choice(SurfaceModel::WORDS), "", "",
            "the surface the samples lie on: the mirror's exact one (a generated patch, sphere or \
             cap; the default where there is one), its triangles as the renderer shades them \
             (mesh), or a smooth surface fitted to them").group(GROUND),
        regulation: Option<String> = Opt::new(ParamKind::Choice(reg::REGULATION_NAMES), "", "",
            "judge the mirror against a regulation's prescribed fields and mirror rules \
             (docs/analyses/mirror-view.md)").group(REGULATION),
        outermost: Option<Vec3> = Opt::point(
            "the vehicle's outermost point on the mirror's side: the fields' inner boundary plane \
             passes through it, parallel to the median plane (default: the outermost point of \
             the vehicle parts on that side, R46's rule)").group(REGULATION),
        median: Option<Vec3> = Opt::point(
            "a point of the vehicle's median longitudinal plane (class I's field is centred on \
             it; default: the plane through the eye points' middle)").group(REGULATION),
        side: Option<Side> = Opt::new(ParamKind::Choice(Side::WORDS), "", "",
            "the side of the vehicle the mirror serves (default: the side the mirror's centre \
             lies on, seen from the eye points' middle)").group(REGULATION),
        vehicle: Vec<String> = Opt::object(
            "a part of the vehicle's own body or fittings: with a regulation only these hide the \
             mirror and the road, and what they hide is reported apart").repeatable()
            .group(REGULATION),
        adjust: Option<Vec3> = Opt::point(
            "turn the mirror about this pivot (yaw and pitch within ±20°) and report the poses \
             that pass, the widest-margin one and, failing all, the most seen").group(REGULATION),
        adjust_step: f32 = Opt::number("5", "°", "the pose grid's step").group(REGULATION),
    }
}

pub static INFO: AnalysisInfo = AnalysisInfo {
    name: "mirror-view",
    summary: "What is seen in a mirror from the eye points: its field of view (horizontal and \
              vertical extent, solid angle), its footprint on the ground within a range, and the \
              share of a required region seen by any and by every eye point (its blind part); \
              judged against UN R46 or FMVSS 111 with a regulation.",
    example: "specula analyze mirror-view scenes/car-door-mirror.toml --mirror \"door mirror\" \
              --regulation r46-iii --forward 0,0,-1 --r-point -0.37,0.55,0 --outermost \
              -0.95,0.6,1.5 --vehicle \"car body\" --vehicle \"A-pillar\" --report r46-report",
    options: MirrorViewOptions::SPECS,
    eye_points: true,
    test_only: false,
    create: || Box::new(MirrorViewAnalysis::default()),
};

#[derive(Default)]
pub struct MirrorViewAnalysis {
    pub options: MirrorViewOptions,
}

/// A mirror view as resolved on a scene: what the library's functions are asked.
#[derive(Clone, Debug)]
pub struct Plan {
    pub view: Options,
    pub eyes: ResolvedEyes,
    pub regulation: Option<reg::Request>,
    /// The vehicle as the report shows it (with a regulation).
    pub vehicle_report: Option<VehicleReport>,
    pub adjust: Option<reg::AdjustRequest>,
}

/// What a mirror-view run found.
pub struct MirrorViewResult {
    /// The mirror's mesh.
    pub mirror: usize,
    pub view: MirrorView,
    pub regulation: Option<Judgement>,
}

/// A regulation's verdict and what it was judged on.
pub struct Judgement {
    pub verdict: Verdict,
    pub request: reg::Request,
    pub vehicle: VehicleReport,
    pub adjustment: Option<Adjustment>,
}

impl MirrorViewResult {
    /// The JSON document: the mirror view's figures, and with a regulation the vehicle, the
    /// verdict and the pose search.
    pub fn json(&self) -> Result<String, AnalyzeError> {
        match &self.regulation {
            None => json_of(&self.view.report),
            Some(j) => json_of(&j.document(&self.view)),
        }
    }
}

impl Judgement {
    pub fn document<'a>(&'a self, view: &'a MirrorView) -> reg::Document<'a> {
        reg::Document {
            view: &view.report,
            vehicle: self.vehicle.clone(),
            regulation: &self.verdict,
            adjustment: self.adjustment.as_ref(),
        }
    }
}

/// The rule options that lay out a regulation's fields: refused without one.
const REGULATION_ONLY: &[&str] = &["outermost", "median", "side", "vehicle", "adjust"];

impl MirrorViewAnalysis {
    /// The options resolved on `scene`: the mirror, the eye points (the regulation's own where
    /// none are given), the vehicle layout.
    pub fn plan(&self, scene: &Scene, eyes: &EyePoints) -> Result<Plan, AnalyzeError> {
        let o = &self.options;
        let mirror = crate::object(scene, "mirror", &o.mirror)?;
        let regulation = o.regulation.as_deref().map(reg::by_name).transpose()?;
        if regulation.is_none() {
            if let Some(name) = REGULATION_ONLY
                .iter()
                .find(|n| self.options.get(n).is_some_and(|v| !v.is_empty()))
            {
                return Err(AnalyzeError::BadOption {
                    option: name,
                    reason: "lays out a regulation's fields: give `regulation` too".into(),
                });
            }
        }
        let default_eyes = match regulation.map(|r| r.eyes) {
            Some(EyeRule::OcularPoints) => DefaultEyes::Ocular,
            _ => DefaultEyes::Camera,
        };
        if let Some(r) = regulation {
            if r.eyes == EyeRule::DriversEyes && eyes.r_point.is_some() {
                return Err(AnalyzeError::BadOption {
                    option: "r_point",
                    reason: format!(
                        "{} judges from the driver's eyes (`eye` or `eyellipse`), not from R46's \
                         ocular points",
                        r.name
                    ),
                });
            }
        }
        let resolved = eyes.resolve(scene, default_eyes)?;
        let mut view = Options::new(scene, mirror, resolved.frame, Precision::REPORT);
        view.ground_y = o.ground.unwrap_or(view.ground_y);
        view.range_m = o.range;
        view.region = o
            .region
            .map(|[x0, z0, x1, z1]| Region::new(x0 as f32, z0 as f32, x1 as f32, z1 as f32))
            .transpose()?;
        view.tolerance = o.tolerance;
        view.tolerance_deg = o.tolerance_deg;
        view.surface = o.surface.unwrap_or(view.surface);
        let Some(regulation) = regulation else {
            view.validate(scene)?;
            return Ok(Plan {
                view,
                eyes: resolved,
                regulation: None,
                vehicle_report: None,
                adjust: None,
            });
        };
        let parts = o
            .vehicle
            .iter()
            .map(|n| crate::object(scene, "vehicle", n))
            .collect::<Result<Vec<_>, _>>()?;
        view.obstacles = Obstacles::Vehicle(parts.clone());
        view.validate(scene)?;
        let vehicle = vehicle_layout(scene, &view, &parts, &resolved, o)?;
        if let Some(pivot) = o.adjust {
            reg::check_pivot(scene, mirror, pivot)?;
        }
        let vehicle_report = VehicleReport {
            reference: vehicle.reference.to_array(),
            side: vehicle.side,
            outermost: vehicle.outermost.map(|p| p.to_array()),
            median: vehicle.median.to_array(),
            eyes_from: resolved.from,
            vehicle_parts: o.vehicle.clone(),
        };
        Ok(Plan {
            regulation: Some(reg::Request {
                regulation,
                vehicle,
                eyes: resolved.points.clone(),
                eye_sets: resolved.sets.clone(),
                eyes_option: resolved.from,
                view: view.clone(),
            }),
            adjust: o.adjust.map(|pivot| reg::AdjustRequest {
                pivot,
                step_deg: o.adjust_step,
                limit_deg: 20.0,
            }),
            view,
            eyes: resolved,
            vehicle_report: Some(vehicle_report),
        })
    }
}

/// The vehicle a regulation's fields are laid out in, one rule for every front end: its side
/// (given, else the side of the mirror's area-weighted centre seen from the eye points'
/// middle), its outermost point (given, else R46's "outermost point of the vehicle" on that
/// side: the widest vertex of the vehicle parts), its median plane (given, else through the eye
/// points' middle) and ground.
pub fn vehicle_layout(
    scene: &Scene,
    view: &Options,
    parts: &[usize],
    eyes: &ResolvedEyes,
    options: &MirrorViewOptions,
) -> Result<Vehicle, AnalyzeError> {
    let frame = eyes.frame;
    let surface = MirrorSurface::new(scene, view.mirror, view.surface).expect("validated");
    let (mirror_centre, _) = reg::mirror_centre_and_normal(&surface);
    let side = options
        .side
        .unwrap_or_else(|| Vehicle::side_of(&frame, eyes.reference, mirror_centre));
    let outward = match side {
        Side::Right => frame.right,
        Side::Left => -frame.right,
    };
    let outermost = options.outermost.or_else(|| {
        parts
            .iter()
            .flat_map(|&m| scene.meshes[m].positions.iter().copied())
            .max_by(|a, b| a.dot(outward).total_cmp(&b.dot(outward)))
    });
    let vehicle = Vehicle {
        frame,
        reference: eyes.reference,
        side,
        outermost,
        median: options.median.unwrap_or(eyes.reference),
        ground_y: view.ground_y,
    };
    vehicle.validate()?;
    Ok(vehicle)
}

impl Analysis for MirrorViewAnalysis {
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
        let progress = context.counter("eye points", plan.eyes.points.len());
        let result = match &plan.regulation {
            None => MirrorViewResult {
                mirror: plan.view.mirror,
                view: super::analyze(scene, accel, &plan.eyes.points, &plan.view, &progress)?,
                regulation: None,
            },
            Some(request) => {
                let judged = reg::evaluate(scene, accel, request, &progress)?;
                context.check()?;
                let adjustment = plan
                    .adjust
                    .as_ref()
                    .map(|adjust| {
                        reg::adjust(scene, request, adjust, &|done, total| {
                            (context.progress)(crate::analysis::Progress {
                                stage: "mirror poses",
                                done,
                                total,
                            })
                        })
                    })
                    .transpose()?;
                MirrorViewResult {
                    mirror: plan.view.mirror,
                    view: judged.view,
                    regulation: Some(Judgement {
                        verdict: judged.verdict,
                        request: request.clone(),
                        vehicle: plan.vehicle_report.clone().expect("with a regulation"),
                        adjustment,
                    }),
                }
            }
        };
        context.check()?;
        // Figures from an eye point that sees nothing decide nothing.
        let blind = !result.view.report.warnings.is_empty();
        Ok(Report {
            analysis: INFO.name,
            verdict: match &result.regulation {
                Some(j) => Some(j.verdict.verdict),
                None => blind.then_some(crate::outcome::Outcome::Undecided),
            },
            json: result.json()?,
            eyes: plan.eyes.points.clone(),
            eyes_from: plan.eyes.from,
            result: Box::new(result),
        })
    }

    fn summary(&self, report: &Report) -> String {
        let result: &MirrorViewResult = report.result().expect("a mirror-view report");
        super::summary::text(result, self.options.median.is_none())
    }

    fn checks(&self, report: &Report) -> Vec<crate::analysis::CheckRow> {
        use crate::analysis::CheckRow;
        let result: &MirrorViewResult = report.result().expect("a mirror-view report");
        let Some(j) = &result.regulation else {
            let f = &result.view.report.figures;
            let mut rows = vec![
                CheckRow::figure("horizontal extent", f.horizontal_deg, "°"),
                CheckRow::figure("vertical extent", f.vertical_deg, "°"),
                CheckRow::figure("solid angle", f.solid_angle_sr, "sr"),
                CheckRow::figure("ground area", f.ground_area_m2, "m²"),
            ];
            if let Some(any) = f.region_seen_by_any {
                rows.push(CheckRow::figure(
                    "region seen by any eye point",
                    any * 100.0,
                    "%",
                ));
            }
            return rows;
        };
        // The share the verdict judged, as the report's table gives it (seen, with the body's
        // share where the allowance excuses it), its margin to the whole field and uncertainty.
        let fields = j.verdict.fields.iter().map(|f| {
            let (share, margin, uncertainty) =
                crate::verdict_page::field_figures(f, j.verdict.allowance_share);
            CheckRow {
                check: f.name.clone(),
                verdict: Some(f.figures.verdict),
                value: Some(share * 100.0),
                limit: Some(100.0),
                margin: Some(margin * 100.0),
                uncertainty: Some(uncertainty * 100.0),
                unit: "%",
            }
        });
        let mirror = j.verdict.mirror_checks.iter().map(|c| CheckRow {
            check: c.name.clone(),
            verdict: Some(c.verdict),
            value: c.value,
            limit: Some(c.limit),
            margin: c.margin,
            uncertainty: c.uncertainty,
            unit: c.unit,
        });
        fields.chain(mirror).collect()
    }

    fn write_report(
        &self,
        report: &Report,
        dir: &Path,
        scene: &Scene,
        accel: &SceneAccel,
    ) -> Result<PathBuf, AnalyzeError> {
        let result: &MirrorViewResult = report.result().expect("a mirror-view report");
        let document = result.regulation.as_ref().map(|j| j.document(&result.view));
        let page = super::report::MirrorViewPage {
            view: &result.view,
            scene,
            accel,
            mirror: result.mirror,
            regulation: result.regulation.as_ref().map(|j| {
                (
                    document.as_ref().expect("with a regulation"),
                    j.request.regulation,
                    &j.request.vehicle,
                )
            }),
        };
        super::report::write_mirror_view(dir, &page)
    }
}
