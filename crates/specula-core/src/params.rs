//! Parameters, each declared once: the declarations are `specula-params`'s (re-exported here,
//! shared with the analyses' options); what applies a setting to a technique is here.

pub use specula_params::*;

use crate::technique::{Technique, TechniqueError};

impl From<ParamError> for TechniqueError {
    fn from(e: ParamError) -> TechniqueError {
        TechniqueError::BadParameter {
            technique: e.owner,
            name: e.name,
            value: e.value,
            reason: e.reason,
        }
    }
}

/// Parses `NAME=VALUE` and applies it to `technique`, invalidating what the spec says.
pub fn apply_setting(technique: &mut dyn Technique, setting: &str) -> Result<(), TechniqueError> {
    let info = technique.info();
    let bad = |name: &str, value: &str, reason: String| TechniqueError::BadParameter {
        technique: info.name,
        name: name.to_string(),
        value: value.to_string(),
        reason,
    };
    let (name, value) = setting
        .split_once('=')
        .ok_or_else(|| bad(setting, "", "expected NAME=VALUE".into()))?;
    let (name, value) = (name.trim(), value.trim());
    let spec = info.param(name).ok_or_else(|| {
        let names: Vec<&str> = info.params.iter().map(|p| p.name).collect();
        bad(
            name,
            value,
            format!("{}'s parameters are {}", info.name, names.join(", ")),
        )
    })?;
    let parsed = spec.parse(info.name, value)?;
    technique.set_parameter(name, &parsed)?;
    technique.invalidate(spec.invalidates);
    Ok(())
}

/// Applies `NAME=VALUE` settings to a technique, in order.
pub fn apply_parameters(
    technique: &mut dyn Technique,
    settings: &[String],
) -> Result<(), TechniqueError> {
    settings
        .iter()
        .try_for_each(|s| apply_setting(technique, s))
}

/// Applies those of the `NAME=VALUE` settings whose name the technique has, in order; returns,
/// per setting, whether it was applied. For runs over several techniques, where a parameter
/// belongs to some of them only.
pub fn apply_known_parameters(
    technique: &mut dyn Technique,
    settings: &[String],
) -> Result<Vec<bool>, TechniqueError> {
    let info = technique.info();
    let mut applied = Vec::with_capacity(settings.len());
    for setting in settings {
        let name = setting.split_once('=').map(|(n, _)| n.trim());
        let used = name.is_some_and(|n| info.param(n).is_some());
        if used {
            apply_setting(technique, setting)?;
        }
        applied.push(used);
    }
    Ok(applied)
}

/// The error a technique returns for a valid-looking value it cannot use.
pub fn bad_value(
    technique: &'static str,
    name: &str,
    value: &ParamValue,
    reason: &str,
) -> TechniqueError {
    TechniqueError::BadParameter {
        technique,
        name: name.to_string(),
        value: value.to_string(),
        reason: reason.to_string(),
    }
}
