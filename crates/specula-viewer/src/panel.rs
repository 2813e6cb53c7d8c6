//! The egui panel, docked on the left (a third of the window at most, H hides it): scene, technique picker, the parameter controls built from the registry's
//! specs, the view, the selected object's move controls, the analysis
//! ([`crate::analysis_panel`]), per-stage timings, the frame-time graph, and the key help.

use egui::{Color32, RichText};
use glam::Vec3;
use specula_methods::ParamKind;

use crate::app::UiState;
use crate::session::{Session, ViewMode};

/// The keys, for the help window and docs/viewer.md.
pub const KEYS: &[(&str, &str)] = &[
    ("left drag", "orbit the eye about the target"),
    ("right / middle drag, Shift + left drag", "pan"),
    ("wheel, + / -", "zoom"),
    (
        "W A S D, Q E",
        "walk the eye forward, left, back, right, down, up",
    ),
    ("click", "select the object under the cursor"),
    (
        "Ctrl + left drag",
        "move the selected object in the view plane",
    ),
    (
        "arrows, PageUp / PageDown",
        "move the selected object (Shift: 5x)",
    ),
    (
        "[ ]  , .",
        "turn the selected object about world Y / X (Shift: 5x)",
    ),
    ("T / Shift + T", "next / previous technique"),
    ("Space", "toggle the reference"),
    ("V", "cycle views: technique, split, error"),
    (
        "P or F12",
        "screenshot of the view (analysis overlay, no UI) to specula-N.png",
    ),
    ("Home or 0", "reset the view to the scene's camera"),
    ("C", "render continuously (for timing)"),
    ("H", "hide / show the panel"),
    ("? or F1", "this help"),
    ("Esc", "quit"),
];

/// Draws the UI; returns a scene to load when the user asked for one.
pub fn show(ctx: &egui::Context, session: &mut Session, ui_state: &mut UiState) -> Option<String> {
    let mut load = None;
    if ui_state.settings.show_help {
        egui::Window::new("keys")
            .collapsible(false)
            .show(ctx, |ui| {
                egui::Grid::new("keys").striped(true).show(ui, |ui| {
                    for (keys, what) in KEYS {
                        ui.monospace(*keys);
                        ui.label(*what);
                        ui.end_row();
                    }
                });
            });
    }
    let max_width = (ctx.content_rect().width() * MAX_PANEL_SHARE).floor();
    let mut expanded = ui_state.settings.show_panel;
    ctx.root_ui(|root| {
        egui::Panel::left("specula")
            .resizable(true)
            .default_size(DEFAULT_PANEL_WIDTH.min(max_width))
            .size_range(MIN_PANEL_WIDTH.min(max_width)..=max_width)
            .show_collapsible(root, &mut expanded, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    load = sections(ui, session, ui_state);
                });
                if let Some((true, message)) = &ui_state.message {
                    ui.label(RichText::new(message).color(Color32::LIGHT_RED));
                }
            });
        ui_state.scene_left_points = root.available_rect_before_wrap().left();
    });
    ui_state.settings.show_panel = expanded;
    load
}

/// The panel's widest share of the window, so that the scene keeps two thirds of it.
const MAX_PANEL_SHARE: f32 = 1.0 / 3.0;
const DEFAULT_PANEL_WIDTH: f32 = 280.0;
pub(crate) const MIN_PANEL_WIDTH: f32 = 160.0;

/// The panel's sections; only the technique, view and analysis are open at first.
fn sections(ui: &mut egui::Ui, session: &mut Session, ui_state: &mut UiState) -> Option<String> {
    let mut load = None;
    egui::CollapsingHeader::new("scene").show(ui, |ui| {
        load = scene_section(ui, session, ui_state);
    });
    egui::CollapsingHeader::new("technique")
        .default_open(true)
        .show(ui, |ui| technique_section(ui, session, ui_state));
    egui::CollapsingHeader::new("view")
        .default_open(true)
        .show(ui, |ui| view_section(ui, session, ui_state));
    egui::CollapsingHeader::new("object").show(ui, |ui| object_section(ui, session, ui_state));
    egui::CollapsingHeader::new("analysis")
        .default_open(true)
        .show(ui, |ui| {
            crate::analysis_panel::show(ui, session, ui_state);
            crate::analysis_panel::details(ui, session, ui_state);
        });
    egui::CollapsingHeader::new("timings").show(ui, |ui| timing_section(ui, session, ui_state));
    load
}

