//! What a regulation asks of the mirror's own surface, measured as the regulation measures it,
//! each check three-valued ([`Outcome`]) with its value, limit, margin and uncertainty.
//!
//! - **UN R46, 04 series** (read in its consolidated text and Directive 2003/97/EC, whose
//!   Annex I and the appendix to its Annex II are the same text): r_i and r'_i are the radii of
//!   the normal sections along the arc through the surface's centre parallel to segment b (the
//!   vertical: b is parallel to the rectangle's height) and across it, measured with a
//!   spherometer at points as near as possible to 1/3, 1/2 and 2/3 of that arc, or of the
//!   arc across it where that one is longer (Annex 7 §1.2.1; 2003/97/EC Annex I §1.1.1.5 and
//!   Appendix 1 to Annex II); r_p = (r_i + r'_i) / 2 at each point (Annex I §1.1.1.6); r is
//!   the mean of the three r_p (Annex 7 §2). The surface must be flat or spherically convex, an
//!   exterior mirror may carry an additional aspherical part (§6.1.2.2); r_i and r'_i may
//!   differ from r_p by at most 0.15 r, each r_p from r by at most 0.15 r, 0.25 r where r is
//!   3000 mm or more; r at least 1200 mm for classes I–III, 300 mm for IV and V; an aspherical
//!   part's r_i at least 150 mm; class I's surface holds a rectangle 40 mm by
//!   a = 150 / (1 + 1000 / r) mm, class II's and III's one 40 mm high and a = 170 and 130 /
//!   (1 + 1000 / r) mm long and a segment of 200 and 70 mm parallel to its height (§6.1.2.1).
//!   The definitions and the measuring points were confirmed in 2003/97/EC's text; the limits
//!   and the a formulas are as commonly quoted, not confirmed against the text: see
//!   docs/analyses/mirror-view.md. Supplement 9 to the 04 series (free-form mirrors) is not
//!   applied: a free-form mirror is judged as a spherical one and fails where it is not.
//! - **FMVSS No. 111**: the driver's side mirror is flat (unit magnification, S5.2.1); a
//!   passenger-side convex mirror (S5.4.1) has an average radius of curvature of 889 to
//!   1651 mm, none of its 10 readings deviating from the average by more than 12.5 %, the
//!   readings taken as S12 takes them: 5 locations (the centre and the ends of the horizontal
//!   and vertical bisectors), two perpendicular readings at each (S12.1–S12.6, as NHTSA's 1993
//!   interpretation describes them). The bisectors' end readings are taken 25.4 mm in from the
//!   edge (the spherometer's 19 mm half-span and S12.3's 6.4 mm border, as recalled, not
//!   confirmed); S5.4.2's marking is not checked.
//!
//! How the radii are measured ([`crate::spherometer`]): on the exact surface where the mirror
//! has one, else on a local fit to the mesh that does not see its facets; every radius carries
//! its measured uncertainty, which enters every check that uses it. "Flat" has no figure in
//! either text: a surface is read as flat where no curvature can be told from zero within the
//! measurement's uncertainty and, for R46, none at its uncertainty's edge is sharper than the
//! class's least radius (else the surface checks are undecided).

use glam::{DVec2, DVec3, Vec3};
use serde::Serialize;

use crate::frame::VehicleFrame;
use crate::mirror_surface::MirrorSurface;
use crate::outcome::Outcome;
use crate::spherometer::{Curvature, LocalShape, Probe};

