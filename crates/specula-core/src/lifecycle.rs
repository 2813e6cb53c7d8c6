//! The frame lifecycle of a GPU technique: what every GPU technique's frame does, done once.
//!
//! A GPU technique implements [`GpuTechnique`]: what it builds for a scene (`prepare`) and its
//! own stages of a frame (`shade`). [`GpuMethod`] wraps it into a [`Technique`] and owns the
//! rest of the frame, in this order:
//! 1. the device lookup (a clear error where the run has no GPU);
//! 2. the preparation, kept per scene id: the technique's, and the scene raster pass it
//!    declares ([`GpuTechnique::SCENE_RASTER`], [`GpuTechnique::scene_raster`]), rebuilt for another scene or after a change
//!    that invalidates the scene's preparation;
//! 3. the frame's start: the raster pass's G-buffer pool handed back (and its shadow maps drawn
//!    again after a move), the stage timer started;
//! 4. the camera's G-buffer (stage `g-buffer`), unless the technique draws its own;
//! 5. the technique's `shade`, into the output texture (or its own G-buffer's), timing its own stages by
//!    [`GpuFrame::lap`] and counting by [`GpuFrame::count`];
//! 6. the stage times and the [`Drawn`] the frame lifecycle of [`Technique::render`] measures.

use std::ops::{Deref, DerefMut};

use specula_gpu::shaders::CameraUniform;
use specula_gpu::{GpuContext, GpuError, StageTimer};
use specula_scene::Camera;

use crate::live_scene::LiveScene;
use crate::params::{Invalidates, ParamSet};
use crate::raster::{self, GBuffer, OutputTexture, RasterPass, RasterSpec};
use crate::technique::{Context, Drawn, MethodInfo, Pixels, Technique, TechniqueError};

/// A GPU technique's own part of a frame; [`GpuMethod`] does the rest (the module doc lists
/// it).
pub trait GpuTechnique: 'static {
    /// What it builds for a scene: pipelines, maps, bind groups.
    type Prepared;

    /// Its parameters: the `params!` struct it keeps (as its field `params`).
    type Params: ParamSet;

    /// What the registry lists for it: the [`Technique::info`] of its [`GpuMethod`].
    const INFO: &'static MethodInfo;

    /// Whether its frames start from the scene raster pass: [`RasterSpec::scene`] at its
    /// parameter `shadow_resolution` ([`raster::SHADOW_RESOLUTION`]). False: it draws no
    /// G-buffer.
    const SCENE_RASTER: bool = true;

    /// Its parameters, as [`Technique::params`] hands them out.
    fn params(&self) -> &Self::Params;
    fn params_mut(&mut self) -> &mut Self::Params;

    /// The scene raster pass its frames start from, or None (it draws no G-buffer): by default
    /// as [`GpuTechnique::SCENE_RASTER`] says.
    fn scene_raster(&self) -> Option<RasterSpec> {
        Self::SCENE_RASTER.then(|| RasterSpec::scene(raster::shadow_resolution(self.params())))
    }

    /// Whether it draws the camera's G-buffer itself (from [`GpuFrame::raster`], in a stage of
    /// its own) instead of the lifecycle drawing it first, and shows that G-buffer's colour
    /// ([`GpuFrame::show`]) instead of an output texture.
    fn draws_own_g_buffer(&self) -> bool {
        false
    }

    /// Whether its stages are timed on the CPU's clock even where the GPU has timestamps (its
    /// stages run on the CPU too).
    fn wall_clock(&self) -> bool {
        false
    }

    /// Builds what depends on the scene (the raster pass is the one it declared).
    fn prepare(
        &mut self,
        gpu: &GpuContext,
        live: &LiveScene,
        raster: Option<&RasterPass>,
    ) -> Result<Self::Prepared, TechniqueError>;

    /// Drops what a parameter change made stale below the scene's preparation (a change that
    /// invalidates that drops it all, here and in the lifecycle). Returns whether `prepared` is
    /// still good: false rebuilds it at the next frame.
    fn invalidate(&mut self, prepared: Option<&mut Self::Prepared>, what: Invalidates) -> bool {
        let _ = prepared;
        what < Invalidates::Resources
    }

    /// Its stages of one frame, into `frame.output`.
    fn shade(
        &mut self,
        prepared: &mut Self::Prepared,
        frame: &mut GpuFrame<'_>,
    ) -> Result<(), TechniqueError>;
}

