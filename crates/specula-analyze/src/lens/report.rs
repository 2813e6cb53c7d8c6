//! lens's report folder: report.html (the verdict first where a standard was checked), report.json,
//! the maps (mean power, cylinder, prism, lateral colour) and the distortion picture as PNG and
//! SVG.

use std::path::{Path, PathBuf};

use crate::figure::html_escape;
use crate::report::{write, write_error, write_plot, STYLE};
use crate::AnalyzeError;

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
                html_escape(z.criterion),
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
    use super::plot::{self, Map};
    std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
    let json = serde_json::to_string_pretty(r).map_err(|e| write_error(dir, e))?;
    write(&dir.join("report.json"), json.as_bytes())?;
    let mut figures = String::new();
    for map in Map::of(r) {
        write_plot(dir, map.name(), &plot::lens_map(r, map))?;
        figures.push_str(&format!(
            "<figure><img src=\"{0}.svg\"><figcaption>{0}</figcaption></figure>\n",
            map.name()
        ));
    }
    for kind in plot::LensCoordinateMap::ALL {
        if let Some(plot) = plot::lens_coordinate_map(r, kind) {
            write_plot(dir, kind.name(), &plot)?;
            figures.push_str(&format!(
                "<figure><img src=\"{0}.svg\"><figcaption>{0}</figcaption></figure>\n",
                kind.name()
            ));
        }
    }
    write_plot(dir, "distortion", &plot::distortion(r))?;
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
        scene = html_escape(&r.scene),
        lens = html_escape(&r.lens),
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
