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

const R46: &str = "UN Regulation No. 46, 04 series of amendments";

/// The regulations `--regulation` knows. Every figure is the one the cited paragraph states as
/// we read it; docs/analyses/mirror-view.md says which were checked against the text and which not.
/// The names of [`REGULATIONS`], in order (the `regulation` option's choices; a test holds the
/// two lists equal).
pub const REGULATION_NAMES: &[&str] = &[
    "r46-i",
    "r46-ii",
    "r46-iii",
    "r46-iv",
    "r46-v",
    "fmvss111",
    "fmvss111-convex",
];

pub const REGULATIONS: &[Regulation] = &[
    Regulation {
        name: "r46-i",
        title: "UN R46 class I: interior rear-view mirror",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: true,
        fields: &[FieldSpec {
            name: "20 m wide from 60 m behind to the horizon",
            lateral: Lateral::AboutMedian { width: 20.0 },
            from_m: 60.0,
            to_m: None,
            source: "R46 §15.2.4.1; 71/127/EEC Annex III §5.2",
        }],
        surface: r46_surface(
            1.2,
            false,
            Some(RectangleRule {
                a_numerator_mm: 150.0,
                segment_mm: None,
                either_way: true,
            }),
            "R46 §6.1.2.1.1, §6.1.2.2",
        ),
    },
    Regulation {
        name: "r46-ii",
        title: "UN R46 class II: main exterior rear-view mirror, large",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[
            FieldSpec {
                name: "5 m wide from 30 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 5.0,
                },
                from_m: 30.0,
                to_m: None,
                source: "R46 §15.2.4.2",
            },
            FieldSpec {
                name: "1 m wide from 4 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 1.0,
                },
                from_m: 4.0,
                to_m: None,
                source: "R46 §15.2.4.2",
            },
        ],
        surface: r46_surface(
            1.2,
            true,
            Some(RectangleRule {
                a_numerator_mm: 170.0,
                segment_mm: Some(200.0),
                either_way: false,
            }),
            "R46 §6.1.2.1.2.1, §6.1.2.2",
        ),
    },
    Regulation {
        name: "r46-iii",
        title: "UN R46 class III: main exterior rear-view mirror, small",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[
            FieldSpec {
                name: "4 m wide from 20 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 4.0,
                },
                from_m: 20.0,
                to_m: None,
                source: "R46 §15.2.4.3",
            },
            FieldSpec {
                name: "1 m wide from 4 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 1.0,
                },
                from_m: 4.0,
                to_m: None,
                source: "R46 §15.2.4.3",
            },
        ],
        surface: r46_surface(
            1.2,
            true,
            Some(RectangleRule {
                a_numerator_mm: 130.0,
                segment_mm: Some(70.0),
                either_way: false,
            }),
            "R46 §6.1.2.1.2.2, §6.1.2.2",
        ),
    },
    Regulation {
        name: "r46-iv",
        title: "UN R46 class IV: wide-angle exterior mirror",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[
            FieldSpec {
                name: "15 m wide from 10 m to 25 m behind",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 15.0,
                },
                from_m: 10.0,
                to_m: Some(25.0),
                source: "R46 §15.2.4.4",
            },
            FieldSpec {
                name: "4.5 m wide from 1.5 m to 10 m behind",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 4.5,
                },
                from_m: 1.5,
                to_m: Some(10.0),
                source: "R46 §15.2.4.4",
            },
        ],
        surface: r46_surface(0.3, true, None, "R46 §6.1.2.2"),
    },
    Regulation {
        name: "r46-v",
        title: "UN R46 class V: close-proximity exterior mirror",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[FieldSpec {
            name: "2 m out from 1.75 m behind to 1 m ahead",
            lateral: Lateral::FromSide {
                inner: 0.0,
                outer: 2.0,
            },
            from_m: -1.0,
            to_m: Some(1.75),
            source: "R46 §15.2.4.5",
        }],
        surface: r46_surface(0.3, true, None, "R46 §6.1.2.2"),
    },
    Regulation {
        name: "fmvss111",
        title: "FMVSS No. 111, passenger car, driver's side outside mirror",
        edition: "49 CFR 571.111 (FMVSS No. 111)",
        eyes: EyeRule::DriversEyes,
        interior: false,
        fields: &[FieldSpec {
            name: "2.4 m wide from 10.7 m behind the eyes to the horizon",
            lateral: Lateral::FromSide {
                inner: 0.0,
                outer: 2.4,
            },
            from_m: 10.7,
            to_m: None,
            source: "FMVSS 111 S5.2.1 (read as a field: the 2.4 m line at 10.7 m, to the horizon)",
        }],
        surface: SurfaceRule {
            spherical: None,
            flat: true,
            convex: None,
            rectangle: None,
            source: "FMVSS 111 S5.2.1 (unit magnification)",
        },
    },
    Regulation {
        name: "fmvss111-convex",
        title: "FMVSS No. 111, passenger car, passenger's side convex outside mirror",
        edition: "49 CFR 571.111 (FMVSS No. 111)",
        eyes: EyeRule::DriversEyes,
        interior: false,
        // S5.4 prescribes no field for the convex mirror: its surface is what is judged.
        fields: &[],
        surface: SurfaceRule {
            spherical: None,
            flat: false,
            convex: Some(ConvexRule {
                min_average_m: 0.889,
                max_average_m: 1.651,
                max_deviation_share: 0.125,
            }),
            rectangle: None,
            source: "FMVSS 111 S5.4.1, S12",
        },
    },
];