/// What a regulation asks of the mirror's own surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceRule {
    /// R46: flat or spherically convex, r measured as Annex 7 does at least this, metres.
    pub spherical: Option<SphericalRule>,
    /// FMVSS 111 S5.2.1: flat (unit magnification).
    pub flat: bool,
    /// FMVSS 111 S5.4.1: a convex mirror's average radius within a range, its readings within
    /// a share of it.
    pub convex: Option<ConvexRule>,
    /// R46 §6.1.2.1: a rectangle 40 mm by a = `a_numerator_mm` / (1 + 1000 / r) mm, and a
    /// segment parallel to its height.
    pub rectangle: Option<RectangleRule>,
    pub source: &'static str,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphericalRule {
    pub min_radius_m: f64,
    /// An exterior mirror may carry an aspherical part (its r_i at least 150 mm).
    pub aspherical_part_allowed: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConvexRule {
    pub min_average_m: f64,
    pub max_average_m: f64,
    pub max_deviation_share: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RectangleRule {
    pub a_numerator_mm: f64,
    /// The segment parallel to the rectangle's height (None: no segment rule).
    pub segment_mm: Option<f64>,
    /// Whether the rectangle's 40 mm side may lie either way (class I: "one side of which is
    /// 40 mm"); else it is the height.
    pub either_way: bool,
}

/// R46's deviation limit: 0.15 r, or 0.25 r where r is 3000 mm or more.
fn deviation_share(r_m: f64) -> f64 {
    if r_m >= 3.0 {
        0.25
    } else {
        0.15
    }
}

/// An aspherical part's r_i must be at least this (R46 §6.1.2.2), metres.
const ASPHERICAL_MIN_RADIUS_M: f64 = 0.15;

/// A rule for the mirror's own surface and how it fares.
#[derive(Clone, Debug, Serialize)]
pub struct MirrorCheck {
    pub name: String,
    pub source: String,
    pub required: String,
    pub measured: String,
    /// The measured value, the limit it is held to, the margin (positive: passing by that
    /// much) and the measurement's uncertainty, all in `unit` (None: infinite, a flat
    /// surface's radius).
    pub value: Option<f64>,
    pub limit: f64,
    pub margin: Option<f64>,
    pub uncertainty: Option<f64>,
    pub unit: &'static str,
    pub verdict: Outcome,
    pub passed: bool,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

impl MirrorCheck {
    #[allow(clippy::too_many_arguments)]
    fn new(
        name: &str,
        source: &str,
        required: String,
        measured: String,
        (value, limit, margin, uncertainty): (f64, f64, f64, f64),
        unit: &'static str,
        verdict: Outcome,
    ) -> MirrorCheck {
        MirrorCheck {
            name: name.into(),
            source: source.into(),
            required,
            measured,
            value: finite(value),
            limit,
            margin: finite(margin),
            uncertainty: finite(uncertainty),
            unit,
            verdict,
            passed: verdict.passed(),
        }
    }
}

fn mm(r: f64) -> String {
    if r.is_finite() {
        format!("{:.0} mm", r * 1e3)
    } else {
        "flat".to_string()
    }
}

/// The mirror's surface against `rule`, measured on `surface` seen from `facing` (the eyes).
pub fn mirror_checks(
    rule: &SurfaceRule,
    surface: &MirrorSurface,
    frame: &VehicleFrame,
    facing: Vec3,
) -> Vec<MirrorCheck> {
    let probe = Probe::new(surface, frame.up, facing);
    let mut checks = Vec::new();
    let mut r_for_rectangle = (f64::INFINITY, 0.0);
    if let Some(spherical) = rule.spherical {
        match Annex7::measure(&probe) {
            Ok(annex7) => {
                checks.extend(spherical_checks(&spherical, rule.source, &probe, &annex7));
                r_for_rectangle = (annex7.r, annex7.r_uncertainty);
            }
            Err(reason) => checks.push(refused("radius of curvature r", rule.source, reason)),
        }
    }
    if rule.flat {
        checks.push(flat_check(rule.source, &probe));
    }
    if let Some(convex) = rule.convex {
        match s12_readings(&probe) {
            Ok(readings) => checks.extend(convex_checks(&convex, rule.source, &readings)),
            Err(reason) => checks.push(refused("average radius of curvature", rule.source, reason)),
        }
    }
    if let Some(rectangle) = rule.rectangle {
        checks.extend(rectangle_checks(
            &rectangle,
            rule.source,
            &probe,
            r_for_rectangle,
        ));
    }
    checks
}

/// A check that cannot be measured on this mirror: undecided, saying why.
fn refused(name: &str, source: &str, reason: String) -> MirrorCheck {
    MirrorCheck::new(
        name,
        source,
        "a measurement as the standard takes it".into(),
        format!("not measurable: {reason}"),
        (f64::NAN, 0.0, f64::NAN, f64::NAN),
        "m",
        Outcome::Undecided,
    )
}

/// One of R46's measuring points: where, and the two normal-section radii.
#[derive(Clone, Copy, Debug)]
pub struct Annex7Point {
    pub along: Curvature,
    pub across: Curvature,
}

impl Annex7Point {
    /// r_p = (r_i + r'_i) / 2 and its uncertainty.
    fn r_p(&self) -> (f64, f64) {
        let (a, ua) = self.along.radius();
        let (b, ub) = self.across.radius();
        (0.5 * (a + b), 0.5 * (ua + ub))
    }

    /// |r_i − r_p| = |r'_i − r_p| = |r_i − r'_i| / 2 and its uncertainty.
    fn spread(&self) -> (f64, f64) {
        let (a, ua) = self.along.radius();
        let (b, ub) = self.across.radius();
        if a.is_infinite() && b.is_infinite() {
            return (0.0, 0.0);
        }
        (0.5 * (a - b).abs(), 0.5 * (ua + ub))
    }

    fn is_flat(&self) -> bool {
        self.along.is_flat() && self.across.is_flat()
    }
}

/// R46 Annex 7's measurement: the arc, its three points, r.
#[derive(Clone, Debug)]
pub struct Annex7 {
    /// "parallel to b" (the vertical) or "across b" (the horizontal, where it is longer).
    pub arc: &'static str,
    pub arc_length_m: f64,
    pub points: [Annex7Point; 3],
    pub r: f64,
    pub r_uncertainty: f64,
    /// No section's curvature told from zero.
    pub flat: bool,
    /// The largest |curvature| + uncertainty over the sections: how curved the surface may be
    /// at most, 1/m.
    pub greatest_curvature: f64,
}

impl Annex7 {
    pub fn measure(probe: &Probe) -> Result<Annex7, String> {
        let vertical = arc(probe, DVec2::Y).ok_or_else(no_centre)?;
        let horizontal = arc(probe, DVec2::X).ok_or_else(no_centre)?;
        let (name, chosen, along, across) = if horizontal.length > vertical.length {
            ("across b", horizontal, probe.plane.h, probe.plane.v)
        } else {
            ("parallel to b", vertical, probe.plane.v, probe.plane.h)
        };
        let mut points = Vec::new();
        for fraction in [1.0 / 3.0, 0.5, 2.0 / 3.0] {
            let q = chosen.at(fraction * chosen.length);
            let shape = probe
                .shape(q)
                .ok_or_else(|| format!("no surface to measure at {fraction:.2} of the arc"))?;
            points.push(reading(&shape, along, across)?);
        }
        let points: [Annex7Point; 3] = points.try_into().expect("three points");
        let flat = points.iter().all(Annex7Point::is_flat);
        let greatest_curvature = points
            .iter()
            .flat_map(|p| [p.along, p.across])
            .map(|c| c.value.abs() + c.uncertainty)
            .fold(0.0, f64::max);
        let (r, r_uncertainty) = if flat {
            (f64::INFINITY, 0.0)
        } else {
            let (sum, u) = points
                .iter()
                .map(Annex7Point::r_p)
                .fold((0.0, 0.0), |(s, u), (r, ur)| (s + r, u + ur));
            (sum / 3.0, u / 3.0)
        };
        Ok(Annex7 {
            arc: name,
            arc_length_m: chosen.length,
            points,
            r,
            r_uncertainty,
            flat,
            greatest_curvature,
        })
    }
}

fn no_centre() -> String {
    "the reflecting surface does not cover its own centre (the arcs through it cannot be \
     laid)"
        .into()
}

fn reading(shape: &LocalShape, along: DVec3, across: DVec3) -> Result<Annex7Point, String> {
    let cut = || "the surface's normal lies in its own plane here".to_string();
    Ok(Annex7Point {
        along: shape.curvature_along(along).ok_or_else(cut)?,
        across: shape.curvature_along(across).ok_or_else(cut)?,
    })
}

/// An arc of the surface through its centre along a plane direction: its samples (plane
/// point, mm) and the arc length up to each, metres.
struct Arc {
    samples: Vec<(DVec2, f64)>,
    length: f64,
}

impl Arc {
    /// The plane point at arc length `s` metres from the arc's start.
    fn at(&self, s: f64) -> DVec2 {
        let k = self
            .samples
            .windows(2)
            .position(|w| w[1].1 >= s)
            .unwrap_or(self.samples.len() - 2);
        let ((a, sa), (b, sb)) = (self.samples[k], self.samples[k + 1]);
        let t = if sb > sa { (s - sa) / (sb - sa) } else { 0.0 };
        a + (b - a) * t.clamp(0.0, 1.0)
    }
}

/// The arc through the plane's centre along `direction`: the covered run of the line through
/// it, walked in 0.25 mm steps, its length along the surface.
fn arc(probe: &Probe, direction: DVec2) -> Option<Arc> {
    let step = 0.25;
    probe.point(DVec2::ZERO)?;
    let reach = |sign: f64| {
        let mut t = 0.0;
        while probe.point(direction * sign * (t + step)).is_some() && t < 10_000.0 {
            t += step;
        }
        t
    };
    let (lo, hi) = (-reach(-1.0), reach(1.0));
    let count = (((hi - lo) / step).round() as usize).max(1);
    let mut samples = Vec::with_capacity(count + 1);
    let mut length = 0.0;
    let mut previous: Option<DVec3> = None;
    for k in 0..=count {
        let q = direction * (lo + (hi - lo) * k as f64 / count as f64);
        let p = probe.point(q)?;
        if let Some(before) = previous {
            length += (p - before).length();
        }
        previous = Some(p);
        samples.push((q, length));
    }
    (samples.len() >= 2).then_some(Arc { samples, length })
}

/// R46's spherical-surface checks on the Annex 7 measurement, and the shape over the whole
/// surface (convex or flat everywhere; outside the spherical main part, an aspherical part
/// where the class allows one).
fn spherical_checks(
    rule: &SphericalRule,
    source: &str,
    probe: &Probe,
    annex7: &Annex7,
) -> Vec<MirrorCheck> {
    let mut checks = vec![convex_or_flat(source, probe, rule.min_radius_m)];
    let (r, ur) = (annex7.r, annex7.r_uncertainty);
    // Flat: no section told from zero, and even at its uncertainty's edge none curved beyond
    // the least radius allowed; flat within a wider uncertainty cannot be told from too curved.
    let flat = annex7
        .flat
        .then_some(annex7.greatest_curvature <= 1.0 / rule.min_radius_m);
    let judged = |outcome: Outcome| match flat {
        Some(true) => Outcome::Pass,
        Some(false) => Outcome::Undecided,
        None => outcome,
    };
    let listed = annex7
        .points
        .iter()
        .map(|p| mm(p.r_p().0))
        .collect::<Vec<_>>()
        .join(", ");
    let arc = format!(
        "r_p at 1/3, 1/2, 2/3 of the arc {} ({:.0} mm long): {listed}",
        annex7.arc,
        annex7.arc_length_m * 1e3
    );
    let margin = r - rule.min_radius_m;
    checks.push(MirrorCheck::new(
        "radius of curvature r",
        source,
        format!("r at least {:.0} mm (or flat)", rule.min_radius_m * 1e3),
        format!("r = {} ± {:.2} mm; {arc}", mm(r), ur * 1e3),
        (r, rule.min_radius_m, margin, ur),
        "m",
        judged(Outcome::of_margin(margin, ur)),
    ));
    // The limit's share by r's least value: 0.25 only where r is surely 3000 mm or more.
    let share = deviation_share(r - ur);
    let limit = share * r;
    let limit_check = |name: &str, required: String, (worst, worst_u): (f64, f64)| {
        let u = worst_u + share * ur;
        MirrorCheck::new(
            name,
            source,
            required,
            format!("largest {} (limit {})", mm(worst), mm(limit)),
            (worst, limit, limit - worst, u),
            "m",
            judged(Outcome::of_margin(limit - worst, u)),
        )
    };
    checks.push(limit_check(
        "r_i, r'_i within the limit of r_p",
        format!("|r_i − r_p| and |r'_i − r_p| at most {share} r at each point"),
        annex7
            .points
            .iter()
            .map(Annex7Point::spread)
            .fold((0.0f64, 0.0f64), worse),
    ));
    checks.push(limit_check(
        "r_p1, r_p2, r_p3 within the limit of r",
        format!("|r_pk − r| at most {share} r"),
        annex7
            .points
            .iter()
            .map(|p| {
                let (rp, u) = p.r_p();
                ((rp - r).abs(), u + ur)
            })
            .fold((0.0f64, 0.0f64), worse),
    ));
    if flat != Some(true) {
        checks.push(aspherical_part(rule, source, probe, annex7));
    }
    checks
}

/// Of two (value, uncertainty) pairs held below a limit, the one that may reach higher (an
/// unknown one, NaN, first: it leaves its check undecided).
fn worse(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    if (b.0 + b.1).total_cmp(&(a.0 + a.1)).is_ge() || (b.0 + b.1).is_nan() {
        b
    } else {
        a
    }
}

/// The surface's shapes over a grid of plane points (15 × 15 over its outline's bounds,
/// those on the surface).
fn shapes_over(probe: &Probe) -> Vec<LocalShape> {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in probe.flat_cells().iter().flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let n = 15;
    let mut shapes = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let t = DVec2::new(i as f64 + 0.5, j as f64 + 0.5) / n as f64;
            if let Some(shape) = probe.shape(lo + (hi - lo) * t) {
                shapes.push(shape);
            }
        }
    }
    shapes
}

