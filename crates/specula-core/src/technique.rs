//! The one interface every technique implements.
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
use crate::params::{bad_value, Invalidates, ParamSet, ParamSpec, ParamValue};

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
/// use specula_core::{Drawn, Pixels};
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
/// use specula_core::{Drawn, Frame, Pixels};
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

/// A named list of settings of one method (`METHOD:PRESET`).
#[derive(Debug)]
pub struct Preset {
    /// The name after the colon (`c3rc:paper`).
    pub name: &'static str,
    /// One line: what running with it means.
    pub summary: &'static str,
    /// `NAME=VALUE` settings, applied in order over the defaults.
    pub settings: &'static [&'static str],
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
    /// published algorithm.
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

    /// Its parameters (a [`params!`](crate::params) block's struct, whose `SPECS` are
    /// [`MethodInfo::params`]).
    fn params(&self) -> &dyn ParamSet;
    fn params_mut(&mut self) -> &mut dyn ParamSet;

    /// The current value of the parameter `name` of [`MethodInfo::params`], as text.
    fn parameter(&self, name: &str) -> String {
        self.params().get(name).unwrap_or_default()
    }

    /// Sets a parameter, already parsed by its spec (only names in [`MethodInfo::params`]
    /// arrive). Returns an error where the value is valid for the kind but not for the
    /// technique's type.
    fn set_parameter(&mut self, name: &str, value: &ParamValue) -> Result<(), TechniqueError> {
        let technique = self.info().name;
        match self.params_mut().set(name, value) {
            Some(Err(reason)) => Err(bad_value(technique, name, value, &reason)),
            _ => Ok(()),
        }
    }

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

/// One frame of a still scene from its own camera, with its pixels on the CPU: for tests,
/// benches and one-shot renders. Wraps the scene in a fresh [`LiveScene`], so the technique
/// prepares for it.
pub trait RenderStill {
    fn render_still(
        &mut self,
        ctx: &Context,
        scene: &specula_scene::Scene,
        width: u32,
        height: u32,
    ) -> Result<Still, TechniqueError>;
}

/// A frame and its image on the CPU.
pub struct Still {
    pub frame: Frame,
    pub image: specula_trace::Image,
}

impl std::ops::Deref for Still {
    type Target = Frame;
    fn deref(&self) -> &Frame {
        &self.frame
    }
}

impl RenderStill for dyn Technique + '_ {
    fn render_still(
        &mut self,
        ctx: &Context,
        scene: &specula_scene::Scene,
        width: u32,
        height: u32,
    ) -> Result<Still, TechniqueError> {
        let live = LiveScene::new(scene.clone());
        self.prepare(ctx, &live)?;
        let frame = self.render(ctx, &live, &scene.camera, width, height)?;
        let image = frame.image(ctx)?;
        Ok(Still { frame, image })
    }
}

impl<T: Technique> RenderStill for T {
    fn render_still(
        &mut self,
        ctx: &Context,
        scene: &specula_scene::Scene,
        width: u32,
        height: u32,
    ) -> Result<Still, TechniqueError> {
        (self as &mut dyn Technique).render_still(ctx, scene, width, height)
    }
}

/// The context for GPU tests: a missing Vulkan adapter fails the test unless the runner opted
/// out, and then it is `None` (see [`specula_gpu::test_context`]).
pub fn test_context(test: &str) -> Option<Context> {
    specula_gpu::test_context(test).map(Context::with_gpu)
}
