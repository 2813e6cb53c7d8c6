//! glare's report folder: report.html, report.json, the eye points' map and the worst eye
//! point's view with its glare outlined (a sweep adds its map and polar plot), as PNG and SVG.

use std::path::{Path, PathBuf};

use crate::figure::html_escape;
use crate::report::{write, write_error, write_plot, STYLE};
use crate::AnalyzeError;

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
    write_plot(dir, "eyebox", &super::plots::glare_eyebox(r, frame))?;
    let shown = r.worst_eye.unwrap_or(0);
    write_plot(dir, "worst", &super::plots::glare_image(glare, shown))?;
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
        scene = html_escape(&r.scene),
        source = html_escape(&r.source),
        surface = html_escape(&r.surface),
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
            html_escape(&d.name),
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
            html_escape(&day.date),
            day.day_of_year,
            day.latitude_deg,
            day.heading_deg,
            solar_runs(&day.glare_hours),
            solar_runs(&day.washed_out_hours)
        ));
    }
    text
}
