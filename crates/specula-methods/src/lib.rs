//! specula's techniques: one folder each, with its WGSL beside its Rust, all behind one
//! [`Technique`] trait; plus what they share: the scene uploaded to the GPU ([`GpuScene`]) and
//! the scene raster pass with its G-buffer ([`raster`]).

pub mod distance_maps;
pub mod envmap;
pub mod gpu_scene;
pub mod pvrr;
pub mod raster;
pub mod technique;

pub use gpu_scene::GpuScene;
pub use technique::{
    apply_known_parameters, apply_parameters, by_name, Frame, StageTime, Technique, TechniqueError,
    METHODS,
};