fn scene_section(ui: &mut egui::Ui, session: &Session, state: &mut UiState) -> Option<String> {
    let mut load = None;
    ui.horizontal(|ui| {
        ui.label("scene");
        egui::ComboBox::from_id_salt("built-in")
            .selected_text(&session.source)
            .show_ui(ui, |ui| {
                for name in specula_scene::builtin::names() {
                    if ui.selectable_label(session.source == name, name).clicked() {
                        state.scene_input = name.to_string();
                        load = Some(name.to_string());
                    }
                }
            });
    });
    ui.horizontal(|ui| {
        let field = ui.text_edit_singleline(&mut state.scene_input);
        let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        if ui.button("load").clicked() || enter {
            load = Some(state.scene_input.clone());
        }
    });
    ui.small("or drop a .toml / .gltf / .glb / .obj / .ply / .stl file on the window");
    if let Some((is_error, message)) = &state.message {
        let color = if *is_error {
            Color32::LIGHT_RED
        } else {
            Color32::LIGHT_GREEN
        };
        ui.label(RichText::new(message).color(color));
    }
    ui.separator();
    load
}

/// A label's line: the method's summary, and the preset's with the settings it changes.
fn summary(label: specula_methods::Label) -> String {
    match label.preset {
        Some(preset) => format!(
            "{} Preset {}: {} ({})",
            label.info.summary,
            preset.name,
            preset.summary,
            preset.settings.join(", ")
        ),
        None => label.info.summary.to_string(),
    }
}

fn technique_section(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    let current = session.label();
    ui.horizontal(|ui| {
        ui.label("technique");
        egui::ComboBox::from_id_salt("technique")
            .selected_text(current.to_string())
            .show_ui(ui, |ui| {
                for label in session.labels().to_vec() {
                    if ui
                        .selectable_label(label == current, label.to_string())
                        .on_hover_text(summary(label))
                        .clicked()
                    {
                        state.message = session
                            .set_method(&label.to_string())
                            .err()
                            .map(|e| (true, e.to_string()));
                        state.dirty = true;
                    }
                }
            });
    });
    ui.small(summary(current));
    if let Some(failure) = &session.failure {
        ui.label(
            RichText::new(format!(
                "{current} failed on this scene: {failure}. Showing the reference."
            ))
            .color(Color32::LIGHT_RED),
        );
    }
    let specs = session.method().params;
    let mut change = None;
    match session.technique() {
        Ok(technique) => {
            egui::Grid::new("parameters").num_columns(2).show(ui, |ui| {
                for spec in specs {
                    let value = technique.parameter(spec.name);
                    ui.label(spec.name).on_hover_text(spec.doc);
                    if let Some(new) = control(ui, spec.name, spec.kind, spec.doc, &value) {
                        change = Some(format!("{}={new}", spec.name));
                    }
                    ui.end_row();
                }
            });
        }
        Err(e) => {
            ui.label(RichText::new(e.to_string()).color(Color32::LIGHT_RED));
        }
    }
    if let Some(setting) = change {
        state.message = session
            .set_param(&setting)
            .err()
            .map(|e| (true, e.to_string()));
        state.dirty = true;
    }
    ui.separator();
}

