//! mirror-view's report in words: the figures per eye point, and with a regulation the
//! verdict, its fields and mirror checks, why it is not a pass, and the pose search.

use crate::outcome::Outcome;
use crate::verdict_page;

use super::analysis::MirrorViewResult;

/// The whole report as the terminal prints it (`median_assumed`: no median plane was given).
pub fn text(result: &MirrorViewResult, median_assumed: bool) -> String {
    let mut out = String::new();
    for warning in &result.view.report.warnings {
        say!(out, "warning: {warning}");
    }
    match &result.regulation {
        None => mirror_view(&mut out, &result.view.report),
        Some(j) => {
            verdict(
                &mut out,
                &j.document(&result.view),
                &j.request.vehicle,
                median_assumed,
            );
            if let Some(a) = &j.adjustment {
                adjustment(&mut out, a);
            }
        }
    }
    out
}

fn share(value: Option<f64>) -> String {
    value
        .map(|v| format!("{:.1} %", v * 100.0))
        .unwrap_or_else(|| "-".into())
}

fn mirror_view(out: &mut String, r: &super::Report) {
    say!(
        out,
        "{}: mirror '{}', ground y = {} m, range {} m{}",
        r.scene,
        r.mirror,
        r.ground_y,
        r.range_m,
        r.region
            .map(|g| format!(", region x {}..{}, z {}..{}", g.x0, g.x1, g.z0, g.z1))
            .unwrap_or_default()
    );
    say!(
        out,
        "{:<28}{:>10}{:>10}{:>12}{:>12}{:>10}{:>10}{:>12}",
        "eye point",
        "horiz °",
        "vert °",
        "solid sr",
        "ground m²",
        "region",
        "blind m²",
        "samples/m²"
    );
    let mut row = |label: String, f: &super::Figures, density: String| {
        say!(
            out,
            "{label:<28}{:>10.2}{:>10.2}{:>12.5}{:>12.2}{:>10}{:>10}{:>12}",
            f.horizontal_deg,
            f.vertical_deg,
            f.solid_angle_sr,
            f.ground_area_m2,
            share(f.region_seen_by_any),
            f.blind_area_m2
                .map(|b| format!("{b:.2}"))
                .unwrap_or_else(|| "-".into()),
            density
        )
    };
    for eye in &r.eyes {
        let [x, y, z] = eye.position;
        row(
            format!("({x:.3}, {y:.3}, {z:.3})"),
            &eye.figures,
            format!(
                "{:.0}{}",
                eye.density_per_m2,
                if eye.converged {
                    ""
                } else {
                    " (not converged)"
                }
            ),
        );
    }
    if r.eyes.len() > 1 {
        row("all eye points (any)".into(), &r.figures, String::new());
        say!(
            out,
            "region seen by every eye point: {}",
            share(r.figures.region_seen_by_all)
        );
    }
}

fn verdict(
    out: &mut String,
    document: &crate::regulation::Document,
    vehicle: &crate::regulation::Vehicle,
    median_assumed: bool,
) {
    let v = document.regulation;
    say!(
        out,
        "{} ({}): {}",
        v.title,
        v.edition,
        match v.verdict {
            Outcome::Pass => "PASSES",
            Outcome::Fail => "FAILS",
            Outcome::Undecided => "UNDECIDED (a margin within its uncertainty)",
        }
    );
    say!(out, "{}", document.judged_from());
    let [x, y, z] = vehicle.reference.to_array();
    say!(
        out,
        "fields from ({x:.3}, {y:.3}, {z:.3}), {} side{}; the body may hide {:.0} % unexcused",
        match vehicle.side {
            crate::regulation::Side::Left => "left",
            crate::regulation::Side::Right => "right",
        },
        if median_assumed {
            ", median plane through the ocular points (give --median)"
        } else {
            ""
        },
        v.allowance_share * 100.0
    );
    say!(
        out,
        "{:<46}{:>9}{:>9}{:>9}{:>10}{:>9}{:>9}{:>9}  verdict",
        "field",
        "seen",
        "±",
        "body",
        "blind m²",
        "beyond",
        "horizon",
        "margin"
    );
    for f in &v.fields {
        let g = &f.figures;
        say!(
            out,
            "{:<46}{:>9}{:>9}{:>9}{:>10.2}{:>9}{:>9}{:>9}  {}",
            f.name,
            format!("{:.2} %", g.seen_share * 100.0),
            format!(
                "{:.2} %",
                (g.seen_share_uncertainty + f.surface_uncertainty.unwrap_or(0.0)) * 100.0
            ),
            format!("{:.2} %", g.hidden_by_vehicle_share * 100.0),
            g.blind_area_m2,
            g.beyond_range_seen_share
                .map(|s| format!("{:.1} %", s * 100.0))
                .unwrap_or_else(|| "-".into()),
            g.horizon_seen
                .map(|h| if h { "seen" } else { "NOT" }.to_string())
                .unwrap_or_else(|| "-".into()),
            format!("{:.2} m", g.outer_margin_m.min(g.near_margin_m)),
            g.verdict.word()
        );
        if let Some(w) = &f.worst_eye {
            let [x, y, z] = w.position;
            say!(
                out,
                "    worst eye point ({x:.3}, {y:.3}, {z:.3}): {:.2} % seen",
                w.seen_share * 100.0
            );
        }
    }
    for c in &v.mirror_checks {
        let number =
            |x: Option<f64>| x.map_or_else(|| "-".to_string(), |x| verdict_page::number(x, ""));
        say!(
            out,
            "mirror: {} ({}): required {}; measured {}; value {} {unit}, limit {} {unit}, \
             margin {} ± {} {unit}: {}",
            c.name,
            c.source,
            c.required,
            c.measured,
            number(c.value),
            verdict_page::number(c.limit, ""),
            number(c.margin),
            number(c.uncertainty),
            c.verdict.word(),
            unit = c.unit,
        );
    }
    reasons(out, &verdict_page::regulation_reasons(v));
}

/// Why a verdict is not a pass, a line each.
pub(crate) fn reasons(out: &mut String, reasons: &[String]) {
    if !reasons.is_empty() {
        say!(out, "why:");
        for reason in reasons {
            say!(out, "  - {reason}");
        }
    }
}

fn adjustment(out: &mut String, a: &crate::regulation::Adjustment) {
    let range = |r: Option<[f32; 2]>| {
        r.map(|[lo, hi]| format!("{lo:+.1}° to {hi:+.1}°"))
            .unwrap_or_else(|| "none".into())
    };
    say!(out,
        "adjustment about ({:.3}, {:.3}, {:.3}), ±{}° in steps of {}°: {} of {} poses pass the fields (confirmed at the command's tolerances); yaw {}, pitch {}",
        a.pivot[0],
        a.pivot[1],
        a.pivot[2],
        a.limit_deg,
        a.step_deg,
        a.passing_poses,
        a.poses.len(),
        range(a.passing_yaw_deg),
        range(a.passing_pitch_deg)
    );
    let b = &a.best;
    say!(out,
        "{} pose: yaw {:+.1}°, pitch {:+.1}°: least share {:.2} % ('{}'), least margin {:.2} m; at the command's tolerance its fields {}",
        if a.passing_poses > 0 { "widest-margin" } else { "most-seen" },
        b.yaw_deg,
        b.pitch_deg,
        b.least_share * 100.0,
        b.least_share_field,
        b.least_margin_m,
        Outcome::all(a.best_verdict.fields.iter().map(|f| f.figures.verdict)).lower()
    );
}
