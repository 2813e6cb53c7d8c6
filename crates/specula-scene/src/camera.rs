use glam::Vec3;

/// A pinhole camera. It looks from `eye` towards `target`; `up` fixes the roll. The vertical
/// field of view is kept when an image's aspect ratio differs from `aspect`.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_y_deg: f32,
    /// Width / height the camera was authored for (glTF `aspectRatio`); informative only.
    pub aspect: Option<f32>,
}

/// Orthonormal camera frame in world space: `forward` is the viewing direction (-Z of camera
/// space), `right` is +X and `up` is +Y of camera space.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
}

/// A camera's rays for one image size ([`Camera::pixel_rays`]): the same directions as
/// [`Camera::ray_direction`], bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct PixelRays {
    pub eye: Vec3,
    pub frame: CameraFrame,
    tan_half: f32,
    aspect: f32,
    width: f32,
    height: f32,
}

impl PixelRays {
    /// Unit direction (world space) of the ray through the image point (`x`, `y`) in pixels
    /// from the top-left corner.
    #[inline]
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        self.direction_from(self.column(x), self.row(y))
    }

    /// The horizontal image-plane coordinate of image column `x` (pixels from the left), for
    /// [`PixelRays::direction_from`]: a caller tracing many rays of one column or row computes
    /// it once (the same directions bit for bit, two divisions fewer a ray).
    #[inline]
    pub fn column(&self, x: f32) -> f32 {
        (2.0 * x / self.width - 1.0) * self.tan_half * self.aspect
    }

    /// The vertical image-plane coordinate of image row `y` (pixels from the top).
    #[inline]
    pub fn row(&self, y: f32) -> f32 {
        (1.0 - 2.0 * y / self.height) * self.tan_half
    }

    /// Unit direction (world space) through image-plane point ([`PixelRays::column`],
    /// [`PixelRays::row`]).
    #[inline]
    pub fn direction_from(&self, column: f32, row: f32) -> Vec3 {
        (self.frame.forward + column * self.frame.right + row * self.frame.up).normalize()
    }
}

impl Camera {
    pub fn frame(&self) -> CameraFrame {
        let forward = (self.target - self.eye).normalize();
        let mut right = forward.cross(self.up);
        if right.length_squared() < 1e-12 {
            // `up` parallel to the view direction: any perpendicular will do.
            right = forward.any_orthonormal_vector();
        }
        let right = right.normalize();
        let up = right.cross(forward);
        CameraFrame { right, up, forward }
    }

    /// Unit direction (world space) of the ray through the image point (`x`, `y`) in pixels,
    /// measured from the top-left corner of a `width` x `height` image.
    pub fn ray_direction(&self, x: f32, y: f32, width: u32, height: u32) -> Vec3 {
        self.pixel_rays(width, height).direction(x, y)
    }

    /// The rays of a `width` × `height` image, the frame and field of view worked out once (a
    /// frame's millions of rays need not each recompute them).
    pub fn pixel_rays(&self, width: u32, height: u32) -> PixelRays {
        PixelRays {
            eye: self.eye,
            frame: self.frame(),
            tan_half: (self.fov_y_deg.to_radians() * 0.5).tan(),
            aspect: width as f32 / height as f32,
            width: width as f32,
            height: height as f32,
        }
    }

    pub fn is_valid(&self) -> bool {
        self.eye.is_finite()
            && self.target.is_finite()
            && self.up.is_finite()
            && (self.target - self.eye).length_squared() > 0.0
            && self.fov_y_deg > 0.0
            && self.fov_y_deg < 180.0
    }
}
