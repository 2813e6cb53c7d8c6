//! `specula compare` over several scenes (or a folder of them): one comparison per scene, each
//! in its own sub-folder, and a summary page with a methods × scenes table of mean FLIP and
//! frame time (schema: docs/compare-suite.schema.json). A cell's figures are over the surfaces
//! the method shades itself; those it delegates are listed apart with the delegate's name (see
//! [`crate::method_figures`]). A scene that fails to load or to render is a row with its error;
//! the others still run.

use std::path::{Path, PathBuf};

use serde::Serialize;
use specula_methods::SurfaceClass;

use crate::{escape, write_error, CompareError, Comparison, FailedMethod};

/// The version of [`SuiteReport`]'s JSON (docs/compare-suite.schema.json). 2: a cell's figures
/// are over the surfaces the method shades itself (null when none), `pixels` counts those, and
/// `delegated` lists the others. 3: cells and columns are keyed by `label` (`c3rc`,
/// `c3rc:paper`). 4: a row's `failed` lists the methods that failed on its scene, with their
/// errors (the others are in `methods`). 5: every time is a warm median (`reference_ms` too:
/// compare times the reference as it times every method), with the reference's BVH build
/// apart (`reference_build_ms`) and the number of warm frames (`frames`).
pub const SCHEMA_VERSION: u32 = 5;

/// One method's figures on one scene, under one label.
#[derive(Clone, Debug, Serialize)]
pub struct SuiteCell {
    /// The method, or the method, a colon and the preset it ran (`c3rc:paper`).
    pub label: String,
    pub method: String,
    /// Masked pixels of the surfaces the method shades itself; the three figures are over
    /// these, and are None (null) when there are none.
    pub pixels: usize,
    pub mean_flip: Option<f64>,
    pub share_flip_over_0_1: Option<f64>,
    pub rmse: Option<f64>,
    pub total_ms: f64,
    /// The reference's warm median over this one's.
    pub speedup_over_reference: f64,
    pub warnings: usize,
    /// The surfaces in view it hands to another method, with the figure there (the
    /// delegate's).
    pub delegated: Vec<SuiteDelegated>,
}

/// A method's delegated surfaces on one scene ([`crate::DelegatedReport`], in short).
#[derive(Clone, Debug, Serialize)]
pub struct SuiteDelegated {
    pub material: SurfaceClass,
    pub delegate: String,
    pub pixels: usize,
    pub mean_flip: f64,
}

