//! lens as an [`Analysis`]: its options declared once and resolved on the scene (the eye's
//! centre of rotation, the wear, the prescription and standard, the progressive and near
//! figures), one run.

use std::path::{Path, PathBuf};

use glam::Vec3;
use specula_params::{options, Opt, ParamKind, ParamSet};
use specula_scene::Scene;
use specula_trace::SceneAccel;

use super::{Eye, Gaze, Options, Rx, Wear};
use crate::analysis::{json_of, Analysis, AnalysisInfo, EyePoints, Report, RunContext};
use crate::mirror_surface::SurfaceModel;
use crate::AnalyzeError;

const EYE: &str = "The eye";
const RX: &str = "Prescription and standard";
const NEAR: &str = "Progressive lenses and near vision";
const SURFACE: &str = "Surface";

options! {
    /// lens's options.
    pub struct LensOptions {
        lens: String = Opt::object("the lens (a solid glass), as the scene names it").required(),
        eye: Eye = Opt::new(ParamKind::Choice(Eye::WORDS), "right", "",
            "the eye behind the lens: it decides which way is base in and base out").group(EYE),
        rotation_centre: Option<Vec3> = Opt::point(
            "the eye's centre of rotation (default: vertex_distance and rotation_behind_cornea \
             behind the lens's back vertex along the camera's view axis)").group(EYE),
        vertex_distance: Option<f64> = Opt::number("", "mm",
            "from the cornea to the lens's back surface along the primary line of sight \
             (default 12)").group(EYE),
        rotation_behind_cornea: f64 = Opt::number("15", "mm",
            "from the cornea to the eye's centre of rotation (the entrance pupil, for spectacle \
             magnification, is 3 mm behind the cornea)").group(EYE),
        pantoscopic: f64 = Opt::number("0", "°",
            "pantoscopic tilt: the lens turned about the horizontal through the fitting point, \
             its lower edge towards the face (at most 30)").group(EYE),
        wrap: f64 = Opt::number("0", "°",
            "face-form wrap: the lens turned about the vertical through the fitting point, its \
             temporal edge towards the face (at most 30)").group(EYE),
        gaze: [f64; 3] = Opt::new(ParamKind::Numbers { names: "H_MAX,V_MAX,STEP" }, "30,30,2.5",
            "°", "the gaze grid (cells at 0 included)").group(EYE),
        object_distance: Option<f64> = Opt::number("", "m",
            "the object's distance from the eye's centre of rotation (default: infinity; e.g. \
             0.4 for near vision)").group(EYE),
        prescription: Option<String> = Opt::new(
            ParamKind::Text { expected: "SPHERE[,CYLINDER,AXIS][,PRISM...]" }, "", "D",
            "the prescription (prisms such as 1.5BO, 0.5BU): what the power error and unwanted \
             cylinder are taken against and what standard checks (default: the one a \
             spectacle-lens shape was made from, if any)").group(RX),
        refraction_vertex: Option<f64> = Opt::number("", "mm",
            "the vertex distance the prescription was refracted at: it is re-referenced to the \
             lens's by F / (1 − d F) per meridian").group(RX),
        compensate: bool = Opt::flag(
            "solve the prescription to order whose lens, on the same blank and worn the same \
             way, gives the prescription at the fitting point; standard then checks against it")
            .group(RX),
        standard: Option<String> = Opt::new(ParamKind::Choice(super::standard::NAMES), "", "",
            "check the focimeter reading against a standard's tolerances (iso-8980-2 for \
             progressive lenses; with add, ansi-z80.1 uses its progressive table)").group(RX),
        focimeter: bool = Opt::flag("print the focimeter's readings (they are always in the JSON)")
            .group(RX),
        distance_reference: Option<[f64; 2]> = Opt::numbers("X,Y", "mm",
            "the distance reference point from the back vertex (the lens's right and up; \
             default: a spectacle-lens shape's, else 0,0)").group(RX),
        prism_reference: [f64; 2] = Opt::new(ParamKind::Numbers { names: "X,Y" }, "0,0", "mm",
            "the prism reference point from the back vertex").group(RX),
        add: Option<f64> = Opt::number("", "D",
            "a progressive lens's ordered addition: reads the add on the progressive surface's \
             side and reports the corridor, the zones and the largest unwanted cylinder \
             (default: a spectacle-lens shape's add)").group(NEAR),
        near_reference: Option<[f64; 2]> = Opt::numbers("X,Y", "mm",
            "a progressive lens's near reference point from the back vertex (default: a \
             spectacle-lens shape's)").group(NEAR),
        near: Option<f64> = Opt::number("", "m",
            "turn both eyes to a near point on the midline this far away (convergence) and \
             report the near zone's power, prism and inset").group(NEAR),
        pd: f64 = Opt::number("64", "mm", "the interpupillary distance for near").group(NEAR),
        near_down: Option<f64> = Opt::number("", "°",
            "the near point's depression below the primary gaze (default: so that the line of \
             sight crosses the near reference point's height, else 0)").group(NEAR),
        lens_step: f64 = Opt::number("1", "mm",
            "the lens map's spacing: the clear zones and the progressive figures come from it")
            .group(NEAR),
        surface: Option<SurfaceModel> = Opt::new(ParamKind::Choice(SurfaceModel::WORDS), "", "",
            "the lens's surface: its exact one (the default where the scene made it from a lens \
             or spectacle-lens shape), its triangles (mesh) or a smooth fit to them")
            .group(SURFACE),
        step_mm: f64 = Opt::number("0.5", "mm",
            "the bundle's half-width at the lens (each figure is also taken at half of it, and \
             the change reported)").group(SURFACE),
    }
}