/// The least and greatest normal curvature at `shape` over 12 directions of its tangent
/// plane (the principal curvatures to within 1 − cos 7.5° of their spread).
fn extremes(shape: &LocalShape) -> Option<(Curvature, Curvature)> {
    let e1 = shape.n.any_orthonormal_vector();
    let e2 = shape.n.cross(e1);
    let all: Vec<Curvature> = (0..12)
        .filter_map(|k| {
            let a = std::f64::consts::PI * k as f64 / 12.0;
            shape.curvature_along(e1 * a.cos() + e2 * a.sin())
        })
        .collect();
    let least = *all.iter().min_by(|a, b| a.value.total_cmp(&b.value))?;
    let most = *all.iter().max_by(|a, b| a.value.total_cmp(&b.value))?;
    Some((least, most))
}

/// R46 §6.1.2.2: flat or spherically convex: the least normal curvature over the surface
/// (convex-positive) is not below zero; a surface whose every curvature is zero within its
/// uncertainty is flat.
fn convex_or_flat(source: &str, probe: &Probe, min_radius_m: f64) -> MirrorCheck {
    let shapes = shapes_over(probe);
    let least = shapes
        .iter()
        .filter_map(extremes)
        .map(|(least, _)| least)
        .min_by(|a, b| a.value.total_cmp(&b.value));
    let Some(least) = least else {
        return refused(
            "flat or spherically convex",
            source,
            "no point of the surface could be measured".into(),
        );
    };
    // Flat: no curvature told from zero, and none that at its uncertainty's edge passes the
    // least radius allowed either way.
    let flat = shapes.iter().filter_map(extremes).all(|(a, b)| {
        a.is_flat()
            && b.is_flat()
            && (a.value.abs() + a.uncertainty).max(b.value.abs() + b.uncertainty)
                <= 1.0 / min_radius_m
    });
    let (r, _) = least.radius();
    MirrorCheck::new(
        "flat or spherically convex",
        source,
        "no concave normal section anywhere (curvature ≥ 0, convex positive)".into(),
        if flat {
            "flat: no curvature told from zero".into()
        } else if least.value < 0.0 {
            format!("most concave section radius {} (concave)", mm(-r))
        } else {
            format!("least convex section radius {}", mm(r))
        },
        (least.value, 0.0, least.value, least.uncertainty),
        "1/m",
        if flat {
            Outcome::Pass
        } else {
            Outcome::of_margin(least.value, least.uncertainty)
        },
    )
}

