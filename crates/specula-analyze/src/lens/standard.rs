//! A lens's focimeter reading against the tolerances of a spectacle-lens standard, for a
//! finished uncut single-vision lens. The tables are data ([`STANDARDS`]), each value with the
//! edition it comes from; docs/analyses/lens.md says which of them could be checked against a text
//! and which could not.
//!
//! - **ANSI Z80.1-2015** (its published quick reference; the standard's own table numbers
//!   were not seen): the principal meridian of highest absolute power ±0.13 D from −6.50 to
//!   +6.50 D, ±2 % beyond; cylinder ±0.13 D up to 2.00 D, ±0.15 D over 2.00 to 4.50 D, ±4 %
//!   above; axis by cylinder ±14° (0.12 to 0.25 D), ±7° (to 0.50), ±5° (to 0.75), ±3° (to
//!   1.50), ±2° (above), none below 0.12 D; prism at the prism reference point 0.33 Δ, or the
//!   point with the ordered prism within 1.0 mm of it. Each band includes its upper edge.
//! - **ISO 8980-1:2017**, Table 1 as commonly reproduced: tolerance A on each principal
//!   meridian and B on the cylinder, by the highest meridian's absolute power (B also by the
//!   cylinder); the axis by cylinder (±16 / 9 / 6 / 4 / 3°); prism ±(0.25 + 0.1 S_max) Δ up
//!   to 2 Δ, ±(0.37 + 0.1 S_max) Δ over 2 to 10 Δ, ±(0.50 + 0.1 S_max) Δ over 10 Δ, by the
//!   ordered prism (S_max the highest meridian's absolute power). None of these could be
//!   confirmed against the standard's text.
//!
//! Bands are taken by the ordered values, each including its upper edge. A check's value is
//! |measured − ordered|, its limit the tolerance, its margin tolerance − value (negative:
//! failed by that much); it passes when the margin is at least the measurement's uncertainty,
//! fails when it is below minus it, and is undecided between ([`Outcome`]). Prism is checked
//! as the magnitude of the prism vector's error.

use serde::Serialize;

use super::focimeter::Reading;
use super::wear::Rx;
use crate::outcome::Outcome;

/// A tolerance: a fixed value, or a share of the ordered value's magnitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    Dioptres(f64),
    Percent(f64),
}

impl Tolerance {
    fn of(self, ordered: f64) -> f64 {
        match self {
            Tolerance::Dioptres(d) => d,
            Tolerance::Percent(p) => p * 0.01 * ordered.abs(),
        }
    }
}

/// A banded table: `(upper edge, value)` rows by increasing edge, each including its edge.
type Bands<T> = &'static [(f64, T)];

fn band<T: Copy>(rows: Bands<T>, x: f64) -> T {
    // The tables are quoted to 0.01 D: a rounding past an edge is still the edge.
    let x = x.abs() - 1e-9;
    rows.iter()
        .find(|(edge, _)| x <= *edge)
        .map_or(rows[rows.len() - 1].1, |(_, v)| *v)
}

/// One standard's tolerances.
#[derive(Debug)]
pub struct Table {
    pub id: &'static str,
    pub edition: &'static str,
    /// Where the values come from, and what of them was confirmed.
    pub source: &'static str,
    /// Which principal meridians the power tolerance applies to.
    pub meridians: MeridianRule,
    /// The power tolerance by the highest meridian's absolute power.
    pub power: Bands<Tolerance>,
    /// The cylinder tolerance: by the highest meridian's absolute power, then by cylinder.
    pub cylinder: Bands<Bands<Tolerance>>,
    /// Cylinders below this have no axis tolerance.
    pub axis_from_cylinder_d: f64,
    pub axis_deg: Bands<f64>,
    pub prism: PrismRule,
    /// A progressive lens's addition tolerance by the ordered add (empty: a single-vision
    /// table).
    pub add: Bands<Tolerance>,
    /// The same standard's table for progressive lenses, where it has one apart.
    pub progressive: Option<&'static Table>,
}

