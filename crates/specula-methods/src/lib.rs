//! specula's techniques: one folder each, with its WGSL beside its Rust, all behind one
//! [`Technique`] trait and listed in one [`registry`]; plus what they share: the live scene
//! (CPU scene, BVH, GPU upload, kept current as objects move: [`LiveScene`]) and the scene
//! raster pass with its G-buffer ([`raster`]).

pub mod c3rc;
pub mod distance_maps;
pub mod envmap;
pub mod gpu_scene;
pub mod gpu_trace;
pub mod image_space;
pub mod live_scene;
pub mod preset;
pub mod pvrr;
pub mod raster;
pub mod reference;
pub mod registry;
pub mod screen;
pub mod technique;
pub mod vertex_tracing;

pub use gpu_scene::GpuScene;
pub use live_scene::{AccelUpdate, LiveScene, MoveError};
pub use preset::{all_labels, check_settings, Label, Preset};
pub use registry::{approximate_methods, by_name, exact_method, method, METHODS};
pub use technique::{
    apply_known_parameters, apply_parameters, apply_setting, Context, Delegation, Drawn, Frame,
    Invalidates, MethodInfo, ParamKind, ParamSpec, ParamValue, Pixels, StageTime, SurfaceClass,
    Technique, TechniqueError, COUNTER_RAYS_TRACED, COUNTER_SHADOW_RAYS,
};

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
