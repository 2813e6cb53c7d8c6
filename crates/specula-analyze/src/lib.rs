//! `specula analyze`: the questions a design engineer asks of a scene, answered with exact
//! rays through the reference tracer's geometry and optics (the BVH, the shading normals,
//! `reflect`), not with a technique's approximation.
//!
//! - [`frame`]: the vehicle frame (forward, up, right) and the eye points analyses run from:
//!   the camera's eye, given points, an eyebox grid, or UN ECE R46's two ocular points.
//! - [`mirror_view`]: what a driver sees in a mirror: the mirror's field of view (horizontal
//!   and vertical extent of the reflected directions, their solid angle), its footprint on the
//!   ground, and the share of a required region seen, per eye point and for all together.
//! - [`glare`]: whether, where and how brightly a source is seen reflected in a surface (a
//!   cover glass reflecting a window over a dial), per eye point and over them.
//! - [`lens`]: a spectacle lens's power, cylinder, prism, lateral colour and distortion as the
//!   wearer gets them at each gaze direction, from exact rays through the lens.
//! - [`plot`] and [`report`]: the plots (PNG, and SVG with axes and legends) and the report
//!   folder (HTML, JSON, plots).
//!
//! Objects are named as the scene names them (`NAME#k` for a component split on load); an
//! unknown name is an error listing the valid ones ([`object`]).

/// Writes a line of a report's text into `out` (a `String`).
macro_rules! say {
    ($out:expr) => {
        $out.push('\n')
    };
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        writeln!($out, $($arg)*).expect("writing to a String")
    }};
}

pub mod analysis;
pub mod figure;
pub mod frame;
pub mod glare;
pub mod lens;
pub mod mirror_rules;
pub mod mirror_surface;
pub mod mirror_view;
pub mod outcome;
pub mod regulation;
pub mod report;
pub mod spherometer;
#[cfg(any(test, feature = "toy"))]
pub mod toy_analysis;
pub mod verdict_page;

use specula_scene::Scene;

#[derive(Debug, thiserror::Error)]
pub enum AnalyzeError {
    #[error("unknown {role} '{name}'; the scene's objects are: {valid}")]
    UnknownObject {
        role: &'static str,
        name: String,
        valid: String,
    },
    #[error("{role} '{name}' names {count} objects of the scene; an analysis takes one (rename them in the scene file)")]
    AmbiguousObject {
        role: &'static str,
        name: String,
        count: usize,
    },
    #[error("{role} '{name}' is {kind}, not {expected}")]
    WrongMaterial {
        role: &'static str,
        name: String,
        kind: String,
        expected: &'static str,
    },
    #[error("{path}: {message}")]
    Write { path: String, message: String },
    /// An option's value the analysis cannot use: the option's name (front ends show it in
    /// their own words: the command as `--name`, a script as its key) and why.
    #[error("{option}: {reason}")]
    BadOption {
        option: &'static str,
        reason: String,
    },
    /// An option's value its declaration refuses (kind, range).
    #[error("{}: {}: {}", .0.name, .0.value, .0.reason)]
    Option(#[from] specula_params::ParamError),
    #[error("the analysis was cancelled")]
    Cancelled,
}

/// The mesh the scene names `name`, for the analysis's `role` (`--mirror`, `--surface`...): an
/// unknown name lists the scene's objects, a name several objects share is refused (say which
/// with `NAME#k` where the loader split one, or rename them in the scene file).
pub fn object(scene: &Scene, role: &'static str, name: &str) -> Result<usize, AnalyzeError> {
    let matches: Vec<usize> = (0..scene.meshes.len())
        .filter(|&m| scene.meshes[m].name == name)
        .collect();
    let mut names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
    names.dedup();
    let mut valid: Vec<&str> = Vec::new();
    for n in names {
        if !valid.contains(&n) {
            valid.push(n);
        }
    }
    match matches.as_slice() {
        [one] => Ok(*one),
        [] => Err(AnalyzeError::UnknownObject {
            role,
            name: name.to_string(),
            valid: valid.join(", "),
        }),
        several => Err(AnalyzeError::AmbiguousObject {
            role,
            name: name.to_string(),
            count: several.len(),
        }),
    }
}
