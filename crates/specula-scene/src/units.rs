//! A file's length unit and up axis, and the transform that takes its coordinates to world
//! space (metres, +Y up; docs/conventions.md). Mesh files carry neither; a STEP file carries
//! its length unit. A scene file names them with `unit` and `up` on a `mesh` or `step` shape.

use glam::{DMat4, DVec3};
use serde::Deserialize;

/// A length unit a file's coordinates may be in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    Mm,
    Cm,
    M,
    In,
}

impl LengthUnit {
    /// Metres in one of this unit.
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Mm => 1e-3,
            LengthUnit::Cm => 1e-2,
            LengthUnit::M => 1.0,
            LengthUnit::In => 0.0254,
        }
    }

    /// The name a scene file uses.
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::Cm => "cm",
            LengthUnit::M => "m",
            LengthUnit::In => "in",
        }
    }
}

/// The axis a file takes as up. World space is +Y up; many CAD systems are +Z up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    #[default]
    Y,
    Z,
}

/// World from file coordinates: scale by `metres_per_unit`, then turn a +Z-up file's +Z onto
/// +Y (a right-handed quarter turn about +X: file (x, y, z) → world (x, z, −y)).
pub fn world_from_file(metres_per_unit: f64, up: UpAxis) -> DMat4 {
    let scale = DMat4::from_scale(DVec3::splat(metres_per_unit));
    match up {
        UpAxis::Y => scale,
        UpAxis::Z => DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2) * scale,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_z_up_millimetre_point_lands_y_up_in_metres() {
        let world = world_from_file(LengthUnit::Mm.metres(), UpAxis::Z)
            .transform_point3(DVec3::new(1000.0, 2000.0, 3000.0));
        assert!((world - DVec3::new(1.0, 3.0, -2.0)).length() < 1e-12, "{world}");
        let inch = world_from_file(LengthUnit::In.metres(), UpAxis::Y)
            .transform_point3(DVec3::new(0.0, 1.0, 0.0));
        assert!((inch.y - 0.0254).abs() < 1e-15);
    }
}