/// One frame as a GPU technique's `shade` sees it.
pub struct GpuFrame<'a> {
    pub gpu: &'a GpuContext,
    pub live: &'a LiveScene,
    pub camera: &'a Camera,
    pub width: u32,
    pub height: u32,
    /// The camera as the raster pass and the shaders read it.
    pub camera_uniform: CameraUniform,
    /// The frame's pixels: the output texture, or what the technique shows instead.
    pixels: Option<wgpu::Texture>,
    raster: Option<&'a RasterPass>,
    g: Option<GBuffer>,
    timer: &'a mut StageTimer,
    counters: Vec<(String, u64)>,
    warnings: Vec<String>,
}

impl<'a> GpuFrame<'a> {
    /// Ends the current stage, named `stage`, and starts the next.
    pub fn lap(&mut self, stage: &str) -> Result<(), GpuError> {
        self.timer.lap(Some(self.gpu), stage)
    }

    /// Records a stage timed by its own code (on the CPU's clock: [`GpuTechnique::wall_clock`]).
    pub fn measured(&mut self, stage: &str, milliseconds: f64) {
        self.timer.measured(stage, milliseconds);
    }

    /// The scene raster pass the technique declared.
    pub fn raster(&self) -> &'a RasterPass {
        self.raster
            .expect("GpuTechnique::scene_raster declared the raster pass")
    }

    /// The camera's G-buffer: the lifecycle's, or the one the technique drew and handed over by
    /// [`GpuFrame::set_g_buffer`].
    pub fn g(&self) -> &GBuffer {
        self.g.as_ref().expect("the frame has its G-buffer")
    }

    /// Hands over the G-buffer a technique drew itself ([`GpuTechnique::draws_own_g_buffer`]).
    pub fn set_g_buffer(&mut self, g: GBuffer) {
        self.g = Some(g);
    }

    /// The colour target, `width` × `height`, kept across frames: the frame's pixels.
    pub fn output(&self) -> &wgpu::Texture {
        self.pixels
            .as_ref()
            .expect("a technique that draws its own G-buffer shows it instead")
    }

    /// Makes `texture` the frame's pixels: a technique that drew its own G-buffer
    /// ([`GpuTechnique::draws_own_g_buffer`]) shows that G-buffer's colour.
    pub fn show(&mut self, texture: wgpu::Texture) {
        self.pixels = Some(texture);
    }

    /// A counter of this frame, as reports list it.
    pub fn count(&mut self, name: &str, value: u64) {
        self.counters.push((name.to_string(), value));
    }

    /// Something the frame had to approximate or fall back on (said once per cause).
    pub fn warn(&mut self, warning: String) {
        self.warnings.push(warning);
    }
}

/// What the lifecycle keeps for one scene.
struct Prepared<P> {
    scene_id: u64,
    raster: Option<RasterPass>,
    technique: P,
}

/// A [`GpuTechnique`] run through the frame lifecycle: the [`Technique`] the registry makes.
/// It reads as the technique it wraps (`Deref`), so its parameters are `method.params`.
pub struct GpuMethod<T: GpuTechnique> {
    technique: T,
    prepared: Option<Prepared<T::Prepared>>,
    timer: StageTimer,
    output: OutputTexture,
}