pub static INFO: AnalysisInfo = AnalysisInfo {
    name: "lens",
    summary: "A spectacle lens as worn, per gaze direction: sphere, cylinder and axis at the \
              vertex sphere, mean power, prism, lateral colour and distortion, from exact rays \
              (Listing's law about the eye's centre of rotation); focimeter readings checked \
              against ISO 8980 or ANSI Z80.1.",
    example: "specula analyze lens scenes/spectacles-wrap.toml --lens \"right lens\" \
              --pantoscopic 10 --wrap 5 --compensate --standard iso-8980-1 --focimeter",
    options: LensOptions::SPECS,
    eye_points: false,
    test_only: false,
    create: || Box::new(LensAnalysis::default()),
};

#[derive(Default)]
pub struct LensAnalysis {
    pub options: LensOptions,
}

impl LensAnalysis {
    /// The options resolved on `scene`: the lens's defaults (a spectacle-lens shape's
    /// prescription and reference points), then what was given.
    pub fn plan(&self, scene: &Scene) -> Result<Options, AnalyzeError> {
        let o = &self.options;
        let mesh = super::find_lens(scene, &o.lens)?;
        if o.rotation_centre.is_some() && o.vertex_distance.is_some() {
            return Err(AnalyzeError::BadOption {
                option: "vertex_distance",
                reason: "places the centre of rotation, which `rotation_centre` gives: not both"
                    .into(),
            });
        }
        let mut options = super::default_options_with(scene, mesh, false)?;
        options.rotation_behind_cornea_m = o.rotation_behind_cornea * 1e-3;
        options.rotation_centre = match o.rotation_centre {
            Some(centre) => centre.as_dvec3(),
            None => super::rotation_centre_behind(
                scene,
                mesh,
                o.vertex_distance
                    .map_or(super::DEFAULT_VERTEX_DISTANCE_M, |d| d * 1e-3),
                options.rotation_behind_cornea_m,
            )?,
        };
        options.eye = o.eye;
        let [h_max_deg, v_max_deg, step_deg] = o.gaze;
        options.gaze = Gaze {
            h_max_deg,
            v_max_deg,
            step_deg,
        };
        options.object_distance_m = o.object_distance;
        if !(o.step_mm.is_finite() && o.step_mm > 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "step_mm",
                reason: format!("{}: the bundle needs a positive width", o.step_mm),
            });
        }
        options.step_m = o.step_mm * 1e-3;
        options.surface = o.surface.unwrap_or(options.surface);
        options.wear = Wear {
            pantoscopic_deg: o.pantoscopic,
            wrap_deg: o.wrap,
        };
        if let Some(text) = &o.prescription {
            options.prescription =
                Some(Rx::parse(text).map_err(|reason| AnalyzeError::BadOption {
                    option: "prescription",
                    reason,
                })?);
        }
        options.refraction_vertex_m = o.refraction_vertex.map(|d| d * 1e-3);
        options.compensate = o.compensate;
        options.standard = o
            .standard
            .as_deref()
            .map(super::standard::find)
            .transpose()
            .map_err(|reason| AnalyzeError::BadOption {
                option: "standard",
                reason,
            })?;
        options.reference_points_mm = [
            o.distance_reference
                .unwrap_or(options.reference_points_mm[0]),
            o.prism_reference,
        ];
        options.add_d = o.add.or(options.add_d);
        options.near_reference_mm = o.near_reference.or(options.near_reference_mm);
        options.near = o.near.map(|distance_m| super::near::Near {
            distance_m,
            half_pd_m: o.pd * 0.5e-3,
            down_deg: o.near_down,
        });
        options.lens_step_mm = Some(o.lens_step);
        super::validate(&options)?;
        Ok(options)
    }
}

