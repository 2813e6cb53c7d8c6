//! The panel's analysis section: the analysis (off, or any of the registry), its options (the
//! controls made from their declarations, as the command's flags and a script's keys are),
//! the figures as they arrive, the verdict, and for glare the eye points' heat map (click a
//! cell to show that eye point's glare over the view).

use egui::{Color32, RichText};
use specula_analyze::outcome::Outcome;
use specula_analyze::regulation::Verdict;
use specula_params::{OptionSpec, ParamKind};
use specula_scene::Scene;

use specula_analyze::glare::analysis::GlareResult;
use specula_analyze::mirror_view::analysis::MirrorViewResult;

use crate::analysis::{Analysis, Settings};
use crate::app::UiState;
use crate::session::Session;

/// The main panel's section: the analysis (off, or one of the registry's).
pub fn show(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    let current = session.analysis.as_ref().map(|a| a.settings.name());
    ui.horizontal_wrapped(|ui| {
        if ui.selectable_label(current.is_none(), "off").clicked() {
            session.analysis = None;
        }
        for name in crate::analysis::names() {
            if ui.selectable_label(current == Some(name), name).clicked() && current != Some(name) {
                match Settings::first(session.scene(), name) {
                    Some(settings) => session.analysis = Some(Analysis::new(settings)),
                    None => {
                        state.message = Some((
                            true,
                            format!("{name}: this scene has nothing this analysis can take"),
                        ))
                    }
                }
            }
        }
    });
    ui.small(match current {
        None => {
            "mirror-view: the ground seen in a mirror, drawn on the ground; glare: where a source \
             is seen reflected in a surface, drawn on it; lens: a spectacle lens's mean power or \
             cylinder as worn, drawn on the lens. All follow every move."
        }
        Some(_) => "its options (as `specula analyze` takes them) and figures follow",
    });
}

/// The analysis's details (below its kind, while one is on): its options, the figures as they
/// arrive, the glare's eye point map, and a button to the view that shows the result whole.
pub fn details(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    if session.analysis.is_none() {
        return;
    }
    ui.separator();
    contents(ui, session, state);
}

fn contents(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    let view_eye = session.camera.camera().eye;
    let names: Vec<String> = {
        let scene: &Scene = session.scene();
        let mut names: Vec<String> = Vec::new();
        for m in &scene.meshes {
            if !names.contains(&m.name) {
                names.push(m.name.clone());
            }
        }
        names
    };
    let analysis = session.analysis.as_mut().expect("checked above");
    if analysis.busy() {
        ui.horizontal(|ui| {
            ui.spinner();
            if ui
                .button("cancel")
                .on_hover_text("stop the running analysis; the figures shown stay")
                .clicked()
            {
                analysis.cancel();
            }
        });
    }
    figures_section(ui, analysis);
    ui.separator();
    if let Some(message) = options_section(ui, analysis, &names, view_eye) {
        state.message = Some((true, message));
    }
    if ui
        .button("look at the result")
        .on_hover_text(
            "mirror view: from above the fields or the ground seen; glare: from the eye point \
             shown; lens: from the eye's centre of rotation along the primary gaze",
        )
        .clicked()
    {
        if let Some(camera) = analysis.overview(session.camera.fov_y_deg) {
            session.camera = crate::orbit::OrbitCamera::from_camera(&camera);
            state.dirty = true;
        }
    }
}

