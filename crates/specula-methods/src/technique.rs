//! The one interface every technique implements, with its typed parameters.
//!
//! Lifecycle: a technique is created unprepared ([`MethodInfo::create`]); `prepare` builds what
//! depends on the scene (it is optional: `render` builds whatever is missing); `render` draws one
//! frame for a camera. A rigid move of an object goes through [`LiveScene`] (vertex range written
//! on the GPU, BVH refitted) and bumps its geometry version; the next `render` of any technique
//! sees the new version and redraws only what depends on geometry. A parameter change goes
//! through [`apply_setting`], which parses it by the method's [`ParamSpec`] and tells the
//! technique what the change invalidates.

use std::fmt;

pub use specula_gpu::StageTime;
use specula_gpu::{GpuContext, GpuError, ResourceCounts, TimingSource};
use specula_scene::{Camera, Material, MaterialKind};
use specula_trace::Image;

use crate::live_scene::LiveScene;
use crate::preset::Preset;

#[derive(Debug, thiserror::Error)]
pub enum TechniqueError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("unknown method '{name}'; valid methods: {valid}")]
    UnknownMethod { name: String, valid: String },
    #[error("unknown preset in '{label}'; {valid}")]
    UnknownPreset {
        label: String,
        method: &'static str,
        valid: String,
    },
    #[error("'{label}' is given twice in {given}: each label runs once")]
    DuplicateLabel { label: String, given: String },
    #[error("'{setting}' names a label that is not in this run ({labels})")]
    LabelNotInRun { setting: String, labels: String },
    #[error(
        "parameter '{setting}' belongs to none of the methods in this run ({labels}); {parameters}"
    )]
    UnusedParameter {
        setting: String,
        labels: String,
        parameters: String,
    },
    #[error("{technique} needs a GPU and this run has none")]
    NeedsGpu { technique: &'static str },
    #[error("{technique}: bad parameter '{name}={value}': {reason}")]
    BadParameter {
        technique: &'static str,
        name: String,
        value: String,
        reason: String,
    },
}

/// What the devices a technique may use: a GPU where the run has one (a CPU technique, or a
/// process without a GPU, gets none).
#[derive(Default)]
pub struct Context {
    pub gpu: Option<GpuContext>,
}

impl Context {
    /// A context with a GPU.
    pub fn with_gpu(gpu: GpuContext) -> Context {
        Context { gpu: Some(gpu) }
    }

    /// The GPU, or the error saying `technique` needs one.
    pub fn gpu(&self, technique: &'static str) -> Result<&GpuContext, TechniqueError> {
        self.gpu
            .as_ref()
            .ok_or(TechniqueError::NeedsGpu { technique })
    }

    /// The devices in one line, for reports: the GPU adapter, or "CPU only".
    pub fn describe(&self) -> String {
        self.gpu
            .as_ref()
            .map(|g| g.describe())
            .unwrap_or_else(|| "CPU only".into())
    }

    /// GPU objects created so far (zero without a GPU).
    pub fn resource_counts(&self) -> ResourceCounts {
        self.gpu
            .as_ref()
            .map(|g| g.resource_counts())
            .unwrap_or_default()
    }
}

/// A frame's pixels: on the GPU (an `Rgba32Float` texture the technique owns and reuses; valid
/// until its next frame) or on the CPU.
#[derive(Clone, Debug)]
pub enum Pixels {
    Texture(wgpu::Texture),
    Image(Image),
}

/// What a technique draws for one frame ([`Technique::draw`]): its pixels (linear radiance),
/// where the time went, and what it counted (passes, texels, rays...). The lifecycle
/// (`render`, on `dyn Technique`) turns it into a [`Frame`].
#[derive(Clone, Debug)]
pub struct Drawn {
    pub pixels: Pixels,
    pub stages: Vec<StageTime>,
    pub counters: Vec<(String, u64)>,
    pub timing: TimingSource,
    /// What the technique had to approximate or fall back on this frame (said once per cause).
    pub warnings: Vec<String>,
    /// False while a progressive technique can still refine this view: call `render` again.
    pub converged: bool,
}