impl Table {
    pub fn is_progressive(&self) -> bool {
        !self.add.is_empty()
    }
}

/// ANSI Z80.1-2015's progressive addition lens tolerances (its quick reference's Table 2).
const ANSI_PAL: Table = Table {
    id: "ansi-z80.1",
    edition: "ANSI Z80.1-2015 (progressive addition lenses)",
    source: "ANSI Z80.1-2015's progressive addition lens table as its published quick \
             reference states it: sphere ±0.16 D to ±8.00 D, ±2 % beyond; cylinder ±0.16 D to \
             2.00 D, ±0.18 D to 3.50 D, ±5 % beyond; add ±0.12 D to 4.00 D, ±0.18 D beyond; \
             axis and prism as for single vision",
    meridians: MeridianRule::Highest,
    power: &[
        (8.00, Tolerance::Dioptres(0.16)),
        (INF, Tolerance::Percent(2.0)),
    ],
    cylinder: &[(
        INF,
        &[
            (2.00, Tolerance::Dioptres(0.16)),
            (3.50, Tolerance::Dioptres(0.18)),
            (INF, Tolerance::Percent(5.0)),
        ],
    )],
    axis_from_cylinder_d: 0.12,
    axis_deg: ANSI_AXIS,
    prism: PrismRule::FixedOrWithin {
        prism_d: 0.33,
        within_mm: 1.0,
    },
    add: &[
        (4.00, Tolerance::Dioptres(0.12)),
        (INF, Tolerance::Dioptres(0.18)),
    ],
    progressive: None,
};