/// R46's rule for a spherical mirror's surface: r at least `min_radius_m`, an aspherical part
/// allowed on `exterior` mirrors, and the rectangle.
const fn r46_surface(
    min_radius_m: f64,
    exterior: bool,
    rectangle: Option<RectangleRule>,
    source: &'static str,
) -> SurfaceRule {
    SurfaceRule {
        spherical: Some(SphericalRule {
            min_radius_m,
            aspherical_part_allowed: exterior,
        }),
        flat: false,
        convex: None,
        rectangle,
        source,
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
    fn origin_and_axes(&self, spec: &FieldSpec) -> Result<(Vec2, Vec2, Vec2), AnalyzeError> {
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

/// Which eye points are judged together.
#[derive(Clone, Debug, PartialEq)]
pub enum EyeSets {
    /// All together (ambinocular): a point counts when any of them sees it.
    Together,
    /// Each alone (an eyellipse's points): the worst is the verdict's.
    EachAlone,
}

/// The lateral range of a field, metres from its lateral origin.
fn lateral_range(spec: &FieldSpec) -> (f64, f64) {
    match spec.lateral {
        Lateral::FromSide { inner, outer } => (inner, outer),
        Lateral::AboutMedian { width } => (-0.5 * width, 0.5 * width),
    }
}

/// How far beyond a field's outer edge and before its near end the grid reaches, metres (the
/// margins are measured within it).
const MARGIN_REACH_M: f64 = 5.0;

/// A field's figures from one set of eyes.
#[derive(Clone, Debug, Serialize)]
pub struct FieldFigures {
    pub seen_share: f64,
    pub seen_share_uncertainty: f64,
    /// The uncertainty of the share seen or hidden only by the vehicle (what the mirror's own
    /// edge leaves): twice its change on a grid of half the resolution. Where the body's share
    /// is excused, the field is judged on that share: the boundary between what is seen and
    /// what the body hides moves both shares, not their sum.
    pub clear_share_uncertainty: f64,
    pub blind_area_m2: f64,
    pub hidden_by_vehicle_share: f64,
    /// The share of the part beyond the range seen, by its directions (None: nothing lies
    /// beyond the range).
    pub beyond_range_seen_share: Option<f64>,
    pub beyond_range_uncertainty: Option<f64>,
    /// Whether the field's vanishing direction is seen (None: the field ends before the
    /// horizon): in an eye's cone of reflected directions, and with a cell of the cone's grid
    /// around it (loosely: where only that holds, it is undecided).
    pub horizon_seen: Option<bool>,
    pub horizon_loosely_seen: Option<bool>,
    /// How much farther out, and how much nearer the eyes, the field could reach and still be
    /// seen whole (0 where it is not), metres, up to 5 m, exact to 1/2000 of the field's size
    /// plus 5 m.
    pub outer_margin_m: f64,
    pub near_margin_m: f64,
    /// Pass when the share seen (or excused) is whole beyond its uncertainty (the grid's,
    /// the sampling's and, for a mesh mirror, the surface's), the part beyond the range
    /// likewise and the vanishing direction seen; fail when any is short by more than its
    /// uncertainty; else undecided.
    pub verdict: Outcome,
    pub passed: bool,
}

impl FieldFigures {
    /// The field's verdict from its figures, with `surface_uncertainty` (a mesh mirror's)
    /// added to each share's.
    fn decide(&mut self, allowance: f64, surface_uncertainty: f64) {
        let within_if = |excused: bool| {
            let (_, short, uncertainty) = self.judged(excused, surface_uncertainty);
            Outcome::of_margin(short, uncertainty)
        };
        // Whether the body's share is under the allowance is itself measured: where it lies
        // within its uncertainty of the allowance, the field is decided only if both readings
        // agree.
        let hidden_uncertainty =
            self.seen_share_uncertainty + self.clear_share_uncertainty + surface_uncertainty;
        let margin = allowance - self.hidden_by_vehicle_share;
        let within = match Outcome::of_margin(margin, hidden_uncertainty) {
            Outcome::Pass => within_if(true),
            Outcome::Fail => within_if(false),
            Outcome::Undecided if within_if(true) == within_if(false) => within_if(true),
            Outcome::Undecided => Outcome::Undecided,
        };
        let beyond = self
            .beyond_range_seen_share
            .zip(self.beyond_range_uncertainty)
            .map_or(Outcome::Pass, |(s, u)| {
                Outcome::of_margin(s - 1.0, u + surface_uncertainty)
            });
        let horizon = match (self.horizon_seen, self.horizon_loosely_seen) {
            (None, _) | (Some(true), _) => Outcome::Pass,
            (Some(false), Some(true)) => Outcome::Undecided,
            (Some(false), _) => Outcome::Fail,
        };
        self.verdict = Outcome::all([within, beyond, horizon]);
        self.passed = self.verdict.passed();
    }

    /// The share judged within the range (seen, with the body's share where `excused`), its
    /// margin to the whole field and the uncertainty that enters its verdict.
    pub fn judged(&self, excused: bool, surface_uncertainty: f64) -> (f64, f64, f64) {
        let excused_share = if excused {
            self.hidden_by_vehicle_share
        } else {
            0.0
        };
        let share = self.seen_share + excused_share;
        // Shares are counts of the grid's cells: a sum within rounding of 1 is 1.
        let short = share - 1.0;
        let short = if short.abs() < 1e-12 { 0.0 } else { short };
        let grid = if excused_share > 0.0 {
            self.clear_share_uncertainty
        } else {
            self.seen_share_uncertainty
        };
        (share, short, grid + surface_uncertainty)
    }

    /// Worst first: fail, undecided, pass; then by the share seen or hidden.
    fn rank(&self) -> (u8, f64) {
        let order = match self.verdict {
            Outcome::Fail => 0,
            Outcome::Undecided => 1,
            Outcome::Pass => 2,
        };
        (order, self.seen_share + self.hidden_by_vehicle_share)
    }
}

/// A field and its verdict.
#[derive(Clone, Debug, Serialize)]
pub struct FieldVerdict {
    pub name: String,
    pub source: String,
    /// Metres out from the field's lateral origin (the outermost plane, or the median plane).
    pub lateral_m: [f64; 2],
    pub from_m: f64,
    pub to_m: Option<f64>,
    /// The field's area within range, m².
    pub area_m2: f64,
    #[serde(flatten)]
    pub figures: FieldFigures,
    /// With eye points judged alone: the worst one and its seen share.
    pub worst_eye: Option<WorstEye>,
    /// The change of the seen shares (within and beyond the range) from the mesh to a smooth
    /// fit of it (mesh mirrors only): added to each share's uncertainty in the verdict.
    pub surface_uncertainty: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct WorstEye {
    pub position: [f32; 3],
    pub seen_share: f64,
}

/// The regulation's part of the report.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    pub name: String,
    pub title: String,
    pub edition: String,
    /// The worst of the fields' and the mirror checks' verdicts.
    pub verdict: Outcome,
    pub passed: bool,
    /// Whether every field that runs to the horizon shows its vanishing direction.
    pub horizon_seen: bool,
    pub side: Side,
    pub allowance_share: f64,
    pub mirror_checks: Vec<MirrorCheck>,
    pub fields: Vec<FieldVerdict>,
}

impl Verdict {
    /// The verdict from the fields' and the checks' (after a field's surface uncertainty was
    /// added).
    fn decide(&mut self) {
        self.verdict = Outcome::all(
            self.fields
                .iter()
                .map(|f| f.figures.verdict)
                .chain(self.mirror_checks.iter().map(|c| c.verdict)),
        );
        self.passed = self.verdict.passed();
    }
}

/// A grid over a field's own frame: lateral s (columns) × longitudinal d (rows).
#[derive(Clone, Copy)]
struct FieldGrid {
    s0: f64,
    d0: f64,
    ds: f64,
    dd: f64,
    columns: usize,
    rows: usize,
}

impl FieldGrid {
    fn cell(&self, column: usize, row: usize) -> (f64, f64) {
        (
            self.s0 + (column as f64 + 0.5) * self.ds,
            self.d0 + (row as f64 + 0.5) * self.dd,
        )
    }

    /// Marks the cells whose centres lie in the footprint triangles (world x, z), mapped into the
    /// field's frame.
    fn fill(
        &self,
        covered: &mut [bool],
        triangles: &[[Vec2; 3]],
        to_field: &impl Fn(Vec2) -> (f64, f64),
    ) {
        for t in triangles {
            let q = t.map(to_field);
            let (lo_s, hi_s) = (
                q[0].0.min(q[1].0).min(q[2].0),
                q[0].0.max(q[1].0).max(q[2].0),
            );
            let (lo_d, hi_d) = (
                q[0].1.min(q[1].1).min(q[2].1),
                q[0].1.max(q[1].1).max(q[2].1),
            );
            let c0 = ((lo_s - self.s0) / self.ds).floor().max(0.0) as usize;
            let c1 = (((hi_s - self.s0) / self.ds).ceil().max(0.0) as usize).min(self.columns);
            let r0 = ((lo_d - self.d0) / self.dd).floor().max(0.0) as usize;
            let r1 = (((hi_d - self.d0) / self.dd).ceil().max(0.0) as usize).min(self.rows);
            let edge = |a: (f64, f64), b: (f64, f64), p: (f64, f64)| {
                (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
            };
            let area = edge(q[0], q[1], q[2]);
            if area == 0.0 || !area.is_finite() {
                continue;
            }
            for row in r0..r1 {
                for column in c0..c1 {
                    let p = self.cell(column, row);
                    let inside = [
                        edge(q[1], q[2], p),
                        edge(q[2], q[0], p),
                        edge(q[0], q[1], p),
                    ]
                    .iter()
                    .all(|w| w * area >= 0.0);
                    if inside {
                        covered[row * self.columns + column] = true;
                    }
                }
            }
        }
    }
}

/// One eye's cone of reflected directions, rasterised over (horizontal angle from straight
/// back, elevation), degrees.
struct Cone {
    lo: Vec2,
    cell: Vec2,
    size: usize,
    covered: Vec<bool>,
}

const CONE_GRID: usize = 1024;

impl Cone {
    fn new(frame: &VehicleFrame, directions: &[[Vec3; 3]]) -> Cone {
        let back = -frame.forward;
        let angles = |d: Vec3| {
            Vec2::new(
                frame.horizontal_deg(d, back) as f32,
                frame.elevation_deg(d) as f32,
            )
        };
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for d in directions.iter().flatten() {
            lo = lo.min(angles(*d));
            hi = hi.max(angles(*d));
        }
        if lo.x > hi.x {
            return Cone {
                lo: Vec2::ZERO,
                cell: Vec2::ONE,
                size: 0,
                covered: Vec::new(),
            };
        }
        let cell = ((hi - lo) / CONE_GRID as f32).max(Vec2::splat(1e-6));
        let mut cone = Cone {
            lo,
            cell,
            size: CONE_GRID,
            covered: vec![false; CONE_GRID * CONE_GRID],
        };
        for t in directions {
            let q = t.map(angles);
            // Triangles across the straight-back seam (±180°) are not behind the vehicle.
            if (q[0].x - q[1].x).abs() > 180.0 || (q[1].x - q[2].x).abs() > 180.0 {
                continue;
            }
            let lo_t = q[0].min(q[1]).min(q[2]);
            let hi_t = q[0].max(q[1]).max(q[2]);
            let first = ((lo_t - cone.lo) / cone.cell).floor().max(Vec2::ZERO);
            let last = ((hi_t - cone.lo) / cone.cell).ceil();
            let edge = |a: Vec2, b: Vec2, p: Vec2| (b - a).perp_dot(p - a);
            let area = edge(q[0], q[1], q[2]);
            if area == 0.0 {
                continue;
            }
            for row in first.y as usize..(last.y.max(0.0) as usize).min(cone.size) {
                for column in first.x as usize..(last.x.max(0.0) as usize).min(cone.size) {
                    let p = cone.lo + cone.cell * Vec2::new(column as f32 + 0.5, row as f32 + 0.5);
                    let w = [
                        edge(q[1], q[2], p),
                        edge(q[2], q[0], p),
                        edge(q[0], q[1], p),
                    ];
                    if w.iter().all(|w| w * area >= 0.0) {
                        cone.covered[row * cone.size + column] = true;
                    }
                }
            }
        }
        cone
    }

    /// Whether direction `angles` (horizontal from straight back, elevation; degrees) is in the
    /// cone: its cell, or (`strict` false) any of its 8 neighbours.
    fn contains(&self, angles: Vec2, strict: bool) -> bool {
        if self.size == 0 {
            return false;
        }
        let c = ((angles - self.lo) / self.cell).floor();
        let reach = if strict { 0 } else { 1 };
        let mut any = false;
        for dy in -reach..=reach {
            for dx in -reach..=reach {
                let (x, y) = (c.x as i64 + dx, c.y as i64 + dy);
                if x >= 0 && y >= 0 && (x as usize) < self.size && (y as usize) < self.size {
                    any |= self.covered[y as usize * self.size + x as usize];
                }
            }
        }
        any
    }
}

/// Judges every field of `regulation` from the eye points of `view`, and the mirror's surface.
pub fn judge(
    regulation: &Regulation,
    vehicle: &Vehicle,
    view: &MirrorView,
    eye_sets: &EyeSets,
    surface: &MirrorSurface,
    mirror_centre: Vec3,
) -> Result<Verdict, AnalyzeError> {
    vehicle.validate()?;
    let range = f64::from(view.report.range_m);
    let sets: Vec<Vec<usize>> = match eye_sets {
        EyeSets::Together => vec![(0..view.footprints.len()).collect()],
        EyeSets::EachAlone => (0..view.footprints.len()).map(|k| vec![k]).collect(),
    };
    let cones: Vec<Cone> = view
        .directions
        .iter()
        .map(|d| Cone::new(&vehicle.frame, d))
        .collect();
    let mut fields = Vec::new();
    for spec in regulation.fields {
        let (origin, out, back) = vehicle.origin_and_axes(spec)?;
        let to_field = |p: Vec2| {
            let rel = p - origin;
            (f64::from(rel.dot(out)), f64::from(rel.dot(back)))
        };
        let per_set: Vec<FieldFigures> = sets
            .iter()
            .map(|set| {
                field_figures(
                    spec,
                    regulation,
                    vehicle,
                    view,
                    &cones,
                    set,
                    range,
                    &to_field,
                    origin,
                    out,
                    back,
                    mirror_centre,
                )
            })
            .collect();
        let worst = (0..per_set.len())
            .min_by(|&a, &b| {
                let (ka, kb) = (per_set[a].rank(), per_set[b].rank());
                ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
            })
            .expect("at least one eye point");
        let (s_lo, s_hi) = lateral_range(spec);
        let near = spec.from_m;
        let far = spec.to_m.unwrap_or(f64::INFINITY).min(range);
        fields.push(FieldVerdict {
            name: spec.name.to_string(),
            source: spec.source.to_string(),
            lateral_m: [s_lo, s_hi],
            from_m: spec.from_m,
            to_m: spec.to_m,
            area_m2: (s_hi - s_lo) * (far - near).max(0.0),
            figures: per_set[worst].clone(),
            worst_eye: matches!(eye_sets, EyeSets::EachAlone).then(|| WorstEye {
                position: view.report.eyes[worst].position,
                seen_share: per_set[worst].seen_share,
            }),
            surface_uncertainty: None,
        });
    }
    let facing = mean(view.report.eyes.iter().map(|e| Vec3::from(e.position)));
    let mirror_checks =
        crate::mirror_rules::mirror_checks(&regulation.surface, surface, &vehicle.frame, facing);
    let horizon_seen = fields
        .iter()
        .all(|f| f.figures.horizon_seen.unwrap_or(true));
    let mut verdict = Verdict {
        name: regulation.name.to_string(),
        title: regulation.title.to_string(),
        edition: regulation.edition.to_string(),
        verdict: Outcome::Pass,
        passed: true,
        horizon_seen,
        side: vehicle.side,
        allowance_share: regulation.allowance(),
        mirror_checks,
        fields,
    };
    verdict.decide();
    Ok(verdict)
}

fn mean(points: impl Iterator<Item = Vec3>) -> Vec3 {
    let (sum, count) = points.fold((Vec3::ZERO, 0.0), |(s, n), p| (s + p, n + 1.0));
    sum / f32::max(count, 1.0)
}

#[allow(clippy::too_many_arguments)]
fn field_figures(
    spec: &FieldSpec,
    regulation: &Regulation,
    vehicle: &Vehicle,
    view: &MirrorView,
    cones: &[Cone],
    set: &[usize],
    range: f64,
    to_field: &impl Fn(Vec2) -> (f64, f64),
    origin: Vec2,
    out: Vec2,
    back: Vec2,
    mirror_centre: Vec3,
) -> FieldFigures {
    let (s_lo, s_hi) = lateral_range(spec);
    let near = spec.from_m;
    let far = spec.to_m.unwrap_or(f64::INFINITY).min(range);
    let mut figures = FieldFigures {
        seen_share: 1.0,
        seen_share_uncertainty: 0.0,
        clear_share_uncertainty: 0.0,
        blind_area_m2: 0.0,
        hidden_by_vehicle_share: 0.0,
        beyond_range_seen_share: None,
        beyond_range_uncertainty: None,
        horizon_seen: None,
        horizon_loosely_seen: None,
        outer_margin_m: 0.0,
        near_margin_m: 0.0,
        verdict: Outcome::Pass,
        passed: true,
    };
    let within = far > near;
    if within {
        seen_within_range(&mut figures, view, set, to_field, (s_lo, s_hi), (near, far));
    }
    // Beyond the range: directions from the mirror's centre to the field's far ground.
    let beyond_from = near.max(range);
    let beyond_to = spec.to_m.unwrap_or(f64::INFINITY);
    let angles_of = |d: Vec3| {
        Vec2::new(
            vehicle.frame.horizontal_deg(d, -vehicle.frame.forward) as f32,
            vehicle.frame.elevation_deg(d) as f32,
        )
    };
    let seen_direction =
        |d: Vec3, strict: bool| set.iter().any(|&k| cones[k].contains(angles_of(d), strict));
    if beyond_to > beyond_from {
        let (share, uncertainty) = beyond_range_share(
            &seen_direction,
            vehicle,
            (s_lo, s_hi),
            (beyond_from, beyond_to),
            (origin, out, back),
            mirror_centre,
        );
        figures.beyond_range_seen_share = Some(share);
        figures.beyond_range_uncertainty = Some(uncertainty);
    }
    if spec.to_m.is_none() {
        figures.horizon_seen = Some(seen_direction(-vehicle.frame.forward, true));
        figures.horizon_loosely_seen = Some(seen_direction(-vehicle.frame.forward, false));
    }
    figures.decide(regulation.allowance(), 0.0);
    figures
}

/// The field's seen share within the range on a grid over it (with the grid's own error and
/// the last refinement's change as its uncertainty), the share the vehicle hides, the blind
/// area and the margins.
fn seen_within_range(
    figures: &mut FieldFigures,
    view: &MirrorView,
    set: &[usize],
    to_field: &impl Fn(Vec2) -> (f64, f64),
    (s_lo, s_hi): (f64, f64),
    (near, far): (f64, f64),
) {
    // The share on a grid over the field alone; the margins on one that reaches beyond its
    // outer edge and before its near end.
    let grid = FieldGrid {
        s0: s_lo,
        d0: near,
        ds: (s_hi - s_lo) / 600.0,
        dd: (far - near) / 1200.0,
        columns: 600,
        rows: 1200,
    };
    let cells = grid.columns * grid.rows;
    let (mut seen, mut clear, mut before) =
        (vec![false; cells], vec![false; cells], vec![false; cells]);
    for &k in set {
        grid.fill(&mut seen, &view.footprints[k], to_field);
        grid.fill(&mut clear, &view.clear_footprints[k], to_field);
        grid.fill(&mut before, &view.previous_footprints[k], to_field);
    }
    let count = |cells: &[bool]| cells.iter().filter(|c| **c).count() as f64;
    let hidden = seen.iter().zip(&clear).filter(|(s, c)| **c && !**s).count() as f64;
    // The grid's own error: twice the share's change on a grid of half the resolution
    // (a centre-sampled grid's error halves with its cells, so the change is about the
    // coarse grid's error, twice the fine one's: the factor 2 is a safety margin).
    let coarse = FieldGrid {
        ds: grid.ds * 2.0,
        dd: grid.dd * 2.0,
        columns: grid.columns / 2,
        rows: grid.rows / 2,
        ..grid
    };
    let mut coarse_seen = vec![false; coarse.columns * coarse.rows];
    let mut coarse_clear = coarse_seen.clone();
    for &k in set {
        coarse.fill(&mut coarse_seen, &view.footprints[k], to_field);
        coarse.fill(&mut coarse_clear, &view.clear_footprints[k], to_field);
    }
    let either = |a: &[bool], b: &[bool]| a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    let total = cells as f64;
    figures.clear_share_uncertainty = 2.0
        * (either(&seen, &clear) as f64 / total
            - either(&coarse_seen, &coarse_clear) as f64 / coarse_seen.len() as f64)
            .abs();
    figures.seen_share = count(&seen) / total;
    figures.hidden_by_vehicle_share = hidden / total;
    figures.seen_share_uncertainty = 2.0
        * (figures.seen_share - count(&coarse_seen) / coarse_seen.len() as f64).abs()
        + (count(&seen) - count(&before)).abs() / total;
    figures.blind_area_m2 = (s_hi - s_lo) * (far - near) * (1.0 - figures.seen_share);
    (figures.outer_margin_m, figures.near_margin_m) =
        margins(&view.footprints, set, to_field, (s_lo, s_hi), (near, far));
}

/// The share of the field beyond the range whose directions from the mirror's centre some eye
/// point's cone holds (strictly), on a 48 × 48 grid even in lateral position and in inverse
/// distance; its uncertainty, the share held only loosely.
fn beyond_range_share(
    seen_direction: &impl Fn(Vec3, bool) -> bool,
    vehicle: &Vehicle,
    (s_lo, s_hi): (f64, f64),
    (beyond_from, beyond_to): (f64, f64),
    (origin, out, back): (Vec2, Vec2, Vec2),
    mirror_centre: Vec3,
) -> (f64, f64) {
    let (n, mut covered, mut loose) = (48usize, 0usize, 0usize);
    let w_far = if beyond_to.is_finite() {
        1.0 / beyond_to
    } else {
        0.0
    };
    let w_near = 1.0 / beyond_from;
    for i in 0..n {
        for j in 0..n {
            let s = s_lo + (s_hi - s_lo) * (i as f64 + 0.5) / n as f64;
            let w = w_far + (w_near - w_far) * (j as f64 + 0.5) / n as f64;
            let g = origin + out * s as f32 + back * (1.0 / w) as f32;
            let p = Vec3::new(g.x, vehicle.ground_y, g.y);
            let d = (p - mirror_centre).normalize();
            covered += usize::from(seen_direction(d, true));
            loose += usize::from(seen_direction(d, false));
        }
    }
    let total = (n * n) as f64;
    (covered as f64 / total, (loose - covered) as f64 / total)
}

/// How much farther out, and how much nearer the eyes, the field (lateral `s`, longitudinal
/// `d`) could reach and still be seen whole, up to [`MARGIN_REACH_M`]: on a 2000 × 2000 grid
/// whose cell centres fall on the field's outer edge and near end, the whole columns beyond
/// the edge and the whole rows before the end (each exact to a cell).
fn margins(
    footprints: &[Vec<[Vec2; 3]>],
    set: &[usize],
    to_field: &impl Fn(Vec2) -> (f64, f64),
    (s_lo, s_hi): (f64, f64),
    (near, far): (f64, f64),
) -> (f64, f64) {
    let n = 2000usize;
    let ds = (s_hi - s_lo + MARGIN_REACH_M) / n as f64;
    let dd = (far - near + MARGIN_REACH_M) / n as f64;
    // Column k's centre is at s_hi + (k − k_edge) ds, row j's at near + (j − j_edge) dd.
    let k_edge = ((s_hi - s_lo) / ds).round() as usize;
    let j_edge = (MARGIN_REACH_M / dd).round() as usize;
    let grid = FieldGrid {
        s0: s_hi - (k_edge as f64 + 0.5) * ds,
        d0: near - (j_edge as f64 + 0.5) * dd,
        ds,
        dd,
        columns: n,
        rows: n,
    };
    let mut seen = vec![false; n * n];
    for &k in set {
        grid.fill(&mut seen, &footprints[k], to_field);
    }
    let eps = 1e-9;
    let column_whole = |column: usize| {
        (0..n).all(|row| {
            let (_, d) = grid.cell(column, row);
            !(near - eps..=far + eps).contains(&d) || seen[row * n + column]
        })
    };
    let row_whole = |row: usize| {
        (0..n).all(|column| {
            let (s, _) = grid.cell(column, row);
            !(s_lo - eps..=s_hi + eps).contains(&s) || seen[row * n + column]
        })
    };
    let outer = if column_whole(k_edge) {
        (k_edge + 1..n).take_while(|&c| column_whole(c)).count() as f64 * ds
    } else {
        0.0
    };
    let nearer = if row_whole(j_edge) {
        (0..j_edge).rev().take_while(|&r| row_whole(r)).count() as f64 * dd
    } else {
        0.0
    };
    (outer, nearer)
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

/// What `--json` writes for a regulation run, and the report's report.json: the mirror view's
/// figures, the vehicle as laid out, the verdict and the pose search.
#[derive(Serialize)]
pub struct Document<'a> {
    #[serde(flatten)]
    pub view: &'a mirror_view::Report,
    pub vehicle: VehicleReport,
    pub regulation: &'a Verdict,
    pub adjustment: Option<&'a Adjustment>,
}

#[derive(Clone, Debug, Serialize)]
pub struct VehicleReport {
    /// The fields' longitudinal origin: the ocular points' middle (or the eyes').
    pub reference: [f32; 3],
    pub side: Side,
    pub outermost: Option<[f32; 3]>,
    pub median: [f32; 3],
    pub eyes_from: &'static str,
    pub vehicle_parts: Vec<String>,
}

impl Document<'_> {
    /// Where the verdict was judged from, in words.
    pub fn judged_from(&self) -> String {
        let eyes: Vec<String> = self
            .view
            .eyes
            .iter()
            .map(|e| {
                let [x, y, z] = e.position;
                format!("({x:.3}, {y:.3}, {z:.3})")
            })
            .collect();
        let who = match self.vehicle.eyes_from {
            "r_point" | "ocular" => "R46's ocular points",
            "eyellipse" => "the eyellipse's points",
            _ => "the eye points",
        };
        let how = if self.vehicle.eyes_from == "eyellipse" {
            "each alone, the worst reported"
        } else {
            "together: a point counts when any sees it"
        };
        if eyes.len() > 4 {
            format!("judged from {} {who}, {how}", eyes.len())
        } else {
            format!("judged from {who} {}, {how}", eyes.join(" and "))
        }
    }
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

/// `--adjust`: the mirror turned about a pivot.
#[derive(Clone, Copy, Debug)]
pub struct AdjustRequest {
    pub pivot: Vec3,
    pub step_deg: f32,
    pub limit_deg: f32,
}

/// One pose of the mirror and how its fields fare.
#[derive(Clone, Debug, Serialize)]
pub struct Pose {
    pub yaw_deg: f32,
    pub pitch_deg: f32,
    /// The fields' verdict at the search's tolerances.
    pub search_verdict: Outcome,
    /// The fields' verdict at the command's tolerances, for each pose the search did not fail
    /// (None: the search failed it).
    pub confirmed_verdict: Option<Outcome>,
    /// The fields pass at the command's tolerances (the mirror's own checks do not change with
    /// its pose).
    pub fields_passed: bool,
    /// The least, over the fields, of the share seen or excused.
    pub least_share: f64,
    pub least_share_field: String,
    /// The least, over the fields, of the outer and near margins, metres.
    pub least_margin_m: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Adjustment {
    pub pivot: [f32; 3],
    /// Yaw turns about the vehicle's up axis (positive: right-hand rule), pitch about the
    /// horizontal axis in the mirror's plane, both through the pivot.
    pub yaw_axis: [f32; 3],
    pub pitch_axis: [f32; 3],
    pub step_deg: f32,
    pub limit_deg: f32,
    /// The tolerances the search ran at; every pose it did not fail is judged again at the
    /// command's, and only those confirmed there count as passing.
    pub search_tolerance: f64,
    pub poses: Vec<Pose>,
    /// The yaw and pitch ranges of the poses confirmed to pass (None: none passes).
    pub passing_yaw_deg: Option<[f32; 2]>,
    pub passing_pitch_deg: Option<[f32; 2]>,
    pub passing_poses: usize,
    /// The pose with the widest margin among those that pass; else the one that sees most.
    pub best: Pose,
    /// The best pose judged at the command's tolerances.
    pub best_verdict: Verdict,
}

/// The pivot must be near the mirror (a mirror turns about its own mounting).
pub fn check_pivot(scene: &Scene, mirror: usize, pivot: Vec3) -> Result<(), AnalyzeError> {
    let bounds = scene.meshes[mirror].bounds();
    let nearest = pivot.clamp(bounds.min, bounds.max);
    let distance = pivot.distance(nearest);
    if !pivot.is_finite() || distance > 0.5 {
        return Err(AnalyzeError::BadOption {
            option: "adjust",
            reason: format!(
                "the pivot {pivot} is {distance:.2} m from the mirror's bounds ({} to {}): a \
                 mirror turns about its own mounting, within 0.5 m of it",
                bounds.min, bounds.max
            ),
        });
    }
    Ok(())
}

/// The rigid turn of the mirror about `pivot`: yaw about `up`, then pitch about `pitch_axis`.
pub fn pose_transform(
    pivot: Vec3,
    up: Vec3,
    pitch_axis: Vec3,
    yaw_deg: f32,
    pitch_deg: f32,
) -> Mat4 {
    Mat4::from_translation(pivot)
        * Mat4::from_axis_angle(up, yaw_deg.to_radians())
        * Mat4::from_axis_angle(pitch_axis, pitch_deg.to_radians())
        * Mat4::from_translation(-pivot)
}

/// Turns the mirror over a grid of yaw × pitch within ±`limit_deg`, judging each pose at the
/// viewer's tolerances (2 %, 0.1°), and every pose that search does not fail again at the
/// request's: the passing ranges are of poses confirmed at full precision.
pub fn adjust(
    scene: &Scene,
    request: &Request,
    adjust: &AdjustRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Adjustment, AnalyzeError> {
    let mirror = request.view.mirror;
    check_adjust(scene, request, adjust)?;
    let surface = MirrorSurface::new(scene, mirror, request.view.surface).expect("validated");
    let (_, normal) = mirror_centre_and_normal(&surface);
    let up = request.vehicle.frame.up;
    let pitch_axis = up
        .cross(normal)
        .try_normalize()
        .unwrap_or(request.vehicle.frame.right);
    let steps = (adjust.limit_deg / adjust.step_deg).floor() as i32;
    let angles: Vec<f32> = (-steps..=steps)
        .map(|k| k as f32 * adjust.step_deg)
        .collect();
    let grid: Vec<(f32, f32)> = angles
        .iter()
        .flat_map(|&yaw| angles.iter().map(move |&pitch| (yaw, pitch)))
        .collect();
    let search = Request {
        view: mirror_view::Options {
            tolerance: request.view.tolerance.max(0.02),
            tolerance_deg: request.view.tolerance_deg.max(0.1),
            max_samples: request.view.max_samples.min(1_000_000),
            ..request.view.clone()
        },
        ..request.clone()
    };
    let posed = |yaw: f32, pitch: f32| {
        let mut scene = scene.clone();
        scene.meshes[mirror].transform(pose_transform(adjust.pivot, up, pitch_axis, yaw, pitch));
        scene
    };
    let mut poses = Vec::with_capacity(grid.len());
    for (k, &(yaw, pitch)) in grid.iter().enumerate() {
        let scene = posed(yaw, pitch);
        let accel = SceneAccel::new(&scene);
        let judged = evaluate_quietly(&scene, &accel, &search)?;
        poses.push(pose_of(yaw, pitch, &judged.verdict, request.regulation));
        progress(k + 1, grid.len());
    }
    confirm(&mut poses, &posed, request, progress)?;
    let passing: Vec<&Pose> = poses.iter().filter(|p| p.fields_passed).collect();
    let range = |f: fn(&Pose) -> f32| {
        (!passing.is_empty()).then(|| {
            let v = passing.iter().map(|p| f(p));
            [
                v.clone().fold(f32::INFINITY, f32::min),
                v.fold(f32::NEG_INFINITY, f32::max),
            ]
        })
    };
    let best = if passing.is_empty() {
        poses
            .iter()
            .max_by(|a, b| a.least_share.total_cmp(&b.least_share))
    } else {
        passing
            .iter()
            .copied()
            .max_by(|a, b| a.least_margin_m.total_cmp(&b.least_margin_m))
    }
    .expect("at least one pose")
    .clone();
    let best_scene = posed(best.yaw_deg, best.pitch_deg);
    let best_accel = SceneAccel::new(&best_scene);
    let best_verdict = evaluate_quietly(&best_scene, &best_accel, request)?.verdict;
    Ok(Adjustment {
        pivot: adjust.pivot.to_array(),
        yaw_axis: up.to_array(),
        pitch_axis: pitch_axis.to_array(),
        step_deg: adjust.step_deg,
        limit_deg: adjust.limit_deg,
        search_tolerance: search.view.tolerance,
        passing_yaw_deg: range(|p| p.yaw_deg),
        passing_pitch_deg: range(|p| p.pitch_deg),
        passing_poses: passing.len(),
        poses,
        best,
        best_verdict,
    })
}

/// `--adjust`'s own inputs: a regulation with fields, a pivot at the mirror, a positive step.
fn check_adjust(
    scene: &Scene,
    request: &Request,
    adjust: &AdjustRequest,
) -> Result<(), AnalyzeError> {
    if request.regulation.fields.is_empty() {
        return Err(AnalyzeError::BadOption {
            option: "adjust",
            reason: format!(
                "{} prescribes no field: there is nothing for a pose search to find (the \
                 mirror's own rules do not change with its pose)",
                request.regulation.name
            ),
        });
    }
    check_pivot(scene, request.view.mirror, adjust.pivot)?;
    if !(adjust.step_deg.is_finite() && adjust.step_deg > 0.0) {
        return Err(AnalyzeError::BadOption {
            option: "adjust_step",
            reason: format!("{}°: the step must be a positive angle", adjust.step_deg),
        });
    }
    Ok(())
}

/// Judges every pose the search did not fail again as the command judges (the request's
/// tolerances, a mesh mirror's surface uncertainty included): only those confirmed pass.
fn confirm(
    poses: &mut [Pose],
    posed: &impl Fn(f32, f32) -> Scene,
    request: &Request,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(), AnalyzeError> {
    let searched = poses.len();
    let total = searched
        + poses
            .iter()
            .filter(|p| p.search_verdict != Outcome::Fail)
            .count();
    let mut done = searched;
    for pose in poses
        .iter_mut()
        .filter(|p| p.search_verdict != Outcome::Fail)
    {
        let scene = posed(pose.yaw_deg, pose.pitch_deg);
        let accel = SceneAccel::new(&scene);
        let judged = evaluate(&scene, &accel, request, &|_| {})?;
        let full = pose_of(
            pose.yaw_deg,
            pose.pitch_deg,
            &judged.verdict,
            request.regulation,
        );
        *pose = Pose {
            search_verdict: pose.search_verdict,
            confirmed_verdict: Some(full.search_verdict),
            fields_passed: full.search_verdict.passed(),
            ..full
        };
        done += 1;
        progress(done, total);
    }
    Ok(())
}

/// One pose judged, without the smooth-fit rerun (the pose search compares poses on one surface).
fn evaluate_quietly(
    scene: &Scene,
    accel: &SceneAccel,
    request: &Request,
) -> Result<Judged, AnalyzeError> {
    let surface =
        MirrorSurface::new(scene, request.view.mirror, request.view.surface).expect("validated");
    let (centre, _) = mirror_centre_and_normal(&surface);
    let view = mirror_view::analyze(scene, accel, &request.eyes, &request.view, &|_| {})?;
    let verdict = judge(
        request.regulation,
        &request.vehicle,
        &view,
        &request.eye_sets,
        &surface,
        centre,
    )?;
    Ok(Judged { verdict, view })
}

fn pose_of(yaw: f32, pitch: f32, verdict: &Verdict, regulation: &Regulation) -> Pose {
    let share = |f: &FieldVerdict| {
        let excused = if f.figures.hidden_by_vehicle_share < regulation.allowance() {
            f.figures.hidden_by_vehicle_share
        } else {
            0.0
        };
        let beyond = f.figures.beyond_range_seen_share.unwrap_or(1.0);
        (f.figures.seen_share + excused).min(beyond)
    };
    let least = verdict
        .fields
        .iter()
        .min_by(|a, b| share(a).total_cmp(&share(b)));
    let fields = Outcome::all(verdict.fields.iter().map(|f| f.figures.verdict));
    Pose {
        yaw_deg: yaw,
        pitch_deg: pitch,
        search_verdict: fields,
        confirmed_verdict: None,
        fields_passed: false,
        least_share: least.map_or(1.0, share),
        least_share_field: least.map_or_else(String::new, |f| f.name.clone()),
        least_margin_m: verdict
            .fields
            .iter()
            .map(|f| f.figures.outer_margin_m.min(f.figures.near_margin_m))
            .fold(f64::INFINITY, f64::min),
    }
}
