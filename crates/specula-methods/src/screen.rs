//! The view as pixels: where a world point lands on the image ([`ScreenView`]), and what the
//! CPU knows of each pixel's first surface ([`PixelSurfaces`]: the ID buffer with positions),
//! read back from the scene raster pass's G-buffer or traced on the CPU where there is no GPU.

use glam::Vec3;
use rayon::prelude::*;
use specula_scene::Camera;
use specula_trace::{Ray, SceneAccel};

/// How the camera maps world points to pixels (the raster pass's pinhole, top-left origin).
#[derive(Clone, Copy, Debug)]
pub struct ScreenView {
    pub eye: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    tan_half: f32,
    aspect: f32,
    pub width: u32,
    pub height: u32,
}

impl ScreenView {
    pub fn new(camera: &Camera, width: u32, height: u32) -> ScreenView {
        let frame = camera.frame();
        ScreenView {
            eye: camera.eye,
            right: frame.right,
            up: frame.up,
            forward: frame.forward,
            tan_half: (camera.fov_y_deg.to_radians() * 0.5).tan(),
            aspect: width as f32 / height as f32,
            width,
            height,
        }
    }

    /// Pixel coordinates (x right, y down, pixel centres at +0.5) and view depth of `p_world`;
    /// None behind the eye.
    pub fn project(&self, p_world: Vec3) -> Option<(f32, f32, f32)> {
        let v = p_world - self.eye;
        let z = v.dot(self.forward);
        if z <= 1e-6 {
            return None;
        }
        let x = v.dot(self.right) / (z * self.tan_half * self.aspect);
        let y = v.dot(self.up) / (z * self.tan_half);
        Some((
            (x + 1.0) * 0.5 * self.width as f32,
            (1.0 - y) * 0.5 * self.height as f32,
            z,
        ))
    }

    /// The side of one pixel, in metres, at view depth `z`.
    pub fn footprint(&self, z: f32) -> f32 {
        2.0 * z * self.tan_half / self.height as f32
    }
}

/// The G-buffer as the CPU sees it: per pixel (mesh + 1, triangle) and the world position.
pub struct PixelSurfaces {
    pub ids: Vec<[u32; 2]>,
    pub position: Vec<[f32; 4]>,
}

impl PixelSurfaces {
    /// The ID buffer traced on the CPU: each pixel centre's closest hit from `camera`, as the
    /// reference's primary rays meet it (what a run without a GPU uses).
    pub fn trace(accel: &SceneAccel, camera: &Camera, width: u32, height: u32) -> PixelSurfaces {
        let (ids, position) = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (x, y) = (k % width, k / width);
                let dir = camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
                let ray = Ray {
                    origin: camera.eye,
                    dir,
                };
                match accel.intersect(&ray, f32::INFINITY) {
                    Some(hit) => {
                        let p = camera.eye + dir * hit.t;
                        ([hit.mesh + 1, hit.triangle], [p.x, p.y, p.z, 1.0])
                    }
                    None => ([0, 0], [0.0; 4]),
                }
            })
            .unzip();
        PixelSurfaces { ids, position }
    }

    /// The world position seen through pixel `k` (None where the background shows).
    pub fn position(&self, k: usize) -> Option<Vec3> {
        (self.ids[k][0] != 0).then(|| Vec3::from_slice(&self.position[k][..3]))
    }
}