const ANSI_AXIS: Bands<f64> = &[
    (0.25, 14.0),
    (0.50, 7.0),
    (0.75, 5.0),
    (1.50, 3.0),
    (INF, 2.0),
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeridianRule {
    /// ANSI Z80.1: the meridian of highest absolute power.
    Highest,
    /// ISO 8980-1: each principal meridian.
    Each,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PrismRule {
    /// A fixed tolerance, or the point with the ordered prism within `within_mm` of the
    /// prism reference point.
    FixedOrWithin { prism_d: f64, within_mm: f64 },
    /// base + per_dioptre × S_max, the base by the ordered prism's magnitude.
    ByPower {
        base_d: Bands<f64>,
        per_dioptre: f64,
    },
}

/// ISO 8980-1's prism tolerance's base by the ordered prism (Δ).
const ISO_PRISM_BASE: Bands<f64> = &[(2.00, 0.25), (10.00, 0.37), (INF, 0.50)];

const INF: f64 = f64::INFINITY;

/// The ids of [`STANDARDS`], in order (the `standard` option's choices; a test holds the two
/// lists equal).
pub const NAMES: &[&str] = &["ansi-z80.1", "iso-8980-1", "iso-8980-2"];

pub const STANDARDS: &[Table] = &[
    Table {
        id: "ansi-z80.1",
        edition: "ANSI Z80.1-2015",
        source: "ANSI Z80.1-2015 as its published quick reference states it (sphere, \
                 cylinder, axis and prism tolerances; a later edition, Z80.1-2020, could not be \
                 read)",
        meridians: MeridianRule::Highest,
        power: &[
            (6.50, Tolerance::Dioptres(0.13)),
            (INF, Tolerance::Percent(2.0)),
        ],
        cylinder: &[(
            INF,
            &[
                (2.00, Tolerance::Dioptres(0.13)),
                (4.50, Tolerance::Dioptres(0.15)),
                (INF, Tolerance::Percent(4.0)),
            ],
        )],
        axis_from_cylinder_d: 0.12,
        axis_deg: ANSI_AXIS,
        prism: PrismRule::FixedOrWithin {
            prism_d: 0.33,
            within_mm: 1.0,
        },
        add: &[],
        progressive: Some(&ANSI_PAL),
    },
    Table {
        id: "iso-8980-1",
        edition: "ISO 8980-1:2017",
        source: "ISO 8980-1:2017 Table 1 (tolerances A and B), the axis and prism tolerances, \
                 as commonly reproduced: not confirmed against the standard's text",
        meridians: MeridianRule::Each,
        power: ISO_POWER,
        cylinder: ISO_CYLINDER,
        axis_from_cylinder_d: 0.12,
        axis_deg: ISO_AXIS,
        prism: PrismRule::ByPower {
            base_d: ISO_PRISM_BASE,
            per_dioptre: 0.1,
        },
        add: &[],
        progressive: None,
    },
    Table {
        id: "iso-8980-2",
        edition: "ISO 8980-2:2017",
        source: "ISO 8980-2 (progressive power lenses): the distance power by ISO 8980-1's \
                 tolerances, to which its 1997 edition refers, and the addition ±0.12 D to \
                 4.00 D, ±0.18 D beyond, as commonly reproduced: none confirmed against the \
                 standard's text",
        meridians: MeridianRule::Each,
        power: ISO_POWER,
        cylinder: ISO_CYLINDER,
        axis_from_cylinder_d: 0.12,
        axis_deg: ISO_AXIS,
        prism: PrismRule::ByPower {
            base_d: ISO_PRISM_BASE,
            per_dioptre: 0.1,
        },
        add: &[
            (4.00, Tolerance::Dioptres(0.12)),
            (INF, Tolerance::Dioptres(0.18)),
        ],
        progressive: None,
    },
];

const ISO_POWER: Bands<Tolerance> = &[
    (3.00, Tolerance::Dioptres(0.12)),
    (6.00, Tolerance::Dioptres(0.12)),
    (9.00, Tolerance::Dioptres(0.12)),
    (12.00, Tolerance::Dioptres(0.18)),
    (20.00, Tolerance::Dioptres(0.25)),
    (INF, Tolerance::Dioptres(0.37)),
];

const ISO_CYLINDER: Bands<Bands<Tolerance>> = &[
    (
        3.00,
        // The table has no entry over 6.00 D of cylinder here; the next row's is used.
        &[
            (0.75, Tolerance::Dioptres(0.09)),
            (4.00, Tolerance::Dioptres(0.12)),
            (6.00, Tolerance::Dioptres(0.18)),
            (INF, Tolerance::Dioptres(0.25)),
        ],
    ),
    (
        6.00,
        &[
            (0.75, Tolerance::Dioptres(0.12)),
            (4.00, Tolerance::Dioptres(0.12)),
            (6.00, Tolerance::Dioptres(0.18)),
            (INF, Tolerance::Dioptres(0.25)),
        ],
    ),
    (
        9.00,
        &[
            (0.75, Tolerance::Dioptres(0.12)),
            (4.00, Tolerance::Dioptres(0.18)),
            (6.00, Tolerance::Dioptres(0.18)),
            (INF, Tolerance::Dioptres(0.25)),
        ],
    ),
    (
        12.00,
        &[
            (0.75, Tolerance::Dioptres(0.12)),
            (4.00, Tolerance::Dioptres(0.18)),
            (6.00, Tolerance::Dioptres(0.18)),
            (INF, Tolerance::Dioptres(0.25)),
        ],
    ),
    (
        20.00,
        &[
            (0.75, Tolerance::Dioptres(0.18)),
            (4.00, Tolerance::Dioptres(0.25)),
            (6.00, Tolerance::Dioptres(0.25)),
            (INF, Tolerance::Dioptres(0.25)),
        ],
    ),
    (
        INF,
        &[
            (0.75, Tolerance::Dioptres(0.25)),
            (4.00, Tolerance::Dioptres(0.25)),
            (6.00, Tolerance::Dioptres(0.37)),
            (INF, Tolerance::Dioptres(0.37)),
        ],
    ),
];

const ISO_AXIS: Bands<f64> = &[
    (0.25, 16.0),
    (0.50, 9.0),
    (0.75, 6.0),
    (1.50, 4.0),
    (INF, 3.0),
];

/// The standard named `id`; an unknown one lists the valid ones.
pub fn find(id: &str) -> Result<&'static Table, String> {
    STANDARDS.iter().find(|t| t.id == id).ok_or_else(|| {
        let valid: Vec<&str> = STANDARDS.iter().map(|t| t.id).collect();
        format!(
            "unknown standard '{id}'; the standards are: {}",
            valid.join(", ")
        )
    })
}

/// One check of a verdict.
#[derive(Clone, Debug, Serialize)]
pub struct Check {
    /// "sphere" (a principal meridian's power), "cylinder", "axis", "prism" or "add".
    pub quantity: &'static str,
    /// The ordered meridian a sphere check is on, TABO degrees.
    pub meridian: Option<f64>,
    pub measured: f64,
    pub ordered: f64,
    pub tolerance: f64,
    /// The value held to the limit, |measured − ordered| (prism: the prism vector's error), and
    /// the limit, the tolerance; all in `unit`: D, ° or Δ.
    pub value: f64,
    pub limit: f64,
    pub unit: &'static str,
    pub margin: f64,
    pub verdict: Outcome,
    pub passed: bool,
    /// How far the measured value may be off (the focimeter's finite differences and, for a
    /// mesh, its surface), in the check's unit.
    pub uncertainty: f64,
    /// Why a check passed otherwise (ANSI's prism reference point within 1.0 mm).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    pub standard: &'static str,
    pub edition: &'static str,
    /// The worst of the checks' verdicts.
    pub verdict: Outcome,
    pub passed: bool,
    pub checks: Vec<Check>,
}

impl Verdict {
    fn new(table: &Table, checks: Vec<Check>) -> Verdict {
        let verdict = Outcome::all(checks.iter().map(|c| c.verdict));
        Verdict {
            standard: table.id,
            edition: table.edition,
            verdict,
            passed: verdict.passed(),
            checks,
        }
    }
}

/// A check's verdict: the tables are to 0.01 D and 1°, so a margin rounding left a hair below
/// zero is on the edge.
fn decide(margin: f64, uncertainty: f64) -> Outcome {
    Outcome::of_margin(margin + 1e-9, uncertainty)
}

fn check(
    quantity: &'static str,
    meridian: Option<f64>,
    measured: f64,
    ordered: f64,
    tolerance: f64,
    uncertainty: f64,
) -> Check {
    let value = (measured - ordered).abs();
    let margin = tolerance - value;
    let verdict = decide(margin, uncertainty);
    Check {
        quantity,
        meridian,
        measured,
        ordered,
        tolerance,
        value,
        limit: tolerance,
        unit: match quantity {
            "axis" => "°",
            "prism" => "Δ",
            _ => "D",
        },
        margin,
        verdict,
        passed: verdict.passed(),
        uncertainty,
        note: None,
    }
}

/// The difference of two axes, degrees in (−90, 90].
fn axis_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    if d > 90.0 {
        d - 180.0
    } else {
        d
    }
}