/// Every option of the analysis, grouped as the command's help groups them, each control made
/// from its declaration; returns why a change was refused.
fn options_section(
    ui: &mut egui::Ui,
    analysis: &mut Analysis,
    names: &[String],
    view_eye: glam::Vec3,
) -> Option<String> {
    let info = analysis.settings.info;
    let mut groups: Vec<&str> = Vec::new();
    for spec in info.all_options() {
        if !groups.contains(&spec.group) {
            groups.push(spec.group);
        }
    }
    let mut change: Option<(&'static str, String)> = None;
    for (k, group) in groups.iter().enumerate() {
        let title = if group.is_empty() { info.name } else { group };
        let id = ui.make_persistent_id(("analysis options", info.name, *group));
        egui::collapsing_header::CollapsingState::load_with_default_open(ui.ctx(), id, k == 0)
            .show_header(ui, |ui| ui.add(egui::Label::new(title).wrap()))
            .body(|ui| {
                // Each option's name above its control, so that both fit any panel width.
                for spec in info.all_options().filter(|s| s.group == *group) {
                    let value = analysis.settings.value(spec.name);
                    let label = match spec.unit {
                        "" => spec.name.to_string(),
                        unit => format!("{} ({unit})", spec.name),
                    };
                    ui.add(egui::Label::new(label).wrap())
                        .on_hover_text(spec.doc);
                    if let Some(new) = option_control(ui, spec, &value, names, view_eye) {
                        change = Some((spec.name, new));
                    }
                }
            });
    }
    let is_lens = analysis
        .outcome()
        .is_some_and(|o| o.report.result::<specula_analyze::lens::Report>().is_some());
    if is_lens {
        ui.horizontal(|ui| {
            use specula_analyze::lens::plot::Map;
            ui.label("map");
            ui.selectable_value(&mut analysis.lens_map, Map::MeanPower, "mean power");
            ui.selectable_value(&mut analysis.lens_map, Map::Cylinder, "cylinder");
        });
    }
    let (name, value) = change?;
    analysis
        .settings
        .set(name, &value)
        .err()
        .map(|e| format!("{name}: {}", crate::script::in_keys(e)))
}

/// One option's control: a scene object's name from a list, a point with a button to the view's
/// eye, otherwise the control its kind makes (`panel::control`).
fn option_control(
    ui: &mut egui::Ui,
    spec: &OptionSpec,
    value: &str,
    names: &[String],
    view_eye: glam::Vec3,
) -> Option<String> {
    if spec.names_an_object() {
        return object_control(ui, spec, value, names);
    }
    let optional_choice = matches!(spec.kind, ParamKind::Choice(_)) && spec.default.is_empty();
    if let (true, ParamKind::Choice(words)) = (optional_choice, spec.kind) {
        let mut chosen = None;
        egui::ComboBox::from_id_salt(spec.name)
            .selected_text(if value.is_empty() { "default" } else { value })
            .show_ui(ui, |ui| {
                if ui.selectable_label(value.is_empty(), "default").clicked() {
                    chosen = Some(String::new());
                }
                for w in words {
                    if ui.selectable_label(*w == value, *w).clicked() {
                        chosen = Some(w.to_string());
                    }
                }
            });
        return chosen.filter(|w| w != value);
    }
    let point = matches!(spec.kind, ParamKind::Numbers { names: "X,Y,Z" });
    ui.horizontal(|ui| {
        let mut new = crate::panel::control(ui, spec.name, spec.kind, spec.doc, value);
        if point
            && ui
                .small_button("view's eye")
                .on_hover_text("put it where the view's camera is")
                .clicked()
        {
            new = Some(format!("{},{},{}", view_eye.x, view_eye.y, view_eye.z));
        }
        new
    })
    .inner
}

/// A scene object's name (several, as checkboxes, for a repeatable option).
fn object_control(
    ui: &mut egui::Ui,
    spec: &OptionSpec,
    value: &str,
    names: &[String],
) -> Option<String> {
    if spec.repeatable {
        let mut chosen: Vec<&str> = value.split(';').filter(|v| !v.is_empty()).collect();
        let mut changed = false;
        egui::CollapsingHeader::new(format!("{} chosen", chosen.len()))
            .id_salt(("objects", spec.name))
            .show(ui, |ui| {
                for name in names {
                    let mut on = chosen.contains(&name.as_str());
                    if ui.checkbox(&mut on, name).changed() {
                        changed = true;
                        chosen.retain(|c| c != name);
                        if on {
                            chosen.push(name);
                        }
                    }
                }
            });
        return changed.then(|| chosen.join(";"));
    }
    let mut picked = None;
    egui::ComboBox::from_id_salt(("object", spec.name))
        .selected_text(if value.is_empty() { "none" } else { value })
        .show_ui(ui, |ui| {
            if !spec.required && ui.selectable_label(value.is_empty(), "none").clicked() {
                picked = Some(String::new());
            }
            for name in names {
                if ui.selectable_label(name == value, name).clicked() {
                    picked = Some(name.clone());
                }
            }
        });
    picked.filter(|p| p != value)
}

fn figures_section(ui: &mut egui::Ui, analysis: &mut Analysis) {
    if let Some(error) = &analysis.error {
        ui.label(RichText::new(error).color(Color32::LIGHT_RED));
        return;
    }
    let Some(outcome) = analysis.outcome() else {
        ui.small("computing…");
        return;
    };
    let progress = if analysis.busy() {
        " (updating…)"
    } else {
        ""
    };
    ui.small(format!("{}{progress}", outcome.timing()));
    if !outcome.complete {
        ui.small("the eye points' middle alone (a preview); every eye point's follows");
    }
    ui.label(eye_points_text(&outcome.report));
    let mut select = None;
    let report = &outcome.report;
    if let Some(m) = report.result::<MirrorViewResult>() {
        for warning in &m.view.report.warnings {
            ui.label(RichText::new(warning).color(Color32::from_rgb(240, 200, 90)));
        }
        match &m.regulation {
            Some(j) => verdict_section(ui, &j.verdict),
            None => mirror_figures(ui, &m.view),
        }
    } else if let Some(r) = report.result::<specula_analyze::lens::Report>() {
        lens_figures(ui, r);
    } else if let Some(g) = report.result::<GlareResult>() {
        select = glare_figures(ui, analysis, &g.glare, outcome.complete);
    } else {
        if let Some(verdict) = report.verdict {
            ui.label(format!("{}: {}", report.analysis, verdict.word()));
        }
        ui.monospace(&report.json);
    }
    if let Some(k) = select {
        analysis.selected_eye = Some(k);
    }
    lens_map_legend(ui, analysis);
}

/// What the overlay's colours mean, and the verdict, in the view's bottom-left corner (so
/// that a window screenshot carries its own key).
pub fn legend(ctx: &egui::Context, scene: egui::Rect, analysis: &Analysis) {
    let Some(outcome) = analysis.outcome() else {
        return;
    };
    let report = &outcome.report;
    let rgb = |c: [u8; 3]| Color32::from_rgb(c[0], c[1], c[2]);
    let ends = |t: f64| rgb(specula_analyze::figure::scale_colour(t));
    let keys: Vec<(Color32, &str)> = if report.result::<MirrorViewResult>().is_some() {
        vec![
            (rgb(crate::analysis::SEEN), "ground seen in the mirror"),
            (
                rgb(crate::analysis::REGION_SEEN),
                "required region or field: seen",
            ),
            (
                rgb(crate::analysis::BLIND),
                "required region or field: blind",
            ),
        ]
    } else if report.result::<GlareResult>().is_some() {
        vec![
            (ends(0.0), "glare, 1 cd/m² (or at the threshold)"),
            (ends(1.0), "glare, 10⁹ cd/m² (or a luminance factor of 1)"),
            (rgb(crate::analysis::WASHED_OUT_RGB), "display washed out"),
        ]
    } else if report.result::<specula_analyze::lens::Report>().is_some() {
        vec![(ends(0.0), "least over the lens"), (ends(1.0), "largest")]
    } else {
        Vec::new()
    };
    egui::Area::new(egui::Id::unique("analysis legend"))
        .fixed_pos(scene.left_bottom() + egui::vec2(8.0, -8.0))
        .pivot(egui::Align2::LEFT_BOTTOM)
        .interactable(false)
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                if let Some(verdict) = report.verdict {
                    ui.label(
                        RichText::new(format!("{}: {}", report.analysis, verdict.word())).strong(),
                    );
                }
                for (colour, text) in keys {
                    ui.horizontal(|ui| {
                        let (rect, _) =
                            ui.allocate_exact_size(egui::vec2(14.0, 14.0), egui::Sense::hover());
                        ui.painter().rect_filled(rect, 0.0, colour);
                        ui.small(text);
                    });
                }
            });
        });
}

