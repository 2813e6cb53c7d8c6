//! The lens as the frame holds it, the prescription the wearer should get there, and the one
//! to order so that they do.
//!
//! **Placement.** The fitting point F is where the primary line of sight (from the centre of
//! rotation along the primary gaze) meets the back surface of the lens as the scene places it.
//! Pantoscopic tilt turns the lens about the eye's horizontal axis through F, its lower edge
//! towards the face; wrap then turns it about the vertical axis through F, its temporal edge
//! (the wearer's right for the right eye) towards the face. F stays on the back surface, so the
//! vertex distance (cornea to F along the primary line) is unchanged. Both are refused beyond
//! 30°, where no frame holds a lens.
//!
//! **The prescription as worn.** A prescription refracted with the trial lens `d_r` from the
//! cornea is what the wearer needs at that distance; at the lens's vertex distance `d` each
//! principal meridian's power F becomes F / (1 − (d_r − d) F) (the lens moved d_r − d towards
//! the eye keeps the far point). That, at the vertex sphere along the primary line of sight, is
//! the target the as-worn power is compared with.
//!
//! **Compensation.** The ordered sphere, cylinder and axis whose lens, made on the same blank
//! (base curve, index, thickness, diameter) and worn the same way, gives the target at the
//! fitting point: a fixed-point iteration in power-vector space, ordered += target − as worn,
//! from the target itself (the as-worn power depends on the ordered one almost linearly: a few
//! iterations reach 1e-9 D).

use glam::{DMat4, DQuat, DVec3};
use serde::Serialize;
use specula_scene::{Mesh, Prescription};

use super::Eye;
use crate::AnalyzeError;

/// The largest tilt (pantoscopic or wrap) accepted, degrees.
pub const MAX_TILT_DEG: f64 = 30.0;

/// How the frame tilts the lens (module doc); zero: the lens as the scene places it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Wear {
    pub pantoscopic_deg: f64,
    pub wrap_deg: f64,
}

impl Wear {
    pub fn is_flat(&self) -> bool {
        self.pantoscopic_deg == 0.0 && self.wrap_deg == 0.0
    }

    pub(crate) fn check(&self) -> Result<(), AnalyzeError> {
        for (option, value) in [
            ("pantoscopic", self.pantoscopic_deg),
            ("wrap", self.wrap_deg),
        ] {
            if !(value.is_finite() && value.abs() <= MAX_TILT_DEG) {
                return Err(AnalyzeError::BadOption {
                    option,
                    reason: format!(
                        "{value}°: a frame tilts a lens by at most {MAX_TILT_DEG}° (give a tilt \
                         between −{MAX_TILT_DEG} and {MAX_TILT_DEG})"
                    ),
                });
            }
        }
        Ok(())
    }

    /// The rigid motion taking the lens as placed to the lens as worn, about the fitting point.
    pub fn world_from_placed(&self, pivot: DVec3, forward: DVec3, up: DVec3, eye: Eye) -> DMat4 {
        let right = forward.cross(up).normalize();
        // Turning about `right` by −θ brings −up (the lower edge) towards −forward (the eye);
        // turning about `up` by −φ brings +right towards the eye.
        let temporal = match eye {
            Eye::Right => 1.0,
            Eye::Left => -1.0,
        };
        let tilt = DQuat::from_axis_angle(right, -self.pantoscopic_deg.to_radians());
        let wrap = DQuat::from_axis_angle(up, -temporal * self.wrap_deg.to_radians());
        DMat4::from_translation(pivot)
            * DMat4::from_quat(wrap * tilt)
            * DMat4::from_translation(-pivot)
    }
}

/// `mesh` moved by `world_from_placed`: its triangles in single precision, its exact surface
/// in double.
pub(crate) fn moved(mesh: &Mesh, world_from_placed: DMat4) -> Mesh {
    let mut worn = mesh.clone();
    worn.transform(world_from_placed.as_mat4());
    if let (Some(exact), Some(placed)) = (&mut worn.exact, &mesh.exact) {
        exact.world_from_object = world_from_placed * placed.world_from_object;
    }
    worn
}

/// A prescription: sphere, cylinder and axis (TABO), and prism (Δ, base out and base up
/// positive).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Rx {
    pub sphere_d: f64,
    pub cylinder_d: f64,
    pub axis_deg: f64,
    pub prism_d: [f64; 2],
}

impl Rx {
    pub fn new(sphere_d: f64, cylinder_d: f64, axis_deg: f64) -> Rx {
        Rx {
            sphere_d,
            cylinder_d,
            axis_deg,
            prism_d: [0.0; 2],
        }
        .minus_cylinder()
    }

    pub fn of(p: &Prescription) -> Rx {
        Rx::new(p.sphere, p.cylinder, p.axis_deg)
    }

