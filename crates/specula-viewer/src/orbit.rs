//! The viewer's camera: an eye orbiting a target point, in world space (Y up, metres; see
//! docs/conventions.md). Orbit turns the eye about the target, pan moves both in the view
//! plane, zoom changes the distance, and walking moves both along the view.

use glam::Vec3;
use specula_scene::Camera;

/// Pitch stops short of the poles, where the orbit's yaw would be undefined.
const MAX_PITCH_DEG: f32 = 89.0;

#[derive(Clone, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target: Vec3,
    /// Eye distance from the target.
    pub distance: f32,
    /// Turn of the eye about world +Y, from +Z towards +X, in degrees.
    pub yaw_deg: f32,
    /// Height angle of the eye above the target's horizontal plane, in degrees.
    pub pitch_deg: f32,
    pub fov_y_deg: f32,
    /// The camera the orbit was made from, shown exactly (roll and all) until the first change.
    authored: Option<Camera>,
}

impl OrbitCamera {
    /// The orbit that shows what `camera` shows (its roll is dropped: the viewer keeps Y up).
    pub fn from_camera(camera: &Camera) -> OrbitCamera {
        let offset = camera.eye - camera.target;
        let distance = offset.length().max(1e-6);
        let pitch_deg = (offset.y / distance)
            .clamp(-1.0, 1.0)
            .asin()
            .to_degrees()
            .clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
        OrbitCamera {
            target: camera.target,
            distance,
            yaw_deg: offset.x.atan2(offset.z).to_degrees(),
            pitch_deg,
            fov_y_deg: camera.fov_y_deg,
            authored: Some(camera.clone()),
        }
    }

    pub fn eye(&self) -> Vec3 {
        let (yaw, pitch) = (self.yaw_deg.to_radians(), self.pitch_deg.to_radians());
        self.target
            + self.distance
                * Vec3::new(
                    pitch.cos() * yaw.sin(),
                    pitch.sin(),
                    pitch.cos() * yaw.cos(),
                )
    }

    pub fn camera(&self) -> Camera {
        if let Some(camera) = &self.authored {
            return camera.clone();
        }
        Camera {
            eye: self.eye(),
            target: self.target,
            up: Vec3::Y,
            fov_y_deg: self.fov_y_deg,
            aspect: None,
        }
    }

    /// Turns the eye about the target.
    pub fn orbit(&mut self, yaw_deg: f32, pitch_deg: f32) {
        self.authored = None;
        self.yaw_deg = (self.yaw_deg + yaw_deg).rem_euclid(360.0);
        self.pitch_deg = (self.pitch_deg + pitch_deg).clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
    }

    /// Moves eye and target in the view plane by fractions of the view's height at the target.
    pub fn pan(&mut self, right: f32, up: f32) {
        self.authored = None;
        let frame = self.camera().frame();
        let height = 2.0 * self.distance * (self.fov_y_deg.to_radians() * 0.5).tan();
        self.target += height * (right * frame.right + up * frame.up);
    }

    /// Multiplies the eye's distance to the target by `factor`.
    pub fn zoom(&mut self, factor: f32) {
        self.authored = None;
        self.distance = (self.distance * factor).clamp(1e-4, 1e6);
    }

    /// Moves eye and target together: `forward` along the view, `right` across it, `up` along
    /// world +Y (metres).
    pub fn walk(&mut self, forward: f32, right: f32, up: f32) {
        self.authored = None;
        let frame = self.camera().frame();
        self.target += forward * frame.forward + right * frame.right + up * Vec3::Y;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(eye: Vec3, target: Vec3) -> Camera {
        Camera {
            eye,
            target,
            up: Vec3::Y,
            fov_y_deg: 40.0,
            aspect: None,
        }
    }

    #[test]
    fn orbit_reproduces_the_camera_it_was_made_from() {
        let c = camera(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-0.5, 0.2, 0.1));
        let mut o = OrbitCamera::from_camera(&c);
        assert_eq!(o.camera(), c);
        o.orbit(0.0, 0.0);
        assert!(
            o.camera().eye.abs_diff_eq(c.eye, 1e-5),
            "{}",
            o.camera().eye
        );
        assert_eq!(o.camera().target, c.target);
    }

    #[test]
    fn orbit_keeps_distance_and_half_turn_mirrors_the_eye() {
        let mut o = OrbitCamera::from_camera(&camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO));
        o.orbit(180.0, 0.0);
        assert!(
            o.eye().abs_diff_eq(Vec3::new(0.0, 0.0, -5.0), 1e-5),
            "{}",
            o.eye()
        );
        o.orbit(0.0, 200.0);
        assert_eq!(o.pitch_deg, MAX_PITCH_DEG);
        assert!((o.eye().length() - 5.0).abs() < 1e-5);
    }

    #[test]
    fn pan_by_a_full_height_moves_the_target_by_the_view_height() {
        let mut o = OrbitCamera::from_camera(&camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO));
        o.pan(0.0, 1.0);
        let height = 2.0 * 2.0 * (20f32).to_radians().tan();
        assert!(
            o.target.abs_diff_eq(Vec3::new(0.0, height, 0.0), 1e-5),
            "{}",
            o.target
        );
    }
}