/// Outside the spherical main part (where a point's normal-section radii along and across the
/// arc differ from r by more than the deviation limit), the surface is an aspherical part:
/// allowed on exterior mirrors with r_i at least 150 mm, not on interior ones.
fn aspherical_part(
    rule: &SphericalRule,
    source: &str,
    probe: &Probe,
    annex7: &Annex7,
) -> MirrorCheck {
    let (r, ur) = (annex7.r, annex7.r_uncertainty);
    let limit = deviation_share(r) * r;
    let (along, across) = if annex7.arc == "parallel to b" {
        (probe.plane.v, probe.plane.h)
    } else {
        (probe.plane.h, probe.plane.v)
    };
    // Per grid point: its least radius and how far beyond the deviation limit from r it lies.
    let mut aspherical = 0usize;
    let mut total = 0usize;
    let (mut least_radius, mut least_u, mut worst_excess, mut worst_u) =
        (f64::INFINITY, 0.0, f64::NEG_INFINITY, 0.0);
    for shape in shapes_over(probe) {
        let Ok(point) = reading(&shape, along, across) else {
            continue;
        };
        total += 1;
        for c in [point.along, point.across] {
            let (radius, u) = c.radius();
            let excess = (radius - r).abs() - limit;
            if excess + u + ur > worst_excess + worst_u || (excess + u).is_nan() {
                (worst_excess, worst_u) = (excess, u + ur);
            }
            if excess > 0.0 {
                aspherical += 1;
                if radius - u < least_radius - least_u || (radius - u).is_nan() {
                    (least_radius, least_u) = (radius, u);
                }
            }
        }
    }
    if rule.aspherical_part_allowed {
        let margin = least_radius - ASPHERICAL_MIN_RADIUS_M;
        MirrorCheck::new(
            "aspherical part's r_i",
            source,
            format!(
                "where the surface departs from r by more than {} (an aspherical part), r_i at \
                 least {:.0} mm",
                mm(limit),
                ASPHERICAL_MIN_RADIUS_M * 1e3
            ),
            if aspherical == 0 {
                format!("no aspherical part: all {total} points within the limit of r")
            } else {
                format!(
                    "{aspherical} of {} sections outside the spherical part; least r_i {}",
                    2 * total,
                    mm(least_radius)
                )
            },
            (least_radius, ASPHERICAL_MIN_RADIUS_M, margin, least_u),
            "m",
            if aspherical == 0 {
                Outcome::Pass
            } else {
                Outcome::of_margin(margin, least_u)
            },
        )
    } else {
        let margin = -worst_excess;
        MirrorCheck::new(
            "spherical over the whole surface",
            source,
            format!(
                "no aspherical part (an interior mirror): every section within {} of r",
                mm(limit)
            ),
            format!(
                "{aspherical} of {} sections beyond it; the farthest {} beyond",
                2 * total,
                mm(worst_excess.max(0.0))
            ),
            (worst_excess + limit, limit, margin, worst_u),
            "m",
            Outcome::of_margin(margin, worst_u),
        )
    }
}