/// The eye points a result was judged from, and the option they came from.
pub fn eye_points_text(report: &specula_analyze::analysis::Report) -> String {
    let points: Vec<String> = report
        .eyes
        .iter()
        .map(|p| format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z))
        .collect();
    let shown = match points.len() {
        0..=4 => points.join(", "),
        n => format!("{n} points from {} to {}", points[0], points[n - 1]),
    };
    format!("eye points ({}): {shown}", report.eyes_from)
}

/// A two-column grid of named figures: `add` calls `row(name, value)` once for each.
fn figure_grid(ui: &mut egui::Ui, id: &str, add: impl FnOnce(&mut dyn FnMut(&str, String))) {
    egui::Grid::new(id).num_columns(2).show(ui, |ui| {
        add(&mut |name: &str, value: String| {
            ui.label(name);
            ui.label(value);
            ui.end_row();
        })
    });
}

/// A mirror view's figures over the eye points.
fn mirror_figures(ui: &mut egui::Ui, view: &specula_analyze::mirror_view::MirrorView) {
    let f = &view.report.figures;
    figure_grid(ui, "mirror figures", |row| {
        row("horizontal", format!("{:.2}°", f.horizontal_deg));
        row("vertical", format!("{:.2}°", f.vertical_deg));
        row("solid angle", format!("{:.4} sr", f.solid_angle_sr));
        row(
            "ground",
            format!(
                "{:.2} m² within {} m",
                f.ground_area_m2, view.report.range_m
            ),
        );
        if let (Some(any), Some(blind)) = (f.region_seen_by_any, f.blind_area_m2) {
            row(
                "region seen",
                format!("{:.1} % by any eye point", any * 100.0),
            );
            if let Some(all) = f.region_seen_by_all {
                row("", format!("{:.1} % by every one", all * 100.0));
            }
            row("blind", format!("{blind:.2} m²"));
        }
        let unconverged = view.report.eyes.iter().filter(|e| !e.converged).count();
        if unconverged > 0 {
            row(
                "not converged",
                format!("{unconverged} eye point(s): raise the tolerance"),
            );
        }
    });
    ui.small(
        "on the ground: cyan seen (stronger: by every eye point); in the region green \
         seen, red blind",
    );
}

