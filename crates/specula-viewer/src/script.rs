//! Script mode: a TOML file of `[[step]]` tables, each with exactly one key, run in order.
//!
//! ```toml
//! [[step]]
//! method = "pvrr"                                   # switch technique
//! [[step]]
//! reference = "gpu-trace"                           # the exact method compared against
//! [[step]]
//! param = "depth=1"                                 # NAME=VALUE of the current technique
//! [[step]]
//! orbit = [30, -10]                                 # yaw, pitch in degrees about the target
//! [[step]]
//! translate = { object = "door mirror", by = [0, 0.02, 0] }   # world metres
//! [[step]]
//! rotate = { object = "door mirror", axis = [0, 1, 0], degrees = 10 }  # about its box centre
//! [[step]]
//! frames = 10                                       # draw 10 frames, the technique each time
//! [[step]]
//! drag = [90, 0, 30]                                # orbit yaw, pitch over 30 frames, as a drag
//! [[step]]
//! view = "split"                                    # technique | reference | split | error
//! [[step]]
//! analysis = { kind = "mirror-view", object = "door mirror", eyes = "ocular", region = [1, 2, 5, 20] }
//! [[step]]
//! analysis = { kind = "glare", object = "cover glass", source = "side window", eyebox = [0.3, 0.15, 5, 3] }
//! [[step]]
//! analysis = { kind = "off" }
//! [[step]]
//! camera = { eye = [3, 18, -4], target = [3, -1, 10] }   # the view, world metres
//! [[step]]
//! camera = "analysis"                               # the analysis's overview (its panel button)
//! [[step]]
//! panel = true                                      # show the docked panel (H); false hides it
//! [[step]]
//! screenshot = "mirror.png"                         # the view as shown, no UI
//! [[step]]
//! window_screenshot = "window.png"                  # the window as shown: panel, overlay
//! ```
//!
//! A script starts with the panel hidden, so that the view fills the window (`--size`) until a
//! `panel = true` step shows it; the view then fills what the panel leaves.
//!
//! An `analysis` step also takes `eye = [x, y, z]` (the centre eye point; a lens's centre of
//! rotation), `range`, `ground` and `tolerance`; `eyes` is "centre" or "ocular", `eyebox` is
//! [W, H, NX, NY], `region` is [X0, Z0, X1, Z1]; `kind = "lens"` takes `map = "mean-power"` or
//! `"cylinder"`. A mirror view takes `regulation = "r46-iii"` (any of `specula analyze
//! mirror-view --regulation`'s) with `forward`, `r_point`, `outermost` ([x, y, z]), `side` ("left" or
//! "right") and `vehicle` (the body's parts by name), as the command's options. The step waits for the analysis and prints its figures; so does each
//! screenshot taken while one is on (the screenshot shows its overlay).

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use specula_analyze::frame::Eyes;
use specula_analyze::mirror_view::Region;

use crate::analysis::{Kind, LensMap, RegulationRequest, Request};
use crate::session::ViewMode;
use specula_analyze::regulation::Side;

#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    Method(String),
    Reference(String),
    Param(String),
    Orbit {
        yaw_deg: f32,
        pitch_deg: f32,
    },
    Translate {
        object: String,
        by: Vec3,
    },
    Rotate {
        object: String,
        axis: Vec3,
        degrees: f32,
    },
    Frames(u32),
    Drag {
        yaw_deg: f32,
        pitch_deg: f32,
        frames: u32,
    },
    Screenshot(PathBuf),
    View(ViewMode),
    /// Turns the analysis on (or off: None).
    Analysis(Option<Box<Request>>),
    /// Puts the view's camera here.
    Camera {
        eye: Vec3,
        target: Vec3,
    },
    /// Puts the view's camera at the analysis's overview.
    AnalysisCamera,
    /// Draws a frame and saves the window as shown (the panel, the overlay) to this file.
    WindowScreenshot(PathBuf),
    /// Shows (true) or hides the docked panel.
    Panel(bool),
}