/// FMVSS 111 S5.2.1: unit magnification, read as no curvature told from zero anywhere.
fn flat_check(source: &str, probe: &Probe) -> MirrorCheck {
    let shapes = shapes_over(probe);
    let worst = shapes
        .iter()
        .filter_map(extremes)
        .flat_map(|(a, b)| [a, b])
        .max_by(|a, b| (a.value.abs() - a.uncertainty).total_cmp(&(b.value.abs() - b.uncertainty)));
    let Some(worst) = worst else {
        return refused(
            "flat (unit magnification)",
            source,
            "no point of the surface could be measured".into(),
        );
    };
    let (r, _) = worst.radius();
    MirrorCheck::new(
        "flat (unit magnification)",
        source,
        "no curvature told from zero anywhere".into(),
        if worst.is_flat() {
            "flat within the measurement".into()
        } else {
            format!("a section of radius {}", mm(r.abs()))
        },
        (
            worst.value.abs(),
            0.0,
            -worst.value.abs(),
            worst.uncertainty,
        ),
        "1/m",
        if worst.is_flat() {
            Outcome::Pass
        } else {
            Outcome::Fail
        },
    )
}

/// FMVSS 111 S12's ten readings: at the centre and the ends of the horizontal and vertical
/// bisectors (25.4 mm in from the edge), along the horizontal and the vertical at each.
pub fn s12_readings(probe: &Probe) -> Result<Vec<Curvature>, String> {
    let inset = 25.4;
    let horizontal = arc(probe, DVec2::X).ok_or_else(no_centre)?;
    let vertical = arc(probe, DVec2::Y).ok_or_else(no_centre)?;
    let ends = |a: &Arc| {
        let (first, last) = (a.samples[0].0, a.samples[a.samples.len() - 1].0);
        let span = (last - first).length();
        (span > 2.0 * inset).then(|| {
            let d = (last - first) / span;
            [first + d * inset, last - d * inset]
        })
    };
    let too_small = || {
        format!(
            "a bisector is shorter than {:.1} mm: S12's end readings (25.4 mm in from each \
             edge) cannot be taken",
            2.0 * inset
        )
    };
    let [left, right] = ends(&horizontal).ok_or_else(too_small)?;
    let [bottom, top] = ends(&vertical).ok_or_else(too_small)?;
    let mut readings = Vec::new();
    for q in [DVec2::ZERO, left, right, bottom, top] {
        let shape = probe
            .shape(q)
            .ok_or_else(|| format!("no surface at the reading point {q:?} mm"))?;
        let point = reading(&shape, probe.plane.h, probe.plane.v)?;
        readings.extend([point.along, point.across]);
    }
    Ok(readings)
}

