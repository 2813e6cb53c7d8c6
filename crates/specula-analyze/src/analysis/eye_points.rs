//! The eye points every analysis looks from, declared once: the camera's eye, given points, an
//! eyebox grid, UN R46's ocular points (about the camera's eye, or 635 mm above a given R
//! point), or an eyellipse's surface points; and the vehicle frame they are laid out in.
//!
//! **One default rule.** With none of them given, an analysis looks from the camera's eye,
//! except where the rule it judges by names other eyes: R46 judges from the driver's ocular
//! points (2003/97/EC Annex III §2.1.1.1 ... "the driver's ocular points"), so a mirror view
//! judged against an R46 class takes the two ocular points about the camera's eye.

use glam::Vec3;
use specula_params::{options, Opt, ParamKind};
use specula_scene::Scene;

use crate::frame::{Eyes, VehicleFrame};
use crate::regulation::EyeSets;
use crate::AnalyzeError;

/// R46's ocular points are this far above the R point, metres.
pub const OCULAR_HEIGHT_M: f32 = 0.635;

options! {
    /// Where the eyes are; at most one of `eye`, `eyebox`, `ocular`, `r_point`, `eyellipse`.
    pub struct EyePoints {
        eye: Vec<Vec3> = Opt::point(
            "an eye point X,Y,Z (default: the camera's eye; R46's ocular points about it for an \
             R46 verdict)",
        )
        .repeatable()
        .group("Eye points"),
        eyebox: Option<[f64; 4]> = Opt::new(
            ParamKind::Numbers { names: "W,H,NX,NY" },
            "",
            "m",
            "a grid of NX × NY eye points spanning W × H metres, centred on the camera's eye, \
             horizontal and vertical in the vehicle frame",
        )
        .group("Eye points"),
        ocular: bool = Opt::flag(
            "UN R46's two ocular points: 65 mm apart across the vehicle, centred on the camera's eye",
        )
        .group("Eye points"),
        r_point: Option<Vec3> = Opt::point(
            "the driver's R point: R46's ocular points lie 635 mm above it, 65 mm apart across \
             the vehicle",
        )
        .group("Eye points"),
        eyellipse: Option<String> = Opt::new(
            ParamKind::Text { expected: "CX,CY,CZ,AX,AY,AZ[,N]" },
            "",
            "m",
            "an eyellipse: centre and semi-axes along the vehicle's forward, lateral and up axes, \
             N points on its surface (default 26), each judged alone",
        )
        .group("Eye points"),
        eyellipse_tilt: f32 = Opt::new(
            ParamKind::Number { min: -90.0, max: 90.0 },
            "0",
            "°",
            "the eyellipse's side-view tilt (its forward axis turned up)",
        )
        .group("Eye points"),
        forward: Option<Vec3> = Opt::new(
            ParamKind::Numbers { names: "X,Y,Z" },
            "",
            "",
            "the vehicle's longitudinal axis (default: the camera's view direction on the \
             ground plane); up is +Y",
        )
        .group("Eye points"),
    }
}

/// The eye points as an analysis uses them.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedEyes {
    pub points: Vec<Vec3>,
    pub frame: VehicleFrame,
    /// Judged together (any sees) or each alone (an eyellipse's).
    pub sets: EyeSets,
    /// The option they came from (`eye` where none was given and the camera's eye is used).
    pub from: &'static str,
    /// Their middle: the ocular points' (above the R point), the eyellipse's centre, the
    /// camera's eye for a grid or the ocular points about it, the mean of given points.
    pub reference: Vec3,
}

/// Which eyes an analysis takes when none are given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DefaultEyes {
    /// The camera's eye.
    Camera,
    /// R46's two ocular points about the camera's eye.
    Ocular,
}

