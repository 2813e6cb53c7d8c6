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
//! analysis = { kind = "mirror-view", mirror = "door mirror", ocular = true, region = [1, 2, 5, 20] }
//! [[step]]
//! analysis = { kind = "glare", surface = "cover glass", source = "side window", eyebox = [0.3, 0.15, 5, 3] }
//! [[step]]
//! analysis_json = "mirror-view.json"                # the finished analysis's JSON, as --json
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
//! An `analysis` step's keys are `kind` (an analysis of `specula analyze`, or "off") and that
//! analysis's options by their declared names, as `specula analyze KIND` takes them as flags
//! (`--tolerance-deg` is `tolerance_deg`): a point or a box as an array of numbers, a
//! repeatable option (`vehicle`, `eye`) as an array, a flag as `true`; docs/viewer.md lists
//! every key, made from the declarations. `kind = "lens"` also takes `map = "mean-power"` or
//! `"cylinder"` (what the overlay draws). The step waits for the analysis and prints its
//! figures; so does each screenshot taken while one is on (the screenshot shows its overlay).

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use crate::analysis::{LensMap, Settings};
use crate::session::ViewMode;

/// An analysis as a script asks for it: its settings (options by name, checked against their
/// declarations) and what the lens overlay maps.
#[derive(Clone, Debug, PartialEq)]
pub struct Request {
    pub settings: Settings,
    pub lens_map: Option<LensMap>,
}

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
    /// An analysis step.
    Analysis(AnalysisStep),
    /// Puts the view's camera here.
    Camera {
        eye: Vec3,
        target: Vec3,
    },
    /// Draws a frame and saves the window as shown (the panel, the overlay) to this file.
    WindowScreenshot(PathBuf),
    /// Shows (true) or hides the docked panel.
    Panel(bool),
}

