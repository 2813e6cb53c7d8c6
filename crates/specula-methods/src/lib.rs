//! specula's techniques, one folder each with its WGSL beside its Rust, all behind the one
//! [`Technique`] trait of `specula-core` and listed in one [`registry`]; [`preset`] runs a
//! method several ways in one report. What the techniques share (the frame lifecycle,
//! parameters, the live scene, the raster pass and G-buffer, cube maps) is `specula-core`'s,
//! re-exported here for the binaries.

pub mod preset;
pub mod registry;

// Every technique, in the order reports list them: adding one is its folder and a line here.
registry::techniques! {
    reference,
    gpu_trace,
    envmap,
    pvrr,
    distance_maps,
    image_space,
    c3rc,
    vertex_tracing,
    // What adding a technique takes, held by its own test: one file and this line.
    #[cfg(test)]
    toy_normals,
}

pub use preset::{all_labels, check_settings, Label};
pub use registry::{approximate_methods, by_name, exact_method, method};
pub use specula_core::{
    apply_known_parameters, apply_parameters, apply_setting, cube_maps, gpu_scene, live_scene,
    raster, screen, technique, test_context, AccelUpdate, Context, Delegation, Drawn, Frame,
    GpuScene, Invalidates, LiveScene, MethodInfo, MoveError, ParamKind, ParamSpec, ParamValue,
    Pixels, Preset, RenderStill, StageTime, Still, SurfaceClass, Technique, TechniqueError,
    COUNTER_RAYS_TRACED, COUNTER_SHADOW_RAYS,
};
