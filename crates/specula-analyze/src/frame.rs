//! The vehicle frame an analysis runs in (its eye points are `analysis::eye_points`').
//!
//! The vehicle frame has world +Y as up (docs/conventions.md), `forward` the vehicle's
//! longitudinal axis (horizontal), and `right = forward × up`. Angles in it: a direction's
//! horizontal angle is measured in the ground plane from a reference direction, positive towards
//! `right`; its elevation is the angle above the ground plane.

use glam::Vec3;
use specula_scene::Camera;

use crate::analysis::eye_points::Eyes;
use crate::AnalyzeError;

/// The vehicle's axes in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleFrame {
    pub forward: Vec3,
    pub up: Vec3,
    pub right: Vec3,
}

impl VehicleFrame {
    /// The frame whose forward axis is `forward` (default: `camera`'s view direction), projected
    /// on the ground plane.
    pub fn new(camera: &Camera, forward: Option<Vec3>) -> Result<VehicleFrame, AnalyzeError> {
        let up = Vec3::Y;
        let given = forward.unwrap_or(camera.target - camera.eye);
        let forward = (given - up * given.dot(up))
            .try_normalize()
            .filter(|f| f.is_finite())
            .ok_or_else(|| AnalyzeError::BadOption {
                option: "forward",
                reason: format!(
                    "the vehicle's forward axis {given} has no horizontal part (it is vertical \
                     or zero); give a horizontal direction, e.g. `forward` 0,0,-1"
                ),
            })?;
        Ok(VehicleFrame {
            forward,
            up,
            right: forward.cross(up),
        })
    }

    /// The frame for an analysis that needs vehicle axes only to place `eyes` (glare): as
    /// [`VehicleFrame::new`], except that a camera looking straight up or down, with no
    /// `forward` given, is no error where the eye points need no axes (the camera's eye, given
    /// points): world −Z is taken as forward, which then only orients the report's map.
    pub fn for_eyes(
        camera: &Camera,
        forward: Option<Vec3>,
        eyes: &Eyes,
    ) -> Result<VehicleFrame, AnalyzeError> {
        match VehicleFrame::new(camera, forward) {
            Err(_) if forward.is_none() && matches!(eyes, Eyes::Camera | Eyes::Points(_)) => {
                VehicleFrame::new(camera, Some(Vec3::NEG_Z))
            }
            result => result,
        }
    }

    /// `d`'s angle above the ground plane, degrees.
    pub fn elevation_deg(&self, d: Vec3) -> f64 {
        f64::from(d.normalize().dot(self.up).clamp(-1.0, 1.0))
            .asin()
            .to_degrees()
    }

    /// `d`'s horizontal angle from `reference` (a horizontal unit direction), degrees in
    /// (−180, 180], positive towards the right of `reference`.
    pub fn horizontal_deg(&self, d: Vec3, reference: Vec3) -> f64 {
        let reference_right = reference.cross(self.up);
        f64::from(d.dot(reference_right))
            .atan2(f64::from(d.dot(reference)))
            .to_degrees()
    }

    /// The horizontal part of `d`, normalised (None for a vertical `d`).
    pub fn horizontal(&self, d: Vec3) -> Option<Vec3> {
        (d - self.up * d.dot(self.up)).try_normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: Vec3::new(1.0, 1.2, 3.0),
            target: Vec3::new(1.0, 0.2, -7.0),
            up: Vec3::Y,
            fov_y_deg: 40.0,
            aspect: None,
        }
    }

    #[test]
    fn the_default_forward_is_the_view_direction_on_the_ground() {
        let frame = VehicleFrame::new(&camera(), None).unwrap();
        assert!(frame.forward.abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(frame.right.abs_diff_eq(Vec3::X, 1e-6));
        let vertical = VehicleFrame::new(&camera(), Some(Vec3::Y)).unwrap_err();
        assert!(vertical.to_string().contains("forward"), "{vertical}");
    }

    #[test]
    fn a_camera_looking_straight_down_needs_a_forward_axis_only_where_the_eyes_do() {
        let down = Camera {
            target: camera().eye - Vec3::Y,
            ..camera()
        };
        let one = VehicleFrame::for_eyes(&down, None, &Eyes::Camera).unwrap();
        assert!(one.forward.abs_diff_eq(Vec3::NEG_Z, 1e-6));
        let ocular = VehicleFrame::for_eyes(&down, None, &Eyes::Ocular).unwrap_err();
        assert!(ocular.to_string().contains("forward"), "{ocular}");
        let given = VehicleFrame::for_eyes(&down, Some(Vec3::X), &Eyes::Ocular).unwrap();
        assert!(given.forward.abs_diff_eq(Vec3::X, 1e-6));
    }

    #[test]
    fn angles_in_the_vehicle_frame() {
        let frame = VehicleFrame::new(&camera(), None).unwrap();
        let back = Vec3::Z;
        assert!((frame.horizontal_deg(Vec3::new(1.0, 0.0, 1.0), back) + 45.0).abs() < 1e-5);
        assert!((frame.elevation_deg(Vec3::new(0.0, 1.0, 1.0)) - 45.0).abs() < 1e-5);
    }
}
