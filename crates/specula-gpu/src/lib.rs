//! specula's GPU layer: a wgpu context on the Vulkan backend (Mesa's lavapipe where there is no
//! GPU), texture readback with row alignment, validation errors as Rust errors, GPU timestamps
//! where the adapter has them, and the WGSL shared by the techniques (`shaders/`).

pub mod arena;
mod context;
pub mod counters;
pub mod shaders;
mod timer;
pub mod util;

pub use context::{GpuContext, GpuError, ResourceCounts, TimingSource};
pub use timer::{StageTime, StageTimer};

/// The context for GPU tests: `None` (after a loud SKIPPED line) when this machine has no
/// Vulkan adapter. Under CI (`CI` set) a missing adapter is a failure instead, because CI
/// installs Mesa's driver and must run these tests.
pub fn test_context(test: &str) -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(context) => Some(context),
        Err(e) if std::env::var_os("CI").is_some() => panic!("{test}: no GPU under CI: {e}"),
        Err(e) => {
            eprintln!("\n!!!!!!!! SKIPPED {test}: {e} !!!!!!!!\n");
            None
        }
    }
}
