//! specula's techniques, one folder each with its WGSL beside its Rust, all behind the one
//! [`Technique`] trait of `specula-core` and listed in one [`registry`]; [`preset`] runs a
//! method several ways in one report. What the techniques share (the frame lifecycle,
//! parameters, the live scene, the raster pass and G-buffer, cube maps) is `specula-core`'s,
//! re-exported here for the binaries.

pub mod c3rc;
pub mod distance_maps;
pub mod envmap;
pub mod gpu_trace;
pub mod image_space;
pub mod preset;
pub mod pvrr;
pub mod reference;
pub mod registry;
pub mod vertex_tracing;

pub use preset::{all_labels, check_settings, Label};
pub use registry::{approximate_methods, by_name, exact_method, method, METHODS};
pub use specula_core::{
    apply_known_parameters, apply_parameters, apply_setting, cube_maps, gpu_scene, live_scene,
    raster, screen, technique, test_context, AccelUpdate, Context, Delegation, Drawn, Frame,
    GpuScene, Invalidates, LiveScene, MethodInfo, MoveError, ParamKind, ParamSpec, ParamValue,
    Pixels, Preset, RenderStill, StageTime, Still, SurfaceClass, Technique, TechniqueError,
    COUNTER_RAYS_TRACED, COUNTER_SHADOW_RAYS,
};
