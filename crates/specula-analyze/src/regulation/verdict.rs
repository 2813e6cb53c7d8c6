//! Judging: each field's seen share, the body's share, the margins and the part beyond the
//! range, each with its uncertainty, and the verdict they give; the JSON document.

use super::*;

/// How far beyond a field's outer edge and before its near end the grid reaches, metres (the
/// margins are measured within it).
pub(super) const MARGIN_REACH_M: f64 = 5.0;

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
    pub(super) fn decide(&mut self, allowance: f64, surface_uncertainty: f64) {
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
    pub(super) fn decide(&mut self) {
        self.verdict = Outcome::all(
            self.fields
                .iter()
                .map(|f| f.figures.verdict)
                .chain(self.mirror_checks.iter().map(|c| c.verdict)),
        );
        self.passed = self.verdict.passed();
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

pub(super) fn mean(points: impl Iterator<Item = Vec3>) -> Vec3 {
    let (sum, count) = points.fold((Vec3::ZERO, 0.0), |(s, n), p| (s + p, n + 1.0));
    sum / f32::max(count, 1.0)
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