/// One parameter's or analysis option's control, from its declaration (name, kind, doc);
/// returns the new value as text when changed.
pub fn control(
    ui: &mut egui::Ui,
    name: &str,
    kind: ParamKind,
    doc: &str,
    value: &str,
) -> Option<String> {
    match kind {
        ParamKind::Integer { min, max } => {
            let mut v: i64 = value.parse().unwrap_or(min);
            let response = ui
                .add(egui::DragValue::new(&mut v).range(min..=max))
                .on_hover_text(doc);
            // Apply when the drag ends or the typed value is committed, not at every pixel:
            // some parameters rebuild maps.
            (response.drag_stopped()
                || response.lost_focus()
                || (response.changed() && !response.dragged()))
            .then(|| v.to_string())
            .filter(|s| s != value)
        }
        ParamKind::Number { min, max } => {
            let mut v: f64 = value.parse().unwrap_or(min.max(0.0).min(max));
            // Unbounded numbers (an analysis's metres, degrees) step by hundredths.
            let speed = ((max - min).abs().min(1e3) / 500.0).min(0.01 * v.abs().max(1.0));
            let response = ui
                .add(egui::DragValue::new(&mut v).range(min..=max).speed(speed))
                .on_hover_text(doc);
            (response.drag_stopped()
                || response.lost_focus()
                || (response.changed() && !response.dragged()))
            .then(|| v.to_string())
            .filter(|s| s.parse::<f64>().ok() != value.parse::<f64>().ok())
        }
        ParamKind::Flag => {
            let mut v = value == "true";
            ui.checkbox(&mut v, "")
                .on_hover_text(doc)
                .changed()
                .then(|| v.to_string())
        }
        ParamKind::Choice(words) => {
            let mut chosen = None;
            egui::ComboBox::from_id_salt(name)
                .selected_text(value)
                .show_ui(ui, |ui| {
                    for w in words {
                        if ui.selectable_label(*w == value, *w).clicked() {
                            chosen = Some(w.to_string());
                        }
                    }
                });
            chosen.filter(|w| w != value)
        }
        ParamKind::Text { expected } | ParamKind::Numbers { names: expected } => {
            let id = ui.scope_id().with(name);
            let mut text = ui
                .data_mut(|d| d.get_temp::<String>(id))
                .unwrap_or_else(|| value.to_string());
            let response = ui
                .text_edit_singleline(&mut text)
                .on_hover_text(format!("{doc} ({expected})"));
            let commit = response.lost_focus();
            if response.has_focus() {
                ui.data_mut(|d| d.insert_temp(id, text.clone()));
            } else {
                ui.data_mut(|d| d.remove::<String>(id));
            }
            (commit && text != value).then_some(text)
        }
    }
}

fn view_section(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    ui.horizontal(|ui| {
        ui.label("view");
        for mode in ViewMode::ALL {
            ui.selectable_value(&mut session.view, mode, mode.name());
        }
    });
    if session.view == ViewMode::Split {
        ui.add(egui::Slider::new(&mut state.settings.split, 0.0..=1.0).text("split"));
    }
    if session.view.needs_reference() {
        let current = session.reference_method();
        ui.horizontal(|ui| {
            ui.label("reference");
            let has_gpu = session.ctx.gpu.is_some();
            let exact = specula_methods::METHODS
                .iter()
                .filter(|m| m.exact && (!m.needs_gpu || has_gpu));
            for m in exact {
                if ui
                    .selectable_label(current.name == m.name, m.name)
                    .clicked()
                    && current.name != m.name
                {
                    state.message = session
                        .set_reference(m.name)
                        .err()
                        .map(|e| (true, e.to_string()));
                    state.dirty = true;
                }
            }
        });
        let reference = session.reference_method();
        let device = if reference.needs_gpu { "GPU" } else { "CPU" };
        ui.small(if state.reference_converged {
            format!("{}: converged", reference.name)
        } else {
            format!("{}: refining on the {device}…", reference.name)
        });
    }
    ui.add(
        egui::Slider::new(&mut state.settings.interaction_scale, 0.125..=1.0)
            .text("resolution while moving"),
    )
    .on_hover_text("the technique renders at this fraction of the window's resolution while the view or an object moves, and at full resolution once still");
    ui.checkbox(
        &mut state.settings.continuous,
        "render every frame (for timing)",
    );
    ui.separator();
}