/// The measured principal meridian nearest to the ordered meridian `angle` (the measured
/// axis's where the ordered lens has no cylinder to orient it).
fn measured_meridian(measured: &Rx, ordered: &Rx, which: usize) -> (f64, f64) {
    let m = measured.meridians();
    if ordered.cylinder_d.abs() < 1e-9 {
        return m[which];
    }
    let angle = ordered.meridians()[which].0;
    if axis_difference(m[0].0, angle).abs() <= axis_difference(m[1].0, angle).abs() {
        m[0]
    } else {
        m[1]
    }
}

/// `table`'s verdict on a lens whose focimeter reads `distance` at the distance reference point
/// and `prism` at the prism reference point, ordered as `ordered`.
pub fn judge(table: &Table, distance: &Reading, prism: &Reading, ordered: &Rx) -> Verdict {
    let ordered = ordered.minus_cylinder();
    let measured = distance.rx();
    let meridians = ordered.meridians();
    let highest = if meridians[0].1.abs() >= meridians[1].1.abs() {
        0
    } else {
        1
    };
    let s_max = meridians[highest].1.abs();
    let u = distance.uncertainty_d;
    let mut checks = Vec::new();
    let which: Vec<usize> = match table.meridians {
        MeridianRule::Highest => vec![highest],
        MeridianRule::Each => vec![0, 1],
    };
    for k in which {
        let (angle, power) = meridians[k];
        let tolerance = band(table.power, s_max).of(power);
        let (_, got) = measured_meridian(&measured, &ordered, k);
        checks.push(check("sphere", Some(angle), got, power, tolerance, u));
    }
    let cylinder = band(band(table.cylinder, s_max), ordered.cylinder_d).of(ordered.cylinder_d);
    checks.push(check(
        "cylinder",
        None,
        measured.cylinder_d,
        ordered.cylinder_d,
        cylinder,
        u,
    ));
    if ordered.cylinder_d.abs() >= table.axis_from_cylinder_d - 1e-9 {
        let tolerance = band(table.axis_deg, ordered.cylinder_d);
        let difference = axis_difference(measured.axis_deg, ordered.axis_deg);
        checks.push(check(
            "axis",
            None,
            ordered.axis_deg + difference,
            ordered.axis_deg,
            tolerance,
            distance.axis_uncertainty_deg,
        ));
    }
    checks.push(prism_check(table, prism, &ordered, s_max));
    Verdict::new(table, checks)
}