/// What an analysis step does.
#[derive(Clone, Debug, PartialEq)]
pub enum AnalysisStep {
    /// Turns the analysis on.
    On(Box<Request>),
    Off,
    /// Puts the view's camera at the analysis's overview.
    Camera,
    /// Writes the finished analysis's JSON document (what `--json` writes) to this file.
    Json(PathBuf),
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
    analysis: Option<toml::Table>,
    analysis_json: Option<PathBuf>,
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
    "method, reference, param, orbit, translate, rotate, frames, drag, view, analysis, \
     analysis_json, camera, panel, screenshot or window_screenshot";

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
        Step::Analysis(match analysis(a)? {
            Some(request) => AnalysisStep::On(Box::new(request)),
            None => AnalysisStep::Off,
        })
    } else if let Some(path) = raw.analysis_json {
        if path.as_os_str().is_empty() {
            return Err("analysis_json: expected a file name".into());
        }
        Step::Analysis(AnalysisStep::Json(path))
    } else if let Some(c) = raw.camera {
        if c.as_str() == Some("analysis") {
            Step::Analysis(AnalysisStep::Camera)
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

fn analysis(mut table: toml::Table) -> Result<Option<Request>, String> {
    let kind = match table.remove("kind") {
        Some(toml::Value::String(kind)) => kind,
        _ => return Err("analysis needs kind = \"NAME\" (an analysis, or \"off\")".into()),
    };
    if kind == "off" {
        return match table.is_empty() {
            true => Ok(None),
            false => Err("analysis: kind = \"off\" takes no other key".into()),
        };
    }
    let mut settings =
        Settings::new(&kind).map_err(|e| format!("analysis.kind = \"{kind}\": {}", in_keys(e)))?;
    let lens_map = match table.remove("map") {
        None => None,
        Some(map) if kind == "lens" => Some(match map.as_str() {
            Some("mean-power") => LensMap::MeanPower,
            Some("cylinder") => LensMap::Cylinder,
            _ => {
                return Err(format!(
                    "analysis.map = {map}: expected mean-power or cylinder"
                ))
            }
        }),
        Some(_) => return Err("analysis.map: only a lens analysis draws a map".into()),
    };
    for (key, value) in &table {
        let text = option_text(value).ok_or_else(|| {
            format!(
                "analysis.{key} = {value}: expected a string, a number, a boolean or an array \
                 of them"
            )
        })?;
        settings
            .set(key, &text)
            .map_err(|e| format!("analysis.{key}: {}", in_keys(e)))?;
    }
    Ok(Some(Request { settings, lens_map }))
}

/// A TOML value as an option's text: the numbers of an array comma-separated (a point, a
/// box), the items of a repeatable option's array semicolon-separated.
fn option_text(value: &toml::Value) -> Option<String> {
    use toml::Value;
    Some(match value {
        Value::String(s) => s.clone(),
        Value::Integer(i) => i.to_string(),
        Value::Float(f) => f.to_string(),
        Value::Boolean(b) => b.to_string(),
        Value::Array(items) if items.iter().all(|v| v.is_integer() || v.is_float()) => items
            .iter()
            .map(option_text)
            .collect::<Option<Vec<_>>>()?
            .join(","),
        Value::Array(items) => items
            .iter()
            .map(option_text)
            .collect::<Option<Vec<_>>>()?
            .join(";"),
        _ => return None,
    })
}

/// A library error in a script's words: the reason, the key being named by the caller.
pub fn in_keys(e: specula_analyze::AnalyzeError) -> String {
    let text = match e {
        specula_analyze::AnalyzeError::BadOption { reason, .. } => reason,
        specula_analyze::AnalyzeError::Option(e) => format!("{}: {}", e.value, e.reason),
        other => other.to_string(),
    };
    // The library names options `like_this`: a script's keys are those names.
    text.replace('`', "")
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
analysis = { kind = "mirror-view", mirror = "door mirror", ocular = true, region = [1, 2, 5, 20], range = 50, vehicle = ["car body", "roof"], regulation = "r46-iii" }
[[step]]
analysis = { kind = "glare", surface = "cover glass", source = "side window", eyebox = [0.3, 0.15, 5, 3] }
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
        let Step::Analysis(AnalysisStep::On(mirror)) = &steps[9] else {
            panic!("{:?}", steps[9])
        };
        // The keys are the options by name, their values as the command line writes them.
        let m = &mirror.settings;
        assert_eq!(m.name(), "mirror-view");
        for (name, value) in [
            ("mirror", "door mirror"),
            ("ocular", "true"),
            ("region", "1,2,5,20"),
            ("range", "50"),
            ("vehicle", "car body;roof"),
            ("regulation", "r46-iii"),
            ("tolerance", "0.005"),
        ] {
            assert_eq!(m.value(name), value, "{name}");
        }
        let (analysis, eyes) = m.build().unwrap();
        assert!(eyes.ocular);
        assert_eq!(analysis.options().get("vehicle").unwrap(), "car body;roof");
        let Step::Analysis(AnalysisStep::On(glare)) = &steps[10] else {
            panic!("{:?}", steps[10])
        };
        assert_eq!(glare.settings.value("source"), "side window");
        assert_eq!(
            glare.settings.build().unwrap().1.eyebox,
            Some([0.3, 0.15, 5.0, 3.0])
        );
        assert_eq!(steps[11], Step::Analysis(AnalysisStep::Off));
        assert_eq!(
            steps[12],
            Step::Camera {
                eye: Vec3::new(3.0, 18.0, -4.0),
                target: Vec3::new(3.0, -1.0, 10.0)
            }
        );
        assert_eq!(steps[13], Step::Analysis(AnalysisStep::Camera));
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
                "[[step]]\nanalysis = { kind = \"fog\", mirror = \"m\" }",
                "step 1",
                "the analyses are mirror-view, glare, lens",
            ),
            (
                "[[step]]\nanalysis = { kind = \"lens\", lens = \"l\", map = \"prism\" }",
                "step 1",
                "mean-power or cylinder",
            ),
            (
                "[[step]]\nanalysis = { kind = \"glare\", surface = \"c\", map = \"cylinder\" }",
                "step 1",
                "only a lens",
            ),
            (
                "[[step]]\nanalysis = { mirror = \"m\" }",
                "step 1",
                "needs kind",
            ),
            (
                "[[step]]\nanalysis = { kind = \"off\", mirror = \"m\" }",
                "step 1",
                "no other key",
            ),
            (
                "[[step]]\nanalysis = { kind = \"mirror-view\", object = \"m\" }",
                "step 1",
                "analysis.object: mirror-view takes no option 'object'; its options are mirror,",
            ),
            (
                "[[step]]\nanalysis = { kind = \"mirror-view\", mirror = \"m\", eyebox = [1, 1, 2] }",
                "step 1",
                "analysis.eyebox: 1,1,2: expected W,H,NX,NY",
            ),
            (
                "[[step]]\nanalysis = { kind = \"mirror-view\", mirror = \"m\", side = \"up\" }",
                "step 1",
                "expected one of left, right",
            ),
            (
                "[[step]]\nanalysis = { kind = \"mirror-view\", mirror = \"m\", range = { a = 1 } }",
                "step 1",
                "expected a string, a number",
            ),
            ("[[step]]\nanalysis_json = \"\"", "step 1", "file name"),
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
