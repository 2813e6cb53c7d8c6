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

impl std::str::FromStr for LengthUnit {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<Self, UnknownName> {
        [
            LengthUnit::Mm,
            LengthUnit::Cm,
            LengthUnit::M,
            LengthUnit::In,
        ]
        .into_iter()
        .find(|unit| unit.name() == name)
        .ok_or_else(|| UnknownName::new(name, "\"mm\", \"cm\", \"m\" or \"in\""))
    }
}

/// A name that is none of a setting's values; it lists them.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("\"{given}\" is not one of {allowed}")]
pub struct UnknownName {
    given: String,
    allowed: &'static str,
}

impl UnknownName {
    fn new(given: &str, allowed: &'static str) -> UnknownName {
        UnknownName {
            given: given.to_string(),
            allowed,
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

impl std::str::FromStr for UpAxis {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<Self, UnknownName> {
        match name {
            "y" => Ok(UpAxis::Y),
            "z" => Ok(UpAxis::Z),
            _ => Err(UnknownName::new(name, "\"y\" or \"z\"")),
        }
    }
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
        assert!(
            (world - DVec3::new(1.0, 3.0, -2.0)).length() < 1e-12,
            "{world}"
        );
        let inch = world_from_file(LengthUnit::In.metres(), UpAxis::Y)
            .transform_point3(DVec3::new(0.0, 1.0, 0.0));
        assert!((inch.y - 0.0254).abs() < 1e-15);
    }

    #[test]
    fn names_parse_as_a_scene_file_writes_them_and_others_list_the_allowed() {
        for unit in [
            LengthUnit::Mm,
            LengthUnit::Cm,
            LengthUnit::M,
            LengthUnit::In,
        ] {
            assert_eq!(unit.name().parse(), Ok(unit));
        }
        assert_eq!("z".parse(), Ok(UpAxis::Z));
        let wrong = "MM".parse::<LengthUnit>().unwrap_err().to_string();
        assert_eq!(wrong, r#""MM" is not one of "mm", "cm", "m" or "in""#);
        let wrong = "x".parse::<UpAxis>().unwrap_err().to_string();
        assert_eq!(wrong, r#""x" is not one of "y" or "z""#);
    }
}
