//! `specula analyze mirror-view --regulation NAME`: the fields a regulation prescribes for a
//! mirror, laid on the ground in the vehicle frame and judged from the driver's eye points, with
//! the vehicle's own body in the way, and the mirror's own surface against the regulation's
//! rules for it.
//!
//! Steps:
//! 1. The vehicle ([`Vehicle`]): its frame, the fields' longitudinal origin (the ocular points'
//!    transverse plane), the side the mirror serves, the plane through the vehicle's outermost
//!    point on that side (the fields' inner boundary) and the median plane (class I's centre).
//! 2. The eyes ([`EyeSets`]): R46's two ocular points, judged together (ambinocular: a point
//!    counts when either sees it); or each point of an eyellipse alone, the worst reported.
//! 3. Each prescribed field ([`FieldSpec`], one table [`REGULATIONS`]) is rasterised in its own
//!    frame (lateral × longitudinal) within `range_m` behind the ocular points; the eyes'
//!    footprints ([`crate::mirror_view::MirrorView`]) mark what is seen, the footprints with the
//!    vehicle's body taken away mark what the body hides. The part beyond the range, and the
//!    horizon, are judged in direction space: a ground point far behind is seen when its
//!    direction from the mirror lies in an eye's cone of reflected directions (the mirror's size
//!    over the range is the angle this neglects).
//! 4. The verdict ([`FieldVerdict`]): a field passes when its seen share, with the body's share
//!    added where the allowance excuses it (together under 10 % of an exterior mirror's field,
//!    15 % of an interior mirror's: Directive 71/127/EEC, Annex III), is 1 within its stated
//!    uncertainty, its part beyond the range likewise, and, running to the horizon, its
//!    vanishing direction is seen. The mirror's edge is never excused.
//! 5. The mirror ([`MirrorCheck`]): its radius of curvature from the surface's principal
//!    curvatures, and for classes II and III the rectangle and segment its reflecting surface must
//!    hold (R46 §6.1.2), measured on the surface projected onto its tangent plane at the centre.
//!
//! Uncertainty of a share: its change when the field's grid (600 × 1200 cells) is halved in
//! resolution, plus its change between the last two refinements of the sampling.
//! A mesh's surface uncertainty (its change from the mesh to a smooth fit) is added by the
//! caller, which runs both.
//!
//! Files: the regulations' tables (`tables.rs`), the vehicle (`vehicle.rs`), a field's grid and
//! what is seen of it (`fields.rs`), judging and the JSON document (`verdict.rs`), the pose
//! search (`adjust.rs`); here the types they share and [`evaluate`].

use glam::{DVec3, Mat4, Vec2, Vec3};
use serde::Serialize;
use specula_scene::Scene;
use specula_trace::SceneAccel;

use crate::frame::VehicleFrame;
pub use crate::mirror_rules::{ConvexRule, MirrorCheck, RectangleRule, SphericalRule, SurfaceRule};
use crate::mirror_surface::{MirrorSurface, SurfaceModel};
use crate::mirror_view::{self, MirrorView};
use crate::outcome::Outcome;
use crate::AnalyzeError;

mod adjust;
mod fields;
mod tables;
mod vehicle;
mod verdict;

pub use adjust::*;
use fields::*;
pub use tables::*;
pub use vehicle::*;
pub use verdict::*;

/// How a field's lateral extent is measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lateral {
    /// Outwards from the plane through the vehicle's outermost point on the mirror's side,
    /// parallel to the median plane, metres.
    FromSide { inner: f64, outer: f64 },
    /// Centred on the vehicle's median plane, this wide, metres.
    AboutMedian { width: f64 },
}

/// One prescribed field on the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSpec {
    pub name: &'static str,
    pub lateral: Lateral,
    /// Metres behind the ocular points' transverse vertical plane where the field starts
    /// (negative: ahead of it) and where it ends (None: the horizon).
    pub from_m: f64,
    pub to_m: Option<f64>,
    /// The paragraph that prescribes it.
    pub source: &'static str,
}

/// Whose eyes the fields are judged from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EyeRule {
    /// R46's two ocular points (from `--r-point`), or an eyellipse.
    OcularPoints,
    /// The driver's eye points (`--eye`, `--eyellipse`): FMVSS 111.
    DriversEyes,
}

/// A regulation's requirements for one mirror class.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Regulation {
    pub name: &'static str,
    pub title: &'static str,
    pub edition: &'static str,
    pub eyes: EyeRule,
    /// An interior mirror (the 15 % allowance) rather than an exterior one (10 %).
    pub interior: bool,
    pub fields: &'static [FieldSpec],
    pub surface: SurfaceRule,
}

impl Regulation {
    /// The share of a field the vehicle's body may hide and still be disregarded.
    pub fn allowance(&self) -> f64 {
        if self.interior {
            0.15
        } else {
            0.10
        }
    }
}

