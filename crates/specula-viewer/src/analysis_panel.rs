//! The panel's analysis section: the kind (off, mirror view, glare), what is analysed, the eye
//! points, the figures as they arrive, and for glare the eye points' heat map (click a cell to
//! show that eye point's glare over the view).

use egui::{Color32, RichText};
use glam::Vec3;
use specula_analyze::frame::Eyes;
use specula_analyze::outcome::Outcome;
use specula_analyze::regulation::{Side, Verdict, REGULATIONS};

use crate::analysis::{Analysed, Analysis, Kind, RegulationSettings, Settings};
use crate::app::UiState;
use crate::session::Session;

/// The main panel's section: the kind (off, mirror view, glare).
pub fn show(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    let current = session.analysis.as_ref().map(|a| a.settings.kind);
    ui.horizontal(|ui| {
        if ui.selectable_label(current.is_none(), "off").clicked() {
            session.analysis = None;
        }
        for kind in [Kind::MirrorView, Kind::Glare, Kind::Lens] {
            if ui
                .selectable_label(current == Some(kind), kind.name())
                .clicked()
                && current != Some(kind)
            {
                match Settings::first(session.scene(), kind) {
                    Some(settings) => session.analysis = Some(Analysis::new(settings)),
                    None => {
                        state.message = Some((
                            true,
                            format!(
                                "{}: this scene has no {}",
                                kind.name(),
                                match kind {
                                    Kind::MirrorView => "mirror",
                                    Kind::Glare => "mirror or glass with a source to reflect",
                                    Kind::Lens => "lens (solid glass)",
                                }
                            ),
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
        Some(_) => "its settings and figures follow",
    });
}

/// The analysis's details (below its kind, while one is on): what is analysed, the eye
/// points, the figures as they arrive, the glare's eye point map, and a button to the view
/// that shows the result whole.
pub fn details(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    if session.analysis.is_none() {
        return;
    }
    ui.separator();
    contents(ui, session, state);
}

fn contents(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    let scene = session.scene();
    let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
    let camera_eye = scene.camera.eye;
    let view_eye = session.camera.camera().eye;
    let settings = &session.analysis.as_ref().expect("checked above").settings;
    let objects = Settings::objects(scene, settings.kind);
    let sources = Settings::sources(scene);
    let first_layouts: Vec<Option<RegulationSettings>> = REGULATIONS
        .iter()
        .map(|r| RegulationSettings::first(scene, settings, r))
        .collect();
    let parts: Vec<usize> = (0..scene.meshes.len())
        .filter(|&m| m != settings.object)
        .collect();
    let default_centre = (settings.kind == Kind::Lens).then(|| {
        specula_analyze::lens::default_options(scene, settings.object)
            .map(|o| o.rotation_centre.as_vec3())
            .unwrap_or(camera_eye)
    });
    let analysis = session.analysis.as_mut().expect("checked above");
    let mut edited = analysis.settings.clone();
    what_section(ui, &mut edited, &names, &objects, &sources);
    match default_centre {
        Some(default) => lens_section(ui, &mut edited, &mut analysis.lens_map, default, view_eye),
        None => eye_section(ui, &mut edited, camera_eye, view_eye),
    }
    if edited.kind == Kind::MirrorView {
        ground_section(ui, &mut edited);
        regulation_section(ui, &mut edited, &first_layouts, &names, &parts);
    }
    if edited != analysis.settings {
        analysis.settings = edited;
    }
    ui.separator();
    figures_section(ui, analysis);
    let (label, hover) = match analysis.settings.kind {
        Kind::MirrorView => (
            "look at the ground",
            "the view from above the regulation's fields (else the ground seen)",
        ),
        Kind::Glare => (
            "look from the eye point",
            "the view from the eye point shown, aimed at the surface",
        ),
        Kind::Lens => (
            "look through the lens",
            "the view from the eye's centre of rotation, along the primary gaze",
        ),
    };
    if ui.button(label).on_hover_text(hover).clicked() {
        if let Some(camera) = analysis.overview(session.camera.fov_y_deg) {
            session.camera = crate::orbit::OrbitCamera::from_camera(&camera);
            state.dirty = true;
        }
    }
}

fn what_section(
    ui: &mut egui::Ui,
    settings: &mut Settings,
    names: &[String],
    objects: &[usize],
    sources: &[usize],
) {
    let role = match settings.kind {
        Kind::MirrorView => "mirror",
        Kind::Glare => "surface",
        Kind::Lens => "lens",
    };
    egui::Grid::new("analysed").num_columns(2).show(ui, |ui| {
        ui.label(role);
        egui::ComboBox::from_id_salt("analysis object")
            .selected_text(&names[settings.object])
            .show_ui(ui, |ui| {
                for &m in objects {
                    ui.selectable_value(&mut settings.object, m, &names[m]);
                }
            });
        ui.end_row();
        if let Some(source) = &mut settings.source {
            ui.label("source");
            egui::ComboBox::from_id_salt("analysis source")
                .selected_text(&names[*source])
                .show_ui(ui, |ui| {
                    for &m in sources {
                        ui.selectable_value(source, m, &names[m]);
                    }
                });
            ui.end_row();
            ui.label("threshold");
            ui.add(
                egui::DragValue::new(&mut settings.threshold)
                    .range(1e-6..=1.0)
                    .speed(1e-4),
            )
            .on_hover_text("luminance factor (glare over source luminance) above which a pixel counts as glare");
            ui.end_row();
            sun_and_display_controls(ui, settings, names, sources);
        }
    });
}

/// The glare's sun (a direction dragged on a sky disc seen from above, forward up) and the
/// display behind the surface.
fn sun_and_display_controls(
    ui: &mut egui::Ui,
    settings: &mut Settings,
    names: &[String],
    sources: &[usize],
) {
    ui.label("the sun");
    let mut on = settings.sun.is_some();
    ui.checkbox(&mut on, "instead of the source")
        .on_hover_text("glare from the sun at 100,000 lx; drag it on the sky disc below");
    ui.end_row();
    match (on, settings.sun) {
        (true, None) => {
            settings.sun = Some(specula_analyze::glare::Sun {
                azimuth_deg: 180.0,
                elevation_deg: 15.0,
                illuminance_lx: specula_analyze::glare::sun::DEFAULT_ILLUMINANCE_LX,
            })
        }
        (false, Some(_)) => settings.sun = None,
        _ => {}
    }
    if let Some(sun) = &mut settings.sun {
        ui.label("sun position");
        ui.vertical(|ui| {
            sky_disc(ui, sun);
            ui.horizontal(|ui| {
                ui.add(
                    egui::DragValue::new(&mut sun.azimuth_deg)
                        .range(-180.0..=180.0)
                        .suffix("° az"),
                );
                ui.add(
                    egui::DragValue::new(&mut sun.elevation_deg)
                        .range(0.5..=90.0)
                        .suffix("° el"),
                );
            });
        });
        ui.end_row();
    } else {
        ui.label("source cd/m²");
        ui.add(
            egui::DragValue::new(&mut settings.source_luminance)
                .range(1e-3..=1e10)
                .speed(10.0),
        )
        .on_hover_text("the source's luminance: the glare in cd/m²");
        ui.end_row();
    }
    ui.label("display");
    let shown = settings
        .display
        .map_or("none".to_string(), |d| names[d.mesh].clone());
    egui::ComboBox::from_id_salt("glare display")
        .selected_text(shown)
        .show_ui(ui, |ui| {
            if ui
                .selectable_label(settings.display.is_none(), "none")
                .clicked()
            {
                settings.display = None;
            }
            for &m in sources {
                let chosen = settings.display.is_some_and(|d| d.mesh == m);
                if ui.selectable_label(chosen, &names[m]).clicked() {
                    settings.display = Some(specula_analyze::glare::Display {
                        mesh: m,
                        symbol_cd_m2: 300.0,
                        background_cd_m2: 10.0,
                        min_contrast: 3.0,
                    });
                }
            }
        });
    ui.end_row();
    if let Some(display) = &mut settings.display {
        ui.label("display cd/m²");
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut display.symbol_cd_m2).range(0.0..=1e5).prefix("symbols "));
            ui.add(egui::DragValue::new(&mut display.background_cd_m2).range(0.0..=1e5).prefix("background "));
            ui.add(egui::DragValue::new(&mut display.min_contrast).range(1.01..=1e3).speed(0.05).prefix("min contrast "))
                .on_hover_text("washed out below this contrast ratio (the user's figure: ISO 15008's is for passenger cars)");
        });
        ui.end_row();
    }
}

/// The sky seen from above, forward up, the zenith in the centre and the horizon on the rim:
/// drag the sun across it.
fn sky_disc(ui: &mut egui::Ui, sun: &mut specula_analyze::glare::Sun) {
    let size = egui::vec2(120.0, 120.0);
    let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
    let centre = rect.center();
    let radius = rect.width() * 0.5 - 4.0;
    if let Some(p) = response.interact_pointer_pos() {
        let d = p - centre;
        let r = (d.length() / radius).min(1.0 - 0.5 / 90.0);
        sun.elevation_deg = f64::from(90.0 * (1.0 - r));
        sun.azimuth_deg = f64::from(d.x.atan2(-d.y).to_degrees());
    }
    let painter = ui.painter_at(rect);
    let stroke = egui::Stroke::new(1.0, egui::Color32::GRAY);
    for ring in [1.0, 2.0 / 3.0, 1.0 / 3.0] {
        painter.circle_stroke(centre, radius * ring, stroke);
    }
    painter.line_segment([centre, centre - egui::vec2(0.0, radius)], stroke);
    let (az, r) = (
        sun.azimuth_deg.to_radians() as f32,
        radius * (90.0 - sun.elevation_deg as f32) / 90.0,
    );
    let at = centre + egui::vec2(az.sin(), -az.cos()) * r;
    painter.circle_filled(at, 5.0, egui::Color32::from_rgb(255, 200, 40));
    response.on_hover_text("the sky from above, the vehicle's forward axis up: drag the sun");
}

/// How [`point_controls`] presents a point.
struct PointControls {
    label: &'static str,
    /// What the point is (the fields' hover text).
    what: &'static str,
    /// Metres per pixel of drag.
    speed: f64,
    view_eye: Vec3,
    view_hover: &'static str,
    /// The reset button: its label, its hover text and the point it puts back.
    reset: (&'static str, &'static str, Vec3),
}

/// A point's x, y, z fields, a button that puts it at the view's eye and one that resets it.
fn point_controls(ui: &mut egui::Ui, point: &mut Vec3, c: PointControls) {
    ui.horizontal(|ui| {
        ui.label(c.label);
        for (value, name) in [
            (&mut point.x, "x"),
            (&mut point.y, "y"),
            (&mut point.z, "z"),
        ] {
            ui.add(
                egui::DragValue::new(value)
                    .speed(c.speed)
                    .prefix(format!("{name} ")),
            )
            .on_hover_text(c.what);
        }
    });
    ui.horizontal(|ui| {
        if ui
            .button("the view's eye")
            .on_hover_text(c.view_hover)
            .clicked()
        {
            *point = c.view_eye;
        }
        let (label, hover, value) = c.reset;
        if ui.button(label).on_hover_text(hover).clicked() {
            *point = value;
        }
    });
}

/// A lens's eye: its centre of rotation (dragged, the view's eye, or the default 27 mm behind
/// the back vertex), which eye (base in and out), and what the overlay maps.
fn lens_section(
    ui: &mut egui::Ui,
    settings: &mut Settings,
    map: &mut crate::analysis::LensMap,
    default_centre: Vec3,
    view_eye: Vec3,
) {
    use specula_analyze::lens::Eye;
    use specula_analyze::lens_plot::Map;
    point_controls(
        ui,
        &mut settings.eye,
        PointControls {
            label: "centre of rotation",
            what: "the eye's centre of rotation, world metres: drag to move it",
            speed: 0.0005,
            view_eye,
            view_hover: "put the centre of rotation where the view's camera is",
            reset: (
                "27 mm behind the lens",
                "the default: 27 mm behind the back vertex on the scene camera's view axis",
                default_centre,
            ),
        },
    );
    ui.horizontal(|ui| {
        ui.label("eye");
        ui.selectable_value(&mut settings.lens_eye, Eye::Right, "right");
        ui.selectable_value(&mut settings.lens_eye, Eye::Left, "left");
        ui.separator();
        ui.label("map");
        ui.selectable_value(map, Map::MeanPower, "mean power");
        ui.selectable_value(map, Map::Cylinder, "cylinder");
    });
}

fn eye_section(ui: &mut egui::Ui, settings: &mut Settings, camera_eye: Vec3, view_eye: Vec3) {
    point_controls(
        ui,
        &mut settings.eye,
        PointControls {
            label: "eye",
            what: "the centre eye point, world metres: drag to move it",
            speed: 0.002,
            view_eye,
            view_hover: "put the centre eye point where the view's camera is",
            reset: (
                "the scene's eye",
                "put it back at the scene camera's eye",
                camera_eye,
            ),
        },
    );
    let mut choice = match settings.eyes {
        Eyes::Camera | Eyes::Points(_) => 0,
        Eyes::Ocular => 1,
        Eyes::Eyebox { .. } => 2,
    };
    ui.horizontal(|ui| {
        ui.label("eye points");
        ui.selectable_value(&mut choice, 0, "centre");
        ui.selectable_value(&mut choice, 1, "ocular (R46)")
            .on_hover_text("two points 65 mm apart across the vehicle");
        ui.selectable_value(&mut choice, 2, "eyebox");
    });
    settings.eyes = match (choice, &settings.eyes) {
        (0, _) => Eyes::Camera,
        (1, _) => Eyes::Ocular,
        (_, Eyes::Eyebox { .. }) => settings.eyes.clone(),
        _ => Eyes::Eyebox {
            width: 0.3,
            height: 0.15,
            columns: 5,
            rows: 3,
        },
    };
    if let Eyes::Eyebox {
        width,
        height,
        columns,
        rows,
    } = &mut settings.eyes
    {
        ui.horizontal(|ui| {
            ui.add(
                egui::DragValue::new(width)
                    .range(0.0..=2.0)
                    .speed(0.005)
                    .suffix(" m"),
            );
            ui.label("×");
            ui.add(
                egui::DragValue::new(height)
                    .range(0.0..=2.0)
                    .speed(0.005)
                    .suffix(" m"),
            );
            ui.add(egui::DragValue::new(columns).range(1..=15));
            ui.label("×");
            ui.add(egui::DragValue::new(rows).range(1..=15));
        })
        .response
        .on_hover_text("width × height in the vehicle frame, columns × rows of eye points");
    }
}

fn ground_section(ui: &mut egui::Ui, settings: &mut Settings) {
    egui::Grid::new("ground").num_columns(2).show(ui, |ui| {
        ui.label("ground y");
        ui.add(
            egui::DragValue::new(&mut settings.ground_y)
                .speed(0.01)
                .suffix(" m"),
        );
        ui.end_row();
        ui.label("range");
        ui.add(
            egui::DragValue::new(&mut settings.range_m)
                .range(0.1..=10_000.0)
                .speed(0.5)
                .suffix(" m"),
        );
        ui.end_row();
        ui.label("tolerance");
        ui.add(
            egui::DragValue::new(&mut settings.tolerance)
                .range(1e-4..=0.5)
                .speed(1e-3),
        )
        .on_hover_text("refinement stops when the figures change by less than this share");
        ui.end_row();
    });
}

/// The regulation the mirror is judged against and the vehicle's layout: its R point (the
/// ocular points are 635 mm above it), the outermost point on the mirror's side, the side, and
/// the parts of the body that may hide the mirror and the road.
fn regulation_section(
    ui: &mut egui::Ui,
    settings: &mut Settings,
    first_layouts: &[Option<RegulationSettings>],
    names: &[String],
    parts: &[usize],
) {
    let mut chosen = settings
        .regulation
        .as_ref()
        .and_then(|r| REGULATIONS.iter().position(|x| x.name == r.regulation.name));
    ui.horizontal(|ui| {
        ui.label("regulation");
        egui::ComboBox::from_id_salt("regulation")
            .selected_text(chosen.map(|k| REGULATIONS[k].name).unwrap_or("none"))
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut chosen, None, "none");
                for (k, r) in REGULATIONS.iter().enumerate() {
                    ui.selectable_value(&mut chosen, Some(k), r.name)
                        .on_hover_text(r.title);
                }
            });
    });
    match (chosen, &mut settings.regulation) {
        (None, _) => settings.regulation = None,
        (Some(k), Some(layout)) if layout.regulation.name == REGULATIONS[k].name => {}
        (Some(k), Some(layout)) => layout.regulation = &REGULATIONS[k],
        (Some(k), None) => settings.regulation = first_layouts[k].clone(),
    }
    let Some(layout) = &mut settings.regulation else {
        ui.small("a regulation lays its fields on the ground in the vehicle frame and judges them");
        return;
    };
    let xyz = |ui: &mut egui::Ui, label: &str, p: &mut Vec3, hover: &str| {
        ui.horizontal(|ui| {
            ui.label(label);
            for v in [&mut p.x, &mut p.y, &mut p.z] {
                ui.add(egui::DragValue::new(v).speed(0.005).suffix(" m"));
            }
        })
        .response
        .on_hover_text(hover);
    };
    xyz(
        ui,
        "forward",
        &mut layout.forward,
        "the vehicle's forward axis (made horizontal); up is +Y",
    );
    xyz(
        ui,
        "R point",
        &mut layout.r_point,
        "the driver's R point: the ocular points are 635 mm above it, 65 mm apart",
    );
    xyz(
        ui,
        "outermost",
        &mut layout.outermost,
        "the vehicle's outermost point on the mirror's side: the fields' inner boundary",
    );
    ui.horizontal(|ui| {
        ui.label("side");
        ui.selectable_value(&mut layout.side, Side::Left, "left");
        ui.selectable_value(&mut layout.side, Side::Right, "right");
    });
    egui::CollapsingHeader::new(format!("vehicle parts ({})", layout.vehicle.len()))
        .id_salt("vehicle parts")
        .show(ui, |ui| {
            let mut shown: Vec<&str> = Vec::new();
            for &m in parts {
                if shown.contains(&names[m].as_str()) {
                    continue;
                }
                shown.push(&names[m]);
                let same: Vec<usize> = parts
                    .iter()
                    .copied()
                    .filter(|&k| names[k] == names[m])
                    .collect();
                let mut on = same.iter().all(|k| layout.vehicle.contains(k));
                if ui.checkbox(&mut on, &names[m]).changed() {
                    layout.vehicle.retain(|k| !same.contains(k));
                    if on {
                        layout.vehicle.extend(&same);
                    }
                }
            }
        });
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
    ui.small(format!(
        "centre eye point {:.0} ms; {} eye point{} {:.0} ms{progress}",
        outcome.centre_milliseconds,
        outcome.eyes.len(),
        if outcome.eyes.len() == 1 { "" } else { "s" },
        outcome.milliseconds,
    ));
    if !outcome.complete {
        ui.small("the centre eye point's result; every eye point's follows");
    }
    let mut select = None;
    match &outcome.result {
        Analysed::MirrorView {
            judged: Some(judged),
            ..
        } => verdict_section(ui, &judged.0),
        Analysed::MirrorView { view, .. } => mirror_figures(ui, view),
        Analysed::Lens(r) => lens_figures(ui, r),
        Analysed::Glare(g) => select = glare_figures(ui, analysis, g, outcome.complete),
    }
    if let Some(k) = select {
        analysis.selected_eye = Some(k);
    }
    lens_map_legend(ui, analysis);
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
        analysis.settings.threshold
    ));
    select
}