/// FMVSS 111 S5.4.1 on the ten readings.
fn convex_checks(rule: &ConvexRule, source: &str, readings: &[Curvature]) -> Vec<MirrorCheck> {
    let radii: Vec<(f64, f64)> = readings.iter().map(|c| c.radius()).collect();
    let n = radii.len() as f64;
    let average = radii.iter().map(|r| r.0).sum::<f64>() / n;
    let average_u = radii.iter().map(|r| r.1).sum::<f64>() / n;
    let margin = (average - rule.min_average_m).min(rule.max_average_m - average);
    // The average's bounds from each reading's curvature interval: a reading that may be flat
    // has no upper bound, one surely concave fails the convex mirror outright.
    let concave = readings.iter().any(|c| c.value + c.uncertainty < 0.0);
    let bound = |c: &Curvature, sign: f64| {
        let k = c.value + sign * c.uncertainty;
        if k > 0.0 {
            1.0 / k
        } else {
            f64::INFINITY
        }
    };
    let low = readings.iter().map(|c| bound(c, 1.0)).sum::<f64>() / n;
    let high = readings.iter().map(|c| bound(c, -1.0)).sum::<f64>() / n;
    let average_verdict = if concave || high < rule.min_average_m || low > rule.max_average_m {
        Outcome::Fail
    } else if low >= rule.min_average_m && high <= rule.max_average_m {
        Outcome::Pass
    } else {
        Outcome::Undecided
    };
    let listed = radii.iter().map(|r| mm(r.0)).collect::<Vec<_>>().join(", ");
    let mut checks = vec![MirrorCheck::new(
        "average radius of curvature",
        source,
        format!(
            "between {:.0} and {:.0} mm",
            rule.min_average_m * 1e3,
            rule.max_average_m * 1e3
        ),
        format!(
            "{} ± {:.2} mm over 10 readings: {listed}",
            mm(average),
            average_u * 1e3
        ),
        (
            average,
            if average - rule.min_average_m < rule.max_average_m - average {
                rule.min_average_m
            } else {
                rule.max_average_m
            },
            margin,
            average_u,
        ),
        "m",
        average_verdict,
    )];
    let (worst, worst_u) = radii
        .iter()
        .map(|(r, u)| {
            let share = (r - average).abs() / average;
            (share, (u + average_u) / average)
        })
        .fold((0.0f64, 0.0f64), worse);
    let limit = rule.max_deviation_share;
    checks.push(MirrorCheck::new(
        "readings' deviation from the average",
        source,
        format!("none more than {:.1} % from the average", limit * 100.0),
        format!("largest {:.1} %", worst * 100.0),
        (
            worst * 100.0,
            limit * 100.0,
            (limit - worst) * 100.0,
            worst_u * 100.0,
        ),
        "%",
        if concave || average <= 0.0 {
            Outcome::Fail
        } else {
            Outcome::of_margin(limit - worst, worst_u)
        },
    ));
    checks
}