/// A lens's figures at the centre and over the gaze grid.
fn lens_figures(ui: &mut egui::Ui, r: &specula_analyze::lens::Report) {
    let c = &r.centre;
    let number = |v: Option<f64>| {
        v.map(|v| format!("{v:.3}"))
            .unwrap_or_else(|| "outside".into())
    };
    figure_grid(ui, "lens figures", |row| {
        row(
            "at the centre",
            format!(
                "{} / {} × {}",
                number(c.sphere_d),
                number(c.cylinder_d),
                c.axis_deg.map(|a| format!("{a:.0}")).unwrap_or_default()
            ),
        );
        row("mean power", format!("{} D", number(c.mean_power_d)));
        if let Some([h, v]) = c.prism_d {
            row("prism", format!("{h:.2} Δ out, {v:.2} Δ up"));
        }
        let largest = |f: &dyn Fn(&specula_analyze::lens::Cell) -> Option<f64>| {
            r.grid
                .iter()
                .filter_map(f)
                .fold(0.0, |a: f64, v| a.max(v.abs()))
        };
        row(
            "largest cylinder",
            format!(
                "{:.3} D over ±{}° × ±{}°",
                largest(&|c| c.cylinder_d),
                r.gaze.h_max_deg,
                r.gaze.v_max_deg
            ),
        );
        if r.prescription.is_some() {
            row(
                "unwanted cylinder",
                format!("{:.3} D at most", largest(&|c| c.unwanted_cylinder_d)),
            );
        }
        row(
            "outside the lens",
            format!(
                "{} of {} gazes",
                r.grid.iter().filter(|c| c.outside).count(),
                r.grid.len()
            ),
        );
    });
}