impl<T: GpuTechnique> GpuMethod<T> {
    pub fn new(technique: T) -> GpuMethod<T> {
        let timer = match technique.wall_clock() {
            true => StageTimer::wall_clock(),
            false => StageTimer::default(),
        };
        GpuMethod {
            technique,
            prepared: None,
            timer,
            output: OutputTexture::default(),
        }
    }

    /// The preparation for `live`, made when missing or made for another scene.
    fn ensure_prepared(
        &mut self,
        gpu: &GpuContext,
        live: &LiveScene,
    ) -> Result<(), TechniqueError> {
        if self.prepared.as_ref().map(|p| p.scene_id) == Some(live.id()) {
            return Ok(());
        }
        self.prepared = None;
        let raster = match self.technique.scene_raster() {
            Some(spec) => Some(RasterPass::new(gpu, live, spec)?),
            None => None,
        };
        let technique = self.technique.prepare(gpu, live, raster.as_ref())?;
        self.prepared = Some(Prepared {
            scene_id: live.id(),
            raster,
            technique,
        });
        Ok(())
    }
}

impl<T: GpuTechnique + Default> Default for GpuMethod<T> {
    fn default() -> Self {
        GpuMethod::new(T::default())
    }
}

impl<T: GpuTechnique> Deref for GpuMethod<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.technique
    }
}

impl<T: GpuTechnique> DerefMut for GpuMethod<T> {
    fn deref_mut(&mut self) -> &mut T {
        &mut self.technique
    }
}

impl<T: GpuTechnique> Technique for GpuMethod<T> {
    fn info(&self) -> &'static MethodInfo {
        T::INFO
    }

    fn params(&self) -> &dyn ParamSet {
        self.technique.params()
    }

    fn params_mut(&mut self) -> &mut dyn ParamSet {
        self.technique.params_mut()
    }

    fn invalidate(&mut self, what: Invalidates) {
        let prepared = self.prepared.as_mut().map(|p| &mut p.technique);
        let keep = self.technique.invalidate(prepared, what);
        if !keep || what >= Invalidates::Scene {
            self.prepared = None;
        }
    }

    fn prepare(&mut self, ctx: &Context, live: &LiveScene) -> Result<(), TechniqueError> {
        self.ensure_prepared(ctx.gpu(T::INFO.name)?, live)
    }

    fn draw(
        &mut self,
        ctx: &Context,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Drawn, TechniqueError> {
        let gpu = ctx.gpu(T::INFO.name)?;
        self.ensure_prepared(gpu, live)?;
        let prepared = self.prepared.as_mut().expect("prepared above");
        let raster = prepared.raster.as_ref();
        if let Some(raster) = raster {
            raster.begin_frame(gpu, live)?;
        }
        self.timer.start(Some(gpu));
        let camera_uniform = raster::camera_uniform(camera, &live.scene().bounds(), width, height);
        let own_g_buffer = self.technique.draws_own_g_buffer();
        let g = match raster {
            Some(raster) if !own_g_buffer => {
                let g = raster.render(gpu, live.gpu(gpu), &camera_uniform, None)?;
                self.timer.lap(Some(gpu), "g-buffer")?;
                Some(g)
            }
            _ => None,
        };
        let mut frame = GpuFrame {
            gpu,
            live,
            camera,
            width,
            height,
            camera_uniform,
            pixels: (!own_g_buffer).then(|| self.output.get(gpu, width, height)),
            raster,
            g,
            timer: &mut self.timer,
            counters: Vec::new(),
            warnings: Vec::new(),
        };
        self.technique.shade(&mut prepared.technique, &mut frame)?;
        let GpuFrame {
            pixels,
            counters,
            warnings,
            ..
        } = frame;
        let pixels = pixels.expect("a technique that draws its own G-buffer shows it");
        let (stages, timing) = self.timer.finish(Some(gpu))?;
        Ok(Drawn {
            pixels: Pixels::Texture(pixels),
            stages,
            counters,
            timing,
            warnings,
            converged: true,
        })
    }
}