/// One rendered frame: what the technique drew (its fields read through `Deref`), and the GPU
/// objects created while it drew, measured by the frame lifecycle around [`Technique::draw`].
/// Both fields are private: only `render` (on `dyn Technique`) makes a `Frame`, so no
/// technique can write the count. A technique builds what it drew:
///
/// ```
/// use specula_methods::{Drawn, Pixels};
/// let drawn = Drawn {
///     pixels: Pixels::Image(specula_trace::Image::new(1, 1)),
///     stages: Vec::new(),
///     counters: Vec::new(),
///     timing: specula_gpu::TimingSource::CpuWallClock,
///     warnings: Vec::new(),
///     converged: true,
/// };
/// ```
///
/// and the same, with a count, as a `Frame`, does not compile:
///
/// ```compile_fail
/// use specula_methods::{Drawn, Frame, Pixels};
/// let frame = Frame {
///     drawn: Drawn {
///         pixels: Pixels::Image(specula_trace::Image::new(1, 1)),
///         stages: Vec::new(),
///         counters: Vec::new(),
///         timing: specula_gpu::TimingSource::CpuWallClock,
///         warnings: Vec::new(),
///         converged: true,
///     },
///     created: specula_gpu::ResourceCounts::default(),
/// };
/// ```
#[derive(Clone, Debug)]
pub struct Frame {
    drawn: Drawn,
    created: ResourceCounts,
}

impl std::ops::Deref for Frame {
    type Target = Drawn;
    fn deref(&self) -> &Drawn {
        &self.drawn
    }
}

impl Frame {
    pub fn total_milliseconds(&self) -> f64 {
        self.stages.iter().map(|s| s.milliseconds).sum()
    }

    /// GPU textures, buffers and bind groups created while the frame was drawn.
    pub fn created(&self) -> ResourceCounts {
        self.created
    }

    /// The pixels on the CPU: read back from the GPU where they are there (through the
    /// context's kept readback buffer: a warm readback creates nothing).
    pub fn image(&self, ctx: &Context) -> Result<Image, TechniqueError> {
        match &self.pixels {
            Pixels::Image(image) => Ok(image.clone()),
            Pixels::Texture(texture) => {
                Ok(crate::raster::read_rgba32f(ctx.gpu("readback")?, texture)?)
            }
        }
    }
}

impl dyn Technique + '_ {
    /// One frame of `camera`'s view at `width` × `height`: the frame lifecycle. The technique
    /// draws ([`Technique::draw`]); the GPU objects created meanwhile are counted here, outside
    /// it, from the context's own counters.
    pub fn render(
        &mut self,
        ctx: &Context,
        scene: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Frame, TechniqueError> {
        let before = ctx.resource_counts();
        let drawn = self.draw(ctx, scene, camera, width, height)?;
        Ok(Frame {
            drawn,
            created: ctx.resource_counts() - before,
        })
    }
}

/// Counter names of methods that trace rays (both exact methods report them; `bench` turns
/// them into rays per second): closest-hit rays, primary and secondary alike, and shadow rays.
pub const COUNTER_RAYS_TRACED: &str = "rays traced (primary and secondary)";
pub const COUNTER_SHADOW_RAYS: &str = "shadow rays";

/// What a parameter's value may be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamKind {
    /// A whole number in `min..=max`.
    Integer { min: i64, max: i64 },
    /// A number in `min..=max`.
    Number { min: f64, max: f64 },
    /// `true` or `false`.
    Flag,
    /// One of these words.
    Choice(&'static [&'static str]),
    /// Free text the technique parses itself; `expected` says what it takes.
    Text { expected: &'static str },
}

/// What changing a parameter makes stale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Invalidates {
    /// Nothing but a value read each frame (a uniform, a loop bound).
    Uniform,
    /// The technique's own GPU resources (maps, pipelines); the scene preparation is kept.
    Resources,
    /// Everything the technique prepared for the scene.
    Scene,
}