/// R46 §6.1.2.1: the rectangle and the segment on the reflecting surface as laid in the
/// mirror's plane, each to ± the layout grid's cell; a's uncertainty from r's adds to the
/// rectangle's.
fn rectangle_checks(
    rule: &RectangleRule,
    source: &str,
    probe: &Probe,
    (r, ur): (f64, f64),
) -> Vec<MirrorCheck> {
    let a_of = |r: f64| {
        if r.is_finite() && r > 0.0 {
            rule.a_numerator_mm / (1.0 + 1.0 / r)
        } else if r.is_finite() {
            0.0
        } else {
            rule.a_numerator_mm
        }
    };
    let a = a_of(r);
    let a_u = if ur > 0.0 {
        0.5 * (a_of(r + ur) - a_of((r - ur).max(1e-9))).abs()
    } else {
        0.0
    };
    let outline = Outline::of(probe);
    let mut longest = outline.longest_rectangle_mm(40.0, false);
    if rule.either_way {
        longest = longest.max(outline.longest_rectangle_mm(40.0, true));
    }
    let u = outline.cell_mm + a_u;
    let mut checks = vec![MirrorCheck::new(
        if rule.either_way {
            "rectangle with a 40 mm side"
        } else {
            "rectangle 40 mm high"
        },
        source,
        format!(
            "a = {:.0} / (1 + 1000 / r) = {a:.1} mm long (r = {})",
            rule.a_numerator_mm,
            mm(r)
        ),
        format!(
            "at most {longest:.1} mm long fits (±{:.1} mm)",
            outline.cell_mm
        ),
        (longest, a, longest - a, u),
        "mm",
        Outcome::of_margin(longest - a, u),
    )];
    if let Some(segment_mm) = rule.segment_mm {
        let segment = outline.longest_vertical_mm();
        checks.push(MirrorCheck::new(
            "segment parallel to the height",
            source,
            format!("{segment_mm:.0} mm"),
            format!("{segment:.1} mm (±{:.1} mm)", outline.cell_mm),
            (segment, segment_mm, segment - segment_mm, outline.cell_mm),
            "mm",
            Outcome::of_margin(segment - segment_mm, outline.cell_mm),
        ));
    }
    checks
}