impl EyePoints {
    /// Which of the exclusive options are given.
    fn given(&self) -> Vec<&'static str> {
        [
            ("eye", !self.eye.is_empty()),
            ("eyebox", self.eyebox.is_some()),
            ("ocular", self.ocular),
            ("r_point", self.r_point.is_some()),
            ("eyellipse", self.eyellipse.is_some()),
        ]
        .into_iter()
        .filter_map(|(name, given)| given.then_some(name))
        .collect()
    }

    /// The points and the vehicle frame on `scene`, with `default` where none are given.
    pub fn resolve(
        &self,
        scene: &Scene,
        default: DefaultEyes,
    ) -> Result<ResolvedEyes, AnalyzeError> {
        let given = self.given();
        if given.len() > 1 {
            return Err(AnalyzeError::BadOption {
                option: given[1],
                reason: format!(
                    "give one of `eye`, `eyebox`, `ocular`, `r_point` and `eyellipse`, not {}",
                    given
                        .iter()
                        .map(|g| format!("`{g}`"))
                        .collect::<Vec<_>>()
                        .join(" and ")
                ),
            });
        }
        let camera_eye = scene.camera.eye;
        let from = match given.first() {
            Some(option) => *option,
            None if default == DefaultEyes::Ocular => "ocular",
            None => "eye",
        };
        let eyes = match from {
            "eyebox" => {
                let values = self.eyebox.expect("given").map(|v| v as f32);
                Eyes::eyebox(values).map_err(|reason| AnalyzeError::BadOption {
                    option: "eyebox",
                    reason,
                })?
            }
            "ocular" => Eyes::Ocular,
            "eye" if !self.eye.is_empty() => Eyes::Points(self.eye.clone()),
            _ => Eyes::Camera,
        };
        // Points laid out across the vehicle need its frame; the camera's eye or given points
        // take a level one where the camera looks straight down.
        let frame = match from {
            "r_point" | "eyellipse" | "ocular" | "eyebox" => {
                VehicleFrame::new(&scene.camera, self.forward)?
            }
            _ => VehicleFrame::for_eyes(&scene.camera, self.forward, &eyes)?,
        };
        let together = |points: Vec<Vec3>, reference: Vec3| ResolvedEyes {
            points,
            frame,
            sets: EyeSets::Together,
            from,
            reference,
        };
        Ok(match from {
            "r_point" => {
                let r = self.r_point.expect("given");
                together(
                    ocular_points(&frame, r).to_vec(),
                    r + frame.up * OCULAR_HEIGHT_M,
                )
            }
            "eyellipse" => {
                let (centre, axes, count) =
                    parse_eyellipse(self.eyellipse.as_deref().unwrap_or("")).map_err(|reason| {
                        AnalyzeError::BadOption {
                            option: "eyellipse",
                            reason,
                        }
                    })?;
                let points = eyellipse_points(&frame, centre, axes, self.eyellipse_tilt, count)?;
                ResolvedEyes {
                    points,
                    frame,
                    sets: EyeSets::EachAlone,
                    from,
                    reference: centre,
                }
            }
            "eye" if !self.eye.is_empty() => {
                let mean = self.eye.iter().copied().sum::<Vec3>() / self.eye.len() as f32;
                together(self.eye.clone(), mean)
            }
            _ => together(eyes.points(camera_eye, &frame)?, camera_eye),
        })
    }
}

/// An eyellipse `CX,CY,CZ,AX,AY,AZ[,N]` (N 26 where left out).
pub fn parse_eyellipse(text: &str) -> Result<(Vec3, Vec3, usize), String> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| v.trim().parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("expected CX,CY,CZ,AX,AY,AZ[,N], finite numbers, got '{text}'"))?;
    let count = match values.len() {
        6 => 26,
        7 if values[6].fract() == 0.0 && values[6] >= 0.0 => values[6] as usize,
        7 => return Err(format!("N must be a whole number of points, got '{text}'")),
        _ => {
            return Err(format!(
                "expected CX,CY,CZ,AX,AY,AZ[,N] (6 or 7 numbers), got '{text}'"
            ))
        }
    };
    Ok((
        Vec3::new(values[0], values[1], values[2]),
        Vec3::new(values[3], values[4], values[5]),
        count,
    ))
}

/// Eye points on an eyellipse: centre, semi-axes along forward, lateral (right) and up, a
/// side-view tilt (degrees, turning forward towards up about the lateral axis), `count` points
/// on its surface: the 26 directions to a cube's faces, edges and corners for 26, else a
/// Fibonacci lattice.
pub fn eyellipse_points(
    frame: &VehicleFrame,
    centre: Vec3,
    semi_axes: Vec3,
    tilt_deg: f32,
    count: usize,
) -> Result<Vec<Vec3>, AnalyzeError> {
    let bad = |reason: String| AnalyzeError::BadOption {
        option: "eyellipse",
        reason,
    };
    if !(semi_axes.is_finite() && semi_axes.min_element() > 0.0) {
        return Err(bad(format!(
            "semi-axes {semi_axes} m: each must be a positive length (a flat or empty eyellipse \
             has no surface to put eye points on)"
        )));
    }
    if !centre.is_finite() || !tilt_deg.is_finite() {
        return Err(bad(format!(
            "centre {centre} and tilt {tilt_deg}° must be finite"
        )));
    }
    if !(2..=1000).contains(&count) {
        return Err(bad(format!("{count} points: between 2 and 1000")));
    }
    let directions: Vec<Vec3> = if count == 26 {
        let mut d = Vec::new();
        for i in -1..=1 {
            for j in -1..=1 {
                for k in -1..=1 {
                    if (i, j, k) != (0, 0, 0) {
                        d.push(Vec3::new(i as f32, j as f32, k as f32).normalize());
                    }
                }
            }
        }
        d
    } else {
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        (0..count)
            .map(|k| {
                let z = 1.0 - 2.0 * (k as f32 + 0.5) / count as f32;
                let r = (1.0 - z * z).sqrt();
                let phi = golden * k as f32;
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect()
    };
    let (c, s) = (tilt_deg.to_radians().cos(), tilt_deg.to_radians().sin());
    let forward = frame.forward * c + frame.up * s;
    let up = frame.up * c - frame.forward * s;
    Ok(directions
        .iter()
        .map(|d| {
            centre
                + forward * (d.x * semi_axes.x)
                + frame.right * (d.y * semi_axes.y)
                + up * (d.z * semi_axes.z)
        })
        .collect())
}

/// R46's ocular points from the R point: 635 mm above it, 65 mm apart across the vehicle.
pub fn ocular_points(frame: &VehicleFrame, r_point: Vec3) -> [Vec3; 2] {
    let middle = r_point + frame.up * OCULAR_HEIGHT_M;
    let half = frame.right * (0.5 * crate::frame::OCULAR_SEPARATION_M);
    [middle - half, middle + half]
}
