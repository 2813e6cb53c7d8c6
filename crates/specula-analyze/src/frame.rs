//! The vehicle frame and the eye points an analysis runs from.
//!
//! The vehicle frame has world +Y as up (docs/conventions.md), `forward` the vehicle's
//! longitudinal axis (horizontal), and `right = forward × up`. Angles in it: a direction's
//! horizontal angle is measured in the ground plane from a reference direction, positive towards
//! `right`; its elevation is the angle above the ground plane.

use glam::Vec3;
use specula_scene::Camera;

use crate::AnalyzeError;

/// UN ECE Regulation 46's ocular points are 65 mm apart.
pub const OCULAR_SEPARATION_M: f32 = 0.065;

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

/// Where the eyes are.
#[derive(Clone, Debug, PartialEq)]
pub enum Eyes {
    /// The scene camera's eye.
    Camera,
    /// These points (world space, metres).
    Points(Vec<Vec3>),
    /// A grid of `columns` × `rows` points spanning `width` × `height` metres, centred on the
    /// camera's eye, horizontal along the vehicle's right axis and vertical along up.
    Eyebox {
        width: f32,
        height: f32,
        columns: u32,
        rows: u32,
    },
    /// UN ECE R46's two ocular points: 65 mm apart on the horizontal line perpendicular to
    /// the vehicle's longitudinal median plane, centred on the camera's eye.
    Ocular,
}

/// The most eye points an eyebox may have each way.
pub const MAX_EYEBOX_POINTS: u32 = 10_000;

impl Eyes {
    /// The eyebox `[W, H, NX, NY]` as a command or a script gives it: sizes in metres, finite
    /// and not negative; NX and NY whole numbers from 1 to [`MAX_EYEBOX_POINTS`]. The error
    /// says what is wrong.
    pub fn eyebox(values: [f32; 4]) -> Result<Eyes, String> {
        let [width, height, columns, rows] = values;
        if !(width.is_finite() && height.is_finite() && width >= 0.0 && height >= 0.0) {
            return Err(format!(
                "{width} × {height} m: the size must be finite and not negative"
            ));
        }
        let count = |v: f32| {
            (v.fract() == 0.0 && (1.0..=MAX_EYEBOX_POINTS as f32).contains(&v))
                .then_some(v as u32)
                .ok_or(format!(
                    "NX and NY must be whole numbers, at least one point each way and at most \
                     {MAX_EYEBOX_POINTS}, got {v}"
                ))
        };
        Ok(Eyes::Eyebox {
            width,
            height,
            columns: count(columns)?,
            rows: count(rows)?,
        })
    }

    /// The eye points, about the camera's eye `centre`.
    pub fn points(&self, centre: Vec3, frame: &VehicleFrame) -> Result<Vec<Vec3>, AnalyzeError> {
        let bad = |reason: String| AnalyzeError::BadOption {
            option: "eyebox",
            reason,
        };
        let points = match self {
            Eyes::Camera => vec![centre],
            Eyes::Points(points) => points.clone(),
            Eyes::Ocular => {
                let half = frame.right * (0.5 * OCULAR_SEPARATION_M);
                vec![centre - half, centre + half]
            }
            Eyes::Eyebox {
                width,
                height,
                columns,
                rows,
            } => {
                if *columns == 0 || *rows == 0 {
                    return Err(bad(format!(
                        "{columns} × {rows} points: an eyebox needs at least one point each way"
                    )));
                }
                if !(width.is_finite() && height.is_finite() && *width >= 0.0 && *height >= 0.0) {
                    return Err(bad(format!(
                        "{width} × {height} m: the size must be finite and not negative"
                    )));
                }
                // Evenly from one edge to the other; a single column or row sits at the centre.
                let spread = |k: u32, n: u32, size: f32| {
                    if n == 1 {
                        0.0
                    } else {
                        size * (k as f32 / (n - 1) as f32 - 0.5)
                    }
                };
                (0..*rows)
                    .flat_map(|row| {
                        (0..*columns).map(move |column| {
                            centre
                                + frame.right * spread(column, *columns, *width)
                                + frame.up * spread(row, *rows, *height)
                        })
                    })
                    .collect()
            }
        };
        if points.is_empty() {
            return Err(AnalyzeError::BadOption {
                option: "eye",
                reason: "no eye point".into(),
            });
        }
        if let Some(p) = points.iter().find(|p| !p.is_finite()) {
            return Err(AnalyzeError::BadOption {
                option: "eye",
                reason: format!("{p} is not a finite point"),
            });
        }
        Ok(points)
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

    #[test]
    fn eye_points() {
        let frame = VehicleFrame::new(&camera(), None).unwrap();
        let centre = camera().eye;
        let ocular = Eyes::Ocular.points(centre, &frame).unwrap();
        assert!((ocular[0].distance(ocular[1]) - OCULAR_SEPARATION_M).abs() < 1e-6);
        assert!(((ocular[0] + ocular[1]) * 0.5).abs_diff_eq(centre, 1e-6));
        assert!((ocular[1] - ocular[0])
            .normalize()
            .abs_diff_eq(frame.right, 1e-6));
        let grid = Eyes::Eyebox {
            width: 0.3,
            height: 0.15,
            columns: 4,
            rows: 3,
        }
        .points(centre, &frame)
        .unwrap();
        assert_eq!(grid.len(), 12);
        assert!(grid[0].abs_diff_eq(centre + Vec3::new(-0.15, -0.075, 0.0), 1e-6));
        assert!(grid[11].abs_diff_eq(centre + Vec3::new(0.15, 0.075, 0.0), 1e-6));
        let empty = Eyes::Eyebox {
            width: 0.3,
            height: 0.1,
            columns: 0,
            rows: 3,
        }
        .points(centre, &frame)
        .unwrap_err();
        assert!(empty.to_string().contains("at least one point"), "{empty}");
    }

    /// The eyebox as a command or a script gives it: the same checks for both.
    #[test]
    fn an_eyebox_from_its_four_numbers_is_checked_once() {
        assert_eq!(
            Eyes::eyebox([0.3, 0.15, 4.0, 3.0]).unwrap(),
            Eyes::Eyebox {
                width: 0.3,
                height: 0.15,
                columns: 4,
                rows: 3
            }
        );
        for (values, says) in [
            ([0.3, 0.1, 0.0, 3.0], "at least one point"),
            ([0.3, 0.1, 2.5, 3.0], "whole numbers"),
            ([0.3, 0.1, 3.0, 20_000.0], "at most 10000"),
            ([f32::NAN, 0.1, 3.0, 3.0], "finite"),
            ([0.3, -0.1, 3.0, 3.0], "not negative"),
        ] {
            let error = Eyes::eyebox(values).unwrap_err();
            assert!(error.contains(says), "{values:?}: {error}");
        }
    }
}
