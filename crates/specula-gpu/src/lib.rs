//! specula's GPU layer: a wgpu context on the Vulkan backend (Mesa's lavapipe where there is no
//! GPU), texture readback with row alignment, validation errors as Rust errors, GPU timestamps
//! where the adapter has them, and the WGSL shared by the techniques (`shaders/`).

pub mod arena;
mod context;
pub mod counters;
pub mod shaders;
mod timer;
pub mod util;

pub use context::{GpuContext, GpuError, LiveObjects, ResourceCounts, TimingSource};
pub use timer::{StageTime, StageTimer};

/// The context for GPU tests. A machine without a Vulkan adapter fails the test, naming what to
/// install, unless the runner opts out with `SPECULA_ALLOW_SKIP=gpu` (see `specula-testkit`):
/// then the skip is logged and this returns `None`, and the test returns at once.
pub fn test_context(test: &str) -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(context) => Some(context),
        Err(e) => {
            specula_testkit::missing(specula_testkit::Requirement::Gpu, test, &e.to_string());
            None
        }
    }
}