#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    #[error("script {file}: {message}")]
    File { file: String, message: String },
    #[error("script {file}, step {step}: {message}")]
    Step {
        file: String,
        step: usize,
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScriptFile {
    #[serde(default)]
    step: Vec<toml::Table>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawStep {
    method: Option<String>,
    reference: Option<String>,
    param: Option<String>,
    orbit: Option<[f32; 2]>,
    translate: Option<RawTranslate>,
    rotate: Option<RawRotate>,
    frames: Option<u32>,
    drag: Option<[f32; 3]>,
    screenshot: Option<PathBuf>,
    view: Option<String>,
    analysis: Option<RawAnalysis>,
    camera: Option<toml::Value>,
    window_screenshot: Option<PathBuf>,
    panel: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    eye: [f32; 3],
    target: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAnalysis {
    kind: String,
    object: Option<String>,
    source: Option<String>,
    eye: Option<[f32; 3]>,
    eyes: Option<String>,
    eyebox: Option<[f32; 4]>,
    region: Option<[f32; 4]>,
    range: Option<f32>,
    ground: Option<f32>,
    tolerance: Option<f64>,
    map: Option<String>,
    regulation: Option<String>,
    forward: Option<[f32; 3]>,
    r_point: Option<[f32; 3]>,
    outermost: Option<[f32; 3]>,
    side: Option<String>,
    vehicle: Option<Vec<String>>,
    sun: Option<[f64; 2]>,
    display: Option<String>,
    display_luminance: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTranslate {
    object: String,
    by: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRotate {
    object: String,
    axis: [f32; 3],
    degrees: f32,
}

const STEP_KEYS: &str =
    "method, reference, param, orbit, translate, rotate, frames, drag, view, analysis, camera, \
     panel, screenshot or window_screenshot";

/// Reads a script; relative screenshot paths resolve against the current directory.
pub fn load(path: &Path) -> Result<Vec<Step>, ScriptError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ScriptError::File {
        file: file.clone(),
        message: e.to_string(),
    })?;
    parse(&file, &text)
}

/// Parses script text; `file` names it in errors. Steps are numbered from 1.
pub fn parse(file: &str, text: &str) -> Result<Vec<Step>, ScriptError> {
    let script: ScriptFile = toml::from_str(text).map_err(|e| ScriptError::File {
        file: file.to_string(),
        message: e.to_string().trim_end().replace('\n', "\n    "),
    })?;
    if script.step.is_empty() {
        return Err(ScriptError::File {
            file: file.to_string(),
            message: "no [[step]] tables".into(),
        });
    }
    script
        .step
        .into_iter()
        .enumerate()
        .map(|(i, table)| {
            step(table).map_err(|message| ScriptError::Step {
                file: file.to_string(),
                step: i + 1,
                message,
            })
        })
        .collect()
}

fn finite(values: &[f32], what: &str) -> Result<(), String> {
    match values.iter().all(|v| v.is_finite()) {
        true => Ok(()),
        false => Err(format!("{what} must be finite numbers, got {values:?}")),
    }
}

fn step(table: toml::Table) -> Result<Step, String> {
    if table.len() != 1 {
        let keys: Vec<&str> = table.keys().map(String::as_str).collect();
        return Err(format!(
            "give exactly one of {STEP_KEYS}; got {}",
            if keys.is_empty() {
                "none".into()
            } else {
                keys.join(", ")
            }
        ));
    }
    let raw = RawStep::deserialize(toml::Value::Table(table))
        .map_err(|e| e.to_string().trim_end().replace('\n', " "))?;
    let step = if let Some(m) = raw.method {
        specula_methods::Label::parse(&m).map_err(|e| e.to_string())?;
        Step::Method(m)
    } else if let Some(r) = raw.reference {
        let info = specula_methods::method(&r).map_err(|e| e.to_string())?;
        if !info.exact {
            return Err(format!("reference = \"{r}\": {r} is not an exact method"));
        }
        Step::Reference(r)
    } else if let Some(p) = raw.param {
        if !p.contains('=') {
            return Err(format!("param = \"{p}\": expected NAME=VALUE"));
        }
        Step::Param(p)
    } else if let Some([yaw_deg, pitch_deg]) = raw.orbit {
        finite(&[yaw_deg, pitch_deg], "orbit")?;
        Step::Orbit { yaw_deg, pitch_deg }
    } else if let Some(t) = raw.translate {
        finite(&t.by, "translate.by")?;
        Step::Translate {
            object: t.object,
            by: Vec3::from_array(t.by),
        }
    } else if let Some(r) = raw.rotate {
        finite(&r.axis, "rotate.axis")?;
        finite(&[r.degrees], "rotate.degrees")?;
        if Vec3::from_array(r.axis).length_squared() == 0.0 {
            return Err("rotate.axis is zero".into());
        }
        Step::Rotate {
            object: r.object,
            axis: Vec3::from_array(r.axis),
            degrees: r.degrees,
        }
    } else if let Some(n) = raw.frames {
        if n == 0 {
            return Err("frames must be at least 1".into());
        }
        Step::Frames(n)
    } else if let Some([yaw_deg, pitch_deg, frames]) = raw.drag {
        finite(&[yaw_deg, pitch_deg], "drag")?;
        if frames < 1.0 || frames.fract() != 0.0 {
            return Err(format!(
                "drag = [yaw, pitch, frames]: frames must be a whole number ≥ 1, got {frames}"
            ));
        }
        Step::Drag {
            yaw_deg,
            pitch_deg,
            frames: frames as u32,
        }
    } else if let Some(path) = raw.screenshot {
        if path.as_os_str().is_empty() {
            return Err("screenshot needs a file name".into());
        }
        Step::Screenshot(path)
    } else if let Some(v) = raw.view {
        Step::View(ViewMode::parse(&v).ok_or_else(|| {
            format!(
                "view = \"{v}\": expected one of {}",
                ViewMode::ALL.map(|m| m.name()).join(", ")
            )
        })?)
    } else if let Some(path) = raw.window_screenshot {
        if path.as_os_str().is_empty() {
            return Err("window_screenshot needs a file name".into());
        }
        Step::WindowScreenshot(path)
    } else if let Some(shown) = raw.panel {
        Step::Panel(shown)
    } else if let Some(a) = raw.analysis {
        Step::Analysis(analysis(a)?.map(Box::new))
    } else if let Some(c) = raw.camera {
        if c.as_str() == Some("analysis") {
            Step::AnalysisCamera
        } else {
            let c = RawCamera::deserialize(c).map_err(|e| {
                format!(
                    "camera: expected \"analysis\" or {{ eye = [x, y, z], target = [x, y, z] }}: {}",
                    e.to_string().trim_end().replace('\n', " ")
                )
            })?;
            finite(&c.eye, "camera.eye")?;
            finite(&c.target, "camera.target")?;
            if c.eye == c.target {
                return Err("camera: the eye and the target are the same point".into());
            }
            Step::Camera {
                eye: Vec3::from_array(c.eye),
                target: Vec3::from_array(c.target),
            }
        }
    } else {
        unreachable!("a one-key table that deserialised names one of the fields")
    };
    Ok(step)
}

fn analysis(a: RawAnalysis) -> Result<Option<Request>, String> {
    let kind = match a.kind.as_str() {
        "off" => {
            if a.has_other_keys() {
                return Err("analysis: kind = \"off\" takes no other key".into());
            }
            return Ok(None);
        }
        "mirror-view" => Kind::MirrorView,
        "glare" => Kind::Glare,
        "lens" => Kind::Lens,
        other => {
            return Err(format!(
                "analysis.kind = \"{other}\": expected mirror-view, glare, lens or off"
            ))
        }
    };
    let object = a
        .object
        .clone()
        .ok_or("analysis needs object = \"NAME\" (the mirror, or the glaring surface)")?;
    if let Some(eye) = a.eye {
        finite(&eye, "analysis.eye")?;
    }
    let eyes = analysis_eyes(&a)?;
    let region = a
        .region
        .map(|[x0, z0, x1, z1]| {
            Region::new(x0, z0, x1, z1).map_err(|e| format!("analysis.region: {e}"))
        })
        .transpose()?;
    let lens_map = match (a.map.as_deref(), kind) {
        (None, _) => None,
        (Some("mean-power"), Kind::Lens) => Some(LensMap::MeanPower),
        (Some("cylinder"), Kind::Lens) => Some(LensMap::Cylinder),
        (Some(other), Kind::Lens) => {
            return Err(format!(
                "analysis.map = \"{other}\": expected mean-power or cylinder"
            ))
        }
        (Some(_), _) => return Err("analysis.map: only a lens analysis draws a map".into()),
    };
    let regulation = regulation_request(&a)?;
    Ok(Some(Request {
        regulation,
        kind,
        lens_map,
        object,
        sun: a.sun,
        display: match (a.display, a.display_luminance) {
            (Some(name), Some(luminances)) => Some((name, luminances)),
            (None, None) => None,
            _ => {
                return Err(
                    "display and display_luminance = [symbol, background, min contrast] \
                            come together"
                        .into(),
                )
            }
        },
        source: a.source,
        eye: a.eye.map(Vec3::from_array),
        eyes,
        region,
        range_m: a.range,
        ground_y: a.ground,
        tolerance: a.tolerance,
    }))
}

impl RawAnalysis {
    /// Whether any key but `kind` is given.
    fn has_other_keys(&self) -> bool {
        let a = self;
        a.object.is_some()
            || a.source.is_some()
            || a.sun.is_some()
            || a.display.is_some()
            || a.eye.is_some()
            || a.eyes.is_some()
            || a.eyebox.is_some()
            || a.region.is_some()
            || a.range.is_some()
            || a.ground.is_some()
            || a.tolerance.is_some()
            || a.map.is_some()
            || a.regulation.is_some()
            || a.forward.is_some()
            || a.r_point.is_some()
            || a.outermost.is_some()
            || a.side.is_some()
            || a.vehicle.is_some()
    }
}

/// The eye points: the camera's, the ocular points or an eyebox (checked as the command
/// checks it).
fn analysis_eyes(a: &RawAnalysis) -> Result<Eyes, String> {
    Ok(match (a.eyes.as_deref(), a.eyebox) {
        (Some(_), Some(_)) => return Err("analysis: give eyes or eyebox, not both".into()),
        (None | Some("centre"), None) => Eyes::Camera,
        (Some("ocular"), None) => Eyes::Ocular,
        (Some(other), None) => {
            return Err(format!(
            "analysis.eyes = \"{other}\": expected centre or ocular (or eyebox = [W, H, NX, NY])"
        ))
        }
        (None, Some(eyebox)) => {
            Eyes::eyebox(eyebox).map_err(|e| format!("analysis.eyebox = [W, H, NX, NY]: {e}"))?
        }
    })
}

/// The regulation a mirror view is judged against, and the vehicle keys that lay it out
/// (refused without one).
fn regulation_request(a: &RawAnalysis) -> Result<Option<RegulationRequest>, String> {
    let vehicle_keys = a.forward.is_some()
        || a.r_point.is_some()
        || a.outermost.is_some()
        || a.side.is_some()
        || a.vehicle.is_some();
    Ok(match a.regulation.clone() {
            None if vehicle_keys => return Err(
                "analysis: forward, r_point, outermost, side and vehicle lay out a regulation's fields: \
                 give regulation = \"NAME\" too"
                    .into(),
            ),
            None => None,
            Some(name) => {
                for (key, p) in [
                    ("analysis.forward", &a.forward),
                    ("analysis.r_point", &a.r_point),
                    ("analysis.outermost", &a.outermost),
                ] {
                    if let Some(p) = p {
                        finite(p, key)?;
                    }
                }
                let side = match a.side.as_deref() {
                    None => None,
                    Some("left") => Some(Side::Left),
                    Some("right") => Some(Side::Right),
                    Some(other) => {
                        return Err(format!(
                            "analysis.side = \"{other}\": expected left or right"
                        ))
                    }
                };
                Some(RegulationRequest {
                    name,
                    forward: a.forward.map(Vec3::from_array),
                    r_point: a.r_point.map(Vec3::from_array),
                    outermost: a.outermost.map(Vec3::from_array),
                    side,
                    vehicle: a.vehicle.clone().unwrap_or_default(),
                })
            }
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_step_kind_parses() {
        let steps = parse(
            "s.toml",
            r#"
[[step]]
method = "envmap"
[[step]]
param = "resolution=128"
[[step]]
orbit = [30, -10]
[[step]]
translate = { object = "door mirror", by = [0, 0.02, 0] }
[[step]]
rotate = { object = "door mirror", axis = [0, 1, 0], degrees = 10 }
[[step]]
frames = 3
[[step]]
drag = [90, 0, 30]
[[step]]
view = "split"
[[step]]
screenshot = "a.png"
[[step]]
analysis = { kind = "mirror-view", object = "door mirror", eyes = "ocular", region = [1, 2, 5, 20], range = 50 }
[[step]]
analysis = { kind = "glare", object = "cover glass", source = "side window", eyebox = [0.3, 0.15, 5, 3] }
[[step]]
analysis = { kind = "off" }
[[step]]
camera = { eye = [3, 18, -4], target = [3, -1, 10] }
[[step]]
camera = "analysis"
[[step]]
window_screenshot = "w.png"
[[step]]
panel = true
"#,
        )
        .unwrap();
        assert_eq!(steps.len(), 16);
        assert_eq!(steps[0], Step::Method("envmap".into()));
        assert_eq!(
            steps[4],
            Step::Rotate {
                object: "door mirror".into(),
                axis: Vec3::Y,
                degrees: 10.0
            }
        );
        assert_eq!(steps[7], Step::View(ViewMode::Split));
        let Step::Analysis(Some(mirror)) = &steps[9] else {
            panic!("{:?}", steps[9])
        };
        assert_eq!(
            (mirror.kind, &mirror.eyes, mirror.range_m),
            (Kind::MirrorView, &Eyes::Ocular, Some(50.0))
        );
        assert_eq!(
            mirror.region,
            Some(Region::new(1.0, 2.0, 5.0, 20.0).unwrap())
        );
        let Step::Analysis(Some(glare)) = &steps[10] else {
            panic!("{:?}", steps[10])
        };
        assert_eq!(glare.source.as_deref(), Some("side window"));
        assert_eq!(
            glare.eyes,
            Eyes::Eyebox {
                width: 0.3,
                height: 0.15,
                columns: 5,
                rows: 3
            }
        );
        assert_eq!(steps[11], Step::Analysis(None));
        assert_eq!(
            steps[12],
            Step::Camera {
                eye: Vec3::new(3.0, 18.0, -4.0),
                target: Vec3::new(3.0, -1.0, 10.0)
            }
        );
        assert_eq!(steps[13], Step::AnalysisCamera);
        assert_eq!(steps[14], Step::WindowScreenshot("w.png".into()));
        assert_eq!(steps[15], Step::Panel(true));
    }

    #[test]
    fn bad_steps_are_named_by_number() {
        let cases = [
            (
                "[[step]]\nmethod = \"raytrace\"",
                "step 1",
                "unknown method",
            ),
            (
                "[[step]]\nframes = 1\n[[step]]\nframes = 0",
                "step 2",
                "at least 1",
            ),
            (
                "[[step]]\nframes = 1\nview = \"split\"",
                "step 1",
                "exactly one",
            ),
            ("[[step]]\nzoom = 2", "step 1", "unknown field"),
            (
                "[[step]]\nview = \"wide\"",
                "step 1",
                "technique, reference, split, error",
            ),
            ("[[step]]\nparam = \"depth\"", "step 1", "NAME=VALUE"),
            (
                "[[step]]\nrotate = { object = \"a\", axis = [0, 0, 0], degrees = 3 }",
                "step 1",
                "zero",
            ),
            ("[[step]]\ntranslate = { object = \"a\" }", "step 1", "by"),
            ("[[step]]\ndrag = [10, 0, 2.5]", "step 1", "whole number"),
            (
                "[[step]]\nanalysis = { kind = \"fog\", object = \"m\" }",
                "step 1",
                "mirror-view, glare, lens or off",
            ),
            (
                "[[step]]\nanalysis = { kind = \"lens\", object = \"l\", map = \"prism\" }",
                "step 1",
                "mean-power or cylinder",
            ),
            (
                "[[step]]\nanalysis = { kind = \"glare\", object = \"c\", map = \"cylinder\" }",
                "step 1",
                "only a lens",
            ),
            (
                "[[step]]\nanalysis = { kind = \"glare\" }",
                "step 1",
                "needs object",
            ),
            (
                "[[step]]\nanalysis = { kind = \"off\", object = \"m\" }",
                "step 1",
                "no other key",
            ),
            (
                "[[step]]\nanalysis = { kind = \"mirror-view\", object = \"m\", eyes = \"ocular\", eyebox = [1, 1, 2, 2] }",
                "step 1",
                "not both",
            ),
            (
                "[[step]]\nanalysis = { kind = \"mirror-view\", object = \"m\", eyebox = [1, 1, 2.5, 2] }",
                "step 1",
                "whole numbers",
            ),
            (
                "[[step]]\nanalysis = { kind = \"mirror-view\", object = \"m\", region = [1, 2, 1, 5] }",
                "step 1",
                "no area",
            ),
            (
                "[[step]]\ncamera = { eye = [1, 2, 3], target = [1, 2, 3] }",
                "step 1",
                "same point",
            ),
            ("[[step]]\ncamera = \"above\"", "step 1", "expected \"analysis\""),
            ("[[step]]\nwindow_screenshot = \"\"", "step 1", "file name"),
            ("[[step]]\npanel = \"left\"", "step 1", "expected a boolean"),
            ("title = \"x\"", "s.toml", "unknown field"),
            ("", "s.toml", "no [[step]]"),
        ];
        for (text, place, what) in cases {
            let message = parse("s.toml", text).unwrap_err().to_string();
            assert!(
                message.contains(place) && message.contains(what),
                "{text:?}: {message:?} should name {place:?} and say {what:?}"
            );
        }
    }
}