/// A progressive lens's verdict: [`judge`] on the distance power and prism, and the measured
/// add against the ordered one.
pub fn judge_progressive(
    table: &Table,
    distance: &Reading,
    prism: &Reading,
    ordered: &Rx,
    measured_add_d: f64,
    ordered_add_d: f64,
    add_uncertainty_d: f64,
) -> Verdict {
    let mut checks = judge(table, distance, prism, ordered).checks;
    let tolerance = band(table.add, ordered_add_d).of(ordered_add_d);
    checks.push(check(
        "add",
        None,
        measured_add_d,
        ordered_add_d,
        tolerance,
        add_uncertainty_d,
    ));
    Verdict::new(table, checks)
}

fn prism_check(table: &Table, prism: &Reading, ordered: &Rx, s_max: f64) -> Check {
    let error = [
        prism.prism_d[0] - ordered.prism_d[0],
        prism.prism_d[1] - ordered.prism_d[1],
    ];
    let magnitude = |p: [f64; 2]| p[0].hypot(p[1]);
    let tolerance = match table.prism {
        PrismRule::FixedOrWithin { prism_d, .. } => prism_d,
        PrismRule::ByPower {
            base_d,
            per_dioptre,
        } => band(base_d, magnitude(ordered.prism_d)) + per_dioptre * s_max,
    };
    let mut c = check(
        "prism",
        None,
        magnitude(prism.prism_d),
        magnitude(ordered.prism_d),
        tolerance,
        prism.prism_uncertainty_d,
    );
    c.value = magnitude(error);
    c.margin = tolerance - c.value;
    c.verdict = decide(c.margin, c.uncertainty);
    c.passed = c.verdict.passed();
    if let (false, PrismRule::FixedOrWithin { within_mm, .. }) = (c.passed, table.prism) {
        if let Some(offset) = prism.ordered_prism_offset_mm(ordered.prism_d) {
            if offset <= within_mm + 1e-9 {
                c.verdict = Outcome::Pass;
                c.passed = true;
                c.note = Some(format!(
                    "the ordered prism is {offset:.2} mm from the prism reference point (within \
                     {within_mm} mm)"
                ));
            } else {
                c.note = Some(format!(
                    "the ordered prism is {offset:.2} mm from the prism reference point (more \
                     than {within_mm} mm)"
                ));
            }
        }
    }
    c
}
