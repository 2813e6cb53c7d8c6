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

use crate::frame::VehicleFrame;
use crate::regulation::EyeSets;
use crate::AnalyzeError;

/// R46's ocular points are this far above the R point, metres.
pub const OCULAR_HEIGHT_M: f32 = 0.635;

/// UN ECE Regulation 46's ocular points are 65 mm apart.
pub const OCULAR_SEPARATION_M: f32 = 0.065;

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
    let half = frame.right * (0.5 * OCULAR_SEPARATION_M);
    [middle - half, middle + half]
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
    use specula_scene::Camera;

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