impl Analysis for LensAnalysis {
    fn info(&self) -> &'static AnalysisInfo {
        &INFO
    }

    fn options(&self) -> &dyn ParamSet {
        &self.options
    }

    fn options_mut(&mut self) -> &mut dyn ParamSet {
        &mut self.options
    }

    fn check(&self, scene: &Scene, _eyes: &EyePoints) -> Result<(), AnalyzeError> {
        self.plan(scene).map(|_| ())
    }

    fn run(
        &self,
        scene: &Scene,
        _accel: &SceneAccel,
        _eyes: &EyePoints,
        context: &RunContext,
    ) -> Result<Report, AnalyzeError> {
        let options = self.plan(scene)?;
        let rows = context.counter("gaze rows", options.gaze.vertical().len());
        let report = super::analyze(scene, &options, &rows)?;
        context.check()?;
        let json = json_of(&report)?;
        Ok(Report {
            analysis: INFO.name,
            verdict: report.verdict.as_ref().map(|v| v.verdict),
            json,
            eyes: vec![options.rotation_centre.as_vec3()],
            eyes_from: "rotation_centre",
            result: Box::new(report),
        })
    }

    fn summary(&self, report: &Report) -> String {
        let r: &super::Report = report.result().expect("a lens report");
        super::summary::text(r, self.options.focimeter)
    }

    fn checks(&self, report: &Report) -> Vec<crate::analysis::CheckRow> {
        use crate::analysis::CheckRow;
        let r: &super::Report = report.result().expect("a lens report");
        let Some(v) = &r.verdict else {
            let c = &r.centre;
            let figures = [
                ("sphere at the centre", c.sphere_d),
                ("cylinder at the centre", c.cylinder_d),
                ("mean power at the centre", c.mean_power_d),
            ];
            return figures
                .into_iter()
                .filter_map(|(name, value)| Some(CheckRow::figure(name, value?, "D")))
                .collect();
        };
        v.checks
            .iter()
            .map(|c| CheckRow {
                check: match c.meridian {
                    Some(m) => format!("{} at {m:.0}°", c.quantity),
                    None => c.quantity.to_string(),
                },
                verdict: Some(c.verdict),
                value: Some(c.value),
                limit: Some(c.limit),
                margin: Some(c.margin),
                uncertainty: Some(c.uncertainty),
                unit: c.unit,
            })
            .collect()
    }

    fn write_report(
        &self,
        report: &Report,
        dir: &Path,
        _scene: &Scene,
        _accel: &SceneAccel,
    ) -> Result<PathBuf, AnalyzeError> {
        let r: &super::Report = report.result().expect("a lens report");
        super::report::write_lens(dir, r)
    }
}
