//! The vehicle the fields are laid out in: its frame, the side the mirror serves, the plane
//! through its outermost point on that side and its median plane; a field's corners on the
//! ground.

use super::*;

pub use crate::analysis::eye_points::{eyellipse_points, ocular_points, OCULAR_HEIGHT_M};

/// Which side of the vehicle the mirror serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
}

specula_params::choice!(Side {
    Left = "left",
    Right = "right",
});

/// The vehicle as the fields are laid out in it.
#[derive(Clone, Debug)]
pub struct Vehicle {
    pub frame: VehicleFrame,
    /// The fields' longitudinal origin: the middle of the ocular points (or of the eye points).
    pub reference: Vec3,
    pub side: Side,
    /// A point of the plane through the vehicle's outermost point on the mirror's side.
    pub outermost: Option<Vec3>,
    /// A point of the vehicle's median longitudinal plane.
    pub median: Vec3,
    pub ground_y: f32,
}

impl Vehicle {
    /// The unit horizontal direction out of the vehicle on the mirror's side.
    pub fn outward(&self) -> Vec3 {
        match self.side {
            Side::Right => self.frame.right,
            Side::Left => -self.frame.right,
        }
    }

    /// The side `p` lies on, seen from the reference.
    pub fn side_of(frame: &VehicleFrame, reference: Vec3, p: Vec3) -> Side {
        if (p - reference).dot(frame.right) >= 0.0 {
            Side::Right
        } else {
            Side::Left
        }
    }

    /// Checks the outermost point against the side: it must lie on the mirror's side of the
    /// eyes.
    pub fn validate(&self) -> Result<(), AnalyzeError> {
        if let Some(o) = self.outermost {
            let out = (o - self.reference).dot(self.outward());
            if out <= 0.0 {
                return Err(AnalyzeError::BadOption {
                    option: "outermost",
                    reason: format!(
                        "{o} lies {:.3} m towards the other side of the ocular points, not on the \
                         {} side the mirror serves: the outermost point is the vehicle's widest \
                         point on the mirror's side",
                        -out,
                        match self.side {
                            Side::Left => "left",
                            Side::Right => "right",
                        }
                    ),
                });
            }
        }
        Ok(())
    }

    /// The ground point of field coordinates (lateral `s` from the field's lateral origin,
    /// `d` metres behind the reference), x and z.
    pub(super) fn origin_and_axes(
        &self,
        spec: &FieldSpec,
    ) -> Result<(Vec2, Vec2, Vec2), AnalyzeError> {
        let back = Vec2::new(-self.frame.forward.x, -self.frame.forward.z);
        let out = Vec2::new(self.outward().x, self.outward().z);
        let r = Vec2::new(self.reference.x, self.reference.z);
        let lateral_origin = match spec.lateral {
            Lateral::FromSide { .. } => {
                let o = self.outermost.ok_or_else(|| AnalyzeError::BadOption {
                    option: "outermost",
                    reason: format!(
                        "the field '{}' is bounded by the plane through the vehicle's outermost \
                         point on the mirror's side: give it (`outermost` X,Y,Z) or name the \
                         vehicle's parts (`vehicle`)",
                        spec.name
                    ),
                })?;
                (Vec2::new(o.x, o.z) - r).dot(out)
            }
            Lateral::AboutMedian { .. } => (Vec2::new(self.median.x, self.median.z) - r).dot(out),
        };
        Ok((r + out * lateral_origin, out, back))
    }
}

impl Vehicle {
    /// The corners of field `spec` on the ground (x, z), its far end at the range where it runs
    /// farther: for drawing it.
    pub fn field_corners(&self, spec: &FieldSpec, range_m: f32) -> Result<[Vec2; 4], AnalyzeError> {
        let (origin, out, back) = self.origin_and_axes(spec)?;
        let (s0, s1) = lateral_range(spec);
        let far = spec.to_m.unwrap_or(f64::INFINITY).min(f64::from(range_m));
        let at = |s: f64, d: f64| origin + out * s as f32 + back * d as f32;
        Ok([
            at(s0, spec.from_m),
            at(s1, spec.from_m),
            at(s1, far),
            at(s0, far),
        ])
    }
}

/// The lateral range of a field, metres from its lateral origin.
pub(super) fn lateral_range(spec: &FieldSpec) -> (f64, f64) {
    match spec.lateral {
        Lateral::FromSide { inner, outer } => (inner, outer),
        Lateral::AboutMedian { width } => (-0.5 * width, 0.5 * width),
    }
}