    /// `S`, `S,C,A` or either followed by prisms such as `1.5BO`, `0.5BU` (base out, in, up or
    /// down): an axis is required with a cylinder, and means nothing without one.
    pub fn parse(text: &str) -> Result<Rx, String> {
        let tokens: Vec<&str> = text.split(',').map(str::trim).collect();
        let numbers = tokens
            .iter()
            .take_while(|t| t.parse::<f64>().is_ok())
            .count();
        let value = |k: usize| tokens[k].parse::<f64>().expect("counted as a number");
        let mut rx = match numbers {
            1 => Rx::new(value(0), 0.0, 0.0),
            2 => {
                return Err(format!(
                    "'{text}': a cylinder of {} D needs its axis (S,C,A)",
                    value(1)
                ))
            }
            3.. => {
                let axis = value(2);
                if !(0.0..=180.0).contains(&axis) {
                    return Err(format!(
                        "'{text}': the axis {axis}° must lie between 0 and 180 (TABO)"
                    ));
                }
                Rx::new(value(0), value(1), axis)
            }
            _ => {
                return Err(format!(
                    "'{text}': expected SPHERE[,CYLINDER,AXIS][,PRISM...]"
                ))
            }
        };
        let mut prism = [0.0; 2];
        for token in &tokens[numbers.min(3)..] {
            let upper = token.to_ascii_uppercase();
            let (amount, base) = upper.split_at(upper.len().saturating_sub(2));
            let amount: f64 = amount.parse().map_err(|_| {
                format!(
                    "'{token}' in '{text}': a prism is an amount and a base, e.g. 1.5BO or 0.5BU \
                     (BO, BI, BU, BD)"
                )
            })?;
            match base {
                "BO" => prism[0] += amount,
                "BI" => prism[0] -= amount,
                "BU" => prism[1] += amount,
                "BD" => prism[1] -= amount,
                _ => {
                    return Err(format!(
                        "'{token}' in '{text}': the base must be BO, BI, BU or BD"
                    ))
                }
            }
        }
        if numbers > 3 {
            return Err(format!(
                "'{text}': expected SPHERE,CYLINDER,AXIS then prisms such as 1.5BO"
            ));
        }
        rx.prism_d = prism;
        Ok(rx)
    }

    /// In minus-cylinder form, axis in [0, 180).
    pub fn minus_cylinder(mut self) -> Rx {
        if self.cylinder_d > 0.0 {
            self.sphere_d += self.cylinder_d;
            self.cylinder_d = -self.cylinder_d;
            self.axis_deg += 90.0;
        }
        self.axis_deg = self.axis_deg.rem_euclid(180.0);
        if self.axis_deg >= 180.0 - 1e-12 {
            self.axis_deg = 0.0;
        }
        self
    }

    /// The power vector (M, J0, J45).
    pub fn power_vector(&self) -> [f64; 3] {
        let a = 2.0 * self.axis_deg.to_radians();
        [
            self.sphere_d + 0.5 * self.cylinder_d,
            -0.5 * self.cylinder_d * a.cos(),
            -0.5 * self.cylinder_d * a.sin(),
        ]
    }

    /// The minus-cylinder prescription of a power vector.
    pub fn from_power_vector([m, j0, j45]: [f64; 3], prism_d: [f64; 2]) -> Rx {
        let half = j0.hypot(j45);
        let axis = 0.5 * j45.atan2(j0).to_degrees();
        Rx {
            sphere_d: m + half,
            cylinder_d: -2.0 * half,
            axis_deg: axis,
            prism_d,
        }
        .minus_cylinder()
    }

    /// The power in each principal meridian: the axis's (the sphere) and across it.
    pub fn meridians(&self) -> [(f64, f64); 2] {
        [
            (self.axis_deg, self.sphere_d),
            (
                (self.axis_deg + 90.0).rem_euclid(180.0),
                self.sphere_d + self.cylinder_d,
            ),
        ]
    }

    /// The prescription for a lens `towards_eye_m` nearer the eye than the one refracted
    /// (module doc).
    pub fn moved_towards_eye(&self, towards_eye_m: f64) -> Rx {
        let moved = |f: f64| f / (1.0 - towards_eye_m * f);
        let [(_, s), (_, across)] = self.meridians();
        let sphere = moved(s);
        Rx {
            sphere_d: sphere,
            cylinder_d: moved(across) - sphere,
            ..*self
        }
        .minus_cylinder()
    }
}

/// The ordered prescription and how well it was solved.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Compensated {
    pub ordered: Rx,
    pub iterations: usize,
    /// The largest power-vector difference left between the target and the ordered lens's
    /// as-worn power, dioptres.
    pub residual_d: f64,
}

/// The compensated prescription (module doc): `as_worn(ordered)` is the power vector the lens
/// made from `ordered` on `blank` gives at the fitting point as worn.
pub(crate) fn compensate(
    target: Rx,
    blank: &Prescription,
    as_worn: impl Fn(&Prescription) -> Result<[f64; 3], AnalyzeError>,
) -> Result<Compensated, AnalyzeError> {
    let goal = target.power_vector();
    let mut ordered = goal;
    for iteration in 1..=30 {
        let rx = Rx::from_power_vector(ordered, target.prism_d);
        let lens = Prescription {
            sphere: rx.sphere_d,
            cylinder: rx.cylinder_d,
            axis_deg: rx.axis_deg,
            ..blank.clone()
        };
        let got = as_worn(&lens)?;
        let residual = (0..3).map(|k| (goal[k] - got[k]).abs()).fold(0.0, f64::max);
        if residual < 1e-9 || iteration == 30 {
            return Ok(Compensated {
                ordered: rx,
                iterations: iteration,
                residual_d: residual,
            });
        }
        for k in 0..3 {
            ordered[k] += goal[k] - got[k];
        }
    }
    unreachable!("the loop returns on its last iteration")
}
