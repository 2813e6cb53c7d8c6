//! lens's report in words: the verdict and why, the gaze grid's figures across and down, the
//! magnification, base curve, focimeter readings, ordered prescription, zones and checks.

/// The whole report as the terminal prints it (`focimeter`: the readings too).
pub fn text(r: &super::Report, focimeter: bool) -> String {
    let mut out = String::new();
    if let Some(v) = &r.verdict {
        say!(out, "{}: {}", v.edition, v.verdict.word());
        crate::mirror_view::summary::reasons(&mut out, &crate::verdict_page::lens_reasons(v, r));
    }
    grid(&mut out, r);
    checks(&mut out, r, focimeter);
    out
}

fn grid(out: &mut String, r: &super::Report) {
    let number = |v: Option<f64>, digits: usize| {
        v.map(|v| format!("{v:.digits$}"))
            .unwrap_or_else(|| "outside".into())
    };
    say!(
        out,
        "{}: '{}', {} eye, centre of rotation ({:.4}, {:.4}, {:.4}), object {}",
        r.scene,
        r.lens,
        match r.eye {
            super::Eye::Right => "right",
            super::Eye::Left => "left",
        },
        r.rotation_centre[0],
        r.rotation_centre[1],
        r.rotation_centre[2],
        r.object_distance_m
            .map(|d| format!("at {d} m"))
            .unwrap_or_else(|| "at infinity".into())
    );
    say!(
        out,
        "{:<14}{:>10}{:>10}{:>8}{:>10}{:>16}{:>10}{:>10}",
        "gaze h, v °",
        "sphere D",
        "cyl D",
        "axis °",
        "mean D",
        "prism Δ (h, v)",
        "colour ′",
        "dist. %"
    );
    let h = r.gaze.horizontal();
    let v = r.gaze.vertical();
    // Across the centre row, then down the centre column, every few cells from the centre.
    let every = h.len().max(v.len()).div_ceil(7).max(1) as i64;
    let shown = |values: &[f64], x: f64| {
        let i = values.iter().position(|y| *y == x).unwrap_or(0) as i64;
        (i - (values.len() / 2) as i64) % every == 0
    };
    let across = r
        .grid
        .iter()
        .filter(|c| c.gaze_deg[1] == 0.0 && shown(&h, c.gaze_deg[0]));
    let down = r
        .grid
        .iter()
        .filter(|c| c.gaze_deg[0] == 0.0 && c.gaze_deg[1] != 0.0 && shown(&v, c.gaze_deg[1]));
    for c in across.chain(down) {
        // An axis means nothing without cylinder.
        let axis = c
            .axis_deg
            .filter(|_| c.cylinder_d.is_some_and(|x| x.abs() >= 0.005));
        say!(
            out,
            "{:<14}{:>10}{:>10}{:>8}{:>10}{:>16}{:>10}{:>10}",
            format!("{}, {}", c.gaze_deg[0], c.gaze_deg[1]),
            number(c.sphere_d, 3),
            number(c.cylinder_d, 3),
            if c.outside {
                "outside".into()
            } else {
                axis.map(|a| format!("{a:.0}"))
                    .unwrap_or_else(|| "–".into())
            },
            number(c.mean_power_d, 3),
            c.prism_d
                .map(|[a, b]| format!("{a:.2}, {b:.2}"))
                .unwrap_or_else(|| "outside".into()),
            number(c.lateral_colour_arcmin, 2),
            number(c.distortion_percent, 2),
        );
    }
    let outside = r.grid.iter().filter(|c| c.outside).count();
    say!(out,
        "{} gaze directions, {outside} outside the lens; finite differences changed by at most {:.1e} D",
        r.grid.len(),
        r.finite_difference_change_d
    );
}