impl Invalidates {
    pub fn describe(self) -> &'static str {
        match self {
            Invalidates::Uniform => "uniform",
            Invalidates::Resources => "resources",
            Invalidates::Scene => "scene preparation",
        }
    }
}

/// One parameter of a technique: the single source of its parsing, listing, reports and UI.
#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    pub name: &'static str,
    pub kind: ParamKind,
    pub default: &'static str,
    pub doc: &'static str,
    pub invalidates: Invalidates,
}

/// A parsed parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    Integer(i64),
    Number(f64),
    Flag(bool),
    Word(String),
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Integer(v) => write!(f, "{v}"),
            ParamValue::Number(v) => write!(f, "{v}"),
            ParamValue::Flag(v) => write!(f, "{v}"),
            ParamValue::Word(v) => write!(f, "{v}"),
        }
    }
}

impl ParamValue {
    /// The value as a whole number (integers only; the spec's range has been checked).
    pub fn integer(&self) -> i64 {
        match self {
            ParamValue::Integer(v) => *v,
            ParamValue::Number(v) => *v as i64,
            _ => 0,
        }
    }

    pub fn number(&self) -> f64 {
        match self {
            ParamValue::Integer(v) => *v as f64,
            ParamValue::Number(v) => *v,
            _ => 0.0,
        }
    }

    pub fn flag(&self) -> bool {
        matches!(self, ParamValue::Flag(true))
    }

    pub fn word(&self) -> &str {
        match self {
            ParamValue::Word(w) => w,
            _ => "",
        }
    }
}

impl ParamKind {
    /// What a value must be, for error messages and listings.
    pub fn describe(&self) -> String {
        match self {
            ParamKind::Integer { min, max } => format!("a whole number from {min} to {max}"),
            ParamKind::Number { min, max } => format!("a number from {min} to {max}"),
            ParamKind::Flag => "true or false".into(),
            ParamKind::Choice(words) => format!("one of {}", words.join(", ")),
            ParamKind::Text { expected } => expected.to_string(),
        }
    }
}

impl ParamSpec {
    /// Parses `value` for this parameter of `technique`.
    pub fn parse(
        &self,
        technique: &'static str,
        value: &str,
    ) -> Result<ParamValue, TechniqueError> {
        let bad = || TechniqueError::BadParameter {
            technique,
            name: self.name.to_string(),
            value: value.to_string(),
            reason: format!("expected {}", self.kind.describe()),
        };
        let value = value.trim();
        match self.kind {
            ParamKind::Integer { min, max } => value
                .parse::<i64>()
                .ok()
                .filter(|v| (min..=max).contains(v))
                .map(ParamValue::Integer)
                .ok_or_else(bad),
            ParamKind::Number { min, max } => value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && (min..=max).contains(v))
                .map(ParamValue::Number)
                .ok_or_else(bad),
            ParamKind::Flag => value.parse().map(ParamValue::Flag).map_err(|_| bad()),
            ParamKind::Choice(words) => words
                .iter()
                .find(|w| **w == value)
                .map(|w| ParamValue::Word(w.to_string()))
                .ok_or_else(bad),
            ParamKind::Text { .. } => Ok(ParamValue::Word(value.to_string())),
        }
    }
}

/// The class of specular surface a pixel's primary ray meets: what a method's
/// [`MethodInfo::delegates`] is declared per, and what `compare` splits its figures by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceClass {
    /// A conductor mirror ([`MaterialKind::Mirror`]).
    Mirror,
    /// A dielectric, solid or thin-walled ([`MaterialKind::Dielectric`]).
    Refractor,
}

impl SurfaceClass {
    pub const ALL: [SurfaceClass; 2] = [SurfaceClass::Mirror, SurfaceClass::Refractor];

    /// The class of a surface of `material`; None for the non-specular ones (unlit, diffuse),
    /// which the scene raster pass draws for every technique alike.
    pub fn of(material: &Material) -> Option<SurfaceClass> {
        match material.kind {
            MaterialKind::Mirror { .. } => Some(SurfaceClass::Mirror),
            MaterialKind::Dielectric { .. } => Some(SurfaceClass::Refractor),
            MaterialKind::Unlit | MaterialKind::Diffuse => None,
        }
    }