/// The regulation named `name`; an unknown name lists the valid ones.
pub fn by_name(name: &str) -> Result<&'static Regulation, AnalyzeError> {
    REGULATIONS
        .iter()
        .find(|r| r.name == name)
        .ok_or_else(|| AnalyzeError::BadOption {
            option: "regulation",
            reason: format!(
                "unknown regulation '{name}'; valid: {}",
                REGULATIONS
                    .iter()
                    .map(|r| r.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
}

/// Which eye points are judged together.
#[derive(Clone, Debug, PartialEq)]
pub enum EyeSets {
    /// All together (ambinocular): a point counts when any of them sees it.
    Together,
    /// Each alone (an eyellipse's points): the worst is the verdict's.
    EachAlone,
}

/// The mirror's centre and mean unit normal (area-weighted over its cells).
pub fn mirror_centre_and_normal(surface: &MirrorSurface) -> (Vec3, Vec3) {
    let (mut centre, mut normal, mut area) = (DVec3::ZERO, DVec3::ZERO, 0.0);
    for cell in 0..surface.cells() {
        let p = [Vec2::ZERO, Vec2::X, Vec2::Y].map(|b| surface.position(cell, b).as_dvec3());
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let a = 0.5 * n.length();
        centre += (p[0] + p[1] + p[2]) / 3.0 * a;
        normal += n;
        area += a;
    }
    (
        (centre / area.max(1e-30)).as_vec3(),
        normal.normalize_or_zero().as_vec3(),
    )
}

/// Checks that every eye point lies in front of the mirror's reflecting side, away from it.
pub fn check_eyes(
    scene: &Scene,
    mirror: usize,
    surface: &MirrorSurface,
    eyes: &[Vec3],
    option: &'static str,
) -> Result<(), AnalyzeError> {
    let (centre, normal) = mirror_centre_and_normal(surface);
    let bounds = scene.meshes[mirror].bounds();
    for eye in eyes {
        let inside = (bounds.min - 0.01).cmple(*eye).all() && eye.cmple(bounds.max + 0.01).all();
        let front = (*eye - centre).dot(normal);
        if inside || front <= 0.01 {
            return Err(AnalyzeError::BadOption {
                option,
                reason: format!(
                    "it puts an eye point at {eye}, {}: the eyes must be in front of the \
                     mirror's reflecting side (its normal {normal} from its centre {centre})",
                    if inside {
                        "inside the mirror's bounds".to_string()
                    } else {
                        format!("{:.3} m behind the mirror's plane", -front)
                    }
                ),
            });
        }
    }
    Ok(())
}

/// What `--regulation` asks.
#[derive(Clone, Debug)]
pub struct Request {
    pub regulation: &'static Regulation,
    pub vehicle: Vehicle,
    pub eyes: Vec<Vec3>,
    pub eye_sets: EyeSets,
    /// The option the eyes came from (for errors).
    pub eyes_option: &'static str,
    pub view: mirror_view::Options,
}

/// The figures and the verdict from one pose of the mirror.
pub struct Judged {
    pub verdict: Verdict,
    pub view: MirrorView,
}

/// Analyses the mirror from the eyes and judges it; for a mirror without an exact surface,
/// also on a smooth fit of its mesh, each field's share's change being its surface uncertainty.
pub fn evaluate(
    scene: &Scene,
    accel: &SceneAccel,
    request: &Request,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Judged, AnalyzeError> {
    request.view.validate(scene)?;
    let surface =
        MirrorSurface::new(scene, request.view.mirror, request.view.surface).expect("validated");
    check_eyes(
        scene,
        request.view.mirror,
        &surface,
        &request.eyes,
        request.eyes_option,
    )?;
    let (centre, _) = mirror_centre_and_normal(&surface);
    let view = mirror_view::analyze(scene, accel, &request.eyes, &request.view, progress)?;
    let mut verdict = judge(
        request.regulation,
        &request.vehicle,
        &view,
        &request.eye_sets,
        &surface,
        centre,
    )?;
    if request.view.surface == SurfaceModel::Mesh {
        let smooth_options = mirror_view::Options {
            surface: SurfaceModel::Smooth,
            ..request.view.clone()
        };
        let smooth_surface =
            MirrorSurface::new(scene, request.view.mirror, SurfaceModel::Smooth).expect("a mesh");
        let smooth_view =
            mirror_view::analyze(scene, accel, &request.eyes, &smooth_options, &|_| {})?;
        let smooth = judge(
            request.regulation,
            &request.vehicle,
            &smooth_view,
            &request.eye_sets,
            &smooth_surface,
            centre,
        )?;
        for (field, other) in verdict.fields.iter_mut().zip(&smooth.fields) {
            let (a, b) = (&field.figures, &other.figures);
            let beyond = a
                .beyond_range_seen_share
                .zip(b.beyond_range_seen_share)
                .map_or(0.0, |(x, y)| (x - y).abs());
            let u = (a.seen_share - b.seen_share).abs().max(beyond);
            field.surface_uncertainty = Some(u);
            field.figures.decide(request.regulation.allowance(), u);
        }
        verdict.decide();
    }
    Ok(Judged { verdict, view })
}
