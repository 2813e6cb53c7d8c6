//! What every technique plugs into: the [`Technique`] trait and its frame lifecycle,
//! parameters declared once ([`params!`]), the live scene (CPU scene, BVH, GPU upload, kept
//! current as objects move: [`LiveScene`]), the scene raster pass with its G-buffer
//! ([`raster`]), each reflector's environment cube maps ([`cube_maps`]), and the screen and
//! readback helpers ([`screen`]). `specula-methods` holds the techniques, one folder each, and
//! the registry that lists them; docs/architecture.md says how they fit.

pub mod cube_maps;
pub mod gpu_scene;
pub mod lifecycle;
pub mod live_scene;
pub mod params;
pub mod raster;
pub mod screen;
pub mod technique;

pub use gpu_scene::GpuScene;
pub use lifecycle::{GpuFrame, GpuMethod, GpuTechnique};
pub use live_scene::{AccelUpdate, LiveScene, MoveError};
pub use params::{
    apply_known_parameters, apply_parameters, apply_setting, bad_value, Invalidates, NoParams,
    Param, ParamKind, ParamSet, ParamSpec, ParamType, ParamValue,
};
pub use specula_params::{choice, params};
pub use technique::{test_context, RenderStill, Still};
pub use technique::{
    Context, Delegation, Drawn, Frame, MethodInfo, Pixels, Preset, StageTime, SurfaceClass,
    Technique, TechniqueError, COUNTER_RAYS_TRACED, COUNTER_SHADOW_RAYS,
};
