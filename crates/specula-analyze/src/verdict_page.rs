//! The verdict as a report leads with it: a banner (PASS, FAIL or UNDECIDED, the standard, its
//! edition and the eye points judged), a table of every field and check with its value, limit,
//! margin, uncertainty and verdict, and the reason in words for each check that does not pass.
//! The terminal prints the same reasons ([`regulation_reasons`], [`lens_reasons`]).

use crate::figure::html_escape;
use crate::lens::standard::{Check, Verdict as LensVerdict};
use crate::outcome::Outcome;
use crate::regulation::{FieldVerdict, MirrorCheck, Verdict};

/// The page's style for the verdict: a large coloured word.
pub const STYLE: &str = "
.verdict { font-size: 1.4em; padding: 0.6em 1em; margin: 1em 0; border-radius: 6px; }
.verdict b { font-size: 1.6em; margin-right: 0.5em; }
.verdict.pass { background: #d7f0d2; border: 2px solid #2e7d32; }
.verdict.fail { background: #f8d4d2; border: 2px solid #c62828; }
.verdict.undecided { background: #fbebc5; border: 2px solid #b7791f; }
td.pass { color: #2e7d32; font-weight: bold; }
td.fail { color: #c62828; font-weight: bold; }
td.undecided { color: #b7791f; font-weight: bold; }
";

/// The banner: the verdict's word large, what was judged against, and from where.
pub fn banner(outcome: Outcome, against: &str, judged_from: &str) -> String {
    format!(
        "<div class=\"verdict {}\"><b>{}</b> {}<br><small>{}</small></div>\n",
        outcome.lower(),
        outcome.word(),
        html_escape(against),
        html_escape(judged_from)
    )
}

fn cell(outcome: Outcome) -> String {
    format!("<td class=\"{}\">{}</td>", outcome.lower(), outcome.word())
}

/// A number with its unit, four significant digits, plain decimals where they read well.
pub fn number(x: f64, unit: &str) -> String {
    if !x.is_finite() {
        return "–".into();
    }
    let magnitude = if x == 0.0 {
        0
    } else {
        x.abs().log10().floor() as i32
    };
    let digits = (3 - magnitude).clamp(0, 6) as usize;
    let text = if (-4..6).contains(&magnitude) {
        format!("{x:.digits$}")
    } else {
        format!("{x:.3e}")
    };
    if unit.is_empty() {
        text
    } else {
        format!("{text} {unit}")
    }
}

fn percent(share: f64) -> String {
    format!("{:.2} %", share * 100.0)
}

/// A field's share judged (seen, with the body's share where it is under the allowance), its
/// margin and the uncertainty that entered its verdict.
pub(crate) fn field_figures(f: &FieldVerdict, allowance: f64) -> (f64, f64, f64) {
    let g = &f.figures;
    g.judged(
        g.hidden_by_vehicle_share < allowance,
        f.surface_uncertainty.unwrap_or(0.0),
    )
}

/// The regulation's part of a report: the banner, the fields, the mirror's checks, the
/// reasons.
pub fn regulation_html(v: &Verdict, judged_from: &str) -> String {
    let mut html = banner(
        v.verdict,
        &format!("{} ({})", v.title, v.edition),
        judged_from,
    );
    if !v.fields.is_empty() {
        html.push_str(
            "<h2>Fields</h2>\n<table>\n<tr><th>field</th><th>paragraph</th><th>seen or excused</th>\
             <th>limit</th><th>margin</th><th>uncertainty</th><th>hidden by the body</th>\
             <th>beyond the range</th><th>horizon</th><th>verdict</th></tr>\n",
        );
        for f in &v.fields {
            let (share, margin, uncertainty) = field_figures(f, v.allowance_share);
            let g = &f.figures;
            html.push_str(&format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>100 %</td><td>{}</td><td>± {}</td>\
                 <td>{}</td><td>{}</td><td>{}</td>{}</tr>\n",
                html_escape(&f.name),
                html_escape(&f.source),
                percent(share),
                percent(margin),
                percent(uncertainty),
                percent(g.hidden_by_vehicle_share),
                g.beyond_range_seen_share.map_or("–".into(), percent),
                match (g.horizon_seen, g.horizon_loosely_seen) {
                    (None, _) => "–",
                    (Some(true), _) => "seen",
                    (Some(false), Some(true)) => "at the cone's edge",
                    (Some(false), _) => "not seen",
                },
                cell(g.verdict)
            ));
        }
        html.push_str("</table>\n");
    }
    if !v.mirror_checks.is_empty() {
        html.push_str(
            "<h2>The mirror's surface</h2>\n<table>\n<tr><th>check</th><th>paragraph</th>\
             <th>required</th><th>measured</th><th>value</th><th>limit</th><th>margin</th>\
             <th>uncertainty</th><th>verdict</th></tr>\n",
        );
        for c in &v.mirror_checks {
            let n = |x: Option<f64>| x.map_or("–".into(), |x| number(x, c.unit));
            html.push_str(&format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
                 <td>± {}</td>{}</tr>\n",
                html_escape(&c.name),
                html_escape(&c.source),
                html_escape(&c.required),
                html_escape(&c.measured),
                n(c.value),
                number(c.limit, c.unit),
                n(c.margin),
                n(c.uncertainty),
                cell(c.verdict)
            ));
        }
        html.push_str("</table>\n");
    }
    html.push_str(&reasons_html(&regulation_reasons(v)));
    html
}

/// The pose search's part of a report: what the terminal prints of it.
pub fn adjustment_html(a: &crate::regulation::Adjustment) -> String {
    let range =
        |r: Option<[f32; 2]>| r.map_or("none".into(), |[lo, hi]| format!("{lo:+.1}° to {hi:+.1}°"));
    let b = &a.best;
    let best = Outcome::all(a.best_verdict.fields.iter().map(|f| f.figures.verdict));
    format!(
        "<h2>Poses that pass</h2>\n<p>Turning the mirror about ({:.3}, {:.3}, {:.3}), ±{}° in \
         steps of {}°: {} of {} poses pass the fields, confirmed at the command's tolerances; yaw \
         {}, pitch {}. The {} pose: yaw {:+.1}°, pitch {:+.1}°, least share {} ('{}'), least \
         margin {}; its fields at the command's tolerances: <b>{}</b>.</p>\n",
        a.pivot[0],
        a.pivot[1],
        a.pivot[2],
        a.limit_deg,
        a.step_deg,
        a.passing_poses,
        a.poses.len(),
        range(a.passing_yaw_deg),
        range(a.passing_pitch_deg),
        if a.passing_poses > 0 {
            "widest-margin"
        } else {
            "most-seen"
        },
        b.yaw_deg,
        b.pitch_deg,
        percent(b.least_share),
        html_escape(&b.least_share_field),
        number(b.least_margin_m, "m"),
        best.word()
    )
}

fn reasons_html(reasons: &[String]) -> String {
    if reasons.is_empty() {
        return String::new();
    }
    let items: String = reasons
        .iter()
        .map(|r| format!("<li>{}</li>\n", html_escape(r)))
        .collect();
    format!("<h2>Why</h2>\n<ul>\n{items}</ul>\n")
}

/// Each field and check that does not pass, and why, in words.
pub fn regulation_reasons(v: &Verdict) -> Vec<String> {
    let mut reasons = Vec::new();
    for f in v
        .fields
        .iter()
        .filter(|f| f.figures.verdict != Outcome::Pass)
    {
        reasons.push(field_reason(f, v.allowance_share));
    }
    for c in v
        .mirror_checks
        .iter()
        .filter(|c| c.verdict != Outcome::Pass)
    {
        reasons.push(check_reason(c));
    }
    reasons
}

fn field_reason(f: &FieldVerdict, allowance: f64) -> String {
    let g = &f.figures;
    let (share, margin, uncertainty) = field_figures(f, allowance);
    let body = if g.hidden_by_vehicle_share >= allowance {
        format!(
            "; the vehicle's body hides {}, not less than the {} it may hide and be excused, so \
             that part counts as unseen",
            percent(g.hidden_by_vehicle_share),
            percent(allowance)
        )
    } else if g.hidden_by_vehicle_share > 0.0 {
        format!(
            "; the body's {} is excused (under {})",
            percent(g.hidden_by_vehicle_share),
            percent(allowance)
        )
    } else {
        String::new()
    };
    let horizon = match (g.horizon_seen, g.horizon_loosely_seen) {
        (Some(false), Some(true)) => "; the vanishing direction lies at the edge of what the eyes see (within a cell of the cone's grid)",
        (Some(false), _) => "; the vanishing direction (straight back, level) is not seen",
        _ => "",
    };
    let beyond = match g.beyond_range_seen_share {
        Some(s) if s < 1.0 => format!(
            "; beyond the range {} of its directions is seen",
            percent(s)
        ),
        _ => String::new(),
    };
    let verdict = match g.verdict {
        Outcome::Undecided if margin >= 0.0 && horizon.is_empty() && beyond.is_empty() => format!(
            "undecided: all of it is seen, but the share is known only to ± {} (the sampling's \
             last refinement moved it by that much): a smaller `tolerance` may decide it",
            percent(uncertainty)
        ),
        Outcome::Undecided => format!(
            "undecided: {} of it is judged seen, short by {}, within the measurement's ± {}",
            percent(share),
            percent(-margin),
            percent(uncertainty)
        ),
        _ => format!(
            "fails: {} of it is judged seen, {} short of the whole field (± {})",
            percent(share),
            percent(-margin),
            percent(uncertainty)
        ),
    };
    format!(
        "field '{}' ({}) {verdict}{body}{beyond}{horizon}.",
        f.name, f.source
    )
}

fn check_reason(c: &MirrorCheck) -> String {
    let n = |x: Option<f64>| x.map_or("–".into(), |x| number(x, c.unit));
    match c.verdict {
        Outcome::Undecided => format!(
            "{} ({}) is undecided: measured {}; its margin {} lies within the measurement's ± {}.",
            c.name,
            c.source,
            c.measured,
            n(c.margin),
            n(c.uncertainty)
        ),
        _ => format!(
            "{} ({}) fails: required {}; measured {} (margin {}).",
            c.name,
            c.source,
            c.required,
            c.measured,
            n(c.margin)
        ),
    }
}

/// A lens standard's part of a report: the banner, the checks, the reasons.
pub fn lens_html(v: &LensVerdict, r: &crate::lens::Report) -> String {
    let mut html = banner(
        v.verdict,
        v.edition,
        &format!(
            "the focimeter's reading at the distance and prism reference points, against {}",
            ordered_words(r)
        ),
    );
    html.push_str(
        "<table>\n<tr><th>check</th><th>measured</th><th>ordered</th><th>off by</th>\
         <th>tolerance</th><th>margin</th><th>uncertainty</th><th>verdict</th></tr>\n",
    );
    for c in &v.checks {
        html.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>± {}</td><td>{}</td><td>± {}</td>{}</tr>\n",
            check_name(c),
            number(c.measured, c.unit),
            number(c.ordered, c.unit),
            number(c.value, c.unit),
            number(c.limit, c.unit),
            number(c.margin, c.unit),
            number(c.uncertainty, c.unit),
            cell(c.verdict)
        ));
    }
    html.push_str("</table>\n");
    html.push_str(&reasons_html(&lens_reasons(v, r)));
    html
}

fn check_name(c: &Check) -> String {
    match c.meridian {
        Some(m) => format!("{} (meridian {m:.0}°)", c.quantity),
        None => c.quantity.to_string(),
    }
}

/// What the lens is judged against, in words: the prescription, or the compensated order.
fn ordered_words(r: &crate::lens::Report) -> String {
    match (&r.compensated, &r.prescription) {
        (Some(c), _) => format!(
            "the compensated order {:.2} / {:.2} × {:.0}",
            c.ordered.sphere_d, c.ordered.cylinder_d, c.ordered.axis_deg
        ),
        (None, Some(p)) => format!(
            "the prescription {:.2} / {:.2} × {:.0}",
            p.sphere_d, p.cylinder_d, p.axis_deg
        ),
        _ => "the order".into(),
    }
}

/// Each check that does not pass, and why, in words; and, judged against a compensated order
/// the lens was not made to, that.
pub fn lens_reasons(v: &LensVerdict, r: &crate::lens::Report) -> Vec<String> {
    let mut reasons: Vec<String> = v
        .checks
        .iter()
        .filter(|c| c.verdict != Outcome::Pass)
        .map(|c| {
            let what = match c.meridian {
                Some(m) => format!("the measured {} at {m:.0}°", c.quantity),
                None => format!("the measured {}", c.quantity),
            };
            let how = match c.verdict {
                Outcome::Undecided => format!(
                    "undecided: its margin {} lies within the reading's ± {}",
                    number(c.margin, c.unit),
                    number(c.uncertainty, c.unit)
                ),
                _ => format!(
                    "off by {}, beyond the tolerance ± {}",
                    number(c.value, c.unit),
                    number(c.limit, c.unit)
                ),
            };
            format!(
                "{what} is {}, ordered {}: {how}.",
                number(c.measured, c.unit),
                number(c.ordered, c.unit)
            )
        })
        .collect();
    if let (Some(c), false) = (&r.compensated, v.verdict.passed()) {
        let reading = r
            .focimeter
            .first()
            .map(|f| {
                format!(
                    "; the lens reads {:.2} / {:.2} × {:.0} on the focimeter",
                    f.sphere_d, f.cylinder_d, f.axis_deg
                )
            })
            .unwrap_or_default();
        reasons.push(format!(
            "It is judged against the compensated order {:.2} / {:.2} × {:.0}, the lens that \
             gives the prescription as worn{reading}: this lens was not made to that order.",
            c.ordered.sphere_d, c.ordered.cylinder_d, c.ordered.axis_deg
        ));
    }
    reasons
}

#[cfg(test)]
mod tests {
    use super::number;

    #[test]
    fn numbers_read_as_plain_decimals_with_their_units() {
        assert_eq!(number(653.5, "cd/m²"), "653.5 cd/m²");
        assert_eq!(number(0.005974, "sr"), "0.005974 sr");
        assert_eq!(number(1.2, "m"), "1.200 m");
        assert_eq!(number(-0.05255, "D"), "-0.05255 D");
        assert_eq!(number(0.0, "mm"), "0.000 mm");
        assert_eq!(number(1.6e9, "cd/m²"), "1.600e9 cd/m²");
        assert_eq!(number(f64::INFINITY, "m"), "–");
    }
}