/// The reflecting surface laid in the mirror's plane on a grid of 0.5 mm: columns along the
/// horizontal, rows up. A cell counts when its centre lies on the surface.
struct Outline {
    columns: usize,
    rows: usize,
    covered: Vec<bool>,
    cell_mm: f64,
}

impl Outline {
    fn of(probe: &Probe) -> Outline {
        let cell_mm = 0.5;
        let flat = probe.flat_cells();
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in flat.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let size = ((hi - lo) / cell_mm).ceil();
        let (columns, rows) = (
            size.x.clamp(1.0, 4000.0) as usize,
            size.y.clamp(1.0, 4000.0) as usize,
        );
        let mut covered = vec![false; columns * rows];
        let edge = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
        for t in flat {
            let area = edge(t[0], t[1], t[2]);
            if area == 0.0 {
                continue;
            }
            let tlo = ((t[0].min(t[1]).min(t[2]) - lo) / cell_mm)
                .floor()
                .max(DVec2::ZERO);
            let thi = ((t[0].max(t[1]).max(t[2]) - lo) / cell_mm).ceil();
            for row in tlo.y as usize..(thi.y as usize).min(rows) {
                for column in tlo.x as usize..(thi.x as usize).min(columns) {
                    let p = lo + DVec2::new(column as f64 + 0.5, row as f64 + 0.5) * cell_mm;
                    let w = [
                        edge(t[1], t[2], p),
                        edge(t[2], t[0], p),
                        edge(t[0], t[1], p),
                    ];
                    if w.iter().all(|w| w * area >= 0.0) {
                        covered[row * columns + column] = true;
                    }
                }
            }
        }
        Outline {
            columns,
            rows,
            covered,
            cell_mm,
        }
    }

    fn covered(&self, column: usize, row: usize, transposed: bool) -> bool {
        if transposed {
            self.covered[column * self.columns + row]
        } else {
            self.covered[row * self.columns + column]
        }
    }

    /// The longest rectangle `height_mm` high (sides horizontal and vertical) that fits, mm;
    /// `transposed`: `height_mm` wide and as tall as fits.
    fn longest_rectangle_mm(&self, height_mm: f64, transposed: bool) -> f64 {
        let (columns, rows) = if transposed {
            (self.rows, self.columns)
        } else {
            (self.columns, self.rows)
        };
        let tall = (height_mm / self.cell_mm).ceil() as usize;
        if tall > rows {
            return 0.0;
        }
        // Per column, the run of covered cells ending at each row.
        let mut run = vec![0usize; columns];
        let mut best = 0usize;
        for row in 0..rows {
            for (column, r) in run.iter_mut().enumerate() {
                *r = if self.covered(column, row, transposed) {
                    *r + 1
                } else {
                    0
                };
            }
            let mut length = 0;
            for r in &run {
                length = if *r >= tall { length + 1 } else { 0 };
                best = best.max(length);
            }
        }
        best as f64 * self.cell_mm
    }

    /// The longest vertical segment that fits, mm.
    fn longest_vertical_mm(&self) -> f64 {
        let mut best = 0usize;
        for column in 0..self.columns {
            let mut run = 0;
            for row in 0..self.rows {
                run = if self.covered(column, row, false) {
                    run + 1
                } else {
                    0
                };
                best = best.max(run);
            }
        }
        best as f64 * self.cell_mm
    }
}
