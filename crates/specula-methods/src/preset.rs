//! Presets and labels: one method run several ways in one report.
//!
//! A [`Preset`] is a named list of ordinary `NAME=VALUE` settings of one method. Every seed
//! technique has a `paper` preset that runs its published algorithm with its published defaults,
//! every step beyond the paper switched off; each module's top doc lists those steps under
//! "Beyond the paper", each item naming the setting that switches it off as
//! `(paper: `NAME=VALUE`)`, and a test holds the preset to that list.
//!
//! A [`Label`] names one way of running a method: the method's name alone (its defaults), or
//! the name, a colon and a preset (`c3rc:paper`). `compare`, `bench`, `render` and the viewer
//! take labels where they take method names, and key images, rows and JSON by them.
//!
//! Settings reach an instance in this order: its preset's, then each `-p` setting in the
//! order given, so that a `-p` overrides the preset. A `-p NAME=VALUE` goes to every instance
//! whose method has `NAME`; `-p LABEL.NAME=VALUE` only to the instance `LABEL`.

use std::fmt;

use specula_core::{apply_setting, MethodInfo, Preset, Technique, TechniqueError};

use crate::registry::method;
use crate::METHODS;

/// One way of running a method: its defaults, or one of its presets.
#[derive(Clone, Copy)]
pub struct Label {
    pub info: &'static MethodInfo,
    pub preset: Option<&'static Preset>,
}

impl PartialEq for Label {
    fn eq(&self, other: &Label) -> bool {
        self.info.name == other.info.name
            && self.preset.map(|p| p.name) == other.preset.map(|p| p.name)
    }
}

impl fmt::Debug for Label {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Label({self})")
    }
}

impl fmt::Display for Label {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.preset {
            Some(preset) => write!(f, "{}:{}", self.info.name, preset.name),
            None => f.write_str(self.info.name),
        }
    }
}

/// Every label there is: each method, then its presets, in registry order (what the viewer's
/// picker offers).
pub fn all_labels() -> Vec<Label> {
    METHODS
        .iter()
        .flat_map(|&info| {
            std::iter::once(Label { info, preset: None }).chain(info.presets.iter().map(
                move |preset| Label {
                    info,
                    preset: Some(preset),
                },
            ))
        })
        .collect()
}

impl Label {
    /// `METHOD` or `METHOD:PRESET`.
    pub fn parse(text: &str) -> Result<Label, TechniqueError> {
        let text = text.trim();
        let (name, preset) = match text.split_once(':') {
            Some((name, preset)) => (name.trim(), Some(preset.trim())),
            None => (text, None),
        };
        let info = method(name)?;
        let preset = match preset {
            None => None,
            Some(preset) => {
                Some(
                    info.preset(preset)
                        .ok_or_else(|| TechniqueError::UnknownPreset {
                            label: text.to_string(),
                            method: info.name,
                            valid: presets_of(info),
                        })?,
                )
            }
        };
        Ok(Label { info, preset })
    }

    /// Parses each label and refuses one given twice (their images and rows would collide).
    pub fn parse_list(texts: &[String]) -> Result<Vec<Label>, TechniqueError> {
        let mut labels: Vec<Label> = Vec::with_capacity(texts.len());
        for text in texts {
            let label = Label::parse(text)?;
            if labels.contains(&label) {
                return Err(TechniqueError::DuplicateLabel {
                    label: label.to_string(),
                    given: texts.join(", "),
                });
            }
            labels.push(label);
        }
        Ok(labels)
    }

    /// The name of files keyed by this label (`c3rc-paper`): no colon, which some file
    /// systems refuse.
    pub fn file_stem(&self) -> String {
        self.to_string().replace(':', "-")
    }

    /// A new technique with the preset's settings applied.
    pub fn create(&self) -> Result<Box<dyn Technique>, TechniqueError> {
        let mut technique = (self.info.create)();
        if let Some(preset) = self.preset {
            for setting in preset.settings {
                apply_setting(technique.as_mut(), setting)?;
            }
        }
        Ok(technique)
    }
}

