//! WGSL shared by the techniques (`shaders/common/` at the repository root) and the host-side
//! structs that mirror its uniform blocks. Technique shaders live beside their Rust and are
//! composed with [`compose`], which prepends the common files they use.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

pub const OPTICS: &str = include_str!("../../../shaders/common/optics.wgsl");
pub const CAMERA: &str = include_str!("../../../shaders/common/camera.wgsl");
pub const SCENE: &str = include_str!("../../../shaders/common/scene.wgsl");
pub const CUBEMAP: &str = include_str!("../../../shaders/common/cubemap.wgsl");
pub const LIGHTING: &str = include_str!("../../../shaders/common/lighting.wgsl");
pub const SPECULAR_PIXEL: &str = include_str!("../../../shaders/common/specular_pixel.wgsl");

/// Every common WGSL file, by name, for validation and composition.
pub const COMMON: &[(&str, &str)] = &[
    ("optics.wgsl", OPTICS),
    ("camera.wgsl", CAMERA),
    ("scene.wgsl", SCENE),
    ("cubemap.wgsl", CUBEMAP),
    ("lighting.wgsl", LIGHTING),
    ("specular_pixel.wgsl", SPECULAR_PIXEL),
];

/// A shader's full source: the named common files, then the technique's own code.
pub fn compose(common: &[&str], source: &str) -> String {
    let mut out = String::new();
    for name in common {
        let (_, text) = COMMON
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no common shader '{name}'"));
        out.push_str(text);
        out.push('\n');
    }
    out.push_str(source);
    out
}

/// Host mirror of WGSL `Camera` (shaders/common/camera.wgsl); the layout is checked against
/// naga's by a test.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct CameraUniform {
    pub clip_from_world: [[f32; 4]; 4],
    pub eye_world: [f32; 3],
    pub tan_half_fov_y: f32,
    pub right_world: [f32; 3],
    pub aspect: f32,
    pub up_world: [f32; 3],
    pub width: f32,
    pub forward_world: [f32; 3],
    pub height: f32,
}

impl CameraUniform {
    /// The uniform for a pinhole camera at `eye` with the given world-space frame, rendering a
    /// `width` × `height` image. Depth runs from `near` to `far` (wgpu's 0..1 clip depth).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        eye: Vec3,
        right: Vec3,
        up: Vec3,
        forward: Vec3,
        fov_y_deg: f32,
        width: u32,
        height: u32,
        near: f32,
        far: f32,
    ) -> Self {
        let aspect = width as f32 / height as f32;
        let view = Mat4::look_to_rh(eye, forward, up);
        let projection = Mat4::perspective_rh(fov_y_deg.to_radians(), aspect, near, far);
        CameraUniform {
            clip_from_world: (projection * view).to_cols_array_2d(),
            eye_world: eye.to_array(),
            tan_half_fov_y: (fov_y_deg.to_radians() * 0.5).tan(),
            right_world: right.to_array(),
            aspect,
            up_world: up.to_array(),
            width: width as f32,
            forward_world: forward.to_array(),
            height: height as f32,
        }
    }
}
