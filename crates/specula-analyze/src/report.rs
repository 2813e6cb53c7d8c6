//! An analysis's report folder: `report.html` (the figures, the parameters and the plots),
//! `report.json`, and each plot as PNG and SVG.

use std::path::{Path, PathBuf};

use glam::Vec3;
use specula_scene::Scene;
use specula_trace::SceneAccel;

use crate::mirror_view::{Figures, MirrorView};
use crate::plot::{self, Plot};
use crate::AnalyzeError;

/// The reports' shared style sheet.
const STYLE: &str = "
body { font-family: sans-serif; margin: 2em; background: #fafafa; }
table { border-collapse: collapse; margin: 1em 0; }
td, th { border: 1px solid #bbb; padding: 4px 8px; text-align: right; }
td:first-child, th:first-child { text-align: left; }
figure { display: inline-block; margin: 0.5em; vertical-align: top; }
";

fn write_error(path: &Path, e: impl std::fmt::Display) -> AnalyzeError {
    AnalyzeError::Write {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), AnalyzeError> {
    std::fs::write(path, bytes).map_err(|e| write_error(path, e))
}

fn write_plot(dir: &Path, name: &str, plot: &Plot) -> Result<(), AnalyzeError> {
    write(
        &dir.join(format!("{name}.png")),
        &plot::png_bytes(&plot.png),
    )?;
    write(&dir.join(format!("{name}.svg")), plot.svg.as_bytes())
}

fn share(value: Option<f64>) -> String {
    value
        .map(|v| format!("{:.1} %", v * 100.0))
        .unwrap_or_else(|| "–".into())
}

fn cells(f: &Figures) -> String {
    format!(
        "<td>{:.2}</td><td>{:.2}</td><td>{:.5}</td><td>{:.2}</td><td>{}</td><td>{}</td><td>{}</td>",
        f.horizontal_deg,
        f.vertical_deg,
        f.solid_angle_sr,
        f.ground_area_m2,
        share(f.region_seen_by_any),
        share(f.region_seen_by_all),
        f.blind_area_m2
            .map(|b| format!("{b:.2}"))
            .unwrap_or_else(|| "–".into())
    )
}

/// A mirror-view report's parts: the view, the scene it was traced in, and, for a regulation
/// run, the document `--json` writes with the regulation and the vehicle it was laid out for.
pub struct MirrorViewPage<'a> {
    pub view: &'a MirrorView,
    pub scene: &'a Scene,
    pub accel: &'a SceneAccel,
    pub mirror: usize,
    pub regulation: Option<(
        &'a crate::regulation::Document<'a>,
        &'static crate::regulation::Regulation,
        &'a crate::regulation::Vehicle,
    )>,
}

/// Writes the mirror-view report into `dir`: the JSON (`--json`'s document), the ground map
/// (with a regulation's fields in their verdicts' colours) and the mirror seen from the eye
/// point that sees the most ground (PNG and SVG each), and the HTML page, led by the verdict
/// where a regulation was judged; returns the page's path.
pub fn write_mirror_view(dir: &Path, page: &MirrorViewPage) -> Result<PathBuf, AnalyzeError> {
    let (view, scene, accel, mirror) = (page.view, page.scene, page.accel, page.mirror);
    std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
    let r = &view.report;
    let json = match page.regulation {
        Some((document, ..)) => serde_json::to_string_pretty(document),
        None => serde_json::to_string_pretty(r),
    }
    .map_err(|e| write_error(dir, e))?;
    write(&dir.join("report.json"), json.as_bytes())?;
    let fields = page
        .regulation
        .map(|(document, regulation, vehicle)| {
            plot::RegulationFields::of(document.regulation, regulation, vehicle, r.range_m)
        })
        .transpose()?;
    write_plot(dir, "ground", &plot::ground_map(view, fields.as_ref(), 640))?;
    let shown = r
        .eyes
        .iter()
        .enumerate()
        .max_by(|a, b| {
            a.1.figures
                .ground_area_m2
                .total_cmp(&b.1.figures.ground_area_m2)
        })
        .map_or(0, |(k, _)| k);
    let eye = Vec3::from_array(r.eyes[shown].position);
    write_plot(
        dir,
        "mirror",
        &plot::mirror_from_eye(scene, accel, mirror, eye, r.ground_y, 480),
    )?;
    let verdict = page
        .regulation
        .map(|(document, ..)| {
            let mut html =
                crate::verdict_page::regulation_html(document.regulation, &document.judged_from());
            if let Some(a) = document.adjustment {
                html.push_str(&crate::verdict_page::adjustment_html(a));
            }
            html
        })
        .unwrap_or_default();
    let mut rows = String::new();
    for (k, e) in r.eyes.iter().enumerate() {
        let [x, y, z] = e.position;
        rows.push_str(&format!(
            "<tr><td>eye {} ({x:.3}, {y:.3}, {z:.3})</td>{}<td>{} × {} + {} levels, {} rays, {:.0}/m²{}</td></tr>\n",
            k + 1,
            cells(&e.figures),
            e.subdivision,
            e.subdivision,
            e.edge_depth,
            e.samples,
            e.density_per_m2,
            if e.converged { "" } else { " <b>not converged</b>" }
        ));
    }
    if r.eyes.len() > 1 {
        rows.push_str(&format!(
            "<tr><td><b>all eye points</b> (any)</td>{}<td></td></tr>\n",
            cells(&r.figures)
        ));
    }
    let region = r
        .region
        .map(|g| format!("x {} … {} m, z {} … {} m", g.x0, g.x1, g.z0, g.z1))
        .unwrap_or_else(|| "none".into());
    let html = format!(
        r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>specula analyze mirror-view: {scene}</title>
<style>{style}{verdict_style}</style></head><body>
<h1>What '{mirror}' shows: {scene}</h1>
{verdict}<h2>What the mirror shows</h2>
<p>Exact rays from each eye point to points of the mirror, reflected about its shading normals and
followed through the scene (docs/analyses/mirror-view.md). Vehicle frame: forward ({fx:.3}, {fy:.3}, {fz:.3}),
up +Y. Ground: y = {ground} m, counted within {range} m of an eye point where no object hides it.
Required region: {region}. Refinement stopped when the solid angle and the ground area changed by
less than {tol} and the extents by less than {tol_deg}°. "All eye points": a point counts when any
eye sees it (R46's ambinocular view); grids: ground {ground_cell:.3} m, directions
{direction_cell:.4}°.</p>
<table>
<tr><th>eye point</th><th>horizontal °</th><th>vertical °</th><th>solid angle sr</th><th>ground m²</th><th>region seen (any)</th><th>region seen (all)</th><th>blind m²</th><th>sampling</th></tr>
{rows}</table>
<figure><img src="ground.svg"><figcaption>The ground seen in the mirror, per eye point (ground.png: the same map)</figcaption></figure>
<figure><img src="mirror.svg"><figcaption>The mirror from eye {shown_eye} (the eye point that sees the most ground), with the ground's 1 m grid where it shows the ground</figcaption></figure>
</body></html>
"#,
        style = STYLE,
        verdict_style = crate::verdict_page::STYLE,
        shown_eye = shown + 1,
        scene = plot::html_escape(&r.scene),
        mirror = plot::html_escape(&r.mirror),
        fx = r.forward[0],
        fy = r.forward[1],
        fz = r.forward[2],
        ground = r.ground_y,
        range = r.range_m,
        tol = r.tolerance,
        tol_deg = r.tolerance_deg,
        ground_cell = r.ground_cell_m,
        direction_cell = r.direction_cell_deg,
    );
    let path = dir.join("report.html");
    write(&path, html.as_bytes())?;
    Ok(path)
}

/// Writes the glare report into `dir`: the JSON, the eye points' map and the worst eye point's
/// image with its glare outlined (and, for a sweep, the sun positions' map and polar plot; PNG
/// and SVG each), and the HTML page; returns its path.
pub fn write_glare(
    dir: &Path,
    glare: &crate::glare::Glare,
    frame: &crate::frame::VehicleFrame,
) -> Result<PathBuf, AnalyzeError> {
    std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
    let r = &glare.report;
    let json = serde_json::to_string_pretty(r).map_err(|e| write_error(dir, e))?;
    write(&dir.join("report.json"), json.as_bytes())?;
    write_plot(dir, "eyebox", &plot::glare_eyebox(r, frame))?;
    let shown = r.worst_eye.unwrap_or(0);
    write_plot(dir, "worst", &plot::glare_image(glare, shown))?;
    let mut figures = String::new();
    if let Some(sweep) = &r.sweep {
        let what = format!("'{}' over '{}'", r.surface, r.scene);
        let map =
            crate::glare::plots::sweep_map(sweep, &format!("sun positions glaring in {what}"));
        write_plot(dir, "sweep", &map)?;
        let polar = crate::glare::plots::polar(sweep, &format!("the sky seen from above: {what}"));
        write_plot(dir, "polar", &polar)?;
        figures.push_str(
            "<figure><img src=\"sweep.svg\"><figcaption>Each sun position of the sweep: the worst \
             eye point's glare luminance (colour), washed-out display crossed</figcaption></figure>\n\
             <figure><img src=\"polar.svg\"><figcaption>The same from above, forward up</figcaption></figure>\n",
        );
    }
    let html = format!(
        r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>specula analyze glare: {scene}</title>
<style>{style}</style></head><body>
<h1>Glare of '{source}' in '{surface}': {scene}</h1>
<p>Each eye point's image ({width}×{height}, aimed at the surface), its paths followed as the
reference follows them, the Fresnel factors per polarisation (docs/analyses/glare.md). A pixel's glare is
what its paths bring from the source after at least one specular reflection on the surface.
Luminance factor: the glare's luminance over the source's; luminance: the glare's image in cd/m²;
mean: over the solid angle the glare covers; veiling ratio: the glare over what the pixel shows
without it ("over black" where that is nearly nothing). A pixel shows glare above a luminance
factor of {threshold}. {source_line}{verdict}</p>
<table>
<tr><th>eye point</th><th>glare</th><th>luminance factor</th><th>max cd/m²</th><th>mean cd/m²</th><th>veiling ratio</th><th>solid angle sr</th><th>centroid px</th>{display_heads}</tr>
{rows}</table>
{day}
<figure><img src="eyebox.svg"><figcaption>The eye points as the driver's head moves (seen from behind the driver): the glare's solid angle (colour) and luminance factor (figure)</figcaption></figure>
<figure><img src="worst.svg"><figcaption>Eye {shown_eye}'s view, the glare outlined in magenta</figcaption></figure>
{figures}</body></html>
"#,
        style = STYLE,
        scene = plot::html_escape(&r.scene),
        source = plot::html_escape(&r.source),
        surface = plot::html_escape(&r.surface),
        width = r.width,
        height = r.height,
        threshold = r.threshold,
        source_line = glare_source_line(r),
        verdict = glare_verdict(r),
        display_heads = if r.display.is_some() {
            "<th>display τ</th><th>veiling cd/m²</th><th>lowest contrast</th><th>washed out</th>"
        } else {
            ""
        },
        rows = glare_rows(r),
        day = glare_day(r),
        shown_eye = shown + 1,
    );
    let path = dir.join("report.html");
    write(&path, html.as_bytes())?;
    Ok(path)
}

fn glare_source_line(r: &crate::glare::Report) -> String {
    let mut line = String::new();
    if let Some(sun) = &r.sun {
        line.push_str(&format!(
            "The sun at azimuth {:.1}°, elevation {:.1}° (vehicle frame; {}), {:.0} lx \
             direct-normal, its disc {:.3e} cd/m². ",
            sun.azimuth_deg,
            sun.elevation_deg,
            if r.sweep.is_some() {
                "the sweep's worst position"
            } else {
                "as given"
            },
            sun.illuminance_lx,
            sun.luminance_cd_m2
        ));
    }
    if let Some(l) = r.source_luminance_cd_m2 {
        line.push_str(&format!("The source's luminance: {l} cd/m². "));
    }
    if let Some(d) = &r.display {
        line.push_str(&format!(
            "Display '{}': symbols {} cd/m², background {} cd/m², washed out below a contrast \
             ratio of {}. ",
            plot::html_escape(&d.name),
            d.symbol_luminance_cd_m2,
            d.background_luminance_cd_m2,
            d.min_contrast
        ));
    }
    line
}

fn glare_verdict(r: &crate::glare::Report) -> String {
    let washed = crate::glare::washed_out_text(r)
        .map(|w| format!(" With the display: {w}."))
        .unwrap_or_default();
    match r.worst_eye {
        Some(k) => format!(
            "Glare is seen from {:.0} % of the eye points; the worst is eye {} (shown below).{washed} \
             ({})",
            r.share_with_glare * 100.0,
            k + 1,
            crate::glare::VEILING_MEANS
        ),
        None => format!("No glare: no eye point sees the source reflected in the surface.{washed}"),
    }
}

fn glare_rows(r: &crate::glare::Report) -> String {
    use crate::glare::{luminance_text, veiling_text};
    let mut rows = String::new();
    for (k, e) in r.eyes.iter().enumerate() {
        let [x, y, z] = e.position;
        let display = e
            .display
            .as_ref()
            .map(|d| {
                format!(
                    "<td>{:.4}</td><td>{}</td><td>{:.3}</td><td>{:.1} %</td>",
                    d.transmittance,
                    luminance_text(Some(d.veiling_luminance_cd_m2)),
                    d.min_contrast,
                    d.washed_out_share * 100.0
                )
            })
            .unwrap_or_default();
        rows.push_str(&format!(
            "<tr><td>eye {} ({x:.3}, {y:.3}, {z:.3})</td><td>{}</td><td>{:.5}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>{display}</tr>\n",
            k + 1,
            if e.glare { "yes" } else { "no" },
            e.max_luminance_factor,
            luminance_text(e.max_luminance_cd_m2),
            luminance_text(e.mean_luminance_cd_m2),
            veiling_text(e.max_veiling_ratio),
            crate::verdict_page::number(e.solid_angle_sr, ""),
            e.centroid_px
                .map(|[cx, cy]| format!("{cx:.0}, {cy:.0}"))
                .unwrap_or_else(|| "–".into()),
        ));
    }
    rows
}

/// Solar hours as "h:mm".
pub fn solar_clock(hours: f64) -> String {
    let minutes = (hours * 60.0).round() as i64;
    format!("{}:{:02}", minutes / 60, minutes % 60)
}

/// The runs of solar time, "6:05–7:40, 17:00–18:10" ("none" without any).
pub fn solar_runs(runs: &[[f64; 2]]) -> String {
    if runs.is_empty() {
        return "none".into();
    }
    runs.iter()
        .map(|[a, b]| format!("{}–{}", solar_clock(*a), solar_clock(*b)))
        .collect::<Vec<_>>()
        .join(", ")
}

fn glare_day(r: &crate::glare::Report) -> String {
    let Some(sweep) = &r.sweep else {
        return String::new();
    };
    let mut text = format!(
        "<p>The sweep: azimuth {}..{}°, elevation {}..{}°, every {}° ({} positions), traced once in \
         {:.2} s and looked up in {:.3} s.</p>\n",
        sweep.azimuth_deg[0],
        sweep.azimuth_deg[1],
        sweep.elevation_deg[0],
        sweep.elevation_deg[1],
        sweep.step_deg,
        sweep.positions.len(),
        sweep.trace_s,
        sweep.lookup_s
    );
    if let Some(day) = &sweep.day {
        text.push_str(&format!(
            "<p>On {} (day {}) at latitude {}°, heading {}° (compass), apparent solar time: glare \
             {}; display washed out {}.</p>\n",
            plot::html_escape(&day.date),
            day.day_of_year,
            day.latitude_deg,
            day.heading_deg,
            solar_runs(&day.glare_hours),
            solar_runs(&day.washed_out_hours)
        ));
    }
    text
}

/// The lens report's tables of its surface, wear, magnification, focimeter readings, ordered
/// prescription and verdict.
fn lens_sections(r: &crate::lens::Report) -> String {
    let mut html = String::from("<table>\n");
    let row = |html: &mut String, name: &str, value: String| {
        html.push_str(&format!("<tr><td>{name}</td><td>{value}</td></tr>\n"));
    };
    row(
        &mut html,
        "surface",
        match r.surface_uncertainty_d {
            Some(u) => format!("{} (surface uncertainty {u:.4} D)", r.surface.name()),
            None => r.surface.name().into(),
        },
    );
    if let Some(g) = &r.sag_grid {
        row(&mut html, "sag grid", sag_grid_row(g));
    }
    row(
        &mut html,
        "as worn",
        format!(
            "pantoscopic tilt {}°, wrap {}°, vertex distance {:.2} mm, centre of rotation \
             {:.1} mm behind the cornea",
            r.wear.pantoscopic_deg,
            r.wear.wrap_deg,
            r.vertex_distance_mm,
            r.rotation_behind_cornea_mm
        ),
    );
    let [sh, sv] = r.spectacle_magnification;
    let [rh, rv] = r.rotating_eye_magnification;
    row(
        &mut html,
        "spectacle magnification (h, v)",
        format!("{sh:.4}, {sv:.4} (the rotating eye's field: {rh:.4}, {rv:.4})"),
    );
    if let Some(b) = r.base_curve {
        row(
            &mut html,
            "base curve",
            format!(
                "{:.2} D in the lens's index, {:.2} D in the 1.53 tooling index",
                b.lens_index_d, b.tooling_index_d
            ),
        );
    }
    if let Some(c) = r.compensated {
        row(
            &mut html,
            "compensated (to order)",
            format!(
                "{:.3} / {:.3} × {:.1} ({} iterations, residual {:.1e} D)",
                c.ordered.sphere_d,
                c.ordered.cylinder_d,
                c.ordered.axis_deg,
                c.iterations,
                c.residual_d
            ),
        );
    }
    html.push_str("</table>\n<table>\n<tr><th>focimeter</th><th>at (mm)</th><th>sphere D</th><th>cylinder D</th><th>axis °</th><th>prism Δ (out, up)</th><th>± D</th></tr>\n");
    for f in &r.focimeter {
        html.push_str(&format!(
            "<tr><td>{}</td><td>{:.1}, {:.1}</td><td>{:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{:.3}, {:.3}</td><td>{}</td></tr>\n",
            f.point, f.at_mm[0], f.at_mm[1], f.sphere_d, f.cylinder_d, f.axis_deg,
            f.prism_d[0], f.prism_d[1], crate::verdict_page::number(f.uncertainty_d, "")
        ));
    }
    for f in &r.add_focimeter {
        html.push_str(&format!(
            "<tr><td>{} (add, on the progressive side)</td><td>{:.1}, {:.1}</td><td>{:.3}</td><td>{:.3}</td><td>{:.1}</td><td>–</td><td>{}</td></tr>\n",
            f.point, f.at_mm[0], f.at_mm[1], f.sphere_d, f.cylinder_d, f.axis_deg,
            crate::verdict_page::number(f.uncertainty_d, "")
        ));
    }
    html.push_str("</table>\n");
    html.push_str(&zone_sections(r));
    html
}

/// A sag-grid lens's row: where the grid is coarse for the surface, and by how much.
fn sag_grid_row(g: &crate::lens::SagGridUncertainty) -> String {
    match g.marked_box_mm {
        Some([lo, hi]) => format!(
            "<b>coarse for the surface's curvature over {:.1} % of the lens map</b>, from \
             ({:.1}, {:.1}) to ({:.1}, {:.1}) mm: the power there is uncertain by more than \
             {:.3} D (up to {:.3} D), carried into the figures and the verdict",
            g.marked_share * 100.0,
            lo[0],
            lo[1],
            hi[0],
            hi[1],
            g.marked_above_d,
            g.largest_d
        ),
        None => format!(
            "fine enough everywhere: the power uncertain by at most {:.4} D",
            g.largest_d
        ),
    }
}

/// The clear zones, a progressive lens's figures and the near figures as tables.
fn zone_sections(r: &crate::lens::Report) -> String {
    let mut html = String::new();
    if !r.clear_zones.is_empty() {
        html.push_str("<table>\n<tr><th>clear zone</th><th>lens area mm²</th><th>gaze solid angle sr</th><th>width through the fitting point mm</th></tr>\n");
        for z in &r.clear_zones {
            html.push_str(&format!(
                "<tr><td>{}</td><td>{:.0}</td><td>{:.4}</td><td>{:.1}</td></tr>\n",
                plot::html_escape(z.criterion),
                z.lens_area_mm2,
                z.solid_angle_sr,
                z.horizontal_width_mm
            ));
        }
        html.push_str("</table>\n");
    }
    if let Some(p) = &r.progressive {
        let length = |v: Option<f64>| v.map_or_else(|| "not reached".into(), |v| format!("{v:.1}"));
        html.push_str(&format!(
            "<table>\n<tr><th>progressive</th><th></th></tr>\n\
             <tr><td>add (measured on the {}; ordered {:.2})</td><td>{:.3} D (far {:.3}, near {:.3}; as worn {:.3})</td></tr>\n\
             <tr><td>corridor length to 85 % / 95 % of the add</td><td>{} / {} mm</td></tr>\n\
             <tr><td>corridor width at 0.50 / 1.00 D</td><td>{} / {} mm</td></tr>\n\
             <tr><td>far / near zone width at 0.50 D</td><td>{:.1} / {:.1} mm</td></tr>\n\
             <tr><td>largest unwanted cylinder</td><td>{:.2} D at ({:.1}, {:.1}) mm</td></tr>\n</table>\n",
            p.measured_on,
            p.ordered_add_d,
            p.add_d,
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
        ));
    }
    if let Some(n) = &r.near {
        let number = |v: Option<f64>| v.map_or_else(|| "–".into(), |v| format!("{v:.3}"));
        html.push_str(&format!(
            "<table>\n<tr><th>near vision</th><th></th></tr>\n\
             <tr><td>near point</td><td>{:.3} m, {:.1}° down, PD {:.0} mm</td></tr>\n\
             <tr><td>through the lens at</td><td>({:.2}, {:.2}) mm, inset {:.2} mm</td></tr>\n\
             <tr><td>power for the near object</td><td>{} D (the object's vergence {:.3} D)</td></tr>\n\
             <tr><td>power error / unwanted cylinder</td><td>{} / {} D</td></tr>\n\
             <tr><td>prism (out, up)</td><td>{}</td></tr>\n</table>\n",
            n.distance_m,
            n.down_deg,
            n.pd_mm,
            n.point_on_lens_mm[0],
            n.point_on_lens_mm[1],
            n.inset_mm,
            number(n.power_d),
            n.object_vergence_d,
            number(n.cell.power_error_d),
            number(n.cell.unwanted_cylinder_d),
            n.cell
                .prism_d
                .map_or_else(|| "–".into(), |[h, v]| format!("{h:.2}, {v:.2} Δ"))
        ));
    }
    html
}

/// The largest |value| of a cell quantity over the lens, and where (gaze h, v).
fn extreme(
    report: &crate::lens::Report,
    value: impl Fn(&crate::lens::Cell) -> Option<f64>,
) -> String {
    report
        .grid
        .iter()
        .filter_map(|c| value(c).map(|v| (v, c.gaze_deg)))
        .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()))
        .map(|(v, [h, g])| format!("{v:.3} at ({h}, {g})°"))
        .unwrap_or_else(|| "–".into())
}

/// Writes the lens report into `dir`: the JSON, the four maps and the distortion picture (PNG
/// and SVG each), and the HTML page; returns its path.
pub fn write_lens(dir: &Path, r: &crate::lens::Report) -> Result<PathBuf, AnalyzeError> {
    use crate::lens_plot::{self, Map};
    std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
    let json = serde_json::to_string_pretty(r).map_err(|e| write_error(dir, e))?;
    write(&dir.join("report.json"), json.as_bytes())?;
    let mut figures = String::new();
    for map in Map::of(r) {
        write_plot(dir, map.name(), &lens_plot::lens_map(r, map))?;
        figures.push_str(&format!(
            "<figure><img src=\"{0}.svg\"><figcaption>{0}</figcaption></figure>\n",
            map.name()
        ));
    }
    for kind in lens_plot::LensCoordinateMap::ALL {
        if let Some(plot) = lens_plot::lens_coordinate_map(r, kind) {
            write_plot(dir, kind.name(), &plot)?;
            figures.push_str(&format!(
                "<figure><img src=\"{0}.svg\"><figcaption>{0}</figcaption></figure>\n",
                kind.name()
            ));
        }
    }
    write_plot(dir, "distortion", &lens_plot::distortion(r))?;
    let c = &r.centre;
    let number = |v: Option<f64>| v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "–".into());
    let prescription = match (&r.prescription, &r.target) {
        (Some(p), Some(t)) => format!(
            "Prescription: {:.2} / {:.2} × {:.0}; as worn the wearer should get {:.3} / {:.3} \
             × {:.1}, which the power error and unwanted cylinder are against.",
            p.sphere_d, p.cylinder_d, p.axis_deg, t.sphere_d, t.cylinder_d, t.axis_deg
        ),
        _ => "No prescription given: no power error or unwanted cylinder.".into(),
    };
    let sections = lens_sections(r);
    let centre_prism = c
        .prism_d
        .map(|[h, v]| format!("{h:.3} Δ horizontal (base out +), {v:.3} Δ vertical (base up +)"))
        .unwrap_or_else(|| "–".into());
    let html = format!(
        r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>specula analyze lens: {scene}</title>
<style>{style}{verdict_style}</style></head><body>
<h1>'{lens}' as worn: {scene}</h1>
{verdict}<p>The {eye} eye turns about its centre of rotation ({cx:.4}, {cy:.4}, {cz:.4}) by Listing's law;
at each gaze the chief ray from the centre is traced through the lens with Snell's law at its own
normals, and a narrow bundle ({step} mm) from the object ({object}) around it gives the
vergences at the vertex sphere (radius {radius:.1} mm), docs/analyses/lens.md. Indices (red, green,
blue): {n0:.4}, {n1:.4}, {n2:.4}. Gaze grid ±{hmax}° × ±{vmax}° every {gstep}°. The finite differences
changed by at most {fd:.1e} D between the bundle and half of it. {prescription}</p>
<table>
<tr><th>at the centre</th><th></th></tr>
<tr><td>sphere</td><td>{sphere} D</td></tr>
<tr><td>cylinder</td><td>{cylinder} D</td></tr>
<tr><td>axis (TABO)</td><td>{axis}°</td></tr>
<tr><td>mean power</td><td>{mean} D</td></tr>
<tr><td>prism</td><td>{centre_prism}</td></tr>
<tr><th>over the lens, the largest</th><th></th></tr>
<tr><td>cylinder</td><td>{max_cyl} D</td></tr>
<tr><td>prism</td><td>{max_prism} Δ</td></tr>
<tr><td>lateral colour</td><td>{max_colour} arcmin</td></tr>
<tr><td>distortion</td><td>{max_distortion} %</td></tr>
<tr><td>unwanted cylinder</td><td>{max_unwanted} D</td></tr>
<tr><td>power error</td><td>{max_error} D</td></tr>
</table>
{sections}
{figures}<figure><img src="distortion.svg"><figcaption>distortion</figcaption></figure>
</body></html>
"#,
        style = STYLE,
        verdict_style = crate::verdict_page::STYLE,
        verdict = r
            .verdict
            .as_ref()
            .map(|v| crate::verdict_page::lens_html(v, r))
            .unwrap_or_default(),
        sections = sections,
        scene = plot::html_escape(&r.scene),
        lens = plot::html_escape(&r.lens),
        eye = match r.eye {
            crate::lens::Eye::Right => "right",
            crate::lens::Eye::Left => "left",
        },
        cx = r.rotation_centre[0],
        cy = r.rotation_centre[1],
        cz = r.rotation_centre[2],
        step = r.step_mm,
        object = r
            .object_distance_m
            .map(|d| format!("{d} m from the centre of rotation"))
            .unwrap_or_else(|| "at infinity".into()),
        radius = r.vertex_sphere_radius_m * 1e3,
        n0 = r.indices[0],
        n1 = r.indices[1],
        n2 = r.indices[2],
        hmax = r.gaze.h_max_deg,
        vmax = r.gaze.v_max_deg,
        gstep = r.gaze.step_deg,
        fd = r.finite_difference_change_d,
        sphere = number(c.sphere_d),
        cylinder = number(c.cylinder_d),
        axis = number(c.axis_deg),
        mean = number(c.mean_power_d),
        max_cyl = extreme(r, |c| c.cylinder_d),
        max_prism = extreme(r, |c| c.prism_d.map(|[h, v]| h.hypot(v))),
        max_colour = extreme(r, |c| c.lateral_colour_arcmin),
        max_distortion = extreme(r, |c| c.distortion_percent),
        max_unwanted = extreme(r, |c| c.unwanted_cylinder_d),
        max_error = extreme(r, |c| c.power_error_d),
    );
    let path = dir.join("report.html");
    write(&path, html.as_bytes())?;
    Ok(path)
}