/// The glare's figures for the eye point shown, and the eyebox map (returns the eye point
/// clicked there).
fn glare_figures(
    ui: &mut egui::Ui,
    analysis: &Analysis,
    g: &specula_analyze::glare::Glare,
    complete: bool,
) -> Option<usize> {
    let mut select = None;
    let r = &g.report;
    let shown = analysis.glare_eye().min(r.eyes.len() - 1);
    ui.label(match r.worst_eye {
        Some(k) => format!(
            "glare from {:.0} % of the eye points; worst: eye point {}",
            r.share_with_glare * 100.0,
            k + 1
        ),
        None => format!(
            "no glare: no eye point sees '{}' in '{}'",
            r.source, r.surface
        ),
    });
    let e = &r.eyes[shown];
    ui.small(format!(
        "eye point {} shown: relative luminance {:.4}, veiling ratio {}, {:.3e} sr",
        shown + 1,
        e.max_luminance_factor,
        specula_analyze::glare::veiling_text(e.max_veiling_ratio),
        e.solid_angle_sr
    ));
    if r.eyes.len() > 1 && complete {
        select = eyebox_map(ui, analysis, g, shown);
        ui.small(
            "eye points as seen from the seat, coloured by the glare's solid angle \
             (grey: none); red: the worst, white: shown. Click one to show it.",
        );
    }
    ui.small(format!(
        "on the surface: the glare's relative luminance, log scale from {} (blue) to 1 \
         (yellow)",
        g.report.threshold
    ));
    select
}

/// What the lens map over the view shows, and its range.
fn lens_map_legend(ui: &mut egui::Ui, analysis: &Analysis) {
    if let Some(r) = analysis
        .outcome()
        .and_then(|o| o.report.result::<specula_analyze::lens::Report>())
    {
        let values: Vec<f64> = r
            .grid
            .iter()
            .filter_map(|c| analysis.lens_map.value(c))
            .collect();
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            });
        if lo.is_finite() {
            ui.small(format!(
                "on the lens: {} from {lo:.3} D (blue) to {hi:.3} D (yellow), lines every {} D",
                match analysis.lens_map {
                    specula_analyze::lens::plot::Map::Cylinder => "cylinder",
                    _ => "mean power",
                },
                specula_analyze::lens::plot::map_interval(r, analysis.lens_map, lo, hi)
            ));
        }
    }
}

