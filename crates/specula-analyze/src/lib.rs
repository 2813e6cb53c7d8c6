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
    /// An object that exists but has the wrong material: what it is, what the role needs, and
    /// how each kind of input gives it that material.
    #[error("{role} '{name}' is {kind}, not {expected}; {}", .wanted.how(name))]
    WrongMaterial {
        role: &'static str,
        name: String,
        kind: String,
        expected: &'static str,
        wanted: Wanted,
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

/// The material an analysis's object must have, for the advice its error gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Wanted {
    Mirror,
    /// A solid dielectric: a lens.
    SolidGlass,
    /// A mirror or a dielectric: a surface that reflects specularly.
    MirrorOrGlass,
    /// Unlit or diffuse: a surface that emits or is lit.
    Emitting,
}

impl Wanted {
    /// How to give object `name` this material: on the command line (`material`, which front
    /// ends show in their own words), in a scene file, and in an OBJ's MTL file (the `illum`
    /// values `specula_scene::loaders::obj` reads). Nothing else in it is a single word in
    /// backticks, which a front end would take for an option.
    pub fn how(self, name: &str) -> String {
        use specula_scene::{MaterialChoice, MaterialOverride};
        let word = |material| {
            let given = MaterialOverride {
                object: name.to_string(),
                material,
            };
            format!("`material` {}", given.shell_word())
        };
        let glass = MaterialChoice::Glass { ior: 1.5 };
        match self {
            Wanted::Mirror => format!(
                "make it one with {} on the command line, a material of `type = \"mirror\"` in \
                 a scene file, or `illum 3` (or 5) in its OBJ material (F0 from `Ks`)",
                word(MaterialChoice::Mirror)
            ),
            Wanted::SolidGlass => format!(
                "make it one with {} (its index of refraction) on the command line, a material \
                 of `type = \"dielectric\"` with `ior = 1.5` (not `thin = true`) in a scene \
                 file, or `illum 4` (or 6, 7, 9) in its OBJ material with `Ni` the index (1.5 if \
                 absent)",
                word(glass)
            ),
            Wanted::MirrorOrGlass => format!(
                "make it one with {} or {} on the command line, a material of `type = \"mirror\"` \
                 or `\"dielectric\"` in a scene file, or `illum 3` (a mirror) or `illum 4` with \
                 `Ni` (a glass) in its OBJ material",
                word(MaterialChoice::Mirror),
                word(glass)
            ),
            Wanted::Emitting => format!(
                "make it one with {} or {} on the command line, a material of `type = \"unlit\"` \
                 or `\"diffuse\"` in a scene file, or `illum 0` (unlit) or `illum 2` (diffuse) in \
                 its OBJ material",
                word(MaterialChoice::Unlit),
                word(MaterialChoice::Diffuse)
            ),
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn wrong(name: &str, wanted: Wanted) -> String {
        AnalyzeError::WrongMaterial {
            role: "surface",
            name: name.into(),
            kind: "diffuse".into(),
            expected: "what the role takes",
            wanted,
        }
        .to_string()
    }

    #[test]
    fn a_wrong_material_says_how_each_input_gives_the_one_wanted() {
        assert_eq!(
            wrong("door mirror", Wanted::Mirror),
            "surface 'door mirror' is diffuse, not what the role takes; make it one with \
             `material` 'door mirror=mirror' on the command line, a material of \
             `type = \"mirror\"` in a scene file, or `illum 3` (or 5) in its OBJ material (F0 \
             from `Ks`)"
        );
        let lens = wrong("lens", Wanted::SolidGlass);
        assert!(lens.contains("`material` lens=glass:1.5 "), "{lens}");
        assert!(
            lens.contains("`illum 4`") && lens.contains("`Ni`"),
            "{lens}"
        );
        let cover = wrong("cover", Wanted::MirrorOrGlass);
        assert!(
            cover.contains("`material` cover=mirror or `material` cover=glass:1.5 "),
            "{cover}"
        );
        let dial = wrong("dial", Wanted::Emitting);
        assert!(
            dial.contains("`material` dial=unlit or `material` dial=diffuse "),
            "{dial}"
        );
        assert!(dial.contains("`illum 0` (unlit)"), "{dial}");
        // Front ends show a single lowercase word in backticks as their option: only
        // `material` may be one.
        for text in [wrong("x", Wanted::Mirror), lens, cover, dial] {
            let options: Vec<&str> = text
                .split('`')
                .skip(1)
                .step_by(2)
                .filter(|w| w.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
                .collect();
            assert!(options.iter().all(|&w| w == "material"), "{text}");
        }
    }
}