/// The lens's magnification, base curve, focimeter readings (with `focimeter`), ordered
/// prescription and verdict.
fn checks(out: &mut String, r: &super::Report, focimeter: bool) {
    let [sh, sv] = r.spectacle_magnification;
    say!(
        out,
        "surface {}{}; vertex distance {:.2} mm, pantoscopic {}°, wrap {}°; spectacle \
         magnification {sh:.4} (h), {sv:.4} (v)",
        r.surface.name(),
        r.surface_uncertainty_d
            .map(|u| format!(" (surface uncertainty {u:.4} D)"))
            .unwrap_or_default(),
        r.vertex_distance_mm,
        r.wear.pantoscopic_deg,
        r.wear.wrap_deg
    );
    if let Some(b) = r.base_curve {
        say!(
            out,
            "base curve {:.2} D in the lens's index, {:.2} D in the 1.53 tooling index",
            b.lens_index_d,
            b.tooling_index_d
        );
    }
    if focimeter {
        for f in &r.focimeter {
            say!(
                out,
                "focimeter at the {} ({:.1}, {:.1} mm): {:.3} / {:.3} × {:.1}, prism {:.3} \
                 out, {:.3} up (± {:.1e} D)",
                f.point,
                f.at_mm[0],
                f.at_mm[1],
                f.sphere_d,
                f.cylinder_d,
                f.axis_deg,
                f.prism_d[0],
                f.prism_d[1],
                f.uncertainty_d
            );
        }
    }
    if let Some(t) = r.target {
        say!(
            out,
            "as worn the wearer should get {:.3} / {:.3} × {:.1}",
            t.sphere_d,
            t.cylinder_d,
            t.axis_deg
        );
    }
    if let Some(c) = r.compensated {
        say!(
            out,
            "compensated, to order: {:.3} / {:.3} × {:.1} (residual {:.1e} D)",
            c.ordered.sphere_d,
            c.ordered.cylinder_d,
            c.ordered.axis_deg,
            c.residual_d
        );
    }
    zones(out, r);
    if let Some(v) = &r.verdict {
        say!(out, "{}: {}", v.edition, v.verdict.word());
        for c in &v.checks {
            say!(out,
                "  {:<10}{:>12}  measured {:>8.3}  ordered {:>8.3}  off by {:.3} of ± {:.3} {}  margin {:>7.3} ± {:.3}  {}{}",
                c.quantity,
                c.meridian
                    .map(|m| format!("at {m:.0}°"))
                    .unwrap_or_default(),
                c.measured,
                c.ordered,
                c.value,
                c.limit,
                c.unit,
                c.margin,
                c.uncertainty,
                c.verdict.word(),
                c.note
                    .as_deref()
                    .map(|n| format!(" ({n})"))
                    .unwrap_or_default()
            );
        }
    }
}

/// The clear zones, a progressive lens's figures and the near figures.
fn zones(out: &mut String, r: &super::Report) {
    for z in &r.clear_zones {
        say!(
            out,
            "clear where {}: {:.0} mm² of lens, {:.4} sr of gaze, {:.1} mm wide through the \
             fitting point",
            z.criterion,
            z.lens_area_mm2,
            z.solid_angle_sr,
            z.horizontal_width_mm
        );
    }
    if let Some(p) = &r.progressive {
        let length = |v: Option<f64>| {
            v.map(|v| format!("{v:.1} mm"))
                .unwrap_or_else(|| "not reached".into())
        };
        say!(
            out,
            "progressive: add {:.3} D measured on the {} (ordered {:.2}; far {:.3}, near {:.3} \
             D; as worn {:.3} D); corridor length {} (85 %), {} (95 %); corridor width {} \
             (0.50 D), {} (1.00 D); far zone {:.1} mm, near zone {:.1} mm wide (0.50 D); \
             largest unwanted cylinder {:.2} D at ({:.1}, {:.1}) mm",
            p.add_d,
            p.measured_on,
            p.ordered_add_d,
            p.far_power_d,
            p.near_power_d,
            p.map_add_d,
            length(p.corridor_length_mm_85),
            length(p.corridor_length_mm_95),
            length(p.corridor_width_mm_050),
            length(p.corridor_width_mm_100),
            p.far_zone_width_mm_050,
            p.near_zone_width_mm_050,
            p.max_unwanted_cylinder_d,
            p.max_unwanted_cylinder_at_mm[0],
            p.max_unwanted_cylinder_at_mm[1]
        );
    }
    if let Some(n) = &r.near {
        let c = &n.cell;
        say!(
            out,
            "near point {:.3} m away, {:.1}° down (PD {:.0} mm): through the lens at ({:.2}, \
             {:.2}) mm, inset {:.2} mm; power {} D for the object's {:.3} D (error {} D, \
             unwanted cylinder {} D), prism {}",
            n.distance_m,
            n.down_deg,
            n.pd_mm,
            n.point_on_lens_mm[0],
            n.point_on_lens_mm[1],
            n.inset_mm,
            n.power_d
                .map_or_else(|| "outside".into(), |p| format!("{p:.3}")),
            n.object_vergence_d,
            c.power_error_d
                .map_or_else(|| "–".into(), |v| format!("{v:.3}")),
            c.unwanted_cylinder_d
                .map_or_else(|| "–".into(), |v| format!("{v:.3}")),
            c.prism_d
                .map(|[a, b]| format!("{a:.2} Δ out, {b:.2} Δ up"))
                .unwrap_or_else(|| "–".into())
        );
    }
}
