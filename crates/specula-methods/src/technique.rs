//! The one interface every technique implements, and the registry of techniques by name.

pub use specula_gpu::StageTime;
use specula_gpu::{GpuContext, GpuError, TimingSource};
use specula_scene::{Camera, Scene};
use specula_trace::Image;

#[derive(Debug, thiserror::Error)]
pub enum TechniqueError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("unknown method '{name}'; valid methods: {valid}")]
    UnknownMethod { name: String, valid: String },
    #[error("{technique}: render called before prepare")]
    NotPrepared { technique: &'static str },
    #[error("{technique}: bad parameter '{name}={value}': {reason}")]
    BadParameter {
        technique: &'static str,
        name: String,
        value: String,
        reason: String,
    },
}

/// One rendered frame: the image (linear radiance), where the time went, and what the
/// technique counted (passes, texels, rays...).
#[derive(Clone, Debug)]
pub struct Frame {
    pub image: Image,
    pub stages: Vec<StageTime>,
    pub counters: Vec<(String, u64)>,
    pub timing: TimingSource,
    /// What the technique had to approximate or fall back on this frame (said once per cause).
    pub warnings: Vec<String>,
}

impl Frame {
    pub fn total_milliseconds(&self) -> f64 {
        self.stages.iter().map(|s| s.milliseconds).sum()
    }
}

/// A reflection/refraction technique. `prepare` runs once per scene or geometry change;
/// `render` once per frame for a camera.
pub trait Technique {
    /// The name users type (`--method`).
    fn name(&self) -> &'static str;
    /// Parameters and their current values, for reports.
    fn parameters(&self) -> Vec<(String, String)>;
    /// Sets a parameter by its name in [`Technique::parameters`]; takes effect at the next
    /// `prepare`. Unknown names and unparsable values are errors naming the valid choices.
    fn set_parameter(&mut self, name: &str, value: &str) -> Result<(), TechniqueError>;
    fn prepare(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), TechniqueError>;
    fn render(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Frame, TechniqueError>;
}

/// GPU technique names, in the order reports list them.
pub const METHODS: &[&str] = &["envmap", "pvrr", "distance-maps"];

/// A new, unprepared technique by name.
pub fn by_name(name: &str) -> Result<Box<dyn Technique>, TechniqueError> {
    match name {
        "envmap" => Ok(Box::new(crate::envmap::EnvMap::default())),
        "pvrr" => Ok(Box::new(crate::pvrr::Pvrr::default())),
        "distance-maps" => Ok(Box::new(crate::distance_maps::DistanceMaps::default())),
        _ => Err(TechniqueError::UnknownMethod {
            name: name.to_string(),
            valid: std::iter::once("reference")
                .chain(METHODS.iter().copied())
                .collect::<Vec<_>>()
                .join(", "),
        }),
    }
}

/// Applies `name=value` settings to a technique, in order.
pub fn apply_parameters(
    technique: &mut dyn Technique,
    settings: &[String],
) -> Result<(), TechniqueError> {
    for setting in settings {
        let (name, value) =
            setting
                .split_once('=')
                .ok_or_else(|| TechniqueError::BadParameter {
                    technique: technique.name(),
                    name: setting.clone(),
                    value: String::new(),
                    reason: "expected NAME=VALUE".into(),
                })?;
        technique.set_parameter(name.trim(), value.trim())?;
    }
    Ok(())
}

/// Applies those of the `name=value` settings whose name `technique` lists in its
/// [`Technique::parameters`], in order; returns, per setting, whether it was applied. For runs
/// over several techniques, where a parameter belongs to some of them only.
pub fn apply_known_parameters(
    technique: &mut dyn Technique,
    settings: &[String],
) -> Result<Vec<bool>, TechniqueError> {
    let known: Vec<String> = technique.parameters().into_iter().map(|(n, _)| n).collect();
    let mut applied = Vec::with_capacity(settings.len());
    for setting in settings {
        let name = setting.split_once('=').map(|(n, _)| n.trim());
        let used = name.is_some_and(|n| known.iter().any(|k| k == n));
        if used {
            apply_parameters(technique, std::slice::from_ref(setting))?;
        }
        applied.push(used);
    }
    Ok(applied)
}

/// A parameter setting being parsed, for uniform error messages across techniques.
pub struct Setting<'a> {
    pub technique: &'static str,
    pub name: &'a str,
    pub value: &'a str,
}

impl Setting<'_> {
    pub fn bad(&self, reason: &str) -> TechniqueError {
        TechniqueError::BadParameter {
            technique: self.technique,
            name: self.name.to_string(),
            value: self.value.to_string(),
            reason: reason.to_string(),
        }
    }

    /// A texture or map size in texels, 1 to 8192.
    pub fn texels(&self) -> Result<u32, TechniqueError> {
        self.count(1..=8192, "a whole number of texels from 1 to 8192")
    }

    /// A whole number in `range`; `expected` says what in the error.
    pub fn count(
        &self,
        range: std::ops::RangeInclusive<u32>,
        expected: &str,
    ) -> Result<u32, TechniqueError> {
        self.value
            .parse::<u32>()
            .ok()
            .filter(|v| range.contains(v))
            .ok_or_else(|| self.bad(&format!("expected {expected}")))
    }

    /// A number in `range`; `expected` says what in the error.
    pub fn number_in(
        &self,
        range: std::ops::RangeInclusive<f32>,
        expected: &str,
    ) -> Result<f32, TechniqueError> {
        self.value
            .parse::<f32>()
            .ok()
            .filter(|v| range.contains(v))
            .ok_or_else(|| self.bad(&format!("expected {expected}")))
    }

    pub fn flag(&self) -> Result<bool, TechniqueError> {
        self.value
            .parse()
            .map_err(|_| self.bad("expected true or false"))
    }
}