/// The eye points as cells seen from the driver's seat (right to the right, up up), each
/// coloured by the glare's solid angle, as the report's map (dark blue: little of the view,
/// yellow: the most of any eye point; grey: no glare); the worst outlined red, the one shown
/// white. Returns the cell clicked.
fn eyebox_map(
    ui: &mut egui::Ui,
    analysis: &Analysis,
    glare: &specula_analyze::glare::Glare,
    shown: usize,
) -> Option<usize> {
    let count = glare.report.eyes.len();
    // An eyebox's columns and rows, as the eye points were laid out.
    let grid: Vec<usize> = analysis
        .settings
        .value("eyebox")
        .split(',')
        .filter_map(|v| v.trim().parse::<f64>().ok())
        .map(|v| v as usize)
        .collect();
    let (columns, rows) = match grid.as_slice() {
        [_, _, columns, rows] if columns * rows == count => (*columns, *rows),
        _ => (count, 1),
    };
    let cell = (240.0 / columns as f32).min(24.0);
    let (rect, response) = ui.allocate_exact_size(
        egui::vec2(cell * columns as f32, cell * rows as f32),
        egui::Sense::click(),
    );
    let painter = ui.painter_at(rect);
    let cell_rect = |k: usize| {
        let (column, row) = (k % columns, k / columns);
        // Row 0 is the lowest.
        let min =
            rect.left_top() + egui::vec2(column as f32 * cell, (rows - 1 - row) as f32 * cell);
        egui::Rect::from_min_size(min, egui::vec2(cell, cell)).shrink(1.0)
    };
    let widest = glare
        .report
        .eyes
        .iter()
        .map(|e| e.solid_angle_sr)
        .fold(0.0, f64::max);
    for (k, e) in glare.report.eyes.iter().enumerate() {
        let colour = if e.glare && widest > 0.0 {
            let [r, g, b] = specula_analyze::figure::scale_colour(e.solid_angle_sr / widest);
            Color32::from_rgb(r, g, b)
        } else {
            Color32::from_gray(90)
        };
        painter.rect_filled(cell_rect(k), 1.0, colour);
        let outline = if k == shown {
            Some(Color32::WHITE)
        } else if glare.report.worst_eye == Some(k) {
            Some(Color32::RED)
        } else {
            None
        };
        if let Some(outline) = outline {
            painter.rect_stroke(
                cell_rect(k),
                1.0,
                egui::Stroke::new(2.0, outline),
                egui::StrokeKind::Inside,
            );
        }
    }
    let clicked = response
        .clicked()
        .then(|| response.interact_pointer_pos())
        .flatten()?;
    (0..count).find(|&k| cell_rect(k).expand(1.0).contains(clicked))
}