impl SuiteCell {
    /// The cell's mean FLIP for a text table: its own figure, or, where it shades no pixel
    /// itself, the delegates in brackets ("(envmap)").
    pub fn flip_text(&self) -> String {
        match self.mean_flip {
            Some(f) => format!("{f:.4}"),
            None => format!(
                "({})",
                self.delegated
                    .iter()
                    .map(|d| d.delegate.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct SuiteRow {
    /// The scene as it was named on the command line (file path or built-in name).
    pub source: String,
    /// The scene's own name; empty when it failed to load.
    pub scene: String,
    /// The sub-folder holding this scene's report; empty when it failed.
    pub folder: String,
    pub width: u32,
    pub height: u32,
    pub mask_pixels: usize,
    /// Warm frames timed per method.
    pub frames: u32,
    /// The reference's warm median frame time, as every cell's `total_ms`.
    pub reference_ms: f64,
    /// Its BVH build, not in `reference_ms`.
    pub reference_build_ms: f64,
    /// gpu-trace's frame time on the same GPU (None without a GPU, or when the scene failed).
    pub gpu_trace_ms: Option<f64>,
    pub methods: Vec<SuiteCell>,
    /// The methods that failed on this scene, each with its error.
    pub failed: Vec<FailedMethod>,
    /// Why the scene has no figures; null when it has them.
    pub error: Option<String>,
}

impl SuiteRow {
    /// The error of the method `label` on this scene, if it failed.
    pub fn failure(&self, label: &str) -> Option<&str> {
        self.failed
            .iter()
            .find(|f| f.label == label)
            .map(|f| f.error.as_str())
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct SuiteReport {
    pub schema_version: u32,
    pub adapter: String,
    /// The labels compared, in column order.
    pub methods: Vec<String>,
    pub scenes: Vec<SuiteRow>,
}

/// Scene names from the command line: a folder stands for the `.toml` files in it, sorted by
/// name; anything else (a file or a built-in name) is kept as given.
pub fn expand_scenes(names: &[String]) -> Result<Vec<String>, CompareError> {
    let mut scenes = Vec::new();
    for name in names {
        let path = Path::new(name);
        if !path.is_dir() {
            scenes.push(name.clone());
            continue;
        }
        let entries = std::fs::read_dir(path).map_err(|e| write_error(path, e))?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        if files.is_empty() {
            return Err(CompareError::NoScenes {
                folder: path.display().to_string(),
            });
        }
        files.sort();
        scenes.extend(files.iter().map(|f| f.display().to_string()));
    }
    Ok(scenes)
}

/// A folder name for `source` (its file stem, or the built-in name), made unique among `taken`.
fn folder_name(source: &str, taken: &[String]) -> String {
    let stem = Path::new(source)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| source.to_string());
    let clean: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut name = clean.clone();
    let mut k = 2;
    while taken.contains(&name) {
        name = format!("{clean}-{k}");
        k += 1;
    }
    name
}

/// Writes a compared scene's report into its own sub-folder of `dir` (named after `source`,
/// unique among `taken`, which it joins) and returns its row of the summary; a failed scene's
/// row holds its error.
pub fn scene_row(
    dir: &Path,
    source: &str,
    outcome: Result<&Comparison, &str>,
    taken: &mut Vec<String>,
) -> Result<SuiteRow, CompareError> {
    let comparison = match outcome {
        Ok(c) => c,
        Err(message) => {
            return Ok(SuiteRow {
                source: source.to_string(),
                scene: String::new(),
                folder: String::new(),
                width: 0,
                height: 0,
                mask_pixels: 0,
                frames: 0,
                reference_ms: 0.0,
                reference_build_ms: 0.0,
                gpu_trace_ms: None,
                methods: Vec::new(),
                failed: Vec::new(),
                error: Some(message.to_string()),
            })
        }
    };
    let folder = folder_name(source, taken);
    comparison.write_report(&dir.join(&folder))?;
    taken.push(folder.clone());
    let r = &comparison.report;
    Ok(SuiteRow {
        source: source.to_string(),
        scene: r.scene.clone(),
        folder,
        width: r.width,
        height: r.height,
        mask_pixels: r.mask_pixels,
        frames: r.frames,
        reference_ms: r.reference.total_ms,
        reference_build_ms: r.reference.build_ms,
        gpu_trace_ms: r.gpu_trace_ms,
        methods: r
            .methods
            .iter()
            .map(|m| SuiteCell {
                label: m.label.clone(),
                method: m.method.clone(),
                pixels: m.metrics.as_ref().map_or(0, |x| x.mask_pixels),
                mean_flip: m.metrics.as_ref().map(|x| x.mean_flip),
                share_flip_over_0_1: m.metrics.as_ref().map(|x| x.share_flip_over_0_1),
                rmse: m.metrics.as_ref().map(|x| x.rmse),
                total_ms: m.total_ms,
                speedup_over_reference: m.speedup_over_reference,
                warnings: m.warnings.len(),
                delegated: m
                    .delegated
                    .iter()
                    .map(|d| SuiteDelegated {
                        material: d.material,
                        delegate: d.delegate.clone(),
                        pixels: d.metrics.mask_pixels,
                        mean_flip: d.metrics.mean_flip,
                    })
                    .collect(),
            })
            .collect(),
        failed: r.failed.clone(),
        error: None,
    })
}

/// Writes the summary, `report.html` (the methods × scenes table, linking to each scene's
/// page) and `report.json`, into `dir`; returns the HTML's path.
pub fn write_summary(dir: &Path, report: &SuiteReport) -> Result<PathBuf, CompareError> {
    std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
    let json = dir.join("report.json");
    let text = serde_json::to_string_pretty(report).map_err(|e| write_error(&json, e))?;
    std::fs::write(&json, text).map_err(|e| write_error(&json, e))?;
    let html = dir.join("report.html");
    std::fs::write(&html, suite_html(report)).map_err(|e| write_error(&html, e))?;
    Ok(html)
}

/// A cell's background: green at FLIP 0 through yellow to red at 0.3 and above.
fn flip_colour(flip: f64) -> String {
    let t = (flip / 0.3).clamp(0.0, 1.0);
    let (r, g) = if t < 0.5 {
        (510.0 * t, 255.0)
    } else {
        (255.0, 510.0 * (1.0 - t))
    };
    format!("rgb({:.0},{:.0},120)", r * 0.6 + 100.0, g * 0.6 + 100.0)
}

fn suite_html(report: &SuiteReport) -> String {
    let mut head =
        String::from("<tr><th>scene</th><th>pixels</th><th>reference ms (warm; BVH build)</th><th>gpu-trace ms</th>");
    for m in &report.methods {
        head.push_str(&format!(
            "<th>{} FLIP</th><th>{} ms</th>",
            escape(m),
            escape(m)
        ));
    }
    head.push_str("</tr>\n");
    let mut rows = String::new();
    for row in &report.scenes {
        if let Some(error) = &row.error {
            rows.push_str(&format!(
                "<tr><td>{}</td><td colspan=\"{}\" class=\"error\">{}</td></tr>\n",
                escape(&row.source),
                3 + 2 * report.methods.len(),
                escape(error)
            ));
            continue;
        }
        rows.push_str(&format!(
            "<tr><td><a href=\"{}/report.html\">{}</a></td><td>{}</td><td>{:.1}<br><small>{:.1}</small></td><td>{}</td>",
            escape(&row.folder),
            escape(&row.scene),
            row.mask_pixels,
            row.reference_ms,
            row.reference_build_ms,
            row.gpu_trace_ms
                .map(|g| format!("{g:.1}"))
                .unwrap_or_else(|| "–".into())
        ));
        for method in &report.methods {
            match row.methods.iter().find(|c| &c.label == method) {
                Some(c) => rows.push_str(&format!(
                    "<td{}>{}{}</td><td>{:.1}<br><small>{:.2}×</small></td>",
                    match (c.mean_flip, c.share_flip_over_0_1, c.rmse) {
                        (Some(flip), Some(share), Some(rmse)) => format!(
                            " style=\"background:{}\" title=\"{} pixels of its own; FLIP &gt; 0.1 on {:.1} % of them; RMSE {:.4}; {} warnings\"",
                            flip_colour(flip),
                            c.pixels,
                            share * 100.0,
                            rmse,
                            c.warnings
                        ),
                        _ => " class=\"delegated\" title=\"no pixel of its own\"".to_string(),
                    },
                    c.mean_flip
                        .map(|f| format!("{f:.4}"))
                        .unwrap_or_else(|| "–".into()),
                    c.delegated
                        .iter()
                        .map(|d| format!(
                            "<br><small>{} {}: {} {:.4}</small>",
                            d.pixels,
                            d.material,
                            escape(&d.delegate),
                            d.mean_flip
                        ))
                        .collect::<String>(),
                    c.total_ms,
                    c.speedup_over_reference
                )),
                None => match row.failure(method) {
                    Some(error) => rows.push_str(&format!(
                        "<td colspan=\"2\" class=\"error\">failed: {}</td>",
                        escape(error)
                    )),
                    None => rows.push_str("<td>–</td><td>–</td>"),
                },
            }
        }
        rows.push_str("</tr>\n");
    }
    format!(
        r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>specula compare: {count} scenes</title>
<style>
body {{ font-family: sans-serif; margin: 2em; background: #fafafa; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border: 1px solid #bbb; padding: 4px 8px; text-align: right; }}
td:first-child, th:first-child {{ text-align: left; }}
td.error {{ text-align: left; color: #a00; }}
td.delegated, small {{ color: #666; font-style: italic; }}
</style></head><body>
<h1>specula compare: {count} scenes</h1>
<p>On {adapter}. Mean FLIP over each scene's mirror and dielectric pixels against the exact
reference (green 0, red ≥ 0.3; hover for the share over 0.1 and the RMSE), and each method's frame
time in milliseconds with its speed-up over the reference below it: every time, the reference's included, is the
median of warm frames (each method prepared and its first frame rendered before them; the reference's BVH build
is listed apart under its time), so each speed-up divides a warm time by a warm time. A column <code>METHOD:paper</code> runs the method's published algorithm (its
<code>paper</code> preset: every step beyond the paper off), beside the column of specula's version. A cell's figure is over the surfaces the method shades itself; surfaces it
hands to another method are listed under it in small type ("N refractor: envmap 0.36": those N
pixels are envmap's shading, and the figure is envmap's). A scene's name links to its own report
with the images and heat-maps.</p>
<table>
{head}{rows}</table>
</body></html>
"#,
        count = report.scenes.len(),
        adapter = escape(&report.adapter),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folder_names_are_file_stems_made_unique() {
        let mut taken = Vec::new();
        for source in [
            "a/glass.toml",
            "b/glass.toml",
            "door-mirror",
            "x/my scene.toml",
        ] {
            let name = folder_name(source, &taken);
            taken.push(name);
        }
        assert_eq!(taken, ["glass", "glass-2", "door-mirror", "my_scene"]);
    }

    #[test]
    fn a_folder_expands_to_its_toml_files_in_name_order() {
        let dir = tempfile::tempdir().unwrap();
        for f in ["b.toml", "a.toml", "notes.md"] {
            std::fs::write(dir.path().join(f), "").unwrap();
        }
        let folder = dir.path().display().to_string();
        let scenes = expand_scenes(&["door-mirror".into(), folder.clone()]).unwrap();
        assert_eq!(
            scenes,
            [
                "door-mirror".to_string(),
                format!("{folder}/a.toml"),
                format!("{folder}/b.toml")
            ]
        );
        let empty = tempfile::tempdir().unwrap();
        let error = expand_scenes(&[empty.path().display().to_string()]).unwrap_err();
        assert!(error.to_string().contains("no .toml scene"), "{error}");
    }
}