fn presets_of(info: &MethodInfo) -> String {
    if info.presets.is_empty() {
        format!("{} has no presets", info.name)
    } else {
        let names: Vec<String> = info
            .presets
            .iter()
            .map(|p| format!("{}:{}", info.name, p.name))
            .collect();
        format!("valid: {}", names.join(", "))
    }
}

/// "M's parameters are a, b; N's parameters are c" for the methods of `labels`.
fn parameters_of(labels: &[Label]) -> String {
    let mut methods: Vec<&MethodInfo> = Vec::new();
    for label in labels {
        if !methods.iter().any(|m| m.name == label.info.name) {
            methods.push(label.info);
        }
    }
    methods
        .iter()
        .map(|m| {
            let names: Vec<&str> = m.params.iter().map(|p| p.name).collect();
            format!("{}'s parameters are {}", m.name, names.join(", "))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// A `-p` setting, split: the label it is for (None: every instance that has the parameter),
/// and the `NAME=VALUE` itself.
pub fn split_setting(setting: &str) -> (Option<&str>, &str) {
    let key = setting.split_once('=').map_or(setting, |(key, _)| key);
    match key.rfind('.') {
        // Parameter names have no dot; a key with one is LABEL.NAME.
        Some(dot) => (Some(setting[..dot].trim()), &setting[dot + 1..]),
        None => (None, setting),
    }
}

/// Checks the `-p` settings of a run over `labels` before anything is built: a setting
/// `LABEL.NAME=VALUE` must name a label of the run whose method has `NAME`, and a plain
/// `NAME=VALUE` must reach at least one of them.
pub fn check_settings(labels: &[Label], settings: &[String]) -> Result<(), TechniqueError> {
    let run = || {
        labels
            .iter()
            .map(Label::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    };
    for setting in settings {
        let (target, plain) = split_setting(setting);
        let reached: Vec<&Label> = match target {
            Some(target) => {
                let label = Label::parse(target)?;
                let label = labels.iter().find(|l| **l == label).ok_or_else(|| {
                    TechniqueError::LabelNotInRun {
                        setting: setting.clone(),
                        labels: run(),
                    }
                })?;
                vec![label]
            }
            None => labels.iter().filter(|l| l.has_param_of(plain)).collect(),
        };
        if reached.is_empty() {
            return Err(TechniqueError::UnusedParameter {
                setting: setting.clone(),
                labels: run(),
                parameters: parameters_of(labels),
            });
        }
        for label in reached {
            // Parses the value against the parameter's spec: a bad one fails here, early.
            apply_setting((label.info.create)().as_mut(), plain)?;
        }
    }
    Ok(())
}

impl Label {
    /// Whether this label's method has the parameter of `NAME=VALUE`.
    fn has_param_of(&self, setting: &str) -> bool {
        let name = setting.split_once('=').map_or(setting, |(n, _)| n).trim();
        self.info.param(name).is_some()
    }

    /// The `-p` settings that reach this label, in order, as plain `NAME=VALUE`: those naming
    /// it (`LABEL.NAME=VALUE`) and the plain ones whose name its method has.
    pub fn settings_for<'a>(&self, settings: &'a [String]) -> Vec<&'a str> {
        settings
            .iter()
            .filter_map(|setting| match split_setting(setting) {
                (Some(target), plain) => Label::parse(target)
                    .is_ok_and(|l| l == *self)
                    .then_some(plain),
                (None, plain) => self.has_param_of(plain).then_some(plain),
            })
            .collect()
    }

    /// A new technique with the preset's settings, then the `-p` settings that reach it.
    pub fn create_with(&self, settings: &[String]) -> Result<Box<dyn Technique>, TechniqueError> {
        let mut technique = self.create()?;
        for setting in self.settings_for(settings) {
            apply_setting(technique.as_mut(), setting)?;
        }
        Ok(technique)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One technique of a run, under its label.
    type Instance = (Label, Box<dyn Technique>);

    /// The instances of a run: the settings checked ([`check_settings`]), then one technique per
    /// label with its preset and the settings that reach it.
    fn instances(labels: &[Label], settings: &[String]) -> Result<Vec<Instance>, TechniqueError> {
        check_settings(labels, settings)?;
        labels
            .iter()
            .map(|l| Ok((*l, l.create_with(settings)?)))
            .collect()
    }

    #[test]
    fn labels_parse_and_print() {
        let plain = Label::parse("c3rc").unwrap();
        assert_eq!(plain.to_string(), "c3rc");
        assert!(plain.preset.is_none());
        let paper = Label::parse("c3rc:paper").unwrap();
        assert_eq!(paper.to_string(), "c3rc:paper");
        assert_eq!(paper.file_stem(), "c3rc-paper");
        assert_ne!(plain, paper);
    }

    #[test]
    fn bad_labels_say_what_exists() {
        let unknown = Label::parse("c3rc:fast").unwrap_err().to_string();
        assert!(
            unknown.contains("c3rc:fast") && unknown.contains("c3rc:paper"),
            "{unknown}"
        );
        let empty = Label::parse("c3rc:").unwrap_err().to_string();
        assert!(empty.contains("c3rc:paper"), "{empty}");
        let none = Label::parse("reference:paper").unwrap_err().to_string();
        assert!(none.contains("reference has no presets"), "{none}");
        let method = Label::parse("magic:paper").unwrap_err().to_string();
        assert!(
            method.contains("valid methods") && method.contains("c3rc"),
            "{method}"
        );
        let twice = Label::parse_list(&["c3rc".into(), "envmap".into(), "c3rc".into()])
            .unwrap_err()
            .to_string();
        assert!(
            twice.contains("'c3rc'") && twice.contains("twice"),
            "{twice}"
        );
        assert!(Label::parse_list(&["c3rc".into(), "c3rc:paper".into()]).is_ok());
    }

    #[test]
    fn no_parameter_name_has_a_dot() {
        for info in METHODS {
            for p in info.params {
                assert!(!p.name.contains('.'), "{}.{}", info.name, p.name);
            }
        }
    }

    #[test]
    fn settings_reach_instances_in_order_the_preset_first() {
        let labels = Label::parse_list(&["c3rc".into(), "c3rc:paper".into()]).unwrap();
        let paper_value = |instances: &[Instance], i: usize| instances[i].1.parameter("trace_self");
        let run = instances(&labels, &[]).unwrap();
        assert_eq!(paper_value(&run, 0), "true");
        assert_eq!(paper_value(&run, 1), "false");
        // A plain -p overrides the preset on every instance.
        let run = instances(&labels, &["trace_self=true".into()]).unwrap();
        assert_eq!(paper_value(&run, 1), "true");
        // A labelled one reaches that instance only.
        let run = instances(&labels, &["c3rc.trace_self=false".into()]).unwrap();
        assert_eq!(paper_value(&run, 0), "false");
        let run = instances(&labels, &["c3rc:paper.points=5000".into()]).unwrap();
        assert_eq!(run[1].1.parameter("points"), "5000");
        assert_eq!(run[0].1.parameter("points"), "100000");
        // Values keep their dots.
        let run = instances(&labels, &["c3rc:paper.splat_scale=1.25".into()]).unwrap();
        assert_eq!(run[1].1.parameter("splat_scale"), "1.25");

        let missing = instances(&labels, &["envmap.resolution=64".into()])
            .err()
            .unwrap()
            .to_string();
        assert!(missing.contains("c3rc, c3rc:paper"), "{missing}");
        let unused = instances(&labels, &["spp=4".into()])
            .err()
            .unwrap()
            .to_string();
        assert!(
            unused.contains("spp=4") && unused.contains("c3rc:paper"),
            "{unused}"
        );
        let bad = instances(&labels, &["c3rc:paper.magic=1".into()])
            .err()
            .unwrap()
            .to_string();
        assert!(bad.contains("magic") && bad.contains("trace_self"), "{bad}");
    }
}