/// The verdict: each field's seen share with its uncertainty, the body's share, the margin and
/// whether it passes; the mirror's own checks.
fn verdict_section(ui: &mut egui::Ui, v: &Verdict) {
    let colour = |outcome: Outcome| match outcome {
        Outcome::Pass => Color32::LIGHT_GREEN,
        Outcome::Fail => Color32::LIGHT_RED,
        Outcome::Undecided => Color32::from_rgb(240, 200, 90),
    };
    ui.label(
        RichText::new(format!("{}: {}", v.title, v.verdict.word()))
            .strong()
            .color(colour(v.verdict)),
    );
    // One wrapped line a field, so that nothing is cut at any panel width.
    for f in &v.fields {
        let g = &f.figures;
        ui.label(
            RichText::new(format!(
                "{}: {:.2} ± {:.2} % seen, body {:.2} %, margin {:.2} m: {}",
                f.name,
                g.seen_share * 100.0,
                (g.seen_share_uncertainty + f.surface_uncertainty.unwrap_or(0.0)) * 100.0,
                g.hidden_by_vehicle_share * 100.0,
                g.outer_margin_m.min(g.near_margin_m),
                g.verdict.lower()
            ))
            .color(colour(g.verdict)),
        )
        .on_hover_text(&f.source);
    }
    for c in &v.mirror_checks {
        ui.label(
            RichText::new(format!(
                "{}: {} ({}): {}",
                c.name,
                c.measured,
                c.required,
                c.verdict.lower()
            ))
            .color(colour(c.verdict)),
        )
        .on_hover_text(&c.source);
    }
    ui.small(format!(
        "the body's parts may hide {:.0} % of a field unexcused; on the ground: green seen, red \
         blind",
        v.allowance_share * 100.0
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every text the panel's options section lays out for `analysis`.
    fn texts(analysis: &mut Analysis, names: &[String]) -> Vec<String> {
        let ctx = egui::Context::default();
        let mut output = ctx.run_ui(egui::RawInput::default(), |ui| {
            let _ = options_section(ui, analysis, names, glam::Vec3::ZERO);
        });
        fn collect(shape: &egui::Shape, out: &mut Vec<String>) {
            match shape {
                egui::Shape::Text(t) => out.push(t.galley.text().to_string()),
                egui::Shape::Vec(shapes) => shapes.iter().for_each(|s| collect(s, out)),
                _ => {}
            }
        }
        let mut out = Vec::new();
        for clipped in &output.shapes {
            collect(&clipped.shape, &mut out);
        }
        // No renderer takes the font atlas here.
        output.textures_delta.clear();
        out
    }

    /// The panel's controls are made from the declarations: an analysis added by one folder
    /// and one registry line (the test-only toy) gets its options' controls with no code here.
    #[test]
    fn every_option_of_an_analysis_gets_a_control_from_its_declaration() {
        for name in ["toy", "mirror-view"] {
            let mut analysis = Analysis::new(Settings::new(name).unwrap());
            let shown = texts(&mut analysis, &["door mirror".to_string()]);
            let first_group: Vec<&OptionSpec> = analysis
                .settings
                .info
                .all_options()
                .filter(|s| s.group == analysis.settings.info.options[0].group)
                .collect();
            for spec in first_group {
                let label = match spec.unit {
                    "" => spec.name.to_string(),
                    unit => format!("{} ({unit})", spec.name),
                };
                assert!(
                    shown.contains(&label),
                    "{name}: no control labelled {label:?} in {shown:?}"
                );
            }
        }
    }

    /// At the narrowest panel the window allows, the verdict, its fields and checks and every
    /// option's control lie within the panel's width: wrapped, none cut off at its right edge.
    #[test]
    fn the_verdict_and_the_options_fit_the_narrowest_panel() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/car-door-mirror.toml"
        );
        let live = specula_methods::LiveScene::new(specula_scene::load(path).unwrap());
        let mut settings = Settings::new("mirror-view").unwrap();
        for (name, value) in [
            ("mirror", "door mirror"),
            ("regulation", "r46-iii"),
            ("forward", "0,0,-1"),
            ("r_point", "-0.37,0.55,0"),
            ("outermost", "-0.95,0.6,1.5"),
            ("vehicle", "car body;A-pillar"),
            ("tolerance", "0.02"),
        ] {
            settings.set(name, value).unwrap();
        }
        let mut analysis = Analysis::new(settings);
        analysis.finish(&live);
        let width = crate::panel::MIN_PANEL_WIDTH;
        let ctx = egui::Context::default();
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(1280.0, 800.0),
            )),
            ..Default::default()
        };
        let mut output = ctx.run_ui(input, |root| {
            egui::Panel::left("narrow")
                .resizable(false)
                .exact_size(width)
                .show(root, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        figures_section(ui, &mut analysis);
                        let _ = options_section(ui, &mut analysis, &[], glam::Vec3::ZERO);
                    });
                });
        });
        output.textures_delta.clear();
        let mut texts = Vec::new();
        fn collect(shape: &egui::Shape, out: &mut Vec<(String, egui::Rect)>) {
            match shape {
                egui::Shape::Text(t) => out.push((
                    t.galley.text().to_string(),
                    t.galley.rect.translate(t.pos.to_vec2()),
                )),
                egui::Shape::Vec(shapes) => shapes.iter().for_each(|s| collect(s, out)),
                _ => {}
            }
        }
        for clipped in &output.shapes {
            collect(&clipped.shape, &mut texts);
        }
        assert!(
            texts.iter().any(|(t, _)| t.contains("FAIL")),
            "the verdict is laid out: {texts:?}"
        );
        for (text, rect) in &texts {
            assert!(
                rect.max.x <= width + 1.0,
                "{text:?} reaches x = {} past the panel's {width}",
                rect.max.x
            );
        }
    }
}