fn object_section(ui: &mut egui::Ui, session: &mut Session, state: &mut UiState) {
    let names: Vec<(usize, String)> = session
        .scene()
        .meshes
        .iter()
        .enumerate()
        .map(|(i, m)| (i, m.name.clone()))
        .collect();
    let selected_name = session
        .selected
        .map(|i| names[i].1.clone())
        .unwrap_or_else(|| "none".into());
    ui.horizontal(|ui| {
        ui.label("object");
        egui::ComboBox::from_id_salt("object")
            .selected_text(selected_name)
            .show_ui(ui, |ui| {
                for (i, name) in &names {
                    ui.selectable_value(&mut session.selected, Some(*i), format!("{i}: {name}"));
                }
            });
    });
    let Some(mesh) = session.selected else {
        return;
    };
    let step = session.scene().meshes[mesh].bounds().radius().max(1e-4) * 0.005;
    let mut by = Vec3::ZERO;
    ui.horizontal(|ui| {
        ui.label("move");
        for (axis, name) in [(Vec3::X, "x"), (Vec3::Y, "y"), (Vec3::Z, "z")] {
            let mut delta = 0.0f32;
            ui.add(
                egui::DragValue::new(&mut delta)
                    .speed(step)
                    .prefix(format!("{name} ")),
            )
            .on_hover_text("drag to move along this world axis");
            by += axis * delta;
        }
    });
    let mut turn = None;
    ui.horizontal(|ui| {
        ui.label("turn");
        for (axis, name) in [(Vec3::X, "x"), (Vec3::Y, "y"), (Vec3::Z, "z")] {
            let mut degrees = 0.0f32;
            ui.add(
                egui::DragValue::new(&mut degrees)
                    .speed(0.5)
                    .prefix(format!("{name}° ")),
            )
            .on_hover_text("drag to turn about this world axis through the object's box centre");
            if degrees != 0.0 {
                turn = Some((axis, degrees));
            }
        }
    });
    if by != Vec3::ZERO {
        state.message = session
            .translate(mesh, by)
            .err()
            .map(|e| (true, e.to_string()));
        state.dirty = true;
        state.last_input = std::time::Instant::now();
    }
    if let Some((axis, degrees)) = turn {
        state.message = session
            .rotate(mesh, axis, degrees)
            .err()
            .map(|e| (true, e.to_string()));
        state.dirty = true;
        state.last_input = std::time::Instant::now();
    }
    ui.separator();
}

fn timing_section(ui: &mut egui::Ui, session: &Session, state: &UiState) {
    if let Some(stats) = &state.stats {
        ui.label(format!(
            "{} {}x{}: {:.1} ms ({:.0} fps), {} GPU objects made",
            stats.method,
            stats.width,
            stats.height,
            stats.total_ms,
            1e3 / stats.total_ms.max(1e-3),
            stats.created
        ));
        egui::Grid::new("stages").num_columns(2).show(ui, |ui| {
            for (name, ms) in &stats.stages {
                ui.small(name);
                ui.small(format!("{ms:.2} ms"));
                ui.end_row();
            }
            for (name, value) in &stats.counters {
                ui.small(name);
                ui.small(value.to_string());
                ui.end_row();
            }
        });
        for warning in &stats.warnings {
            ui.small(RichText::new(warning).color(Color32::YELLOW));
        }
    }
    let window = &state.times.window_ms;
    if let Some(last) = window.back() {
        ui.label(format!("window: {:.1} ms per frame", last));
    }
    graph(ui, state);
    ui.small(format!("{} on {}", session.label(), session.ctx.describe()));
}

/// The last frames' times: window frame-to-frame (white) and technique (orange); the grey line
/// is 50 ms (20 fps).
fn graph(ui: &mut egui::Ui, state: &UiState) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(280.0, 70.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, Color32::from_black_alpha(160));
    let top_ms = state
        .times
        .window_ms
        .iter()
        .chain(&state.times.technique_ms)
        .fold(100.0f64, |a, &b| a.max(b))
        .min(2000.0);
    let y = |ms: f64| rect.bottom() - (ms / top_ms).min(1.0) as f32 * rect.height();
    painter.line_segment(
        [
            egui::pos2(rect.left(), y(50.0)),
            egui::pos2(rect.right(), y(50.0)),
        ],
        egui::Stroke::new(1.0, Color32::GRAY),
    );
    for (times, color) in [
        (&state.times.window_ms, Color32::WHITE),
        (&state.times.technique_ms, Color32::from_rgb(255, 160, 40)),
    ] {
        let n = times.len().max(2) as f32 - 1.0;
        let points: Vec<egui::Pos2> = times
            .iter()
            .enumerate()
            .map(|(i, &ms)| egui::pos2(rect.left() + rect.width() * i as f32 / n, y(ms)))
            .collect();
        painter.add(egui::Shape::line(points, egui::Stroke::new(1.0, color)));
    }
    painter.text(
        rect.left_top() + egui::vec2(4.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("frame times, top {top_ms:.0} ms; grey 50 ms"),
        egui::FontId::proportional(10.0),
        Color32::LIGHT_GRAY,
    );
}