/// What the lens map over the view shows, and its range.
fn lens_map_legend(ui: &mut egui::Ui, analysis: &Analysis) {
    if let Some(Analysed::Lens(r)) = analysis.outcome().map(|o| &o.result) {
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
                    specula_analyze::lens_plot::Map::Cylinder => "cylinder",
                    _ => "mean power",
                },
                specula_analyze::lens_plot::map_interval(r, analysis.lens_map, lo, hi)
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
    let (columns, rows) = match analysis.settings.eyes {
        Eyes::Eyebox { columns, rows, .. } if (columns * rows) as usize == count => {
            (columns as usize, rows as usize)
        }
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
            let [r, g, b] = specula_analyze::plot::scale_colour(e.solid_angle_sr / widest);
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
    ui.label(RichText::new(format!("{}: {}", v.title, v.verdict.word())).color(colour(v.verdict)));
    egui::Grid::new("fields").num_columns(5).show(ui, |ui| {
        for h in ["field", "seen", "body", "margin", ""] {
            ui.small(h);
        }
        ui.end_row();
        for f in &v.fields {
            let g = &f.figures;
            ui.label(&f.name).on_hover_text(&f.source);
            ui.label(format!(
                "{:.2} ± {:.2} %",
                g.seen_share * 100.0,
                (g.seen_share_uncertainty + f.surface_uncertainty.unwrap_or(0.0)) * 100.0
            ));
            ui.label(format!("{:.2} %", g.hidden_by_vehicle_share * 100.0));
            ui.label(format!("{:.2} m", g.outer_margin_m.min(g.near_margin_m)));
            ui.label(RichText::new(g.verdict.lower()).color(colour(g.verdict)));
            ui.end_row();
        }
    });
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