    /// The word reports use ("mirror", "refractor"), as serialised.
    pub fn name(self) -> &'static str {
        match self {
            SurfaceClass::Mirror => "mirror",
            SurfaceClass::Refractor => "refractor",
        }
    }
}

impl fmt::Display for SurfaceClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A class of surfaces a method does not shade with its own algorithm but hands, code and
/// maps alike, to another registered method: its pixels there are that method's pixels, so its
/// figure there is that method's figure, not its own. `compare` reports such pixels apart,
/// naming the delegate; the suite test checks they equal the delegate's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Delegation {
    /// The surfaces handed over.
    pub material: SurfaceClass,
    /// The [`MethodInfo::name`] of the method whose shading they get.
    pub to: &'static str,
}

/// A registered method: its name, what it is, its parameters and how to make one.
pub struct MethodInfo {
    /// The name users type (`--method`).
    pub name: &'static str,
    /// One line: what it does and its paper.
    pub summary: &'static str,
    /// Its image is the ground truth the others are judged against.
    pub exact: bool,
    /// It cannot run without a GPU.
    pub needs_gpu: bool,
    /// It runs without a GPU, and uses one where the run has one.
    pub gpu_optional: bool,
    /// Its frames refine over calls (see [`Frame::converged`]).
    pub progressive: bool,
    /// The surface classes it hands to another method (at most one entry per class; empty
    /// when it shades every specular surface itself).
    pub delegates: &'static [Delegation],
    pub params: &'static [ParamSpec],
    /// Named lists of settings (`METHOD:PRESET`); a seed technique's `paper` runs the
    /// published algorithm ([`crate::preset`]).
    pub presets: &'static [Preset],
    pub create: fn() -> Box<dyn Technique>,
}

impl MethodInfo {
    pub fn param(&self, name: &str) -> Option<&'static ParamSpec> {
        self.params.iter().find(|p| p.name == name)
    }

    pub fn preset(&self, name: &str) -> Option<&'static Preset> {
        self.presets.iter().find(|p| p.name == name)
    }

    /// The method `material`'s surfaces are handed to; None where this method shades them
    /// itself.
    pub fn delegate_for(&self, material: SurfaceClass) -> Option<&'static str> {
        self.delegates
            .iter()
            .find(|d| d.material == material)
            .map(|d| d.to)
    }
}

impl fmt::Debug for MethodInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MethodInfo")
            .field("name", &self.name)
            .finish()
    }
}

/// A reflection/refraction technique.
pub trait Technique {
    fn info(&self) -> &'static MethodInfo;

    /// The name users type (`--method`).
    fn name(&self) -> &'static str {
        self.info().name
    }

    /// The current value of the parameter `name` of [`MethodInfo::params`], as text.
    fn parameter(&self, name: &str) -> String;

    /// Sets a parameter, already parsed by its spec (only names in [`MethodInfo::params`]
    /// arrive). Returns an error where the value is valid for the kind but not for the
    /// technique (e.g. an unparsable text value).
    fn set_parameter(&mut self, name: &str, value: &ParamValue) -> Result<(), TechniqueError>;

    /// Drops what a parameter change made stale; it is rebuilt by the next `render`.
    fn invalidate(&mut self, what: Invalidates);

    /// Builds what depends on the scene now (otherwise the first `render` does).
    fn prepare(&mut self, ctx: &Context, scene: &LiveScene) -> Result<(), TechniqueError>;

    /// Draws one frame of `camera`'s view at `width` × `height`. Callers use `render` (on
    /// `dyn Technique`), which measures what the frame created.
    fn draw(
        &mut self,
        ctx: &Context,
        scene: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Drawn, TechniqueError>;

    /// Parameters and their current values, in spec order, for reports.
    fn parameters(&self) -> Vec<(String, String)> {
        self.info()
            .params
            .iter()
            .map(|p| (p.name.to_string(), self.parameter(p.name)))
            .collect()
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
