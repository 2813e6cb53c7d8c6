//! mirror-view's report folder: report.html (the verdict first where one was judged, the
//! figures per eye point, the parameters, the plots), report.json, the ground map and the mirror
//! seen from the first eye point as PNG and SVG.

use std::path::{Path, PathBuf};

use glam::Vec3;
use specula_scene::Scene;
use specula_trace::SceneAccel;

use super::plot;
use super::{Figures, MirrorView};
use crate::figure::html_escape;
use crate::report::{write, write_error, write_plot, STYLE};
use crate::AnalyzeError;

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
    // What the terminal warns of, the page says first too.
    let warnings: String = r
        .warnings
        .iter()
        .map(|w| format!("<p><strong>Warning:</strong> {}</p>\n", html_escape(w)))
        .collect();
    let html = format!(
        r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>specula analyze mirror-view: {scene}</title>
<style>{style}{verdict_style}</style></head><body>
<h1>What '{mirror}' shows: {scene}</h1>
{warnings}{verdict}<h2>What the mirror shows</h2>
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
        scene = html_escape(&r.scene),
        mirror = html_escape(&r.mirror),
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
