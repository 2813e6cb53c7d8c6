//! glare's report in words: the source and the sun, each eye point's figures, the worst eye
//! point, and a sweep's and a solar day's summary.

pub fn text(r: &super::Report) -> String {
    let mut text = String::new();
    let out = &mut text;
    say!(
        out,
        "{}: '{}' reflected in '{}', {}x{} per eye point",
        r.scene,
        r.source,
        r.surface,
        r.width,
        r.height
    );
    if let Some(sun) = &r.sun {
        say!(
            out,
            "sun at azimuth {:.1}°, elevation {:.1}°{}: {:.0} lx, disc {:.3e} cd/m²",
            sun.azimuth_deg,
            sun.elevation_deg,
            if r.sweep.is_some() {
                " (the sweep's worst position)"
            } else {
                ""
            },
            sun.illuminance_lx,
            sun.luminance_cd_m2
        );
    }
    eyes(out, r);
    let washed = super::washed_out_text(r)
        .map(|w| format!("; {w}"))
        .unwrap_or_default();
    match r.worst_eye {
        Some(k) => say!(
            out,
            "glare seen from {:.0} % of the eye points{washed}; the worst: eye {}",
            r.share_with_glare * 100.0,
            k + 1,
        ),
        None => say!(
            out,
            "no glare: no eye point sees '{}' reflected in '{}'{washed}",
            r.source,
            r.surface
        ),
    }
    if let Some(s) = &r.sweep {
        sweep(out, s);
    }
    std::mem::take(out)
}

fn eyes(out: &mut String, r: &super::Report) {
    say!(
        out,
        "{:<36}{:>6}{:>11}{:>11}{:>11}{:>12}{:>11}{}",
        "eye point",
        "glare",
        "factor",
        "max cd/m²",
        "mean cd/m²",
        "veiling",
        "solid sr",
        if r.display.is_some() {
            format!(
                "{:>8}{:>11}{:>10}{:>9}",
                "τ", "veil cd/m²", "contrast", "washed"
            )
        } else {
            String::new()
        }
    );
    for (k, e) in r.eyes.iter().enumerate() {
        let [x, y, z] = e.position;
        let display = e
            .display
            .as_ref()
            .map(|d| {
                format!(
                    "{:>8.4}{:>11}{:>10.3}{:>8.1}%",
                    d.transmittance,
                    super::luminance_text(Some(d.veiling_luminance_cd_m2)),
                    d.min_contrast,
                    d.washed_out_share * 100.0
                )
            })
            .unwrap_or_default();
        say!(
            out,
            "{:<36}{:>6}{:>11.5}{:>11}{:>11}{:>12}{:>11}{display}",
            format!("eye {} ({x:.3}, {y:.3}, {z:.3})", k + 1),
            if e.glare { "yes" } else { "no" },
            e.max_luminance_factor,
            super::luminance_text(e.max_luminance_cd_m2),
            super::luminance_text(e.mean_luminance_cd_m2),
            super::veiling_text(e.max_veiling_ratio),
            crate::verdict_page::number(e.solid_angle_sr, ""),
        );
    }
    say!(out, "{}", super::VEILING_MEANS);
}

fn sweep(out: &mut String, s: &super::sweep::SweepReport) {
    let glaring = s.positions.iter().filter(|p| p.glare()).count();
    let washed = s.positions.iter().filter(|p| p.washed_out()).count();
    say!(
        out,
        "sweep: {} sun positions, {glaring} glare from some eye point, {washed} wash the \
         display out; traced in {:.2} s, looked up in {:.3} s",
        s.positions.len(),
        s.trace_s,
        s.lookup_s
    );
    if let Some(day) = &s.day {
        say!(
            out,
            "{} at {}° N, heading {}°: glare {}; washed out {} (apparent solar time)",
            day.date,
            day.latitude_deg,
            day.heading_deg,
            super::report::solar_runs(&day.glare_hours),
            super::report::solar_runs(&day.washed_out_hours)
        );
    }
}
